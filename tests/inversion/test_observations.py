"""One type of a lightcurve with its geometry, and the bad input an inversion refuses.

``LightcurveObservations`` (photometry) is what fitting and inversion read; the
inversion's ``ObservedLightcurve`` is the same type in intensities at the body's epochs.
Each bad input raises a specific error naming the file and the line (or the key).
"""

from __future__ import annotations

import astropy.units as u
import numpy as np
import pytest
from astropy.time import Time

import attitude as att
from attitude.foundations.errors import LightcurveFormatError, PhotometryError
from attitude.inversion import ObservedLightcurve, engine_blocks, read_damit_lightcurves
from attitude.inversion.invert import _example_observations
from attitude.photometry import Geometry, LightcurveObservations

EPOCH = Time("2026-01-01", scale="tdb")
GEOM = Geometry(sun=[1.0, 0.0, 0.0], observer=[1.0, 0.2, 0.0])
ALCDEF = """STARTMETADATA
DELIMITER=PIPE
LTCAPP=NONE
ENDMETADATA
DATA=2461100.50|14.00|0.01
DATA=2461100.51|{}|0.01
DATA=2461100.52|14.20|0.01
ENDDATA
"""


def test_the_inversion_block_is_a_lightcurve_observations_in_intensities():
    obs = ObservedLightcurve(EPOCH, [0.0, 600.0], [1.0, 0.5], GEOM, sigma=[0.01, 0.02])
    assert isinstance(obs, LightcurveObservations)
    assert att.LightcurveObservations is LightcurveObservations        # fitting's name
    # m = -2.5 log10(I) and sigma_m = (2.5 / ln 10) sigma_I / I, each to a few ulps
    np.testing.assert_allclose(obs.magnitudes, [0.0, 2.5 * np.log10(2.0)], rtol=4e-16,
                               atol=0)
    np.testing.assert_allclose(obs.magnitude_sigma,
                               2.5 / np.log(10.0) * np.array([0.01, 0.04]), rtol=4e-16)
    assert obs.time.tolist() == [0.0, 600.0] and obs.brightness.tolist() == [1.0, 0.5]
    assert obs.sigma.tolist() == [0.01, 0.02]          # the engine's unit: intensity


def test_engine_blocks_split_sessions_and_keep_one_clock():
    times = Time("2026-01-01T00:00", scale="tdb") + np.array([0.0, 600.0, 86400.0,
                                                              87000.0]) * u.s
    mag = np.array([14.0, 14.1, 14.5, 14.4])
    obs = LightcurveObservations(times, mag, 0.01, GEOM, sessions=[3, 3, 7, 7],
                                 name="x.alcdef")
    a, b = engine_blocks(obs)
    assert (a.name, b.name) == ("x.alcdef, session 3", "x.alcdef, session 7")
    assert a.epoch == b.epoch == obs.epoch
    # seconds of TDB from JDs differing by whole and 1/144 days: 1e-5 s resolves them
    np.testing.assert_allclose(np.concatenate([a.time, b.time]),
                               [0.0, 600.0, 86400.0, 87000.0], atol=1e-5, rtol=0)
    np.testing.assert_allclose(b.brightness, 10 ** (-0.4 * mag[2:]), rtol=4e-16)
    np.testing.assert_allclose(b.brightness_sigma, b.brightness * 0.01 / (2.5 / np.log(10)),
                               rtol=4e-16)


def test_observations_read_for_an_inversion_take_a_shape_for_a_fit():
    obs = ObservedLightcurve(EPOCH, [0.0, 600.0], [1.0, 0.5], GEOM)
    with pytest.raises(att.AttitudeError, match="with_shape") as err:
        obs.model_magnitudes(np.tile([0.0, 0, 0, 1], (1, 2, 1)))
    assert err.value.key == "shape"
    shaped = obs.with_shape(att.Polyhedron.ellipsoid(2.0, 1.0, 1.0, subdivisions=1))
    assert type(shaped) is LightcurveObservations and shaped.shape is not None
    np.testing.assert_array_equal(shaped.magnitudes, obs.magnitudes)
    np.testing.assert_array_equal(shaped.magnitude_sigma, obs.magnitude_sigma)


# ---------------------------------------------------------------- bad input, named
def test_a_nan_magnitude_names_the_file_and_line(tmp_path):
    path = tmp_path / "nan.alcdef"
    path.write_text(ALCDEF.format("nan"))
    with pytest.raises(LightcurveFormatError, match="non-finite") as err:
        att.read_lightcurve(path, geometry=GEOM)
    assert (err.value.path, err.value.key) == (str(path), "line 6")
    csv = tmp_path / "nan.csv"
    csv.write_text("jd,mag,mag_err\n2461100.5,14.0,0.01\n2461100.6,NaN,0.01\n")
    with pytest.raises(LightcurveFormatError) as err:
        att.read_lightcurve(csv, geometry=GEOM)
    assert (err.value.path, err.value.key) == (str(csv), "line 3")


def test_a_nan_brightness_in_a_damit_file_names_the_line(tmp_path):
    path = tmp_path / "lcs"
    path.write_text("1\n2 0\n2451545.0 1.0 1 0 0 1 0.1 0\n2451545.1 nan 1 0 0 1 0.1 0\n")
    with pytest.raises(LightcurveFormatError, match="not finite") as err:
        read_damit_lightcurves(path)
    assert (err.value.path, err.value.key) == (str(path), "line 4")


def test_a_point_without_geometry_names_the_file_and_line(tmp_path):
    damit = tmp_path / "lcs"
    damit.write_text("1\n2 0\n2451545.0 1.0 1 0 0 1 0.1 0\n2451545.1 1.0 1 0 0\n")
    with pytest.raises(LightcurveFormatError, match="8 numbers") as err:
        read_damit_lightcurves(damit)
    assert err.value.key == "line 4"
    damit.write_text("1\n2 0\n2451545.0 1.0 1 0 0 1 0.1 0\n2451545.1 1.0 0 0 0 1 0.1 0\n")
    with pytest.raises(LightcurveFormatError, match="zero Sun") as err:
        read_damit_lightcurves(damit)
    assert err.value.key == "line 4"
    alcdef = tmp_path / "three.alcdef"
    alcdef.write_text(ALCDEF.format("14.1"))
    two = Geometry(sun=[[1, 0, 0], [1, 0, 0]], observer=[[1, 0.2, 0], [1, 0.2, 0]])
    with pytest.raises(LightcurveFormatError, match="2 directions for the file's 3") as err:
        att.read_lightcurve(alcdef, geometry=two)
    assert (err.value.path, err.value.key) == (str(alcdef), "geometry")


def test_a_point_without_an_uncertainty_needs_sigma(tmp_path):
    path = tmp_path / "noerr.alcdef"
    path.write_text(ALCDEF.format("14.1").replace("|14.20|0.01", "|14.20"))
    with pytest.raises(LightcurveFormatError, match="sigma=") as err:
        att.read_lightcurve(path, geometry=GEOM)
    assert (err.value.path, err.value.key) == (str(path), "line 1")   # its session
    [obs] = att.read_lightcurve(path, geometry=GEOM, sigma=0.05)
    assert obs.magnitude_sigma.tolist() == [0.01, 0.01, 0.05]


def test_a_single_session_too_short_for_the_period_names_it(tmp_path):
    path = tmp_path / "short.alcdef"
    path.write_text(ALCDEF.format("14.1"))                 # 0.02 d = 0.48 h
    obs = att.read_lightcurve(path, geometry=GEOM)
    with pytest.raises(PhotometryError, match="0.48 h cannot give a period of 5 h") as err:
        att.invert(obs, rotation="principal", period="5 h", rows=2, degree=0)
    assert "short.alcdef: session 0 (line 1)" in err.value.reason
    assert err.value.key == "period"


def test_fewer_points_than_parameters_names_the_files():
    obs = _example_observations()                           # 3 x 60 points
    with pytest.raises(PhotometryError, match="180 points for 199 parameters") as err:
        att.invert(obs, rotation="principal", period=7200.0, rows=4, degree=13)
    assert err.value.key == "observations"
    with pytest.raises(PhotometryError, match="180 points for 204 parameters"):
        att.invert(obs, rotation="tumbling", rows=4, degree=13)

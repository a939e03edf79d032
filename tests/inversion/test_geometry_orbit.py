"""ALCDEF / CSV lightcurves with their geometry from the orbit, inverted end to end.

A convex body (pole, period known) on a known heliocentric orbit is seen from the
geocentre on six nights two months apart (aspects a year apart: the pole is
determined); its lightcurves are written as an ALCDEF and a CSV file with
the observer's UTC Julian dates (light time *not* applied), read back with
``read_lightcurve(path, geometry=Geometry.from_orbit(orbit, observer="earth", epoch=...))``
(the geometry recomputed from the elements, the light time solved at reception) and
inverted.

Tolerances: the Julian dates are written with 10 decimals (a rounding of at most
``5e-11 d = 4.3 us``; the JD as one double resolves ``2.5e6 * 2**-52 d = 48 us``), so the
body's rotation phase is off by at most ``2 pi 48e-6 s / P = 4.2e-8 rad`` at ``P = 2 h``
and the relative flux of the model by at most its amplitude (< 1) times that: the rms of
the inversion is below ``1e-7``; a phase error spread over the ``2.6e7 s`` of the data
shifts the period by at most ``P 48e-6 / 2.6e7``, relative ``2e-12``; the pole, fitted to
flux errors of ``1e-7``, moves by well under ``1e-4 deg``.  Without the light time (an
error of 10 to 20 minutes that changes by minutes from night to night) the same fit
cannot follow the data: its rms is at least 1e3 times larger.
"""

from __future__ import annotations

import numpy as np
import pytest
from astropy.time import Time

import attitude as att
from attitude.foundations.constants import SPEED_OF_LIGHT
from attitude.foundations.errors import LightcurveFormatError, PhotometryError
from attitude.inversion import (
    ConvexModel,
    GaussianImage,
    ObservedLightcurve,
    engine_blocks,
    fit_convex,
)
from attitude.model.orbit import KeplerOrbit
from attitude.photometry import Geometry, LightcurveObservations
from attitude.photometry.geometry import OrbitGeometry

EPOCH = Time("2026-03-01T00:00:00", scale="tdb")
ORBIT = KeplerOrbit.from_elements(mu="1.32712440018e20 m3/s2", a="2.2 AU", e=0.12,
                                  i="9 deg", raan="80 deg", argp="30 deg",
                                  mean_anomaly="150 deg")
POLE = (0.5, 1.0)                   # rad, ecliptic J2000
PERIOD = 7200.0                     # s
NIGHTS, POINTS = 6, 40


def observer_times() -> Time:
    """Six nights of six hours, 60 days apart, UTC at the geocentre."""
    start = Time("2026-03-02T18:00:00", scale="utc")
    hours = np.linspace(0.0, 6.0, POINTS)
    jd = np.concatenate([start.jd + 60.0 * k + hours / 24.0 for k in range(NIGHTS)])
    return Time(np.round(jd, 10), format="jd", scale="utc")


def synthetic_magnitudes(times: Time) -> np.ndarray:
    """Magnitudes of the convex body of POLE and PERIOD (plus a zero point per night)."""
    geom = OrbitGeometry(ORBIT, "earth", EPOCH).at(times)
    body = (times.tdb - EPOCH).to_value("s") - geom.light_time
    night = np.repeat(np.arange(NIGHTS), POINTS)
    blocks = [ObservedLightcurve(EPOCH, body[night == k], np.ones(POINTS),
                                 geom.take(night == k)) for k in range(NIGHTS)]
    truth = np.zeros(9)
    truth[6], truth[8] = 0.3, 0.4            # flattened along z, elongated along x
    model = ConvexModel(blocks, GaussianImage(4, 2))
    flux = model.brightness(truth, *POLE, PERIOD)
    return -2.5 * np.log10(flux) + 14.0 + 0.3 * night


def write_alcdef(path, times: Time, mag: np.ndarray) -> None:
    lines = []
    for k in range(NIGHTS):
        lines += ["STARTMETADATA", "OBJECTNAME=Synthetic", "DELIMITER=PIPE",
                  "LTCAPP=NONE", "DIFFERMAGS=TRUE", "ENDMETADATA"]
        sel = slice(k * POINTS, (k + 1) * POINTS)
        lines += [f"DATA={jd:.10f}|{m:.10f}|0.01" for jd, m in zip(times.jd[sel], mag[sel])]
        lines.append("ENDDATA")
    path.write_text("\n".join(lines) + "\n")


def write_csv(path, times: Time, mag: np.ndarray) -> None:
    night = np.repeat(np.arange(NIGHTS), POINTS)
    rows = ["jd,mag,mag_err,session"] + [f"{jd:.10f},{m:.10f},0.01,{s}" for jd, m, s in
                                         zip(times.jd, mag, night)]
    path.write_text("\n".join(rows) + "\n")


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    folder = tmp_path_factory.mktemp("geometry")
    times = observer_times()
    mag = synthetic_magnitudes(times)
    write_alcdef(folder / "synthetic.alcdef", times, mag)
    write_csv(folder / "synthetic.csv", times, mag)
    return folder


def _angle(pole, truth):
    a = np.radians(pole)
    u = [np.cos(a[1]) * np.cos(a[0]), np.cos(a[1]) * np.sin(a[0]), np.sin(a[1])]
    v = [np.cos(truth[1]) * np.cos(truth[0]), np.cos(truth[1]) * np.sin(truth[0]),
         np.sin(truth[1])]
    return np.degrees(np.arctan2(np.linalg.norm(np.cross(u, v)), np.dot(u, v)))


@pytest.mark.parametrize("name", ["synthetic.alcdef", "synthetic.csv"])
def test_alcdef_and_csv_with_the_orbit_invert_to_the_known_pole_and_period(files, name):
    obs = att.read_lightcurve(files / name,
                              geometry=Geometry.from_orbit(ORBIT, observer="earth",
                                                           epoch=EPOCH))
    assert [len(o) for o in obs] == [POINTS] * NIGHTS
    assert all(isinstance(o, LightcurveObservations) for o in obs)
    assert obs[0].epoch.scale == "tdb" and obs[0].times.scale == "utc"
    res = att.invert(obs, rotation="principal", period=PERIOD * 1.000001, poles=10, rows=4,
                     degree=2)
    assert res.rms < 1e-7
    assert abs(res.period / PERIOD - 1.0) < 1e-10
    assert _angle(res.pole, POLE) < 1e-4


def test_without_the_light_time_the_same_data_do_not_fit(files):
    """At the true pole and period, the best shape fits the data read with the light
    time to the rounding of the file, and cannot fit them read without it."""
    path = files / "synthetic.alcdef"
    rms = []
    for light_time in (True, False):
        obs = att.read_lightcurve(path, geometry=Geometry.from_orbit(
            ORBIT, observer="earth", epoch=EPOCH, light_time=light_time))
        model = ConvexModel(engine_blocks(obs), GaussianImage(4, 2))
        rms.append(fit_convex(model, *POLE, PERIOD, free_period=False,
                              max_iterations=50).rms)
    assert rms[0] < 1e-7
    assert rms[1] > 1e3 * 1e-7


def test_the_light_time_is_solved_at_reception():
    """Delta(t) = c tau with the observer at reception t and the body at t - tau, and
    the geometry of the body times given to from_orbit is the same."""
    times = observer_times()[:3]
    geom = OrbitGeometry(ORBIT, "earth", EPOCH).at(times)
    t = (times.tdb - EPOCH).to_value("s")
    body = t - geom.light_time
    r_body = ORBIT.position(body)
    # the Earth from the 'sun' observer path is zero; recompute it from from_orbit
    forward = Geometry.from_orbit(ORBIT, body, "earth", epoch=EPOCH)
    # c tau = |r_earth(t) - r_body(t - tau)|: both sides within the fixed point's residual
    # (contraction |v|/c ~ 1e-4 per iteration, 4 iterations: ~1e-16 relative) and the
    # round-off of 3e11 m distances (~1e-16 relative)
    assert np.allclose(geom.observer_distance, SPEED_OF_LIGHT * geom.light_time,
                       rtol=1e-12, atol=0)
    assert np.allclose(forward.light_time, geom.light_time, rtol=1e-9, atol=0)
    assert np.allclose(forward.observer, geom.observer, rtol=0, atol=1e-9)
    assert np.allclose(-r_body / np.linalg.norm(r_body, axis=1)[:, None], geom.sun,
                       rtol=0, atol=1e-15)
    assert 600.0 < geom.light_time.min() < geom.light_time.max() < 2000.0


def test_an_orbit_geometry_needs_an_epoch():
    with pytest.raises(PhotometryError, match="epoch"):
        Geometry.from_orbit(ORBIT, observer="earth")
    with pytest.raises(PhotometryError, match="astropy Time"):
        OrbitGeometry(ORBIT, "earth", EPOCH).at(np.array([0.0, 1.0]))


def test_an_alcdef_session_corrected_without_ltcdays_is_refused(tmp_path):
    path = tmp_path / "corrected.alcdef"
    path.write_text("STARTMETADATA\nDELIMITER=PIPE\nLTCAPP=HELIO\nENDMETADATA\n"
                    "DATA=2461100.5|14.0|0.01\nDATA=2461100.6|14.1|0.01\nENDDATA\n")
    with pytest.raises(LightcurveFormatError, match="LTCDAYS") as err:
        att.read_lightcurve(path, geometry=Geometry.from_orbit(ORBIT, epoch=EPOCH))
    assert err.value.key == "line 7" and err.value.path == str(path)


def test_an_alcdef_session_corrected_with_ltcdays_gets_its_observer_times_back(tmp_path):
    text = ("STARTMETADATA\nDELIMITER=PIPE\nLTCAPP={}\n{}ENDMETADATA\n"
            "DATA=2461100.5|14.0|0.01\nDATA=2461100.6|14.1|0.01\nENDDATA\n")
    (tmp_path / "a.alcdef").write_text(text.format("NONE", ""))
    (tmp_path / "b.alcdef").write_text(text.format("HELIO", "LTCDAYS=0.25\n")
                                       .replace("2461100.5", "2461100.25")
                                       .replace("2461100.6", "2461100.35"))
    recipe = Geometry.from_orbit(ORBIT, epoch=EPOCH)
    [a] = att.read_lightcurve(tmp_path / "a.alcdef", geometry=recipe)
    [b] = att.read_lightcurve(tmp_path / "b.alcdef", geometry=recipe)
    # the same observer epochs (2.5e6 d resolved to 4.7e-10 d = 40 us as one double)
    assert np.allclose((a.times - b.times).to_value("s"), 0.0, atol=1e-4)

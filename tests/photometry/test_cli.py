"""`attitude lightcurve`: the [photometry] table, the lightcurve [expect] keys, the
figures, and exit code 2 with a one-line message for bad input."""

from __future__ import annotations

import json

import numpy as np
import pytest

from attitude.app.cli import main

SCENARIO = """
[scenario]
name = "spinning ellipsoid"

[body]
principal_moments = [{A}, {B}, {C}]

[state]
epoch = "2030-01-01T00:00:00"
frame = "ICRF"
attitude = {{ quaternion_scalar_last = [0, 0, 0, 1] }}
omega_body = {{ value = [0.0, 0.0, 1.0], unit = "rev/h" }}

[propagation]
duration = "10 h"
step = "5 min"

[photometry]
{photometry}

[expect]
{expect}
"""

# semi-axes 3 : 2 : 1.5 -> moments of the homogeneous ellipsoid
AXES = np.array([3.0, 2.0, 1.5])
A, B, C = AXES[1] ** 2 + AXES[2] ** 2, AXES[0] ** 2 + AXES[2] ** 2, AXES[0] ** 2 + AXES[1] ** 2
GOOD = """shape = "ellipsoid"
subdivisions = 3
law = "lommel-seeliger"
sun = [1.0, 0.0, 0.0]
observer = [1.0, 0.0, 0.0]
periods = 1
order = 4
output = "lc.nc"
"""
# a principal-axis spin about c, seen at zero phase in the equator: a double-peaked curve
# with the rotation period (1 h) and the amplitude 2.5 log10(a/b) (projected area)
EXPECT = """lightcurve_period = { value = 1.0, unit = "h", rel_tol = 1e-4 }
lightcurve_amplitude = { value = %.6f, unit = "mag", abs_tol = 0.01 }
""" % (2.5 * np.log10(AXES[0] / AXES[1]))


def _write(tmp_path, photometry=GOOD, expect=EXPECT):
    path = tmp_path / "lc.toml"
    path.write_text(SCENARIO.format(A=A, B=B, C=C, photometry=photometry, expect=expect))
    return path


def test_lightcurve_command_writes_prints_and_checks(tmp_path, capsys):
    path = _write(tmp_path)
    report = tmp_path / "report.json"
    assert main(["lightcurve", str(path), "--report", str(report), "--plot"]) == 0
    out = capsys.readouterr().out
    assert "lightcurve period (double-peaked" in out and "ok   lightcurve_period" in out
    assert (tmp_path / "lc.nc").is_file()
    for name in ("lightcurve", "periodogram", "folded"):
        assert (tmp_path / f"lc_{name}.png").is_file()
    data = json.loads(report.read_text())
    assert data["lightcurve_period_h"] == pytest.approx(1.0, rel=1e-4)
    assert all(e["ok"] for e in data["expect"])


def test_failed_expectation_exits_1(tmp_path):
    path = _write(tmp_path, expect='lightcurve_period = { value = 2.0, unit = "h", '
                                   'rel_tol = 1e-3 }\n')
    assert main(["lightcurve", str(path), "--quiet"]) == 1


@pytest.mark.parametrize("change, key", [
    (('law = "lommel-seeliger"', 'law = "lambertian"'), "photometry.law"),
    (('law = "lommel-seeliger"', 'law = { name = "lommel-seeliger", albedo = -0.2 }'),
     "photometry.law"),
    (("sun = [1.0, 0.0, 0.0]", "sun = [0.0, 0.0, 0.0]"), "photometry.sun"),
    (("observer = [1.0, 0.0, 0.0]", "observer = [-1.0, 0.0, 0.0]"), "photometry.sun"),
    (('shape = "ellipsoid"', 'shape = "open.obj"'), "photometry.shape"),
    (("periods = 1", "periods = 3"), "photometry.periods"),
    (("order = 4", "colour = 4"), "photometry.colour"),
])
def test_bad_input_exits_2_naming_the_key(tmp_path, capsys, change, key):
    (tmp_path / "open.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n"
                                       "f 1 3 2\nf 1 2 4\nf 1 4 3\n")
    path = _write(tmp_path, GOOD.replace(*change))
    assert main(["lightcurve", str(path)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and f"{path}: {key}:" in err, err


def test_no_photometry_table_exits_2(tmp_path, capsys):
    path = _write(tmp_path)
    text = path.read_text()
    path.write_text(text[:text.index("[photometry]")])
    assert main(["lightcurve", str(path)]) == 2
    assert "no [photometry] table" in capsys.readouterr().err


def test_check_includes_the_lightcurve_expectations(tmp_path, capsys):
    path = _write(tmp_path, expect=EXPECT + 'regime = "PA-short"\n')
    assert main(["check", str(path), "--jobs", "1"]) == 0
    out = capsys.readouterr().out
    assert "lightcurve_period" in out and "lightcurve_amplitude" in out and "3 passed" in out
    assert not (tmp_path / "lc.nc").exists()          # check writes nothing


def test_orbit_geometry_from_the_scenario(tmp_path):
    """[photometry] orbit + observer = "earth": per-epoch geometry with distances and
    light time stored in the lightcurve file."""
    from attitude.photometry import read_lightcurve

    orbit = ('orbit = { mu = "1.32712440018e20 m3/s2", a = "1.2 AU", e = 0.1, '
             'i = "5 deg", mean_anomaly = "30 deg" }\nobserver = "earth"\n')
    photometry = GOOD.replace("sun = [1.0, 0.0, 0.0]\nobserver = [1.0, 0.0, 0.0]\n", orbit)
    path = _write(tmp_path, photometry, expect="")
    assert main(["lightcurve", str(path), "--quiet"]) == 0
    ds = read_lightcurve(tmp_path / "lc.nc").dataset
    au = 149_597_870_700.0
    assert np.all((ds.sun_distance.values > 1.07 * au) & (ds.sun_distance.values < 1.33 * au))
    np.testing.assert_allclose(ds.light_time.values, ds.observer_distance.values
                               / 299_792_458.0, rtol=1e-4)
    assert np.all(ds.phase_angle.values > 0)

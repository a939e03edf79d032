"""Scenario files: parsing, validation errors (one line naming file and key), runs."""

import textwrap

import numpy as np
import pytest

import attitude as att
from attitude.scenario import load_scenario, run_scenario

GOOD = """
[scenario]
name = "test body"

[body]
principal_moments = [1.0, 2.0, 3.0]

[state]
epoch = "2030-01-01T00:00:00"
time_scale = "tdb"
frame = "ICRF"
attitude = { quaternion_scalar_last = [0, 0, 0, 1] }
omega_body = { value = [5.0, 0.0, 20.0], unit = "deg/s" }

[propagation]
duration = "2 min"
step = "10 s"

[output]
netcdf = "out.nc"
"""


def write(tmp_path, text, name="s.toml"):
    path = tmp_path / name
    path.write_text(textwrap.dedent(text))
    return path


def test_good_scenario_is_parsed_with_units(tmp_path):
    sc = load_scenario(write(tmp_path, GOOD))
    assert sc.name == "test body"
    np.testing.assert_allclose(sc.state.omega_body, np.radians([5.0, 0.0, 20.0]), rtol=1e-15)
    assert sc.state.epoch.scale == "tdb"
    assert sc.duration == 120.0 and sc.step == 10.0
    np.testing.assert_allclose(sc.times, np.arange(0.0, 121.0, 10.0))
    assert sc.netcdf == tmp_path / "out.nc"


@pytest.mark.parametrize("old, new, key, message", [
    ('name = "test body"', 'nmae = "x"', "scenario.nmae", "did you mean 'name'"),
    ("[propagation]", "[propagaton]", "propagaton", "did you mean 'propagation'"),
    ('duration = "2 min"', 'duration = "2 parsecs per fortnight"', "propagation.duration",
     "cannot parse"),
    ('duration = "2 min"', 'duration = "2 kg"', "propagation.duration", "cannot be converted"),
    ('step = "10 s"', "step = -1.0", "propagation.step", "must be positive"),
    ('step = "10 s"', "", "propagation.step", "missing key"),
    ("principal_moments = [1.0, 2.0, 3.0]", "principal_moments = [1.0, 1.0, 3.0]",
     "body.principal_moments", "triangle inequality"),
    ("principal_moments = [1.0, 2.0, 3.0]", "principal_moments = [1.0, 2.0]",
     "body.principal_moments", "expected shape"),
    ("principal_moments = [1.0, 2.0, 3.0]", 'principal_moments = "three"', "body.principal_moments",
     "cannot parse"),
    ('frame = "ICRF"', 'frame = "ICFR"', "state.frame", "did you mean 'ICRF'"),
    ('time_scale = "tdb"', 'time_scale = "gps-ish"', "state.time_scale", "not a time scale"),
    ('epoch = "2030-01-01T00:00:00"', 'epoch = "soon"', "state.epoch", "cannot parse"),
    ('epoch = "2030-01-01T00:00:00"', "epoch = 2030", "state.epoch", "expected a string"),
    ("[0, 0, 0, 1]", "[0, 0, 0, 2]", "state.attitude.quaternion_scalar_last", "norm 2"),
    ('unit = "deg/s"', 'unit = "deg"', "state.omega_body", "cannot be converted"),
    ("[5.0, 0.0, 20.0]", '["x", 0.0, 20.0]', "state.omega_body", "cannot read"),
    ("[5.0, 0.0, 20.0]", "[nan, 0.0, 20.0]", "state.omega_body", "must be finite"),
    ('netcdf = "out.nc"', "netcdf = 3", "output.netcdf", "expected a string"),
])
def test_malformed_scenarios_name_the_file_and_key(tmp_path, old, new, key, message):
    assert old in GOOD
    path = write(tmp_path, GOOD.replace(old, new, 1))
    with pytest.raises(att.ScenarioError, match=message) as info:
        load_scenario(path)
    text = str(info.value)
    assert text.startswith(f"{path}: {key}: "), text
    assert "\n" not in text


def test_unreadable_and_invalid_toml(tmp_path):
    with pytest.raises(att.ScenarioError, match="no such file"):
        load_scenario(tmp_path / "nope.toml")
    with pytest.raises(att.ScenarioError, match="not valid TOML"):
        load_scenario(write(tmp_path, "[body\nx = 1"))
    with pytest.raises(att.ScenarioError, match="body: give exactly one of"):
        load_scenario(write(tmp_path, GOOD.replace("principal_moments = [1.0, 2.0, 3.0]",
                                                   "")))


def test_composite_body_and_euler_attitude(tmp_path):
    text = GOOD.replace("principal_moments = [1.0, 2.0, 3.0]", """parts = [
  { primitive = "box", mass = "500 kg", size = [1.0, 1.0, 2.0] },
  { primitive = "plate", mass = 20.0, size = [3.0, 1.0], offset = [2.0, 0.0, 0.0] },
  { primitive = "plate", mass = 20, size = [3, 1], offset = { value = [-200, 0, 0], unit = "cm" } },
]""").replace("{ quaternion_scalar_last = [0, 0, 0, 1] }",
              '{ euler = "ZXZ", angles = { value = [10.0, 40.0, -60.0], unit = "deg" } }')
    sc = load_scenario(write(tmp_path, text))
    assert sc.body.mass == 540.0
    assert sc.body.inertia[1, 1] == pytest.approx(500 / 12 * 5 + 2 * (20 / 12 * 9 + 80))
    np.testing.assert_allclose(sc.state.attitude.as_euler("ZXZ", degrees=True),
                               [10.0, 40.0, -60.0], atol=1e-12)
    bad = text.replace('primitive = "box"', 'primitive = "box", colour = "red"')
    with pytest.raises(att.ScenarioError, match=r"body.parts\[0\].colour: unknown key"):
        load_scenario(write(tmp_path, bad))


def test_run_writes_netcdf_and_reports(tmp_path):
    path = write(tmp_path, GOOD + """
[expect]
regime = "SAM"
energy_rel_drift = { max = 1e-13 }
""")
    result = run_scenario(load_scenario(path))
    assert result.ok
    assert result.outputs == [tmp_path / "out.nc"]
    eph = att.Ephemeris.from_netcdf(tmp_path / "out.nc")
    assert len(eph) == 13
    report = result.report()
    assert report["regime"] == "SAM"
    assert set(report["conservation"]) == {"angular_momentum_rel_drift", "energy_rel_drift"}
    assert report["expect"][0]["ok"] and report["expect"][1]["ok"]


CUBE_OBJ = """\
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 0 0 1
v 1 0 1
v 1 1 1
v 0 1 1
f 1 4 3 2
f 5 6 7 8
f 1 2 6 5
f 2 3 7 6
f 3 4 8 7
f 4 1 5 8
"""


def test_shape_model_body_from_scenario(tmp_path):
    """A 2 km x 2 km x 2 km cube of density 2 g/cm^3 (OBJ in units of 2 km):
    m = 1.6e13 kg, I = m (2 a^2) / 12 with a = 2000 m."""
    (tmp_path / "cube.obj").write_text(CUBE_OBJ)
    text = GOOD.replace("principal_moments = [1.0, 2.0, 3.0]",
                        'shape = "cube.obj"\ndensity = "2 g/cm3"\nlength_unit = "2 km"')
    sc = load_scenario(write(tmp_path, text))
    m = 2000.0 * 2000.0**3
    assert sc.body.mass == pytest.approx(m, rel=1e-14)
    np.testing.assert_allclose(sc.body.principal_moments, m * 2 * 2000.0**2 / 12, rtol=1e-13)
    np.testing.assert_allclose(sc.body.center_of_mass, 1000.0, rtol=1e-13)
    with pytest.raises(att.ScenarioError, match="body.density: missing key"):
        load_scenario(write(tmp_path, text.replace('density = "2 g/cm3"', "")))
    (tmp_path / "open.obj").write_text(CUBE_OBJ.rsplit("f", 1)[0])
    with pytest.raises(att.ScenarioError, match="body.shape: .*not closed"):
        load_scenario(write(tmp_path, text.replace("cube.obj", "open.obj")))


def test_scenario_with_torques_uses_the_splitting_integrator(tmp_path):
    """A sphere under a constant body torque about z: w3 = w0 + M t / I (closed form)."""
    text = GOOD.replace("principal_moments = [1.0, 2.0, 3.0]",
                        "principal_moments = [2.0, 2.0, 2.0]") + """
[[torques]]
type = "constant"
torque = { value = [0.0, 0.0, 0.01], unit = "N m" }
frame = "body"
"""
    sc = load_scenario(write(tmp_path, text))
    result = run_scenario(sc)
    assert "method=splitting" in result.ephemeris.dataset.attrs["source"]   # the default
    w = result.ephemeris.dataset.angular_velocity.values
    np.testing.assert_allclose(w[-1, 2], np.radians(20.0) + 0.01 * 120.0 / 2.0, rtol=1e-11)


@pytest.mark.parametrize("table, key, message", [
    ('type = "gravity_gradient"\nmu = "3.986e14 m3/s2"\norbit = { a = "7000 km", e = 1.2 }',
     "torques[0].orbit.e", "must be in"),
    ('type = "constnat"', "torques[0].type", "did you mean 'constant'"),
])
def test_bad_torque_tables_name_the_key(tmp_path, table, key, message):
    path = write(tmp_path, GOOD + "\n[[torques]]\n" + table + "\n")
    with pytest.raises(att.ScenarioError, match=message) as info:
        load_scenario(path)
    assert str(info.value).startswith(f"{path}: {key}: "), str(info.value)

"""Scenario files: parsing, validation errors (one line naming file and key), runs."""

import textwrap

import numpy as np
import pytest

import attitude as att
from attitude.app.scenario import load_scenario, run_scenario

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
     "body.principal_moments", r"expected 3 numbers \(shape \(3,\)\)"),
    ("principal_moments = [1.0, 2.0, 3.0]", 'principal_moments = "three"', "body.principal_moments",
     "cannot parse"),
    ('frame = "ICRF"', 'frame = "ICFR"', "state.frame", "did you mean 'ICRF'"),
    ('time_scale = "tdb"', 'time_scale = "gps-ish"', "state.time_scale", "unknown time_scale"),
    ('epoch = "2030-01-01T00:00:00"', 'epoch = "soon"', "state.epoch", "cannot parse"),
    ('epoch = "2030-01-01T00:00:00"', "epoch = 2030", "state.epoch", "expected an ISO 8601"),
    ("[0, 0, 0, 1]", "[0, 0, 0, 2]", "state.attitude.quaternion_scalar_last", "norm 2"),
    ('unit = "deg/s"', 'unit = "deg"', "state.omega_body", "cannot be converted"),
    ("[5.0, 0.0, 20.0]", '["x", 0.0, 20.0]', "state.omega_body", "expected numbers"),
    ("[5.0, 0.0, 20.0]", "[nan, 0.0, 20.0]", "state.omega_body", "must be finite"),
    ('netcdf = "out.nc"', "netcdf = 3", "output.netcdf", "expected a string"),
    # a one-sided bound reads as one (it said "must be within [None, 1.0]")
    ('step = "10 s"', 'step = "10 s"\nmethod = "integrator"\nrtol = 2.0', "propagation.rtol",
     r"must be at most 1.0, got 2.0$"),
])
def test_malformed_scenarios_name_the_file_and_key(tmp_path, old, new, key, message):
    assert old in GOOD
    path = write(tmp_path, GOOD.replace(old, new, 1))
    with pytest.raises(att.ScenarioError, match=message) as info:
        load_scenario(path)
    text = str(info.value)
    assert text.startswith(f"{path}: {key}: "), text
    assert "\n" not in text
    last = key.rsplit(".", 1)[-1]
    assert not info.value.reason.startswith(f"{last}: "), text      # the key said once


def test_unreadable_and_invalid_toml(tmp_path):
    with pytest.raises(att.ScenarioError, match="no such file"):
        load_scenario(tmp_path / "nope.toml")
    with pytest.raises(att.ScenarioError, match="not valid TOML"):
        load_scenario(write(tmp_path, "[body\nx = 1"))
    latin = tmp_path / "latin.toml"
    latin.write_bytes(GOOD.replace("test body", "\xc9ole").encode("latin-1"))
    with pytest.raises(att.ScenarioError, match=r"not UTF-8 text \(byte 0xc9 at offset "
                                                r"\d+\); save the scenario as UTF-8"):
        load_scenario(latin)
    (tmp_path / "x.toml").mkdir()
    with pytest.raises(att.ScenarioError, match="is a folder, not a scenario file"):
        load_scenario(tmp_path / "x.toml")
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
    # the run's ephemeris names the shape, so that the pictures draw it (issue 29)
    out = run_scenario(sc, netcdf=tmp_path / "cube.nc").outputs[0]
    attrs = att.Ephemeris.from_netcdf(out).dataset.attrs
    assert attrs["shape_model"] == str((tmp_path / "cube.obj").resolve())
    assert attrs["shape_length_unit"] == "2 km"
    from attitude.pictures.motion import body_polygons
    polys = body_polygons(att.Ephemeris.from_netcdf(out))
    assert polys.shape == (12, 3, 3)                     # the cube's triangles, not a grid
    (tmp_path / "open.obj").write_text(CUBE_OBJ.rsplit("f", 1)[0])
    with pytest.raises(att.ScenarioError, match="body.shape: .*not closed"):
        load_scenario(write(tmp_path, text.replace("cube.obj", "open.obj")))


def test_scenario_with_torques_runs_the_automatic_method(tmp_path):
    """A sphere under a constant body torque about z: w3 = w0 + M t / I (closed form);
    the method chosen for it (tests/propagation/test_choice.py) is named with its reason."""
    text = GOOD.replace("principal_moments = [1.0, 2.0, 3.0]",
                        "principal_moments = [2.0, 2.0, 2.0]") + """
[[torques]]
type = "constant"
torque = { value = [0.0, 0.0, 0.01], unit = "N m" }
frame = "body"
"""
    sc = load_scenario(write(tmp_path, text))
    result = run_scenario(sc)
    attrs = result.ephemeris.dataset.attrs
    assert attrs["method"] in ("splitting", "integrator") and attrs["method_reason"]
    assert f"method={attrs['method']}" in attrs["source"]
    w = result.ephemeris.dataset.angular_velocity.values
    # the automatic choice aims at 1e-8 rad over the run (AUTO_ACCURACY); the rate of a
    # sphere under a constant torque is exact for the splitting, within rtol for DOP853
    np.testing.assert_allclose(w[-1, 2], np.radians(20.0) + 0.01 * 120.0 / 2.0, rtol=1e-8)


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


# --- [expect] nutation_range and [expect.variables] ----------------------------------------

def test_nutation_range_and_variables_torque_free(tmp_path):
    """Torque-free: nutation_range is the analytic one of att.diagnose; variables are
    reduced over the run and converted to the expectation's unit."""
    sc0 = load_scenario(write(tmp_path, GOOD))
    d = att.diagnose(sc0.body, sc0.state)
    lo, hi = (float(x) for x in np.degrees(d.nutation_range))
    L = float(d.angular_momentum)
    path = write(tmp_path, GOOD + f"""
[expect]
nutation_range = {{ min = {lo!r}, max = {hi!r}, unit = "deg", abs_tol = 1e-9 }}

[expect.variables]
angular_momentum_magnitude = {{ at = "mean", value = {L!r}, rel_tol = 1e-12 }}
energy_rel_drift = {{ value = 0.0, abs_tol = 1e-13 }}

[expect.variables.w_start]
variable = "angular_velocity"
at = "start"
component = 2
value = 20.0
unit = "deg/s"
abs_tol = 1e-12

[expect.variables.w_norm]
variable = "angular_velocity"
at = "max"
component = "norm"
value = 0.36
unit = "rad/s"
rel_tol = 0.1
""")
    sc = load_scenario(path)
    keys = [e["key"] for e in sc.expect]
    assert keys == ["nutation_range.min", "nutation_range.max",
                    "variables.angular_momentum_magnitude", "variables.energy_rel_drift",
                    "variables.w_start", "variables.w_norm"]
    result = run_scenario(sc, write_outputs=False)
    assert result.ok, [e for e in result.expectations if not e["ok"]]
    for e in result.expectations:
        assert {"key", "expected", "got", "tolerance", "unit", "ok"} <= set(e)
        assert "variable" not in e and "at" not in e
    got = {e["key"]: e["got"] for e in result.expectations}
    assert got["nutation_range.min"] == pytest.approx(lo, abs=1e-12)
    assert got["variables.w_start"] == pytest.approx(20.0, rel=1e-14)


def test_variables_with_torques_and_a_failing_expectation(tmp_path):
    """A sphere under a constant body torque: w3(end) = w0 + M t / I (closed form); the
    nutation range of a run with torques comes from the nutation_angle diagnostic."""
    w_end = float(np.radians(20.0) + 0.01 * 120.0 / 2.0)
    text = GOOD.replace("principal_moments = [1.0, 2.0, 3.0]",
                        "principal_moments = [2.0, 2.0, 2.0]").replace(
        "[5.0, 0.0, 20.0]", "[0.0, 0.0, 20.0]") + f"""
[[torques]]
type = "constant"
torque = {{ value = [0.0, 0.0, 0.01], unit = "N m" }}
frame = "body"

[expect]
nutation_range = {{ min = 0.0, max = 0.0, abs_tol = 1e-9 }}

[expect.variables]
angular_velocity = {{ at = "end", component = 2, value = {w_end!r}, rel_tol = 1e-10 }}
kinetic_energy = {{ at = "end", value = 1.0, unit = "J", rel_tol = 1e-3 }}
"""
    result = run_scenario(load_scenario(write(tmp_path, text)), write_outputs=False)
    ok = {e["key"]: e["ok"] for e in result.expectations}
    assert ok == {"nutation_range.min": True, "nutation_range.max": True,
                  "variables.angular_velocity": True, "variables.kinetic_energy": False}
    assert "nutation_angle" in result.dataset
    assert not result.ok


@pytest.mark.parametrize("expect, key, message", [
    ('nutation_range = { min = 1, max = 2 }', "expect.nutation_range.abs_tol", "missing key"),
    ('nutation_range = { min = 3, max = 2, abs_tol = 0.1 }', "expect.nutation_range",
     "larger than max"),
    ('nutation_range = { min = 1, max = 2, abs_tol = 0.1, unit = "s" }',
     "expect.nutation_range.unit", "cannot be converted"),
    ('nutation_range = { min = 1, max = 2, abs_tol = 0.1, rel_tol = 0.1 }',
     "expect.nutation_range.rel_tol", "unknown key"),
    ('nutaton_range = 3', "expect.nutaton_range", "did you mean 'nutation_range'"),
    ('[expect.variables]\nnutation_angel = { at = "end", value = 1, abs_tol = 1 }',
     "expect.variables.nutation_angel", "did you mean 'nutation_angle'"),
    ('[expect.variables]\nx = { variable = "spin", at = "end", value = 1, abs_tol = 1 }',
     "expect.variables.x.variable", "unknown variable"),
    ('[expect.variables]\nkinetic_energy = { value = 1, abs_tol = 1 }',
     "expect.variables.kinetic_energy.at", "time series"),
    ('[expect.variables]\nkinetic_energy = { at = "last", value = 1, abs_tol = 1 }',
     "expect.variables.kinetic_energy.at", "unknown at 'last'"),
    ('[expect.variables]\nattitude_noise = { at = "end", value = 1, abs_tol = 1 }',
     "expect.variables.attitude_noise.at", "single number"),
    ('[expect.variables]\nangular_velocity = { at = "end", value = 1, abs_tol = 1 }',
     "expect.variables.angular_velocity.component", "is a vector"),
    ('[expect.variables]\nangular_velocity = { at = "end", component = 3, value = 1, '
     'abs_tol = 1 }', "expect.variables.angular_velocity.component", "index 0..2"),
    ('[expect.variables]\nkinetic_energy = { at = "end", component = 0, value = 1, '
     'abs_tol = 1 }', "expect.variables.kinetic_energy.component", "not a vector"),
    ('[expect.variables]\nkinetic_energy = { at = "end", value = 1 }',
     "expect.variables.kinetic_energy", "exactly one of rel_tol, abs_tol"),
    ('[expect.variables]\nkinetic_energy = { at = "end", value = 1, unit = "deg", '
     'abs_tol = 1 }', "expect.variables.kinetic_energy.unit", "cannot be converted to 'J'"),
    ('[expect.variables]\nkinetic_energy = { at = "end", value = "1 J", abs_tol = 1 }',
     "expect.variables.kinetic_energy.value", "expected a number"),
    ('[expect.variables]\nkinetic_energy = { at = "end", valu = 1, abs_tol = 1 }',
     "expect.variables.kinetic_energy.valu", "did you mean 'value'"),
])
def test_bad_expectations_name_the_key(tmp_path, expect, key, message):
    if not expect.startswith("["):
        expect = "[expect]\n" + expect
    path = write(tmp_path, GOOD + "\n" + expect + "\n")
    with pytest.raises(att.ScenarioError, match=message) as info:
        load_scenario(path)
    text = str(info.value)
    assert text.startswith(f"{path}: {key}: "), text
    assert "\n" not in text
    last = key.rsplit(".", 1)[-1]
    assert not info.value.reason.startswith(f"{last}: "), text      # the key said once


# --- [state] spin_axis -----------------------------------------------------------------------

SPIN = GOOD.replace("principal_moments = [1.0, 2.0, 3.0]",
                    "inertia = [[2.0, 0.3, 0.0], [0.3, 1.5, 0.1], [0.0, 0.1, 3.0]]").replace(
    'attitude = { quaternion_scalar_last = [0, 0, 0, 1] }\n'
    'omega_body = { value = [5.0, 0.0, 20.0], unit = "deg/s" }',
    'spin_axis = { ra = "250 deg", dec = "-75 deg" }\nspin_period = "2.5 h"')


@pytest.mark.parametrize("about, k", [(None, 2), ("A", 0), ("B", 1), ("C", 2)])
def test_spin_axis_state_points_the_principal_axis(tmp_path, about, k):
    text = SPIN if about is None else SPIN.replace("[state]", f'[state]\nspin_about = "{about}"')
    sc = load_scenario(write(tmp_path, text))
    ra, dec = np.radians([250.0, -75.0])
    n = [np.cos(dec) * np.cos(ra), np.cos(dec) * np.sin(ra), np.sin(dec)]
    axis = sc.body.principal_axes[:, k]                   # body frame
    np.testing.assert_allclose(sc.state.attitude.apply(axis), n, rtol=0, atol=1e-12)
    w = sc.state.omega_body
    assert np.linalg.norm(w) == pytest.approx(2 * np.pi / 9000.0, rel=1e-14)
    np.testing.assert_allclose(sc.state.attitude.apply(w) / np.linalg.norm(w), n, atol=1e-12)
    d = att.diagnose(sc.body, sc.state)
    assert d.periods["spin"] == pytest.approx(9000.0, rel=1e-12)


def test_spin_axis_with_rate_and_at_the_pole(tmp_path):
    text = SPIN.replace('spin_period = "2.5 h"', 'spin_rate = "3 deg/s"').replace(
        'dec = "-75 deg"', 'dec = "90 deg"')
    sc = load_scenario(write(tmp_path, text))
    np.testing.assert_allclose(sc.state.attitude.apply(sc.body.principal_axes[:, 2]),
                               [0, 0, 1], atol=1e-12)
    assert np.linalg.norm(sc.state.omega_body) == pytest.approx(np.radians(3.0), rel=1e-14)


@pytest.mark.parametrize("old, new, key, message", [
    ("spin_period", "spin_rate = 0.1\nspin_period", "state.spin_period", "at most one of"),
    ('spin_period = "2.5 h"', "", "state.spin_rate", "exactly one of"),
    ("[state]", "[state]\nomega_body = [0, 0, 1]", "state.omega_body", "not with state.spin_axis"),
    ("[state]", "[state]\nattitude = { quaternion_scalar_last = [0, 0, 0, 1] }",
     "state.attitude", "not with state.spin_axis"),
    ("[state]", '[state]\nspin_about = "D"', "state.spin_about", "unknown spin_about 'D'"),
    ('dec = "-75 deg"', 'dec = "-95 deg"', "state.spin_axis.dec", "within"),
    ('dec = "-75 deg"', 'dec = "-75 s"', "state.spin_axis.dec", "cannot be converted"),
    ('ra = "250 deg", ', "", "state.spin_axis.ra", "missing key"),
    ('ra = "250 deg"', 'ra = "250 deg", rra = 1', "state.spin_axis.rra", "did you mean 'ra'"),
    ('spin_period = "2.5 h"', 'spin_period = "-2.5 h"', "state.spin_period", "positive"),
])
def test_bad_spin_axis_states(tmp_path, old, new, key, message):
    assert old in SPIN
    path = write(tmp_path, SPIN.replace(old, new, 1))
    with pytest.raises(att.ScenarioError, match=message) as info:
        load_scenario(path)
    assert str(info.value).startswith(f"{path}: {key}: "), str(info.value)


def test_spin_rate_without_spin_axis(tmp_path):
    path = write(tmp_path, GOOD.replace(
        'omega_body = { value = [5.0, 0.0, 20.0], unit = "deg/s" }', 'spin_rate = 0.1'))
    with pytest.raises(att.ScenarioError, match=r"state.spin_axis: missing key \(needed with "
                                                r"state.spin_rate\)"):
        load_scenario(path)


def test_integrator_step_and_order_reach_the_splitting_integrator(tmp_path):
    """[propagation] integrator_step / order: a Strang run with a 2 s step on a sphere
    under a constant torque is still exact (the kick is exact for a sphere)."""
    text = GOOD.replace("principal_moments = [1.0, 2.0, 3.0]",
                        "principal_moments = [2.0, 2.0, 2.0]").replace(
        'step = "10 s"', 'step = "10 s"\nintegrator_step = "2 s"\norder = 2') + """
[[torques]]
type = "constant"
torque = { value = [0.0, 0.0, 0.01], unit = "N m" }
"""
    sc = load_scenario(write(tmp_path, text))
    assert sc.integrator_step == 2.0 and sc.order == 2
    w = run_scenario(sc, write_outputs=False).ephemeris.dataset.angular_velocity.values
    np.testing.assert_allclose(w[-1, 2], np.radians(20.0) + 0.01 * 120.0 / 2.0, rtol=1e-12)
    for bad, key in (("order = 2", "order = 3"), ('integrator_step = "2 s"', "rtol = 1e-9")):
        with pytest.raises(att.ScenarioError, match="propagation"):
            load_scenario(write(tmp_path, text.replace(bad, key if "order" in key else
                                                       'integrator_step = "2 s"\n' + key)))


def test_events_table_locates_nutation_crossings(tmp_path):
    """[[events]]: a torque-free SAM state crosses a nutation angle halfway between its
    extremes twice per nutation cycle; at each recorded crossing the angle between L and
    C, recomputed from the recorded rates (independent of the root finder), is the one
    asked for."""
    path = write(tmp_path, GOOD.replace("[output]", """
[[events]]
type = "nutation_crossing"
angle = "{mid} rad"
axis = "C"
terminal = false

[output]"""))
    sc0 = load_scenario(write(tmp_path, GOOD, name="s0.toml"))
    lo, hi = att.diagnose(sc0.body, sc0.state).nutation_range
    mid = 0.5 * (lo + hi)
    path.write_text(path.read_text().replace("{mid}", repr(mid)))
    sc = load_scenario(path)
    assert len(sc.events) == 1 and not sc.events[0].terminal
    result = run_scenario(sc, write_outputs=False)
    found = att.event_table(result.ephemeris)
    assert len(found) >= 2
    ds = result.ephemeris.dataset
    L = np.einsum("ij,nj->ni", sc.body.inertia, ds["event_angular_velocity"].values)
    c_axis = sc.body.principal_axes[:, 2]
    angle = np.arccos(np.clip(L @ c_axis / np.linalg.norm(L, axis=1), -1, 1))
    np.testing.assert_allclose(angle, mid, atol=1e-9)

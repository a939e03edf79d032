"""``attitude run`` and ``attitude check`` on binary scenarios ([binary], issue 28): the
summary, the netCDF ephemeris, the --report JSON, the expectations' exit code, bad input
exits 2 with one line naming the file and the key."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from attitude.app.cli import main
from attitude.app.scenario import load_scenario
from attitude.binary.config import impact_delta_v, load_binary
from attitude.foundations.constants import G
from attitude.foundations.errors import ScenarioError
from attitude.model.ephemeris import Ephemeris
from attitude.model.shape import Polyhedron

M1, M2, A = 5.2e11, 4.3e9, 1190.0
PERIOD = 2 * math.pi * math.sqrt(A**3 / (G * (M1 + M2)))       # Kepler, s

TEXT = f'''
[scenario]
name = "two spheres"

[binary]
epoch = "2026-12-01T00:00:00"
duration = "{1.6 * PERIOD} s"
output_step = "{PERIOD / 60} s"
order = 2
method = "integrator"

[binary.primary]
primitive = "sphere"
mass = 5.2e11
radius = 390.0
spin_period = "2.26 h"

[binary.secondary]
primitive = "sphere"
mass = 4.3e9
radius = 80.0

[binary.orbit]
semi_major_axis = "{A} m"

[expect]
orbit_period = {{ value = {PERIOD / 3600}, unit = "h", rel_tol = 1e-7 }}
primary_spin_period = {{ value = 2.26, unit = "h", rel_tol = 1e-12 }}
secondary_regime = "circulating"
energy_rel_drift = {{ max = 1e-8 }}
'''


@pytest.fixture
def scenario(tmp_path):
    path = tmp_path / "pair.toml"
    path.write_text(TEXT)
    return path


def test_run_writes_the_ephemeris_and_the_report(scenario, capsys):
    """Two spheres: Kepler's period (the measurement is good to the integrator's 1e-10
    and the sampling's Hermite error, far below the 1e-7 asked); a sphere feels no
    torque: its spin period is exact.  The
    secondary, a sphere at rest, keeps its axes while the line of centres turns: its
    (arbitrary) long axis circulates."""
    out, report = scenario.parent / "pair.nc", scenario.parent / "pair.json"
    assert main(["run", str(scenario), "-o", str(out), "--report", str(report)]) == 0
    text = capsys.readouterr().out
    assert "regime circulating" in text and "FAIL" not in text and "Conserved" in text
    data = json.loads(report.read_text())
    assert data["scenario"] == "two spheres" and data["regime"] == "circulating"
    assert set(data["periods"]) >= {"orbit", "libration", "primary_spin"}
    assert data["periods"]["orbit"] == pytest.approx(PERIOD, rel=1e-7)
    assert data["periods"]["libration"] is None                  # not measured: None
    assert data["outputs"] == [str(out)] and all(e["ok"] for e in data["expect"])
    assert len(data["expect"]) == 4 and data["method"] == "integrator"
    assert data["conservation"]["energy_rel_drift"] < 1e-8
    eph = Ephemeris.from_netcdf(out)
    assert eph.dataset.sizes["body"] == 2 and "relative_position" in eph.dataset
    assert eph.dataset.attrs["system"] == "binary"


def test_a_failed_expectation_exits_1(scenario, capsys):
    scenario.write_text(TEXT.replace('secondary_regime = "circulating"',
                                     'secondary_regime = "tumbling"'))
    assert main(["run", str(scenario), "--quiet"]) == 1
    assert main(["check", str(scenario)]) == 1
    out = capsys.readouterr().out
    assert "FAIL" in out and "secondary_regime: expected tumbling" in out


def test_check_runs_binary_scenarios(scenario, capsys):
    assert main(["check", str(scenario.parent)]) == 0
    out = capsys.readouterr().out
    assert out.count("pass  ") == 4 and "orbit_period" in out
    assert not list(scenario.parent.glob("*.nc"))              # check writes nothing


def test_an_impulse_in_the_dart_form_changes_the_period(scenario, capsys):
    """An impactor against the motion after 1.3 turns (the secondary at +x rotated by
    468 deg): less energy, a shorter period, as vis-viva and Kepler's third law say; the
    report holds both sides."""
    t = 1.3 * PERIOD
    angle = 2 * math.pi * 1.3
    along = [-math.sin(angle), math.cos(angle), 0.0]            # the velocity's direction
    U = [-6145.0 * c for c in along]
    text = TEXT.replace("[expect]", f'''[[binary.impulse]]
time = "{t} s"
beta = 3.61
impactor_mass = "580 kg"
impactor_velocity = {{ value = {U}, unit = "m/s" }}

[expect]
period_change = {{ value = 0.0, unit = "min", abs_tol = 100.0 }}
''').replace("orbit_period", "osculating_period").replace(
        f"{1.6 * PERIOD} s", f"{2.8 * PERIOD} s").replace(
        'secondary_regime = "circulating"', "")
    scenario.write_text(text)
    report = scenario.parent / "r.json"
    assert main(["run", str(scenario), "--report", str(report), "--quiet"]) == 0
    change = json.loads(report.read_text())["period_change"]
    v = math.sqrt(G * (M1 + M2) / A)
    dv = np.linalg.norm(impact_delta_v(580.0, U, 3.61, M2))
    a_after = 1 / (2 / A - (v - dv) ** 2 / (G * (M1 + M2)))    # vis-viva
    kepler = 2 * math.pi * math.sqrt(a_after**3 / (G * (M1 + M2))) - PERIOD
    assert change["change"] < 0
    assert change["osculating_after"] - change["osculating_before"] == pytest.approx(
        kepler, rel=1e-6)


def test_a_binary_file_is_not_a_single_body_scenario(scenario):
    with pytest.raises(ScenarioError, match="attitude run"):
        load_scenario(scenario)


def test_the_synchronous_start_locks_the_long_axis_on_the_primary(tmp_path):
    path = tmp_path / "s.toml"
    path.write_text(TEXT.replace('radius = 80.0', 'semi_axes = [103.16, 79.35, 66.13]')
                    .replace('primitive = "sphere"\nmass = 4.3e9',
                             'primitive = "ellipsoid"\nmass = 4.3e9')
                    .replace('order = 2', 'order = 2\nsynchronous = true'))
    sc = load_binary(path)
    long_axis = sc.state.secondary_attitude.apply([1.0, 0.0, 0.0])
    np.testing.assert_allclose(long_axis, -sc.state.position / A, atol=1e-15)
    n = math.sqrt(G * (M1 + M2) / A**3)
    np.testing.assert_allclose(sc.state.secondary_omega, [0, 0, n], rtol=1e-14)


@pytest.mark.parametrize("edit, key", [
    (("order = 2", "order = 1"), "binary.order"),
    (("radius = 80.0", "radius = 80.0\nradiuss = 3"), "binary.secondary.radiuss"),
    (('semi_major_axis = "1190.0 m"', 'semi_major_axis = "400 m"'), "binary.orbit"),
    (('semi_major_axis = "1190.0 m"', 'position = [1190.0, 0, 0]\nvelocity = [0, 2.0, 0]'),
     "binary.orbit"),                                        # not bound: orbit expected
    (("[expect]", '[[binary.impulse]]\ntime = 10.0\nbody = "tertiary"\ndelta_v = [0, 0, 0]'
                  "\n[expect]"), "binary.impulse[0].body"),
    (("[expect]", '[[binary.impulse]]\ntime = "30 d"\ndelta_v = [0, 0, 0]\n[expect]'),
     "binary.impulse[0].time"),
    (("secondary_regime", 'period_change = { value = -1, abs_tol = 1 }\nsecondary_regime'),
     "expect.period_change"),
    (('primitive = "sphere"\nmass = 4.3e9\nradius = 80.0\n', ""), "binary.secondary"),
    (('method = "integrator"', 'method = "rk4"'), "binary.method"),
    (('method = "integrator"', 'method = "integrator"\nstep = "30 s"'), "binary.step"),
    (('method = "integrator"', 'method = "lgvi"\nrtol = 1e-9'), "binary.rtol"),
    (("[expect]", '[[binary.impulse]]\ntime = 0.0\ndelta_v = [0, 0, 0]\n[expect]\n'
                  'period_change = { value = -1, abs_tol = 1 }'), "expect.period_change"),
    ((f'duration = "{1.6 * PERIOD} s"', 'duration = "1e4 yr"'), "binary.duration"),
    (("[binary.orbit]", '[binary.orbit]\neccentricity = 1.5'), "binary.orbit.eccentricity"),
])
def test_bad_binary_scenarios_exit_2_with_one_line(scenario, capsys, edit, key):
    assert edit[0] in TEXT
    scenario.write_text(TEXT.replace(*edit))
    for command in ("run", "check"):
        assert main([command, str(scenario)]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and key in err[0] and str(scenario) in err[0]
        assert "Traceback" not in err[0]


@pytest.mark.slow      # the DART scenario (about 10 s); the slow tier, which CI runs
def test_the_dart_scenario_meets_its_expectations(capsys):
    assert main(["check", "scenarios/binary/didymos_dart.toml"]) == 0
    assert "period_change" in capsys.readouterr().out


def test_a_shape_model_body(scenario, capsys):
    """The secondary from an OBJ and its density: its mass is the polyhedron's, its
    extent the farthest vertex (the overlap check)."""
    shape = Polyhedron.ellipsoid(0.1, 0.08, 0.06, subdivisions=2)        # km
    (scenario.parent / "moon.obj").write_text(shape.obj_text())
    text = TEXT.replace('primitive = "sphere"\nmass = 4.3e9\nradius = 80.0',
                        'shape = "moon.obj"\nlength_unit = "km"\ndensity = "2 g/cm3"')
    scenario.write_text(text)
    sc = load_binary(scenario)
    assert sc.system.secondary.mass == pytest.approx(2000.0 * shape.volume * 1e9, rel=1e-12)
    scenario.write_text(text.replace('semi_major_axis = "1190.0 m"',
                                     'semi_major_axis = "480 m"'))   # 390 + 100 m > 480 m
    assert main(["run", str(scenario)]) == 2
    assert "binary.orbit" in capsys.readouterr().err
    scenario.write_text(text.replace("moon.obj", "missing.obj"))
    assert main(["run", str(scenario)]) == 2
    err = capsys.readouterr().err
    assert "missing.obj" in err and len(err.strip().splitlines()) == 1


def test_a_body_known_by_its_moments_runs_at_order_2_only(scenario, capsys):
    text = TEXT.replace('primitive = "sphere"\nmass = 4.3e9\nradius = 80.0',
                        'principal_moments = [1.0e13, 1.2e13, 1.4e13]\nmass = 4.3e9')
    scenario.write_text(text)
    assert load_binary(scenario).system.secondary.principal_moments.tolist() == [
        1.0e13, 1.2e13, 1.4e13]
    scenario.write_text(text.replace("order = 2", "order = 3"))
    assert main(["run", str(scenario)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "binary.order" in err[0]


def test_the_lgvi_keeps_the_angular_momentum(scenario, capsys):
    """The Lie-group variational integrator (the default method) at a fixed step: the
    total angular momentum to round-off (Lee, Leok & McClamroch 2007), the orbit period
    to its second-order phase error."""
    scenario.write_text(TEXT.replace('method = "integrator"', 'step = "120 s"')
                        .replace("rel_tol = 1e-7", "rel_tol = 1e-3"))
    report = scenario.parent / "r.json"
    assert main(["run", str(scenario), "--report", str(report), "--quiet"]) == 0
    data = json.loads(report.read_text())
    assert data["method"] == "lgvi"
    assert data["conservation"]["angular_momentum_rel_drift"] < 1e-12


# --plot and --workers on binary scenarios -----------------------------------------------

def test_plot_writes_the_binary_figures_next_to_the_output(scenario, capsys):
    """``--plot``: the separation, the libration angle and both spins, as PNG files named
    after the netCDF output (as ``attitude run --plot`` names a single body's), listed
    under Wrote."""
    pytest.importorskip("matplotlib")
    out = scenario.parent / "pair.nc"
    assert main(["run", str(scenario), "-o", str(out), "--plot"]) == 0
    text = capsys.readouterr().out
    for name in ("separation", "libration", "spins"):
        path = scenario.parent / f"pair_{name}.png"
        assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"      # a PNG file
        assert f"Wrote      {path}" in text


def _ensemble_file(tmp_path, n: int = 2):
    from tests.binary.test_ensemble import SCENARIO
    path = tmp_path / "family.toml"
    path.write_text(SCENARIO.replace("n = 4", f"n = {n}"))
    return path


def test_plot_of_a_binary_ensemble(tmp_path, capsys):
    """A ``[binary.ensemble]``: one figure of its outcomes (the regime fractions and the
    period changes)."""
    pytest.importorskip("matplotlib")
    path = _ensemble_file(tmp_path)
    assert main(["run", str(path), "--plot"]) == 0
    figure = tmp_path / "family_outcomes.png"
    assert figure.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert f"Wrote      {figure}" in capsys.readouterr().out


@pytest.mark.parametrize("argv, message", [
    (["--workers", "2"], "--workers: the scenario has no [binary.ensemble] table"),
    (["--workers", "0"], "--workers: must be at least 1"),
])
def test_workers_needs_an_ensemble(scenario, capsys, argv, message):
    assert main(["run", str(scenario), *argv]) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and len(err.splitlines()) == 1


@pytest.mark.slow      # a dask LocalCluster of two processes (> 9 s); CI's slow tier
def test_workers_runs_the_binary_ensemble_on_a_local_cluster(tmp_path):
    """``--workers 2``: the members' chunks on two worker processes, the same outcomes
    as in this process (each member runs the same steps wherever it runs: the family's
    vectorised steps are each member's own, so to round-off of a few operations)."""
    pytest.importorskip("distributed")
    import subprocess
    import sys

    from attitude.binary.config import load_binary, run_binary

    path = _ensemble_file(tmp_path, n=4)
    report = tmp_path / "r.json"
    out = subprocess.run([sys.executable, "-m", "attitude", "run", str(path), "--workers",
                          "2", "--report", str(report), "--quiet"], capture_output=True,
                         text=True, timeout=300)
    assert out.returncode == 0, out.stdout + out.stderr
    assert out.stderr == ""
    there = json.loads(report.read_text())
    here = run_binary(load_binary(path), write_outputs=False).report()
    assert there["status"] == here["status"] == {"ok": 4, "invalid_input": 0, "failed": 0}
    assert there["regime_fractions"] == here["regime_fractions"]
    for key, value in here["period_change_quantiles"].items():
        assert there["period_change_quantiles"][key] == pytest.approx(value, rel=1e-9)

"""Events and progress on the compiled DOP853 (issue 26): the built-in event functions
evaluated at each accepted step and their crossings located on the 7th-degree
interpolant (:func:`attitude.propagation.compiled_dop853.dop853_block`), against scipy's
``solve_ivp`` event location on the same method; runs in blocks of simulated time (the
progress bar) give the same bits as one block.

The root finder's promise (:func:`compiled_dop853.root_tolerance`): it ends on a bracket
of the root of the event function *on the compiled interpolant* at most ``2 tol`` wide,
``tol = 4 eps max(|t|, |t + h|)``, and returns its midpoint (rounded: half an ulp), so
``|te - root| <= tol + ulp(te) / 2``.  scipy's ``brentq`` (``xtol = rtol = 4 eps``) ends
within ``4 eps (1 + |te|)`` of the root on scipy's interpolant.  The two interpolants
differ by the rounding of the two paths (or, if a step's acceptance flips, by up to the
tolerance): the compiled path's own event function at scipy's event time, ``g_c(te_s)``,
measures that, and puts the compiled root within ``|g_c(te_s)| / |g'|`` of ``te_s``
(first order; the second-order term, ``g'' dt^2 / 2 g'``, is ~1e-28 s here).
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from scipy.spatial.transform import Rotation

import attitude as att
from attitude.app.cli import main
from attitude.app.scenario import load_scenario, run_scenario
from attitude.foundations import progress
from attitude.model.torques import EnergyDissipation, FunctionTorque
from attitude.propagation.compiled import COMPILE_NOTICE, NUMBA
from attitude.propagation.events import Event, event_table, nutation_angle, nutation_crossing
from attitude.propagation.reference import (
    integrate_reference,
    integrate_reference_batch,
    integrate_reference_events,
)

from ..tolerances import EPS, INTEGRATOR_PATHS

ROOT = Path(__file__).resolve().parents[2]
pytestmark = pytest.mark.skipif(not NUMBA, reason="the compiled path needs numba")

#: A triaxial body in a torque-free tumble: the angle between L and A swings between
#: 0.328 and 0.472 rad with a period of ~14 s.
BODY = att.RigidBody.from_principal_moments([1.0, 1.2, 1.5])
Q0 = np.array([0.0, 0.0, 0.0, 1.0])
W0 = np.array([0.5, 0.1, 0.1])
TIMES = np.linspace(0.0, 60.0, 61)
AXIS_A = np.array([1.0, 0.0, 0.0])
MID = 0.40


def _angle(w):
    w = np.atleast_2d(w)
    return nutation_angle(BODY.inertia, AXIS_A, w[:, 0], w[:, 1], w[:, 2])


def _slope(te, torques=()):
    """d(angle)/dt at ``te`` by a central difference over +-1e-3 s of the integrator's
    solution (its relative error, ~(1e-3 / 14 s)^2 / 6, is far below the 10 % kept)."""
    t = np.array([te - 1e-3, te + 1e-3])
    _, w = integrate_reference(BODY, Q0, W0, np.concatenate([t, TIMES[-1:]]),
                               torques=torques)
    return float(np.diff(_angle(w[:2]))[0] / 2e-3)


def _events(kind="both"):
    return {"both": [nutation_crossing(MID, "A", terminal=False)],
            "up": [nutation_crossing(MID, "A", terminal=False, direction=1)],
            "down": [nutation_crossing(MID, "A", terminal=False, direction=-1)]}[kind]


def test_compiled_event_times_agree_with_scipy_within_the_root_tolerance():
    _, _, rec_c = integrate_reference_events(BODY, Q0, W0, TIMES, _events(), compiled=True)
    _, _, rec_s = integrate_reference_events(BODY, Q0, W0, TIMES, _events(), compiled=False)
    te_c = np.array([r[0] for r in rec_c])
    te_s = np.array([r[0] for r in rec_s])
    assert te_c.size == te_s.size >= 5                 # two crossings per swing
    bound = _crossing_bound(te_c, te_s)
    assert np.all(np.abs(te_c - te_s) <= bound), (te_c - te_s, bound)


def _crossing_bound(te_c, te_s):
    """The module's bound on ``|te_c - te_s|``: the compiled root tolerance plus the
    compiled event function at scipy's times over its slope (within 10 %)."""
    # the compiled path's event function at scipy's times (outputs do not move the steps)
    _, w_at = integrate_reference(BODY, Q0, W0, np.concatenate([te_s, TIMES[-1:]]),
                                  compiled=True)
    g_c = np.abs(_angle(w_at[:-1]) - MID)
    slope = np.array([abs(_slope(te)) for te in te_s])
    tol_c = 4.0 * EPS * te_c + 0.5 * np.spacing(te_c)
    # g_c itself is rounded: a few operations on |L|-sized numbers (8 ulps of the angle)
    return tol_c + (g_c + 8.0 * EPS * MID) / (0.9 * slope)


def test_recorded_state_is_on_the_event():
    """The state recorded at each crossing (the interpolant at ``te``) has the event
    function within the root tolerance times its slope of zero."""
    _, _, rec = integrate_reference_events(BODY, Q0, W0, TIMES, _events(), compiled=True)
    for te, i, q, w in rec:
        assert i == 0 and abs(np.linalg.norm(q) - 1.0) <= 4 * EPS
        tol = 4.0 * EPS * te + 0.5 * np.spacing(te)
        assert abs(_angle(w)[0] - MID) <= abs(_slope(te)) * 1.1 * tol + 8.0 * EPS * MID


def test_direction_splits_the_crossings():
    runs = {k: integrate_reference_events(BODY, Q0, W0, TIMES, _events(k), compiled=True)[2]
            for k in ("both", "up", "down")}
    both = [r[0] for r in runs["both"]]
    up, down = [r[0] for r in runs["up"]], [r[0] for r in runs["down"]]
    assert up and down
    # the same steps and the same root finder: the same times (one process, one code)
    assert sorted(up + down) == both
    assert all(_slope(te) > 0 for te in up) and all(_slope(te) < 0 for te in down)


def test_terminal_event_stops_the_run_on_both_paths():
    ev = [nutation_crossing(MID, "A", terminal=True, direction=-1)]
    out = {c: integrate_reference_events(BODY, Q0, W0, TIMES, ev, compiled=c)
           for c in (True, False)}
    (_, wc, rc), (_, ws, rs) = out[True], out[False]
    assert len(rc) == len(rs) == 1
    te = rc[0][0]
    assert abs(te - rs[0][0]) <= _crossing_bound(np.array([te]), np.array([rs[0][0]]))[0]
    after = TIMES > te
    assert np.all(np.isnan(wc[after])) and not np.any(np.isnan(wc[~after]))
    np.testing.assert_array_equal(np.isnan(ws), np.isnan(wc))
    scale = np.max(np.abs(ws[~after]))
    assert np.max(np.abs(wc[~after] - ws[~after])) <= INTEGRATOR_PATHS * 1e-13 * scale
    # propagate: the ephemeris ends on the event
    eph = att.propagate(BODY, att.AttitudeState("2030-01-01", Rotation.identity(), W0),
                        TIMES, torques=[EnergyDissipation(1e6)], method="integrator",
                        events=ev)
    assert eph.time[-1] == event_table(eph)[0][0]


def test_python_event_or_torque_takes_scipys_path():
    user = Event(lambda t, q, w, b: t - 30.5, terminal=False, name="half")
    _, _, rec = integrate_reference_events(BODY, Q0, W0, TIMES, [user])
    assert [r[0] for r in rec] == [pytest.approx(30.5, abs=1e-12)]
    with pytest.raises(att.InvalidStateError, match="compiled=True"):
        integrate_reference_events(BODY, Q0, W0, TIMES, [user], compiled=True)
    spin_up = FunctionTorque(lambda t, q, w, body: np.array([1e-3, 0.0, 0.0]))
    _, _, rec = integrate_reference_events(BODY, Q0, W0, TIMES, _events(),
                                           torques=[spin_up])
    assert rec


def test_blocks_give_the_same_bits(monkeypatch):
    """A run in PROGRESS_BLOCKS blocks (a shown progress report) carries the state, its
    derivative, the step size and the event values: the same steps, the same bits."""
    monkeypatch.setattr(progress, "DELAY", float("inf"))     # shown, but silent
    torques = [EnergyDissipation(30.0)]
    t = np.linspace(0.0, 60.0, 7)
    one = integrate_reference(BODY, Q0, W0, t, torques=torques)
    blocks = integrate_reference(BODY, Q0, W0, t, torques=torques, progress=True)
    for a, b in zip(one, blocks):
        np.testing.assert_array_equal(a, b)
    ev = _events()
    one = integrate_reference_events(BODY, Q0, W0, t, ev, torques=torques)
    blocks = integrate_reference_events(BODY, Q0, W0, t, ev, torques=torques, progress=True)
    np.testing.assert_array_equal(one[1], blocks[1])
    assert [r[0] for r in one[2]] == [r[0] for r in blocks[2]] and len(one[2]) >= 1


def test_more_crossings_than_the_record_arrays_hold(monkeypatch):
    """Records read back whenever the kernel's arrays are full, and the run continued
    from its carried state: the same crossings as with room for all of them."""
    from attitude.propagation import reference

    ev = _events() + _events("up")
    whole = integrate_reference_events(BODY, Q0, W0, TIMES, ev)[2]
    monkeypatch.setattr(reference, "_RECORDS", 1)          # room for one step's crossings
    parts = integrate_reference_events(BODY, Q0, W0, TIMES, ev)[2]
    assert len(whole) >= 5              # more than the two slots of each call
    assert [(r[0], r[1]) for r in parts] == [(r[0], r[1]) for r in whole]


def test_batch_progress_and_auto_method_with_builtin_events():
    bodies = [BODY, att.RigidBody.from_principal_moments([1.0, 1.3, 1.5])]
    q, w = integrate_reference_batch(bodies, [Q0, Q0], [W0, W0], TIMES[:5], progress=False)
    assert q.shape == (2, 5, 4)
    state = att.AttitudeState("2030-01-01", Rotation.identity(), W0)
    eph = att.propagate(BODY, state, TIMES, torques=[EnergyDissipation(1e5)],
                        events=_events())
    # built-in events no longer force the splitting: the automatic choice decides
    assert "events given" not in eph.dataset.attrs["method_reason"]
    assert eph.dataset.attrs["event_count"] >= 5


# --- the scenario and the command line ---------------------------------------------------
SCENARIO = """
[scenario]
name = "dissipating spinner"

[body]
principal_moments = [1.0, 1.2, 1.5]

[state]
epoch = "2030-01-01T00:00:00"
time_scale = "tdb"
frame = "ICRF"
attitude = { quaternion_scalar_last = [0, 0, 0, 1] }
omega_body = { value = [0.5, 0.02, 0.02], unit = "rad/s" }

[propagation]
duration = "150 s"
step = "1 s"
method = "integrator"
rtol = 1e-12

[[torques]]
type = "dissipation"
time_constant = "20 s"

[[events]]
type = "nutation_crossing"
angle = "20 deg"
axis = "A"

[[events]]
type = "nutation_crossing"
angle = "40 deg"
axis = "A"
terminal = true

[output]
netcdf = "out.nc"
"""


def _paths_bound(ds, rtol):
    """How far the two paths' crossings may lie apart: both root tolerances (4 eps
    (1 + |te|) each) plus a rate difference of ``INTEGRATOR_PATHS rtol |w|``, which moves
    the angle by at most ``|I| |dw| / |L|`` (``|I| = 1.5``), over the angle's rate (half
    the smallest over the last 20 one-second samples)."""
    w = ds.event_angular_velocity.values
    L = np.linalg.norm(w @ np.diag([1.0, 1.2, 1.5]), axis=1)
    dangle = 1.5 * INTEGRATOR_PATHS * rtol * np.linalg.norm(w, axis=1) / L
    rate = 0.5 * np.min(np.abs(np.diff(_angle(ds.angular_velocity.values)))[-20:])
    te = ds.event_time.values
    return 8.0 * EPS * (1.0 + te) + dangle / rate


def _scenario(tmp_path):
    path = tmp_path / "spinner.toml"
    path.write_text(SCENARIO)
    return path


def test_scenario_events_same_on_both_paths(tmp_path):
    """The [[events]] of a scenario: the compiled run of ``run_scenario`` and scipy's
    (``compiled=False``) on the scenario's body, state, torques and events: the same
    crossings, their times within the root finders' tolerances plus the two paths'
    difference (a rate error of ``INTEGRATOR_PATHS rtol |w|`` moves the angle by at most
    ``|I| |dw| / |L|``, the crossing by that over the angle's rate)."""
    sc = load_scenario(_scenario(tmp_path))
    ds = run_scenario(sc, write_outputs=False).ephemeris.dataset
    assert ds.attrs["method"] == "integrator" and ds.event_name.size == 2
    _, w_s, rec = integrate_reference_events(sc.body, sc.state.attitude.as_quat(),
                                             sc.state.omega_body, sc.times, sc.events,
                                             torques=sc.torques, rtol=sc.rtol,
                                             compiled=False)
    te_c, te_s = ds.event_time.values, np.array([r[0] for r in rec])
    assert [r[1] for r in rec] == [0, 1] and te_c.size == 2
    assert np.all(np.abs(te_c - te_s) <= _paths_bound(ds, sc.rtol))
    keep = ~np.isnan(w_s[:, 0])
    assert keep.sum() + 1 == ds.time.size                  # the event is the last sample
    np.testing.assert_allclose(ds.angular_velocity.values[:-1], w_s[keep], rtol=0,
                               atol=INTEGRATOR_PATHS * sc.rtol * 0.5)


@pytest.mark.slow
def test_scenario_events_same_without_numba(tmp_path):
    """The same scenario run by the command in a process without numba (scipy's path)."""
    path = _scenario(tmp_path)
    compiled = run_scenario(load_scenario(path), write_outputs=False).ephemeris.dataset
    out = tmp_path / "scipy.nc"
    env = dict(os.environ, ATTITUDE_NO_NUMBA="1", PYTHONPATH=str(ROOT))
    done = subprocess.run([sys.executable, "-m", "attitude", "run", str(path), "-o",
                           str(out), "--quiet"], env=env, cwd=tmp_path, capture_output=True,
                          text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    with xr.open_dataset(out) as ds:
        scipy = ds.load()
    assert list(compiled.event_name.values) == [str(n) for n in scipy.event_name.values]
    te_c, te_s = compiled.event_time.values, scipy.event_time.values
    assert np.all(np.abs(te_c - te_s) <= _paths_bound(compiled, 1e-12))
    np.testing.assert_allclose(compiled.angular_velocity.values,
                               scipy.angular_velocity.values, rtol=0,
                               atol=INTEGRATOR_PATHS * 1e-12 * 0.5)


@pytest.fixture
def immediate(monkeypatch):
    """Every progress report shown at once and every update written."""
    monkeypatch.setattr(progress, "DELAY", 0.0)
    monkeypatch.setattr(progress, "INTERVAL", 0.0)


def test_cli_shows_the_integrators_progress_and_quiet_prints_nothing(tmp_path, capsys,
                                                                     immediate):
    path = _scenario(tmp_path)
    out = tmp_path / "out.nc"
    assert main(["run", str(path), "-o", str(out)]) == 0
    err = [ln for ln in capsys.readouterr().err.splitlines() if ln != COMPILE_NOTICE]
    assert len(err) >= 3 and all(ln.startswith("attitude: propagation: ") for ln in err)
    assert err[-1].startswith("attitude: propagation: done, ")
    assert main(["run", str(path), "-o", str(out), "--quiet"]) == 0
    assert capsys.readouterr() == ("", "")

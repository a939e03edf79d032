"""Events of ``att.propagate`` (issue 6, section 2): location, truncation, direction,
batches, records in the ephemeris, errors."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import attitude as att
from attitude.foundations.errors import AttitudeError, InvalidStateError, PropagationError
from attitude.propagation.events import Event, event_table, nutation_crossing

from ..tolerances import FEW_OPS, assert_agree

EPOCH = "2030-01-01"


def _state(w, q=None):
    return att.AttitudeState(EPOCH, Rotation.identity() if q is None else q, w)


def _angle(body, w, axis):
    """Angle between L = I w and principal axis ``axis`` (0, 1, 2), body axes."""
    a = body.body_to_principal.as_matrix()[axis]
    L = np.asarray(w) @ body.inertia.T
    return np.arctan2(np.linalg.norm(np.cross(L, a), axis=-1), L @ a)


# --- a dissipating long-axis spinner -----------------------------------------------
SPINNER = att.RigidBody.from_principal_moments([1.0, 1.2, 1.5])
SPIN0 = _state([0.5, 0.02, 0.02])
DAMPER = att.torques.EnergyDissipation(time_constant=20.0)
THRESHOLD = np.radians(30.0)


@pytest.fixture(scope="module")
def spinner_events():
    out = {}
    for method in ("splitting", "integrator"):
        out[method] = att.propagate(SPINNER, SPIN0, np.linspace(0.0, 150.0, 16),
                                    torques=[DAMPER], method=method,
                                    events=[nutation_crossing(THRESHOLD, axis="A")])
    return out


def test_dissipation_crossing_agrees_between_methods(spinner_events):
    te = {m: event_table(e) for m, e in spinner_events.items()}
    assert len(te["splitting"]) == len(te["integrator"]) == 1
    ts, ti = te["splitting"][0][0], te["integrator"][0][0]
    assert 10.0 < ti < 150.0
    assert abs(ts - ti) <= 1e-6 * ti
    for eph in spinner_events.values():
        w_end = eph.dataset.angular_velocity.values[-1]
        assert abs(_angle(SPINNER, w_end, 0) - THRESHOLD) < 1e-8
        ds = eph.dataset
        assert_agree(ds.event_angular_velocity.values[0], w_end, ulps=FEW_OPS,
                     magnitude=np.linalg.norm(w_end), what="state at the event")
        # the angle grows: below the threshold before the event
        assert np.all(_angle(SPINNER, ds.angular_velocity.values[:-1], 0) < THRESHOLD)


def test_terminal_truncates(spinner_events):
    for eph in spinner_events.values():
        te = event_table(eph)[0][0]
        assert eph.time[-1] == te
        np.testing.assert_array_equal(eph.time[:-1], np.arange(0.0, te, 10.0))
        assert eph.dataset.attrs["event_count"] == 1
        assert eph.dataset.event_time.values[0] == te


def test_events_survive_netcdf(spinner_events, tmp_path):
    eph = spinner_events["integrator"]
    back = att.Ephemeris.from_netcdf(eph.to_netcdf(tmp_path / "ev.nc"))
    assert event_table(back) == event_table(eph)
    np.testing.assert_allclose(back.dataset.event_quaternion.values,
                               eph.dataset.event_quaternion.values)


def test_non_terminal_and_direction():
    # the angle from A grows, so only an upward crossing exists
    kw = dict(torques=[DAMPER], method="integrator")
    times = np.linspace(0.0, 150.0, 4)
    up = att.propagate(SPINNER, SPIN0, times, **kw,
                       events=[nutation_crossing(THRESHOLD, "A", terminal=False,
                                                 direction=1)])
    down = att.propagate(SPINNER, SPIN0, times, **kw,
                         events=[nutation_crossing(THRESHOLD, "A", terminal=False,
                                                   direction=-1)])
    assert len(event_table(up)) == 1 and event_table(down) == []
    np.testing.assert_array_equal(up.time, times)          # not truncated
    assert down.dataset.attrs["event_count"] == 0


def test_torque_free_oblate_no_event():
    body = att.RigidBody.from_principal_moments([1.0, 1.0, 2.0])
    state = _state([0.1, 0.0, 1.0])
    theta = _angle(body, [0.1, 0.0, 1.0], 2)
    times = np.linspace(0.0, 100.0, 11)
    for method, kw in (("exact", {}), ("integrator", {}),
                       ("splitting", {"torques": [att.torques.ConstantTorque([0, 0, 0])],
                                      "step": 0.5})):
        eph = att.propagate(body, state, times, method=method, **kw,
                            events=[nutation_crossing(theta + 1e-3)])
        assert event_table(eph) == [] and len(eph) == times.size, method
    # ...but a threshold at the constant value minus a bit is never crossed either
    eph = att.propagate(body, state, times, events=[nutation_crossing(theta - 1e-3)])
    assert event_table(eph) == []


# --- exact method on a triaxial SAM body ----------------------------------------------
TRI = att.RigidBody.from_principal_moments([0.61, 0.965, 1.0])
TRI_STATE = _state([0.05, 0.0, 0.5])


def test_exact_crossings_match_closed_form_and_diagnosis():
    d = att.diagnose(TRI, TRI_STATE)
    assert d.regime == "SAM" and d.reference_axis == 3
    lo, hi = d.nutation_range
    theta = lo + 0.3 * (hi - lo)
    eph = att.propagate(TRI, TRI_STATE, np.linspace(0.0, 90.0, 10),
                        events=[nutation_crossing(theta, "C", terminal=False)])
    times = [t for t, _ in event_table(eph)]
    # the angle has half the polhode period (~41.9 s): 90 s holds 5 crossings
    assert len(times) == 5
    # finely sampled closed form: angle range and crossing times
    fine = np.linspace(0.0, 90.0, 400001)
    w = att.propagate(TRI, TRI_STATE, fine).dataset.angular_velocity.values
    ang = _angle(TRI, w, 2)
    assert abs(ang.min() - lo) < 1e-8 and abs(ang.max() - hi) < 1e-8
    g = ang - theta
    k = np.flatnonzero(np.sign(g[:-1]) != np.sign(g[1:]))
    analytic = fine[k] - g[k] * (fine[k + 1] - fine[k]) / (g[k + 1] - g[k])
    np.testing.assert_allclose(times, analytic, rtol=1e-7)
    # minimum at t = 0, maximum at a quarter polhode period: symmetric crossings
    half = d.periods["polhode"] / 2
    assert abs(times[0] + times[1] - half) < 1e-9 * half
    assert abs(times[2] - times[0] - half) < 1e-9 * half
    at_events = _angle(TRI, eph.dataset.event_angular_velocity.values, 2)
    np.testing.assert_allclose(at_events, theta, rtol=0, atol=1e-10)
    # outside the range: nothing
    none = att.propagate(TRI, TRI_STATE, [0.0, 90.0],
                         events=[nutation_crossing(min(hi + 1e-3, np.pi))])
    assert event_table(none) == []


def test_exact_terminal_and_user_event():
    calls = []

    def rate_x(t, q, w, body):
        calls.append(t)
        return w[0] - 0.0          # omega_x crosses zero

    eph = att.propagate(TRI, TRI_STATE, np.linspace(0.0, 90.0, 10),
                        events=[Event(rate_x, direction=-1, name="wx_down")])
    (te, name), = event_table(eph)
    assert name == "wx_down" and eph.time[-1] == te
    assert abs(eph.dataset.angular_velocity.values[-1, 0]) < 1e-12
    assert calls


def test_batch_events_per_body():
    bodies = [SPINNER, SPINNER.with_name("slow")]
    states = [SPIN0, _state([0.5, 0.01, 0.01])]
    ev = nutation_crossing(THRESHOLD, "A", terminal=False)
    eph = att.propagate(bodies, states, np.linspace(0.0, 150.0, 4), torques=[DAMPER],
                        events=ev, step=0.5)
    table = event_table(eph)
    assert [b for *_, b in table] == [0, 1]
    single = event_table(att.propagate(SPINNER, SPIN0, np.linspace(0.0, 150.0, 4),
                                       torques=[DAMPER], events=ev, step=0.5))
    assert abs(table[0][0] - single[0][0]) < 1e-9 * single[0][0]


@pytest.mark.parametrize("method", ["splitting", "integrator", "exact"])
def test_terminal_events_stop_each_body_of_a_batch_at_its_own_time(method):
    """Each body stops at its own crossing, as it does alone; its later samples are
    NaN, its earlier ones those of the body alone."""
    t = np.linspace(0.0, 150.0, 31)
    if method == "exact":            # torque-free: the nutation angle oscillates
        bodies = [TRI, TRI.with_name("b")]
        states = [TRI_STATE, _state([0.07, 0.0, 0.45])]
        ev, torques = Event(lambda t, q, w, body: w[0], direction=-1, name="wx_down"), []
        t = np.linspace(0.0, 90.0, 31)
    else:
        bodies = [SPINNER, SPINNER.with_name("slow")]
        states = [SPIN0, _state([0.5, 0.01, 0.01])]
        ev, torques = nutation_crossing(THRESHOLD, "A"), [DAMPER]
    eph = att.propagate(bodies, states, t, torques=torques, method=method, events=ev)
    table = event_table(eph)
    assert [b for *_, b in table] == [0, 1]
    assert table[0][0] != pytest.approx(table[1][0], rel=1e-3)
    for i, (te, _, _) in enumerate(table):
        alone = att.propagate(bodies[i], states[i], t, torques=torques, method=method,
                              events=ev)
        (te1, _), = event_table(alone)
        assert te == pytest.approx(te1, rel=1e-9)
        w = eph.dataset.angular_velocity.values[i]
        assert np.isnan(w[t > te]).all() and np.isfinite(w[t <= te]).all()
        before = t < te
        np.testing.assert_allclose(w[before], alone.dataset.angular_velocity.values[
            :before.sum()], rtol=0, atol=1e-9)
    assert np.isfinite(eph.conservation()["energy_rel_drift"])


@pytest.mark.parametrize("bad, match", [
    (lambda: Event(3.0), "callable"),
    (lambda: Event(lambda *a: 0.0, direction=2), "direction"),
    (lambda: Event(lambda *a: 0.0, terminal="yes"), "terminal"),
    (lambda: nutation_crossing(4.0), "must be within"),
    (lambda: nutation_crossing(0.1, axis="D"), "axis"),
    (lambda: att.propagate(TRI, TRI_STATE, [0.0, 1.0], events=[42]), "callable"),
    (lambda: att.propagate(TRI, TRI_STATE, [-1.0, 1.0], events=[nutation_crossing(0.1)]),
     "forward"),
])
def test_bad_event_input(bad, match):
    with pytest.raises(InvalidStateError, match=match):
        bad()


def test_event_returning_garbage():
    with pytest.raises(PropagationError, match="expected one finite float"):
        att.propagate(TRI, TRI_STATE, [0.0, 1.0], events=[lambda t, q, w, b: [1.0, 2.0]])
    with pytest.raises(AttitudeError):
        att.propagate(TRI, TRI_STATE, [0.0, 1.0], method="integrator",
                      events=[lambda t, q, w, b: np.nan])


def test_splitting_chunks_and_rotated_body_frame(monkeypatch):
    """A body frame that is not principal, and crossings located across chunk
    boundaries (tiny chunks) agree with one chunk and with DOP853."""
    import importlib

    prop = importlib.import_module("attitude.propagation.propagator")

    turn = Rotation.from_rotvec([0.3, -0.2, 0.5])
    inertia = turn.as_matrix().T @ np.diag([1.0, 1.2, 1.5]) @ turn.as_matrix()
    body = att.RigidBody(inertia)
    w0 = turn.inv().apply([0.5, 0.02, 0.02])
    state = _state(w0)
    ev = nutation_crossing(THRESHOLD, "A", terminal=False)
    kw = dict(torques=[DAMPER], events=[ev])
    times = np.linspace(0.0, 120.0, 3)
    ref = event_table(att.propagate(body, state, times, method="integrator", **kw))
    one = event_table(att.propagate(body, state, times, method="splitting", step=0.1,
                                    **kw))
    monkeypatch.setattr(prop, "_EVENT_CHUNK", 50)
    many = att.propagate(body, state, times, method="splitting", step=0.1, **kw)
    assert len(ref) == len(one) == 1
    assert abs(one[0][0] - ref[0][0]) < 1e-6 * ref[0][0]
    assert abs(event_table(many)[0][0] - one[0][0]) < 1e-10 * one[0][0]
    assert abs(_angle(body, many.dataset.event_angular_velocity.values[0], 0)
               - THRESHOLD) < 1e-8
    np.testing.assert_array_equal(many.time, times)


def test_exact_batch_events():
    states = [TRI_STATE, _state([0.06, 0.0, 0.5])]
    ev = Event(nutation_crossing(0.15, "C"), terminal=False, direction=1, name="up",
               vectorized=True)
    eph = att.propagate([TRI, TRI], states, np.linspace(0.0, 40.0, 5), events=ev)
    table = event_table(eph)
    assert sorted({b for *_, b in table}) == [0, 1]
    assert all(name == "up" for _, name, _ in table)
    single = event_table(att.propagate(TRI, TRI_STATE, np.linspace(0.0, 40.0, 5),
                                       events=ev))
    assert [t for t, _, b in table if b == 0] == pytest.approx([t for t, _ in single],
                                                               rel=1e-12)


def test_nutation_crossing_quantity_and_bad_unit():
    import astropy.units as u

    ev = nutation_crossing(30 * u.deg, axis=0)
    assert ev.name == "nutation_A_0.523598776" and ev.terminal and ev.direction == 0
    assert abs(ev(0.0, [0, 0, 0, 1], [0.0, 0.0, 1.0], SPINNER) - (np.pi / 2 - np.pi / 6)) \
        < 1e-15
    with pytest.raises(InvalidStateError, match="angle"):
        nutation_crossing(3 * u.m)

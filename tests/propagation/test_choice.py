"""The method ``propagate`` chooses with torques and no ``method=``
(attitude/propagation/choice.py): which method on clear cases, its settings, the
attributes that record it, and the accuracy of the automatic result."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import attitude as att
from attitude.model.orbit import KeplerOrbit
from attitude.model.torques import EARTH_MU, ConstantTorque, GravityGradient
from attitude.propagation.choice import (
    AUTO_ACCURACY,
    NU_MEASURE_COST,
    _measured_turning,
    _splitting_cost,
    choose_method,
)
from attitude.propagation.compiled import NUMBA
from attitude.propagation.kicks import System
from attitude.propagation.splitting import choose_step
from attitude.propagation.stepsize import torque_rates

BOX = att.RigidBody.from_parts([att.MassProperties.solid_box(100.0, [0.5, 1.0, 2.0])])
AXIS = np.array([0.2, 0.3, 0.93]) / np.linalg.norm([0.2, 0.3, 0.93])
Q0 = Rotation.from_euler("xyz", [0.4, -0.2, 0.3]).as_quat()
GG = GravityGradient(EARTH_MU, KeplerOrbit(EARTH_MU, 7.0e6, 0.001))
HOUR = np.arange(0.0, 3601.0, 60.0)


def _choice(rate_deg, times=HOUR, torques=(GG,)):
    w0 = np.radians(rate_deg) * AXIS
    return choose_method([BOX], Q0[None], w0[None], times, list(torques))


def test_fast_spinner_in_slow_torque_gets_the_splitting():
    # 60 deg/s against an orbital pace of 1.9e-3 rad/s: DOP853 must resolve ~600 turns
    # at a tight rtol, the splitting's exact free flow carries them
    c = _choice(60.0)
    assert c.method == "splitting"
    assert c.cost_splitting < c.cost_integrator
    assert c.rtol is None
    if NUMBA:
        assert c.step is not None and "compiled splitting" in c.reason
    else:
        assert "numba is not installed" in c.reason and c.step is None


def test_slow_spinner_in_fast_torque_gets_the_integrator():
    # 0.05 deg/s (slower than the orbital rate): few turns, DOP853 takes few steps
    c = _choice(0.05)
    assert c.cost_integrator < c.cost_splitting
    if NUMBA:
        assert c.method == "integrator"
        assert c.rtol is not None and c.step is None
        assert "compiled DOP853" in c.reason
    else:
        assert c.method == "splitting"


#: benchmarks/spin_crossover.py's cases (deg/s, an hour, outputs every minute): DOP853
#: at 1 deg/s, the splitting from 10 deg/s up (the crossover it measured)
BENCHMARK_CASES = [(1.0, "integrator"), (10.0, "splitting"), (60.0, "splitting"),
                   (360.0, "splitting")]


@pytest.mark.parametrize(("rate_deg", "method"), BENCHMARK_CASES)
def test_the_benchmark_cases_and_their_reasons(rate_deg, method):
    c = _choice(rate_deg)
    if not NUMBA:
        assert c.method == "splitting" and c.reason.startswith("numba is not installed")
        return
    assert c.method == method
    pace = GG.characteristic_rate(0.0, Q0, np.radians(rate_deg) * AXIS, BOX)
    assert c.reason.startswith(f"spin {np.radians(rate_deg):.3g} rad/s against the "
                               f"torque's pace {pace:.3g} rad/s: ")
    if method == "integrator":
        # DOP853 at its rtol, against the splitting's cost at nu = 0 (a lower bound:
        # nu not measured), which could not save more than measuring nu costs
        assert c.step is None and f"compiled DOP853 at rtol {c.rtol:.2g}" in c.reason
        assert c.cost_integrator <= c.cost_splitting + NU_MEASURE_COST
        assert "or more" in c.reason
    else:
        assert c.rtol is None and f"compiled splitting at step {c.step:.3g} s" in c.reason
        assert c.cost_splitting < c.cost_integrator


@pytest.mark.parametrize("rate_deg", [0.05, 0.5, 1.0, 1.5, 3.0, 5.0, 20.0, 100.0])
def test_not_measuring_nu_loses_at_most_what_measuring_costs(rate_deg):
    # against the decision with nu measured (the splitting's true cost and step): the
    # integrator is chosen only if it is dearer by at most NU_MEASURE_COST, and a
    # splitting runs at the step of the measured nu
    w0 = np.radians(rate_deg) * AXIS
    c = _choice(rate_deg)
    own, nu, rate = _measured_turning([BOX], Q0[None], w0[None], [GG])
    step, cost = _splitting_cost(HOUR, 1, own, rate, nu, AUTO_ACCURACY)
    if not NUMBA:
        assert c.method == "splitting" and c.cost_splitting == cost
    elif c.method == "integrator":
        assert c.cost_integrator <= cost + NU_MEASURE_COST
        assert c.cost_splitting <= cost         # the lower bound it went by
    else:
        assert c.step == step and c.cost_splitting == cost < c.cost_integrator


def test_nu_from_one_call_per_model_is_the_per_state_measurement():
    # a TorqueModel is called once on the five states of the differences, a plain
    # function once per state: the same nu but for the rounding of the differences
    # (the fourth difference at spacing 0.05/|omega| divides rounding by ~(0.05)^4)
    plain = [lambda t, q, w, body: GG(t, q, w, body)]
    for rate_deg in (0.5, 10.0, 60.0):
        system = System([BOX], [GG])
        q_p, w_p = system.to_principal(Q0[None], np.radians(rate_deg) * AXIS[None])
        one = torque_rates(System([BOX], [GG]), q_p, w_p, 4)
        each = torque_rates(System([BOX], plain), q_p, w_p, 4)
        np.testing.assert_allclose(one[1], each[1], rtol=1e-9)
        assert one[1][0] > 0


@pytest.mark.skipif(not NUMBA, reason="without numba the splitting keeps its step rule")
def test_settings_do_not_over_deliver():
    # the automatic step is longer than the step rule's conservative one (1e-10-class),
    # the automatic rtol looser than the reference's 1e-13
    fast = _choice(60.0)
    h_rule = choose_step(BOX, Q0, np.radians(60.0) * AXIS, [GG])
    assert fast.step > 4.0 * h_rule
    slow = _choice(0.05)
    assert slow.rtol > 1e-11


def test_explicit_settings_keep_their_method():
    state = att.AttitudeState("2030-01-01", Rotation.from_quat(Q0), np.radians(60.0) * AXIS)
    t = [0.0, 30.0]
    for kwargs, method in (({"method": "integrator"}, "integrator"),
                           ({"method": "splitting"}, "splitting"),
                           ({"rtol": 1e-9}, "integrator"),
                           ({"step": 1.0}, "splitting"),
                           ({"order": 6}, "splitting")):
        eph = att.propagate(BOX, state, t, torques=[GG], **kwargs)
        assert eph.dataset.attrs["method"] == method
        assert "given" in eph.dataset.attrs["method_reason"]
    eph = att.propagate(BOX, state, t)
    assert eph.dataset.attrs["method"] == "exact"
    assert "no torques" in eph.dataset.attrs["method_reason"]


def test_attributes_record_the_automatic_choice():
    state = att.AttitudeState("2030-01-01", Rotation.from_quat(Q0), np.radians(60.0) * AXIS)
    t = np.array([0.0, 20.0, 40.0])
    eph = att.propagate(BOX, state, t, torques=[GG])
    c = _choice(60.0, times=t)
    assert eph.dataset.attrs["method"] == c.method
    assert eph.dataset.attrs["method_reason"] == c.reason
    assert eph.dataset.attrs["source"].startswith(f"attitude.propagate, method={c.method}")


def test_ensemble_records_the_choice():
    ens = att.Ensemble.from_arrays(principal_moments=[BOX.principal_moments] * 2,
                                   omega_body=[[0.0, 0.0, 1e-3], [1e-3, 0.0, 0.0]],
                                   epoch="2030-01-01")
    eph = att.propagate(ens, [0.0, 60.0], torques=[GG])
    assert eph.dataset.attrs["method"] in ("integrator", "splitting")
    assert eph.dataset.attrs["method_reason"]


@pytest.mark.parametrize("rate_deg", [0.5, 20.0])
def test_automatic_accuracy_against_a_tight_reference(rate_deg):
    # the default accuracy is AUTO_ACCURACY over the run from error models whose fits
    # scatter by a factor ~3: the result is within 10 AUTO_ACCURACY of DOP853 at 1e-13
    # (itself ~1e-11 here), whichever method runs
    state = att.AttitudeState("2030-01-01", Rotation.from_quat(Q0),
                              np.radians(rate_deg) * AXIS)
    t = np.arange(0.0, 1801.0, 60.0)
    eph = att.propagate(BOX, state, t, torques=[GG])
    ref = att.propagate(BOX, state, t, torques=[GG], method="integrator", rtol=1e-13)
    err = np.max((eph.rotation * ref.rotation.inv()).magnitude())
    assert err < 10.0 * AUTO_ACCURACY


def test_automatic_accuracy_against_the_exact_solution():
    # a symmetric top spun about its axis under a constant torque along it: omega_z =
    # w0 + M t / C and the angle turned is w0 t + M t^2 / (2 C), exactly
    body = att.RigidBody.from_principal_moments([2.0, 2.0, 3.0])
    w0, m = 0.5, 1e-3
    state = att.AttitudeState("2030-01-01", Rotation.identity(), [0.0, 0.0, w0])
    t = np.linspace(0.0, 2000.0, 41)
    eph = att.propagate(body, state, t, torques=[ConstantTorque([0.0, 0.0, m])])
    angle = w0 * t + m * t * t / (2.0 * 3.0)
    exact = Rotation.from_rotvec(np.outer(angle, [0.0, 0.0, 1.0]))
    err = np.max((eph.rotation * exact.inv()).magnitude())
    assert err < 10.0 * AUTO_ACCURACY
    w = eph.dataset.angular_velocity.values[:, 2]
    # the rate is linear in t: both methods carry it to round-off of the summed kicks
    np.testing.assert_allclose(w, w0 + m * t / 3.0, rtol=1e-12)


def test_a_torque_without_rate_runs():
    # a zero constant torque: no rate at all, the splitting's step is the whole span
    state = att.AttitudeState("2030-01-01", Rotation.from_quat(Q0), [0.01, 0.02, 0.03])
    t = np.linspace(0.0, 100.0, 5)
    eph = att.propagate(BOX, state, t, torques=[ConstantTorque([0.0, 0.0, 0.0])])
    free = att.propagate(BOX, state, t)
    err = np.max((eph.rotation * free.rotation.inv()).magnitude())
    assert err < 10.0 * AUTO_ACCURACY


def test_events_keep_the_splitting():
    # DOP853's events run in scipy: with events the automatic method is the splitting
    from attitude.propagation.events import Event

    state = att.AttitudeState("2030-01-01", Rotation.from_quat(Q0), np.radians(0.05) * AXIS)
    ev = Event(lambda t, q, w, body: t - 30.0, name="half")
    eph = att.propagate(BOX, state, [0.0, 60.0], torques=[GG], events=[ev])
    assert eph.dataset.attrs["method"] == "splitting"
    assert "events" in eph.dataset.attrs["method_reason"]
    assert eph.dataset.attrs["event_count"] == 1

"""The splitting integrator (attitude/splitting.py): its exact free-flow step against the
closed form, conservation and exactness without torques, measured orders of convergence
against DOP853, bounded energy error and time reversibility for a conservative torque,
batches against single runs, dissipation, the step rule and the ``propagate`` wiring."""

import math

import numpy as np
import pytest
from astropy import units as u
from scipy.spatial.transform import Rotation

import attitude as att
from attitude.model.orbit import ConstantPosition, KeplerOrbit
from attitude.model.torques import (
    ConstantTorque,
    EnergyDissipation,
    GravityGradient,
    as_torque_model,
)
from attitude.propagation import splitting
from attitude.propagation.reference import integrate_reference
from attitude.propagation.splitting import (
    SCHEMES,
    STEPS_PER_PERIOD,
    choose_step,
    free_flow,
    integrate_splitting,
)
from attitude.propagation.torquefree import free_rotation

from ..tolerances import EXACT_SOLUTION, SPLITTING_STEP, assert_agree, ulps

MU = 3.986004418e14
EPOCH = "2030-01-01T00:00:00"


def rotated_body(moments, seed):
    R = Rotation.random(random_state=seed).as_matrix()
    return att.RigidBody(R @ np.diag(moments) @ R.T)


def attitude_error(q, q_ref):
    """Largest rotation angle between two stacks of quaternions, rad."""
    return float(np.max((Rotation.from_quat(q.reshape(-1, 4))
                         * Rotation.from_quat(q_ref.reshape(-1, 4)).inv()).magnitude()))


def _random_states(n, seed):
    rng = np.random.default_rng(seed)
    moments = np.sort(rng.uniform(1.0, 2.0, (n, 3)), axis=1)
    omega = rng.normal(size=(n, 3))
    quat = Rotation.random(n, random_state=rng).as_quat()
    return moments, omega, quat


def _separatrix_distance(moments, omega):
    """|L^2 - 2EB| / L^2 (small near the separatrix, where the motion is ill-conditioned)."""
    L = moments * omega
    L2 = np.sum(L * L, axis=1)
    twoE = np.sum(moments * omega * omega, axis=1)
    return np.abs(L2 - twoE * moments[:, 1]) / L2


# --- the free-flow step ------------------------------------------------------------------


@pytest.mark.parametrize("h", [1e-3, 0.37, 4.0, -2.5, 60.0])
def test_free_flow_step_matches_closed_form(h):
    """One step of the kernel (Jacobi addition theorems + Carlson R_J for the precession
    angle) against the independent closed form of attitude.propagation.torquefree, SAM and
    LAM, short steps and steps spanning many polhode half-periods (|lambda h| >> 2K)."""
    moments, omega, quat = _random_states(400, 3)
    keep = _separatrix_distance(moments, omega) > 1e-2   # ill-conditioned there (below)
    moments, omega, quat = moments[keep], omega[keep], quat[keep]
    q_ref, w_ref = free_rotation(moments, quat, omega, [h])
    q, w = free_flow(moments, quat, omega, h)
    assert attitude_error(q, q_ref[:, 0]) < 1e-13 * max(1.0, abs(h))
    scale = np.linalg.norm(omega, axis=1, keepdims=True)
    assert np.max(np.abs(w - w_ref[:, 0]) / scale) < 1e-13 * max(1.0, abs(h))


@pytest.mark.parametrize("moments, omega", [
    ([1.0, 1.0, 2.0], [0.3, 0.1, 0.5]),         # oblate: regular precession (m = 0)
    ([0.5, 2.0, 2.0], [0.4, 0.2, -0.1]),        # prolate (LAM kernel, m = 0)
    ([1.0, 2.0, 2.0], [0.0, 1.0, 0.5]),         # prolate spinning in its B-C plane
    ([2.0, 2.0, 2.0], [0.2, -0.1, 0.3]),        # spherical
    ([1.0, 2.0, 3.0], [0.0, 0.0, -1.5]),        # pure spin about C
    ([1.0, 2.0, 3.0], [0.7, 0.0, 0.0]),         # pure spin about A
    ([1.0, 2.0, 3.0], [0.0, 0.9, 0.0]),         # unstable equilibrium (intermediate axis)
    ([1.0, 2.0, 3.0], [1e-40, 0.0, 1.0]),       # all but pure spin
    ([1.0, 2.0, 3.0], [0.0, 0.0, 0.0]),         # rest
    ([1.0, 2.0, 4.0], [0.5, 0.3, -0.5 / math.sqrt(8)]),   # on the separatrix (rounded)
])
def test_free_flow_degenerate_cases(moments, omega):
    """Symmetric bodies, principal-axis spins and rest go through the uniform-rotation
    branch or the m = 0 limit of the elliptic one: both must match the closed form."""
    quat = Rotation.from_euler("ZXZ", [0.3, 1.0, -0.4]).as_quat()
    for h in (0.5, -3.0):
        q_ref, w_ref = free_rotation(moments, quat, omega, [h])
        q, w = free_flow(moments, quat, omega, h)
        assert attitude_error(q, q_ref[0]) < 1e-14
        np.testing.assert_allclose(w, w_ref[0], rtol=0, atol=1e-14 * max(1, np.linalg.norm(omega)))


def test_one_body_kernel_equals_batch_kernel():
    """The plain-float one-body kernel and the vectorised kernel are the same formulas."""
    moments, omega, quat = _random_states(200, 8)
    moments[:3] = [[1.0, 1.0, 2.0], [1.0, 2.0, 2.0], [2.0, 2.0, 2.0]]
    omega[3] = [0.0, 0.0, 2.0]
    consts = splitting._FreeConstants(moments)
    for h in (0.2, -7.0, 30.0):
        q, w = splitting._free_flow_vec(consts, quat, omega, h)
        for i in range(len(moments)):
            q1, w1 = splitting._free_flow1(consts.row(i), tuple(quat[i]), tuple(omega[i]), h)
            # math-module scalars against numpy's vector loops: the exact free flow along
            # two paths, ulps of |q| = 1 and of |omega| (22 ulp measured at 100 rad)
            assert_agree(q1, q[i], ulps=EXACT_SOLUTION, magnitude=1.0, what=f"q of {i}")
            assert_agree(w1, w[i], ulps=EXACT_SOLUTION, magnitude=np.linalg.norm(omega[i]),
                         what=f"omega of {i}")


# --- no torque: exact ---------------------------------------------------------------------


def test_torque_free_splitting_is_the_exact_solution_and_conserves_L_and_E():
    """With no torque (and with an identically zero torque, which runs the whole
    kick/free composition) 2000 steps reproduce the closed form through a rotated body
    frame to round-off, and |L|, E stay constant to round-off.  (Round-off: a few 1e-16
    rad per free flow, i.e. < 3e-11 rad after the 14000 flows of the 6th-order scheme
    while the body turns by 220 rad; the invariants random-walk by ~1e-16 per flow.)"""
    body = rotated_body([1.0, 2.0, 2.5], 4)
    state = att.AttitudeState(EPOCH, Rotation.from_euler("ZXZ", [10, 30, -20], degrees=True),
                              [0.3, -0.2, 0.4])
    t = np.linspace(0.0, 400.0, 21)
    exact = att.propagate(body, state, t)
    zero = ConstantTorque([0.0, 0.0, 0.0])
    for torques, order in (([], 4), ([zero], 4), ([zero], 2), ([zero], 6)):
        eph = att.propagate(body, state, t, torques=torques, method="splitting", step=0.2,
                            order=order)
        assert attitude_error(eph.dataset.quaternion.values,
                              exact.dataset.quaternion.values) < 3e-11
        np.testing.assert_allclose(eph.dataset.angular_velocity, exact.dataset.angular_velocity,
                                   rtol=0, atol=3e-11 * 0.54)
        drift = eph.conservation()                    # rounding random walk, ~1e-16 sqrt(n)
        assert drift["angular_momentum_rel_drift"] < 5e-13
        assert drift["energy_rel_drift"] < 5e-13


def test_torque_free_default_step_is_one_exact_step_per_output():
    """Without torques the default step is infinite: one exact free flow per output."""
    body = att.RigidBody.from_principal_moments([1.0, 2.0, 3.0])
    assert choose_step(body, [0, 0, 0, 1], [0.1, 0.2, 0.3]) == math.inf
    q, w = integrate_splitting(body, [0, 0, 0, 1], [0.1, 0.2, 0.3], [1e4])
    q_ref, w_ref = free_rotation([1.0, 2.0, 3.0], [0, 0, 0, 1], [0.1, 0.2, 0.3], [1e4])
    assert attitude_error(q, q_ref) < 1e-14 * 1e4 * np.linalg.norm([0.1, 0.2, 0.3])
    np.testing.assert_allclose(w, w_ref, rtol=0, atol=1e-15 * 1e4 * 0.4)


# --- orders of convergence ----------------------------------------------------------------


@pytest.fixture(scope="module")
def eccentric_gg_case():
    """A triaxial body tumbling in gravity gradient on an e = 0.1 orbit, and its DOP853
    reference (rtol 1e-13) at 4 output times over ~one orbit."""
    body = att.RigidBody.from_principal_moments([1.0, 1.7, 2.2])
    gg = GravityGradient(MU, KeplerOrbit(MU, 7.0e6, 0.1))
    q0 = Rotation.from_euler("xyz", [0.3, 0.2, 0.1]).as_quat()
    w0 = np.array([1e-3, -2e-3, 3e-3])
    t = np.linspace(0.0, 6000.0, 4)
    return body, gg, q0, w0, t


def _slope(case, torques, scheme, steps):
    body, _, q0, w0, t = case
    q_ref, _ = integrate_reference(body, q0, w0, t, torques=torques, rtol=1e-13)
    errors = []
    for h in steps:
        q, _ = integrate_splitting(body, q0, w0, t, torques=torques, step=h, order=None,
                                   scheme=scheme)
        errors.append(attitude_error(q, q_ref))
    assert max(errors) < 0.2 and min(errors) > 1e-11     # asymptotic range, above the ref.
    return np.polyfit(np.log(steps), np.log(errors), 1)[0], errors


@pytest.mark.parametrize("scheme, order", [
    ("strang", 2), ("yoshida4", 4), ("blanes-moan", 4), ("blanes-moan-rkn", 4),
    ("yoshida6", 6),
])
def test_measured_order_against_dop853_gravity_gradient(eccentric_gg_case, scheme, order):
    """log-log slope of the attitude error vs the step (h = 200 ... 25 s), against an
    independent integrator (DOP853 on Euler's equations, rtol 1e-13)."""
    gg = eccentric_gg_case[1]
    slope, _ = _slope(eccentric_gg_case, [gg], scheme, [200.0, 100.0, 50.0, 25.0])
    assert slope == pytest.approx(order, abs=0.35)


def test_rkn_scheme_is_the_most_accurate_fourth_order_at_equal_cost(eccentric_gg_case):
    """Blanes-Moan's RKN coefficients (valid for attitude-only kicks) beat the general
    S6 and, by far, Yoshida's triple jump at the same number of free flows."""
    gg = eccentric_gg_case[1]
    _, rkn = _slope(eccentric_gg_case, [gg], "blanes-moan-rkn", [100.0, 50.0])
    _, bm = _slope(eccentric_gg_case, [gg], "blanes-moan", [100.0, 50.0])
    _, y4 = _slope(eccentric_gg_case, [gg], "yoshida4", [50.0, 25.0])   # 3 flows per step
    assert rkn[1] < bm[1] / 3 and bm[1] < y4[1] / 3


@pytest.mark.parametrize("scheme, order", [("strang", 2), ("blanes-moan", 4)])
def test_measured_order_with_a_velocity_dependent_torque(eccentric_gg_case, scheme, order):
    """Gravity gradient + internal dissipation: the dissipative part goes through the RK
    sub-step of the kick (midpoint for Strang, RK4 otherwise); the order is kept."""
    gg = eccentric_gg_case[1]
    torques = [gg, EnergyDissipation(2000.0)]
    slope, _ = _slope(eccentric_gg_case, torques, scheme, [200.0, 100.0, 50.0, 25.0])
    assert slope == pytest.approx(order, abs=0.35)


def test_rkn_scheme_refuses_velocity_dependent_torques(eccentric_gg_case):
    body, gg, q0, w0, t = eccentric_gg_case
    with pytest.raises(att.InvalidStateError, match="needs attitude-only torques"):
        integrate_splitting(body, q0, w0, t, torques=[gg, EnergyDissipation(10.0)],
                            scheme="blanes-moan-rkn", order=None)


# --- conservative torque: symplectic, reversible -----------------------------------------


def test_energy_error_bounded_without_drift_over_1e5_steps():
    """Gravity gradient from a fixed primary conserves E_kin + V.  Over 1e5 Strang steps
    (h = 20 s, 23 days, V exchanging ~3 E with the kinetic energy) the energy error of the
    symplectic map oscillates at O(h^2) but does not grow: its maximum over the last
    tenth of the run is no larger than over the first tenth."""
    moments = np.array([2.0, 3.0, 4.5])
    body = att.RigidBody.from_principal_moments(moments)
    gg = GravityGradient(MU, ConstantPosition([7.0e6, 0.0, 0.0]))
    q0 = Rotation.from_euler("xyz", [0.4, -0.3, 0.2]).as_quat()
    w0 = np.array([3e-4, -2e-4, 1e-3])
    h, n = 20.0, 100_000
    t = np.arange(0, n + 1, 100) * h
    q, w = integrate_splitting(body, q0, w0, t, torques=[gg], step=h, order=2)
    V = gg.potential(t, q, body)
    E = 0.5 * np.sum(moments * w * w, axis=1) + V
    assert np.ptp(V) > 2.0 * abs(E[0])                    # a strong exchange of energy
    err = np.abs(E - E[0]) / abs(E[0])
    tenth = len(t) // 10
    first, last = err[1:tenth].max(), err[-tenth:].max()
    assert 1e-6 < first < 1e-3                             # O(h^2), well above round-off
    assert last < 1.2 * first


def test_time_reversible_with_a_time_dependent_torque():
    """Forward 300 steps on an eccentric orbit, then from the end state backwards with
    the same steps: the start comes back to round-off (symmetric composition in the
    extended phase space; every schedule of the scheme table is symmetric)."""
    body = rotated_body([1.0, 1.7, 2.2], 6)
    orbit = KeplerOrbit(MU, 7.0e6, 0.3, i=0.5)
    gg = GravityGradient(MU, orbit)
    q0 = Rotation.from_euler("xyz", [0.3, 0.2, 0.1]).as_quat()
    w0 = np.array([1e-3, -2e-3, 3e-3])
    T = 6000.0
    shifted = as_torque_model(lambda t, q, w, b: gg(t + T, q, w, b),
                              velocity_dependent=False)
    for scheme in SCHEMES:
        q1, w1 = integrate_splitting(body, q0, w0, [T], torques=[gg], step=T / 300,
                                     scheme=scheme, order=None)
        q2, w2 = integrate_splitting(body, q1[0], w1[0], [-T], torques=[shifted],
                                     step=T / 300, scheme=scheme, order=None)
        assert attitude_error(q2, q0[None]) < 5e-12, scheme
        np.testing.assert_allclose(w2[0], w0, rtol=0, atol=5e-12 * np.linalg.norm(w0))
        assert attitude_error(q1, q0[None]) > 0.1            # it did go somewhere


# --- batches, outputs ---------------------------------------------------------------------


@pytest.mark.slow      # a long study (> 9 s); the slow tier, which CI runs
def test_batch_equals_single_runs():
    """One vectorised run of 5 bodies (rotated frames, an oblate one, gravity gradient +
    dissipation) equals 5 one-body runs (plain-float path) with the same step."""
    rng = np.random.default_rng(7)
    bodies = [rotated_body(np.sort(rng.uniform(1.0, 2.0, 3)), k) for k in range(4)]
    bodies.append(att.RigidBody.from_principal_moments([1.0, 1.0, 1.6]))
    q0 = Rotation.random(5, random_state=rng).as_quat()
    w0 = rng.normal(size=(5, 3)) * 1e-2
    torques = [GravityGradient(MU, KeplerOrbit(MU, 7.0e6, 0.1)), EnergyDissipation(600.0)]
    t = np.array([0.0, 50.0, 300.0, 1000.0])
    q, w = integrate_splitting(bodies, q0, w0, t, torques=torques, step=5.0)
    assert q.shape == (5, 4, 4) and w.shape == (5, 4, 3)
    for i, body in enumerate(bodies):
        q1, w1 = integrate_splitting(body, q0[i], w0[i], t, torques=torques, step=5.0)
        assert attitude_error(q[i], q1) < 1e-12
        np.testing.assert_allclose(w[i], w1, rtol=0, atol=1e-12 * np.abs(w0[i]).max())


def test_batch_through_propagate_and_moments_input():
    """att.propagate sends a batch to one vectorised run; principal moments work as
    bodies whose frame is principal."""
    bodies = [att.RigidBody.from_principal_moments(m) for m in ([1, 2, 3], [2, 3, 4])]
    states = [att.AttitudeState(EPOCH, Rotation.identity(), [0.01, 0.02, 0.03])] * 2
    gg = GravityGradient(MU, [7.0e6, 0.0, 0.0])
    eph = att.propagate(bodies, states, [0.0, 100.0], torques=[gg], step=10.0)
    assert eph.dataset.quaternion.shape == (2, 2, 4)
    q, w = integrate_splitting([[1, 2, 3], [2, 3, 4]], [0, 0, 0, 1], [0.01, 0.02, 0.03],
                               [0.0, 100.0], torques=[gg], step=10.0)
    # the same 10 steps through propagate() and through the kernel: ulps per step
    assert attitude_error(q, eph.dataset.quaternion.values) <= ulps(1.0, 10 * SPLITTING_STEP)


def test_outputs_in_any_order_negative_and_repeated_times_hit_exactly():
    """Output times are hit exactly whatever the step: t = 0 returns the initial state,
    a repeated time the same state, and a time grid in any order equals the sorted one."""
    body = att.RigidBody.from_principal_moments([1.0, 1.7, 2.2])
    gg = GravityGradient(MU, KeplerOrbit(MU, 7.0e6, 0.1))
    q0 = Rotation.from_euler("xyz", [0.3, 0.2, 0.1]).as_quat()
    w0 = np.array([1e-3, -2e-3, 3e-3])
    t = np.array([300.0, -120.0, 0.0, 77.7, 300.0, -5.0])
    q, w = integrate_splitting(body, q0, w0, t, torques=[gg], step=7.0)
    np.testing.assert_array_equal(w[2], w0)
    np.testing.assert_array_equal(q[0], q[4])
    order = np.argsort(t)
    qs, ws = integrate_splitting(body, q0, w0, t[order], torques=[gg], step=7.0)
    np.testing.assert_array_equal(qs, q[order])
    # and the solution does not depend on where the outputs are (beyond the step size)
    unique = np.unique(t)
    q_ref, _ = integrate_reference(body, q0, w0, unique, torques=[gg])
    assert attitude_error(qs[[0, 1, 2, 3, 5]], q_ref) < 1e-9


# --- dissipation --------------------------------------------------------------------------


def test_dissipation_is_monotone_keeps_L_and_ends_in_flat_spin():
    """Explorer 1 in miniature with the splitting method (the internal kick: RK4 on the
    rates and the attitude increment, then the inertial L restored): E decreases at every
    output, |L| and the inertial L are kept to 1e-12, the end state spins about C."""
    moments = np.array([1.0, 1.5, 2.0])
    body = att.RigidBody.from_principal_moments(moments)
    state = att.AttitudeState(EPOCH, Rotation.identity(), [1.0, 0.05, 0.05])
    t = np.linspace(0.0, 500.0, 1001)
    eph = att.propagate(body, state, t, torques=[EnergyDissipation(30.0)], step=0.5)
    assert "method=splitting" in eph.dataset.attrs["source"]
    w = eph.dataset.angular_velocity.values
    L = np.linalg.norm(w * moments, axis=1)
    E = eph.dataset.kinetic_energy.values
    assert np.abs(L / L[0] - 1).max() < 1e-12
    Li = eph.dataset.angular_momentum.values                  # inertial
    assert np.abs(Li - Li[0]).max() < 1e-12 * L[0]
    assert np.all(np.diff(E) < 0)
    assert (E[-1] - L[-1] ** 2 / (2 * moments[2])) / E[-1] < 1e-5
    assert abs(w[-1, 2]) == pytest.approx(L[0] / moments[2], rel=1e-5)


# --- step rule, options, errors ----------------------------------------------------------


def test_default_step_rule():
    """h = 2 pi / (N rate), rate = max(torque, cbrt(nu^2 torque)); gravity gradient's
    torque rate is sqrt(3 mu / r_p^3) (or the orbital rate at periapsis if larger).  A
    triaxial body spinning in gravity gradient turns its inertial torque at twice the spin,
    so nu reaches its cap, the spin; a pure spin has no dissipation torque (nu = 0)."""
    body = att.RigidBody.from_principal_moments([1.0, 2.0, 3.0])
    r = 7.0e6
    gg = GravityGradient(MU, ConstantPosition([r, 0.0, 0.0]))
    w_gg = math.sqrt(3 * MU / r**3)
    for spin in (1e-4, 1e-1):
        rate = max(w_gg, (spin * spin * w_gg) ** (1 / 3))
        for order in (2, 4, 6):
            h = choose_step(body, [0, 0, 0, 1], [0.0, 0.0, spin], [gg], order=order)
            assert h == pytest.approx(2 * math.pi / (STEPS_PER_PERIOD[order] * rate))
    tau = 5.0
    h = choose_step(body, [0, 0, 0, 1], [0.0, 0.0, 1e-4], [gg, EnergyDissipation(tau)])
    assert h == pytest.approx(2 * math.pi / (STEPS_PER_PERIOD[4] / tau))


def test_propagate_method_selection_and_options(capsys, monkeypatch):
    """Method selection (the automatic choice with torques alone:
    tests/propagation/test_choice.py; integrator if rtol is given, splitting if step or
    order is); step as a Quantity; progress goes to stderr only when asked; bad options
    are reported."""
    body = att.RigidBody.from_principal_moments([1.0, 2.0, 3.0])
    state = att.AttitudeState(EPOCH, Rotation.identity(), [0.01, 0.02, 0.03])
    gg = GravityGradient(MU, [7.0e6, 0.0, 0.0])
    t = [0.0, 60.0]
    assert "method=exact" in att.propagate(body, state, t).dataset.attrs["source"]
    assert "method=splitting" in att.propagate(body, state, t, torques=[gg],
                                               order=4).dataset.attrs["source"]
    assert "method=integrator" in att.propagate(body, state, t, torques=[gg],
                                                rtol=1e-10).dataset.attrs["source"]
    a = att.propagate(body, state, t, torques=[gg], step=1 * u.min, order=2)
    b = att.propagate(body, state, t, torques=[gg], step=60.0, order=2)
    np.testing.assert_array_equal(a.dataset.quaternion, b.dataset.quaternion)
    assert capsys.readouterr().err == ""
    from attitude.foundations import progress
    monkeypatch.setattr(progress, "DELAY", 0.0)    # shown at once (else after 1 s of work)
    att.propagate(body, state, t, torques=[gg], step=1.0, progress=True)
    assert "attitude: propagation: done, 60 s of 60 s simulated" in capsys.readouterr().err
    for kwargs, match in [
        (dict(order=3), "order=3 is not available"),
        (dict(step=-1.0), "positive"),
        (dict(step=1 * u.m), "not a time unit"),
        (dict(rtol=1e-9, step=1.0), "give one of them"),
        (dict(method="splitting", order=None, step=1.0), None),
    ]:
        if match is None:
            att.propagate(body, state, t, torques=[gg], **kwargs)
            continue
        with pytest.raises(att.InvalidStateError, match=match):
            att.propagate(body, state, t, torques=[gg], **kwargs)


def test_bad_torque_shape_is_reported():
    """A torque model returning the wrong shape is named in the error."""
    body = att.RigidBody.from_principal_moments([1.0, 2.0, 3.0])
    with pytest.raises(att.InvalidStateError, match="returned shape"):
        integrate_splitting(body, [0, 0, 0, 1], [0.1, 0.0, 0.0], [10.0], step=1.0,
                            torques=[lambda t, q, w, b: np.zeros(4)])


def test_scheme_and_order():
    """A scheme fixes the order (the default order is 4); contradicting it is an error,
    and order 4 picks the RKN scheme only for attitude-only torques."""
    body = att.RigidBody.from_principal_moments([1.0, 2.0, 3.0])
    gg = GravityGradient(MU, [7.0e6, 0.0, 0.0])
    args = (body, [0, 0, 0, 1], [0.01, 0.0, 0.02], [20.0])
    a, _ = integrate_splitting(*args, torques=[gg], step=5.0, scheme="strang")
    b, _ = integrate_splitting(*args, torques=[gg], step=5.0, order=2)
    np.testing.assert_array_equal(a, b)
    c, _ = integrate_splitting(*args, torques=[gg], step=5.0)
    d, _ = integrate_splitting(*args, torques=[gg], step=5.0, scheme="blanes-moan-rkn")
    np.testing.assert_array_equal(c, d)
    with pytest.raises(att.InvalidStateError, match="is of order 2, not 4"):
        integrate_splitting(*args, torques=[gg], step=5.0, scheme="strang", order=4)
    with pytest.raises(att.InvalidStateError, match="unknown"):
        integrate_splitting(*args, torques=[gg], step=5.0, scheme="leapfrog")

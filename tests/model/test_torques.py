"""Tests of attitude.torques: the protocol (plain functions, ``+``, broadcasting), every
built-in model against a closed form, and the scenario-table builder.

Independent references: the rotation-matrix form of each torque written out here; energy
conservation ``E + V`` for conservative torques; Goldstein, Poole & Safko (2002, Sec. 5.7)
for the heavy top; the linearised gravity-gradient pitch libration (Hughes 1986, Ch. 8);
the exact solution of a sphere in a uniform field for eddy currents.
"""

from __future__ import annotations

import astropy.units as u
import numpy as np
import pytest
from astropy.time import Time
from scipy.integrate import quad
from scipy.interpolate import CubicSpline
from scipy.spatial.transform import Rotation

import attitude as att
from attitude.model.orbit import ConstantPosition, KeplerOrbit, TabulatedPath
from attitude.model.torques import (
    ConstantTorque,
    EddyCurrentDamping,
    EnergyDissipation,
    FunctionTorque,
    GravityGradient,
    HeavyTopPivot,
    SumTorque,
    TiltedDipoleField,
    TorqueConfigError,
    TorqueModel,
    UniformField,
    as_torque_model,
    damping_timescale,
    from_config,
)
from attitude.propagation.reference import integrate_reference
from attitude.propagation.splitting import integrate_splitting

from ..tolerances import TORQUE_EVAL, assert_agree

MU = 3.986004418e14
EPOCH = "2030-01-01T00:00:00"


def _rotated(inertia, rng):
    R = Rotation.random(random_state=rng).as_matrix()
    return R @ inertia @ R.T


def _models():
    """One instance of every built-in model (eccentric orbit, dipole field)."""
    orbit = KeplerOrbit(MU, 7.2e6, 0.2, i=0.9, raan=0.3, argp=1.1, mean_anomaly=0.4)
    return {
        "gravity_gradient": GravityGradient(MU, orbit),
        "constant_body": ConstantTorque([1e-3, -2e-3, 3e-3]),
        "constant_inertial": ConstantTorque([1e-3, -2e-3, 3e-3], frame="inertial"),
        "dissipation": EnergyDissipation(100.0),
        "eddy_current": EddyCurrentDamping(np.diag([1e6, 2e6, 3e6]),
                                           TiltedDipoleField(orbit, rotation_angle=0.7)),
        "heavy_top": HeavyTopPivot(2.0, [0.0, 0.1, 0.3]),
    }


# --- protocol ---------------------------------------------------------------------------


@pytest.mark.parametrize("name", list(_models()))
def test_vectorised_call_equals_per_element_call(name):
    """Stacked (n,), (n, 4), (n, 3) == n single calls (skyfield's vectorisation check)."""
    model = _models()[name]
    rng = np.random.default_rng(7)
    body = att.RigidBody(_rotated(np.diag([1.0, 1.5, 2.0]), rng), mass=3.0)
    n = 6
    t = rng.uniform(0.0, 5000.0, n)
    q = Rotation.random(n, random_state=rng).as_quat()
    w = rng.normal(size=(n, 3))
    stacked = model(t, q, w, body)
    assert stacked.shape == (n, 3)
    # two paths of the same formulas: ulps of the scale of the terms (tests/tolerances.py)
    scale = np.abs(stacked).max()

    def agree(a, b, what):
        assert_agree(a, b, ulps=TORQUE_EVAL, magnitude=scale, what=f"{name}: {what}")

    for k in range(n):
        single = model(float(t[k]), q[k], w[k], body)
        assert single.shape == (3,)
        agree(stacked[k], single, f"element {k}")
    # a scalar time with stacked attitudes, a Rotation stack, a sequence of bodies
    agree(model(t[0], q, w, body)[2], model(t[0], q[2], w[2], body), "scalar time")
    agree(model(t, Rotation.from_quat(q), w, body), stacked, "Rotation stack")
    agree(model(t, q, w, [body] * n), stacked, "sequence of bodies")
    # integrators pass unnormalised stage quaternions: the built-ins normalise
    agree(model(t, 1.001 * q, w, body), stacked, "unnormalised quaternions")


def test_plain_function_is_a_model_and_models_add():
    def spin_up(t, quaternion, omega_body, body):
        return np.broadcast_to([0.0, 0.0, 1.0], np.shape(omega_body))

    c = ConstantTorque([1.0, 0.0, 0.0])
    d = EnergyDissipation("1 h")
    total = c + spin_up
    assert isinstance(total, SumTorque)
    assert isinstance(total.terms[1], FunctionTorque)
    body = att.RigidBody.from_principal_moments([1.0, 2.0, 3.0])
    np.testing.assert_array_equal(total(0.0, [0, 0, 0, 1], [0.0, 0.0, 0.0], body),
                                  [1.0, 0.0, 1.0])
    # a function on the left, nested sums flatten, sum() works
    left = spin_up + c
    assert isinstance(left, SumTorque) and left.terms[1] is c
    assert len((c + d) + (c + spin_up)) == 4
    assert isinstance(sum([c, d]), SumTorque)
    assert as_torque_model(c) is c
    # velocity dependence propagates through sums
    assert not c.velocity_dependent and d.velocity_dependent
    assert not (c + ConstantTorque([0, 0, 1], "inertial")).velocity_dependent
    assert (c + d).velocity_dependent
    assert not as_torque_model(spin_up, velocity_dependent=False).velocity_dependent
    with pytest.raises(TypeError, match="expected a callable"):
        as_torque_model(3.0)
    with pytest.raises(TypeError):
        c + "not a torque"


def test_docs_worked_example_residual_dipole():
    """The worked example of docs/torques.md: a residual dipole written as a plain function,
    run through att.propagate; E + U (U = -m . B) is conserved."""
    b_inertial = np.array([0.0, 0.0, 3.0e-5])           # T
    m_body = np.array([1.0, 0.0, 0.0])                   # A m^2

    def residual_dipole(t, quaternion, omega_body, body):
        b_body = Rotation.from_quat(quaternion).inv().apply(b_inertial)
        return np.cross(m_body, b_body)

    body = att.RigidBody.from_principal_moments([2.0, 3.0, 4.0])
    state = att.AttitudeState(EPOCH, Rotation.identity(), [0.0, 0.0, 1e-3])
    times = np.linspace(0.0, 600.0, 61)
    eph = att.propagate(body, state, times, torques=[residual_dipole])
    q = eph.dataset["quaternion"].values
    U = -Rotation.from_quat(q).apply(m_body) @ b_inertial
    total = eph.dataset["kinetic_energy"].values + U
    assert np.ptp(total) < 1e-10 * np.abs(U).max()
    assert eph.dataset["kinetic_energy"].values.max() > 2.9e-5
    model = as_torque_model(residual_dipole) + EnergyDissipation("10 min")
    eph = att.propagate(body, state, times, torques=[model])
    assert eph.dataset["kinetic_energy"].values[-1] < total[-1] - U[-1]


# --- gravity gradient -------------------------------------------------------------------


@pytest.mark.parametrize("axis", [0, 1, 2])
@pytest.mark.parametrize("theta_deg", [-70.0, 10.0, 45.0, 123.0])
def test_gravity_gradient_pitch_closed_form(axis, theta_deg):
    """Body rotated by theta about principal axis k, primary along principal axis i in the
    plane normal to k: |M| = 3 mu/(2 r^3) (I_j - I_i) sin 2 theta about k, restoring."""
    moments = np.array([100.0, 230.0, 250.0])
    body = att.RigidBody.from_principal_moments(moments)
    i, j = (axis + 1) % 3, (axis + 2) % 3
    r = 7.0e6
    position = np.zeros(3)
    position[i] = r
    gg = GravityGradient(MU, position)
    theta = np.radians(theta_deg)
    rotvec = np.zeros(3)
    rotvec[axis] = theta
    M = gg(0.0, Rotation.from_rotvec(rotvec).as_quat(), np.zeros(3), body)
    expected = np.zeros(3)
    expected[axis] = -1.5 * MU / r**3 * (moments[j] - moments[i]) * np.sin(2 * theta)
    np.testing.assert_allclose(M, expected, rtol=1e-13, atol=1e-16 * np.abs(expected).max())


def test_gravity_gradient_zero_when_principal_axis_points_at_primary():
    rng = np.random.default_rng(11)
    body = att.RigidBody(_rotated(np.diag([3.0, 4.0, 5.5]), rng))
    gg = GravityGradient(MU, [-4.0e6, 5.0e6, 2.0e6])
    r_hat = -np.array([-4.0e6, 5.0e6, 2.0e6]) / np.linalg.norm([-4.0e6, 5.0e6, 2.0e6])
    scale = 3 * MU / 4.0e6**3 * 5.5
    for k in range(3):
        axis_body = body.principal_axes[:, k]
        for sign in (1.0, -1.0):
            # attitude mapping this principal axis onto the direction of the primary
            R, _ = Rotation.align_vectors([sign * r_hat], [axis_body])
            R = Rotation.from_rotvec(rng.normal() * sign * r_hat) * R   # any roll about it
            M = gg(0.0, R.as_quat(), np.zeros(3), body)
            assert np.linalg.norm(M) < 1e-13 * scale
    # and not zero otherwise
    assert np.linalg.norm(gg(0.0, Rotation.random(random_state=rng).as_quat(), np.zeros(3),
                             body)) > 1e-3 * scale


def test_gravity_gradient_random_attitudes_against_matrix_form():
    rng = np.random.default_rng(3)
    body = att.RigidBody(_rotated(np.diag([1.0, 1.7, 2.2]), rng))
    orbit = KeplerOrbit(MU, 8.0e6, 0.3, i=0.4, raan=2.0, argp=0.5)
    gg = GravityGradient(orbit=orbit)
    assert gg.mu == MU
    t = rng.uniform(0, orbit.period, 20)
    R = Rotation.random(20, random_state=rng)
    M = gg(t, R, np.zeros((20, 3)), body)
    r_i = orbit.position(t)
    r_b = np.einsum("nji,nj->ni", R.as_matrix(), r_i)    # R^T r
    r = np.linalg.norm(r_b, axis=1)[:, None]
    expected = 3 * MU / r**3 * np.cross(r_b / r, (body.inertia @ (r_b / r).T).T)
    np.testing.assert_allclose(M, expected, rtol=1e-12, atol=1e-14 * np.abs(expected).max())


def test_gravity_gradient_conserves_energy_in_a_static_field():
    """Conservative: with the primary fixed (ConstantPosition), E_kin + V is constant along
    a propagated tumbling motion (checks sign and size of the torque against the potential
    V = mu/(2 r^3) (3 r_hat . I r_hat - tr I), MacCullagh)."""
    rng = np.random.default_rng(5)
    body = att.RigidBody(_rotated(np.diag([2.0, 3.0, 4.5]), rng))
    gg = GravityGradient(MU, ConstantPosition([6.8e6, 1.0e6, -0.5e6]))
    state = att.AttitudeState(EPOCH, Rotation.random(random_state=rng), [3e-4, -2e-4, 1e-4])
    t = np.linspace(0.0, 4000.0, 41)
    eph = att.propagate(body, state, t, torques=[gg],
                        method="splitting")   # its step rule: 1e-10-class
    V = gg.potential(t, eph.dataset["quaternion"].values, body)
    E = eph.dataset["kinetic_energy"].values
    assert np.ptp(V) > 0.5 * E[0]                       # a real exchange of energy
    assert np.ptp(E + V) < 1e-10 * np.abs(V).max()


def test_gravity_gradient_circular_orbit_conserves_jacobi_integral():
    """In a circular orbit the field turns uniformly at n about the orbit normal h, so the
    Jacobi integral J = E_kin + V - n L . h is conserved (E_kin + V is not): checks the
    torque, the potential and the inclined KeplerOrbit together."""
    orbit = KeplerOrbit(MU, 7.0e6, 0.0, i=0.7, raan=0.3, argp=1.0, mean_anomaly=0.2)
    rng = np.random.default_rng(1)
    body = att.RigidBody(_rotated(np.diag([2.0, 3.0, 4.5]), rng))
    gg = GravityGradient(MU, orbit)
    state = att.AttitudeState(EPOCH, Rotation.random(random_state=rng), [1e-3, -2e-3, 1.5e-3])
    t = np.linspace(0.0, 2 * orbit.period, 101)
    eph = att.propagate(body, state, t, torques=[gg],
                        method="splitting")   # its step rule: 1e-10-class
    V = gg.potential(t, eph.dataset["quaternion"].values, body)
    E = eph.dataset["kinetic_energy"].values
    h = orbit.specific_angular_momentum / np.linalg.norm(orbit.specific_angular_momentum)
    J = E + V - orbit.mean_motion * eph.dataset["angular_momentum"].values @ h
    assert np.ptp(E + V) > 0.1 * np.abs(V).max()
    assert np.ptp(J) < 1e-10 * np.abs(V).max()


def test_gravity_gradient_pitch_libration_frequency():
    """Earth-pointing body in a circular orbit: small pitch librations at
    omega = sqrt(3 mu/r^3 (B - A)/C) (A radial, B along-track, C orbit normal)."""
    orbit = KeplerOrbit(MU, 7.0e6, 0.0)
    n = orbit.mean_motion
    A, B, C = 1.5, 2.0, 3.0
    body = att.RigidBody.from_principal_moments([A, B, C])
    theta0 = 1e-3
    state = att.AttitudeState(EPOCH, Rotation.from_rotvec([0.0, 0.0, theta0]), [0.0, 0.0, n])
    omega = np.sqrt(3 * MU / orbit.a**3 * (B - A) / C)
    period = 2 * np.pi / omega
    t = np.linspace(0.0, 1.3 * period, 400)
    eph = att.propagate(body, state, t, torques=[GravityGradient(MU, orbit)],
                        method="integrator")
    x_body = Rotation.from_quat(eph.dataset["quaternion"].values).apply([1.0, 0.0, 0.0])
    r_hat = orbit.position(t) / orbit.a
    pitch = np.arctan2(np.cross(r_hat, x_body)[:, 2], np.sum(r_hat * x_body, axis=1))
    assert np.abs(pitch).max() == pytest.approx(theta0, rel=1e-4)
    crossings = CubicSpline(t, pitch).roots(extrapolate=False)   # at T/4 and 3T/4
    measured = 2 * (crossings[1] - crossings[0])
    assert measured == pytest.approx(period, rel=1e-6)


def test_gravity_gradient_with_tabulated_path_matches_kepler():
    orbit = KeplerOrbit(MU, 7.0e6, 0.1)
    ts = np.linspace(0, 2000.0, 400)
    path = TabulatedPath(ts, orbit.position(ts))
    body = att.RigidBody.from_principal_moments([1.0, 2.0, 2.5])
    q = Rotation.random(5, random_state=1).as_quat()
    t = np.linspace(100, 1900, 5)
    np.testing.assert_allclose(GravityGradient(MU, path)(t, q, np.zeros((5, 3)), body),
                               GravityGradient(MU, orbit)(t, q, np.zeros((5, 3)), body),
                               rtol=1e-7)
    with pytest.raises(TorqueConfigError, match="^mu: give the gravitational parameter"):
        GravityGradient(orbit=path)


# --- constant torque --------------------------------------------------------------------


def test_constant_torque_frames():
    rng = np.random.default_rng(2)
    R = Rotation.random(8, random_state=rng)
    body = att.RigidBody.from_principal_moments([1.0, 2.0, 3.0])
    T = np.array([0.3, -0.2, 0.1])
    Mb = ConstantTorque(T)(0.0, R, np.zeros((8, 3)), body)
    np.testing.assert_array_equal(Mb, np.tile(T, (8, 1)))
    Mi = ConstantTorque(T * u.N * u.m, frame="inertial")(0.0, R, np.zeros((8, 3)), body)
    np.testing.assert_allclose(R.apply(Mi), np.tile(T, (8, 1)), atol=1e-15)
    with pytest.raises(TorqueConfigError, match="^frame: unknown frame 'inertal'; did you "
                                                "mean 'inertial'"):
        ConstantTorque(T, frame="inertal")


def test_constant_inertial_torque_grows_angular_momentum_linearly():
    """dL_inertial/dt = M exactly, for any body and attitude motion: the splitting keeps
    it to round-off (its kicks add M h in the inertial frame; the free flows keep L), so
    the test is of the model's frame, whatever method the automatic choice would take."""
    body = att.RigidBody(_rotated(np.diag([1.0, 2.0, 2.6]), np.random.default_rng(4)))
    M = np.array([1e-3, -2e-3, 5e-4])
    state = att.AttitudeState(EPOCH, Rotation.from_rotvec([0.3, 0.2, 0.1]), [0.1, 0.2, -0.1])
    t = np.linspace(0.0, 100.0, 11)
    eph = att.propagate(body, state, t, torques=[ConstantTorque(M, "inertial")],
                        method="splitting")
    L = eph.dataset["angular_momentum"].values
    np.testing.assert_allclose(L, L[0] + t[:, None] * M, rtol=0, atol=1e-11)


# --- energy dissipation -----------------------------------------------------------------


def test_dissipation_keeps_L_and_removes_energy_pointwise():
    rng = np.random.default_rng(9)
    d = EnergyDissipation("2 min")
    assert d.time_constant == 120.0
    for _ in range(20):
        body = att.RigidBody(_rotated(np.diag(np.sort(rng.uniform(1, 2, 3))), rng))
        w = rng.normal(size=3)
        M = d(0.0, [0, 0, 0, 1], w, body)
        L = body.inertia @ w
        assert abs(L @ M) <= 1e-15 * np.linalg.norm(L) * np.linalg.norm(M)
        assert w @ M < 0
    # principal-axis spin: nothing to dissipate; spherical body: no torque
    body = att.RigidBody.from_principal_moments([1.0, 2.0, 3.0])
    np.testing.assert_allclose(d(0.0, [0, 0, 0, 1], [0.0, 0.0, 2.0], body), 0.0, atol=1e-16)
    sphere = att.RigidBody.from_principal_moments([2.0, 2.0, 2.0])
    np.testing.assert_array_equal(d(0.0, [0, 0, 0, 1], [1.0, 2.0, 3.0], sphere), 0.0)


def test_dissipation_coefficient():
    d = EnergyDissipation(10.0)
    A, B, C = 1.0, 1.5, 2.0
    assert d.coefficient(att.RigidBody.from_principal_moments([A, B, C])) == pytest.approx(
        C / (10.0 * ((C - A) / A + (C - B) / B)))
    # prolate (B = C) and oblate (A = B): 1/tau = 2 k (C - A) / (A C)
    for moments in ([1.0, 5.0, 5.0], [2.0, 2.0, 3.0]):
        A, _, C = sorted(moments)
        k = d.coefficient(att.RigidBody.from_principal_moments(moments))
        assert 2 * k * (C - A) / (A * C) == pytest.approx(1 / 10.0)
    assert d.coefficient(att.RigidBody.from_principal_moments([1.0, 1.0, 1.0])) == 0.0


def _energy_excess(eph, moments):
    w = eph.dataset["angular_velocity"].values
    L = np.linalg.norm(w * moments, axis=1)
    E = eph.dataset["kinetic_energy"].values
    return L, E, E - L**2 / (2 * moments.max())


def test_dissipation_long_axis_spinner_becomes_flat_spinner():
    """Explorer 1 in miniature (triaxial, so that the nutation near the end is fast
    compared with tau): |L| kept to 1e-10, E decreasing monotonically, final spin about
    the major axis with the same |L|, and the excess energy e-folds in tau."""
    moments = np.array([1.0, 1.5, 2.0])
    body = att.RigidBody.from_principal_moments(moments)
    tau = 30.0
    w0 = np.array([1.0, 0.05, 0.05])                    # spin about the long axis A
    state = att.AttitudeState(EPOCH, Rotation.identity(), w0)
    t = np.linspace(0.0, 500.0, 2001)
    eph = att.propagate(body, state, t, torques=[EnergyDissipation(tau)], rtol=1e-12)
    L, E, excess = _energy_excess(eph, moments)
    assert np.abs(L / L[0] - 1).max() < 1e-10
    assert np.all(np.diff(E) <= 1e-13 * E[0])
    assert excess[0] / E[0] > 0.49 and excess[-1] / E[-1] < 1e-5
    w_end = eph.dataset["angular_velocity"].values[-1]
    assert abs(w_end[2]) == pytest.approx(L[0] / moments[2], rel=1e-5)   # |ω| = |L| / C
    assert np.degrees(np.arccos(abs(w_end[2]) / np.linalg.norm(w_end))) < 0.5
    # e-folding of the excess energy near the end state
    near = (excess / E > 1e-6) & (excess / E < 1e-3)
    slope = np.polyfit(t[near], np.log(excess[near]), 1)[0]
    assert -1 / slope == pytest.approx(tau, rel=0.01)
    # internal dissipation: the inertial L (the pole) does not move; DOP853 holds it to
    # its tolerance (rtol 1e-12 per step: ~1e-11 over the run's ~1e4 steps)
    Li = eph.dataset["angular_momentum"].values
    assert np.abs(Li - Li[0]).max() < 1e-10 * np.linalg.norm(Li[0])


def test_dissipation_prolate_explorer_1_end_state():
    """Explorer 1's moments ratio C/A ~ 5 (prolate, validation/README.md): the flat spin
    rate is |ω0| A / C and the excess energy decays exactly as exp(-t/tau) near the end."""
    moments = np.array([1.0, 5.0, 5.0])
    body = att.RigidBody.from_principal_moments(moments)
    tau = 10.0
    # start close to the final flat spin: linear regime from the start
    w0 = np.array([0.02, 0.0, 0.2])
    state = att.AttitudeState(EPOCH, Rotation.identity(), w0)
    t = np.linspace(0.0, 60.0, 61)
    eph = att.propagate(body, state, t, torques=[EnergyDissipation(tau)])
    L, E, excess = _energy_excess(eph, moments)
    assert np.abs(L / L[0] - 1).max() < 1e-12
    slope = np.polyfit(t[20:], np.log(excess[20:]), 1)[0]
    assert -1 / slope == pytest.approx(tau, rel=2e-3)
    w_end = eph.dataset["angular_velocity"].values[-1]
    assert np.linalg.norm(w_end) == pytest.approx(L[0] / 5.0, rel=1e-3)


def _inertial_L(q, w, moments):
    return Rotation.from_quat(q).apply(w * moments)


@pytest.fixture(scope="module")
def relaxation():
    """A long-axis spinner relaxing to a flat spin (LAM -> separatrix -> SAM -> PA-short)
    under internal dissipation, with the default splitting step, and DOP853 (rtol 1e-12)."""
    moments = np.array([1.0, 1.5, 2.0])
    body = att.RigidBody.from_principal_moments(moments)
    q0 = Rotation.from_rotvec([0.3, 0.2, 0.1]).as_quat()
    w0 = np.array([1.0, 0.05, 0.05])
    t = np.linspace(0.0, 120.0, 481)
    damper = EnergyDissipation(10.0)
    q, w = integrate_splitting(body, q0, w0, t, torques=[damper])
    qr, wr = integrate_reference(body, q0, w0, t, torques=[damper], rtol=1e-12)
    return moments, body, t, (q, w), (qr, wr)


def test_internal_dissipation_keeps_the_inertial_L_exactly(relaxation):
    """Issue 14.4: the splitting kick restores the inertial L at every step (round-off
    only, no drift), E never increases (to a few ulps of E), the end state is a spin
    about C; DOP853 agrees (its tolerance) and keeps L to its own tolerance."""
    moments, body, t, (q, w), (qr, wr) = relaxation
    Lin = _inertial_L(q, w, moments)
    L0 = np.linalg.norm(Lin[0])
    assert np.abs(Lin - Lin[0]).max() < 1e-12 * L0
    E = 0.5 * np.sum(moments * w * w, axis=1)
    assert np.all(np.diff(E) <= 8 * np.finfo(float).eps * E[0])
    assert E[0] - E[-1] > 0.4 * E[0]                                   # it did relax
    assert abs(w[-1, 2]) == pytest.approx(L0 / moments[2], rel=1e-3)   # |w| ~ |L| / C
    L_end = w[-1] * moments                 # L within 0.05 rad of C (and closing: the
    assert np.arctan2(np.hypot(L_end[0], L_end[1]), abs(L_end[2])) < 0.05   # sequence
    # LAM -> ... -> PA-short is classified in tests/analysis/test_classification.py)
    Lr = _inertial_L(qr, wr, moments)
    assert np.abs(Lr - Lr[0]).max() < 1e-10 * L0
    # both methods solve the same equations: attitude and rates agree
    dq = (Rotation.from_quat(q).inv() * Rotation.from_quat(qr)).magnitude()
    assert dq.max() < 1e-8 and np.abs(w - wr).max() < 1e-8 * np.linalg.norm(w[0])


@pytest.mark.slow      # a long study (> 9 s); the slow tier, which CI runs
def test_internal_kick_in_a_rotated_body_frame_batch_and_with_an_external_torque():
    """Body axes not principal, one-body (plain floats) and batch (arrays) paths, alone
    and with gravity gradient: against DOP853 (rtol 1e-13); the inertial L is kept when
    the dissipation is alone and moves by the gravity gradient's torque otherwise."""
    R = Rotation.from_rotvec([0.4, -0.3, 0.7]).as_matrix()
    body = att.RigidBody(R @ np.diag([1.0, 1.5, 2.0]) @ R.T)
    q0 = Rotation.from_rotvec([0.1, 0.2, 0.3]).as_quat()
    w0 = np.array([0.6, -0.5, 0.4])
    t = np.linspace(0.0, 15.0, 4)
    gg = GravityGradient(MU, KeplerOrbit(MU, 7.0e6, 0.1))
    for torques in ([EnergyDissipation(10.0)], [EnergyDissipation(10.0), gg]):
        q, w = integrate_splitting(body, q0, w0, t, torques=torques)
        qr, wr = integrate_reference(body, q0, w0, t, torques=torques, rtol=1e-13)
        assert (Rotation.from_quat(q).inv() * Rotation.from_quat(qr)).magnitude().max() < 1e-9
        np.testing.assert_allclose(w, wr, rtol=0, atol=1e-9 * np.linalg.norm(w0))
        qb, wb = integrate_splitting([body, body], np.array([q0, q0]), np.array([w0, w0]), t,
                                     torques=torques)
        assert (Rotation.from_quat(qb[1]).inv() * Rotation.from_quat(q)).magnitude().max() \
            < 1e-11
        np.testing.assert_allclose(wb[0], w, rtol=0, atol=1e-11 * np.linalg.norm(w0))
        L = Rotation.from_quat(q).apply(w @ body.inertia.T)
        drift = np.abs(L - L[0]).max() / np.linalg.norm(L[0])
        assert drift < 1e-14 if len(torques) == 1 else drift > 1e-6


def test_an_external_torque_of_the_same_form_moves_the_pole():
    """The same torque applied as an external one (internal=False) keeps |L| and the
    body-frame motion but turns the inertial L by per cents: what internal=True fixes."""
    moments = np.array([1.0, 1.5, 2.0])
    body = att.RigidBody.from_principal_moments(moments)
    q0, w0 = [0.0, 0.0, 0.0, 1.0], np.array([1.0, 0.05, 0.05])
    t = np.linspace(0.0, 120.0, 121)
    damper = EnergyDissipation(10.0)
    external = as_torque_model(lambda *a: damper(*a), internal=False)
    qi, wi = integrate_reference(body, q0, w0, t, torques=[damper], rtol=1e-10)
    qe, we = integrate_reference(body, q0, w0, t, torques=[external], rtol=1e-10)
    np.testing.assert_allclose(we, wi, rtol=0, atol=1e-7)                # same body motion
    Le = _inertial_L(qe, we, moments)
    turned = np.degrees(np.arccos(np.clip(Le @ Le[0] / np.sum(Le[0] ** 2), -1, 1)))
    assert turned.max() > 0.5
    Li = _inertial_L(qi, wi, moments)
    assert np.abs(Li - Li[0]).max() < 1e-8 * np.linalg.norm(Li[0])


def test_internal_dissipation_e_folding_time_prolate_splitting():
    """Prolate body (B = C), near the flat spin: the excess energy decays exactly as
    exp(-t / tau) (class notes), and the nutation angle as exp(-t / 2 tau); default
    splitting step."""
    moments = np.array([1.0, 5.0, 5.0])
    body = att.RigidBody.from_principal_moments(moments)
    tau = 10.0
    t = np.linspace(0.0, 60.0, 61)
    q, w = integrate_splitting(body, [0, 0, 0, 1], [0.02, 0.0, 0.2], t,
                               torques=[EnergyDissipation(tau)])
    L = w * moments
    E = 0.5 * np.sum(moments * w * w, axis=1)
    excess = E - np.sum(L * L, axis=1) / (2 * moments[2])
    slope = np.polyfit(t[10:], np.log(excess[10:]), 1)[0]
    assert -1 / slope == pytest.approx(tau, rel=2e-3)
    theta = np.arctan2(np.abs(L[:, 0]), np.hypot(L[:, 1], L[:, 2]))
    slope = np.polyfit(t[10:], np.log(theta[10:]), 1)[0]
    assert -1 / slope == pytest.approx(2 * tau, rel=2e-3)
    Lin = _inertial_L(q, w, moments)
    assert np.abs(Lin - Lin[0]).max() < 1e-12 * np.linalg.norm(Lin[0])


def test_internal_rate_keeps_inertial_L():
    """(M x L)/L^2 x L = -M for M normal to L: the attitude rate cancels the body-frame
    turn of L."""
    rng = np.random.default_rng(3)
    body = att.RigidBody(_rotated(np.diag([1.0, 1.4, 2.1]), rng))
    d = EnergyDissipation(5.0)
    for _ in range(10):
        w = rng.normal(size=3)
        M = d(0.0, [0, 0, 0, 1], w, body)
        L = body.inertia @ w
        extra = att.torques.internal_rate(M, w, body)
        np.testing.assert_allclose(np.cross(extra, L), -M, rtol=0,
                                   atol=1e-14 * np.linalg.norm(M) + 1e-300)
    np.testing.assert_array_equal(att.torques.internal_rate(np.zeros(3), np.zeros(3), body),
                                  0.0)


# --- damping time scale of a tumbling asteroid ----------------------------------------


def test_damping_timescale_formula_and_units():
    """tau = mu Q / (rho K3^2 R^2 w^3) (Harris 1994): written out in SI here."""
    D, rho, P, muq = 340.0, 2500.0, 30.56 * 3600.0, 5e11
    w = 2 * np.pi / P
    expected = muq / (rho * 0.1 * (D / 2) ** 2 * w**3)
    tau = damping_timescale("0.34 km", "2.5 g/cm3", period="30.56 h")
    assert tau.to_value(u.s) == pytest.approx(expected, rel=1e-12)
    # the same with plain SI numbers and with the spin rate
    assert damping_timescale(D, rho, spin_rate=w, rigidity_q=muq).to_value(u.s) == \
        pytest.approx(expected, rel=1e-12)
    # scaling: tau ~ D^-2 P^3 / rho, proportional to mu Q / K3^2
    base = damping_timescale(D, rho, period=P).to_value(u.s)

    def ratio(**kw):
        args = {"diameter": D, "density": rho, "period": P} | kw
        return damping_timescale(**args).to_value(u.s) / base

    assert ratio(diameter=2 * D) == pytest.approx(0.25)
    assert ratio(period=2 * P) == pytest.approx(8.0)
    assert ratio(density=2 * rho) == pytest.approx(0.5)
    assert ratio(k3_squared=0.01) == pytest.approx(10.0)
    assert 5 < (base * u.s).to_value(u.Gyr) < 50          # Apophis: far beyond 4.5 Gyr


@pytest.mark.parametrize("kwargs, match", [
    ({"period": "30 h", "spin_rate": "1e-4 rad/s"}, "^period: give exactly one"),
    ({}, "^period: give exactly one"),
    ({"period": "-3 h"}, "^period: must be positive"),
    ({"period": "3 kg"}, "^period: unit 'kg' cannot be converted"),
    ({"period": "3 h", "rigidity_q": 0.0}, "^rigidity_q: must be positive"),
])
def test_damping_timescale_bad_input(kwargs, match):
    with pytest.raises(TorqueConfigError, match=match):
        damping_timescale("0.34 km", "2.5 g/cm3", **kwargs)


# --- eddy currents -----------------------------------------------------------------------


def test_eddy_current_is_dissipative():
    rng = np.random.default_rng(13)
    for _ in range(50):
        X = rng.normal(size=(3, 3))
        tensor = X @ X.T                                    # symmetric positive semi-definite
        B = rng.normal(size=3) * 3e-5
        model = EddyCurrentDamping(tensor, B)
        q = Rotation.random(random_state=rng).as_quat()
        w = rng.normal(size=3)
        M = model(rng.uniform(0, 1e4), q, w, None)
        assert w @ M <= 1e-30
    with pytest.raises(TorqueConfigError, match="^magnetic_tensor: must be positive"):
        EddyCurrentDamping(np.diag([1.0, -1.0, 1.0]), B)
    with pytest.raises(TorqueConfigError, match="^magnetic_tensor: must be symmetric"):
        EddyCurrentDamping([[1.0, 0.5, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]], B)


def test_eddy_current_sphere_in_uniform_field_closed_form():
    """Sphere (moment I) in a uniform field B with isotropic tensor m: ω_parallel fixed,
    ω_perp (inertial) decays as exp(-m B^2 t / I) without turning."""
    I = 2.0
    body = att.RigidBody.from_principal_moments([I, I, I])
    B = np.array([1e-5, -2e-5, 2.5e-5])
    tau = 100.0
    m = I / (tau * B @ B)
    model = EddyCurrentDamping(m * u.Unit("S m4"), UniformField(B * u.T))
    w0 = np.array([0.3, 0.1, -0.2])
    state = att.AttitudeState(EPOCH, Rotation.from_rotvec([0.2, -0.4, 1.0]), w0)
    t = np.linspace(0.0, 300.0, 31)
    eph = att.propagate(body, state, t, torques=[model],
                        method="splitting")   # its step rule: 1e-10-class
    w_in = eph.dataset["angular_momentum"].values / I
    b = B / np.linalg.norm(B)
    w0_in = state.attitude.apply(w0)
    par = w0_in @ b * b
    expected = par + (w0_in - par) * np.exp(-t / tau)[:, None]
    # the default splitting step: for a sphere the inertial torque is fixed along the free
    # rotation, so the step follows tau (2 s here) and the error is that of RK4 on the
    # exponential, ~(h / tau)^5 / 120 per step: within the rule's ~1e-10 relative target
    np.testing.assert_allclose(w_in, expected, rtol=0, atol=1e-10 * np.linalg.norm(w0))


def test_eddy_current_tensor_constructors():
    field = [0.0, 0.0, 3e-5]
    shell = EddyCurrentDamping.spherical_shell("1.5 m", "3 mm", "3.5e7 S/m", field)
    assert shell.magnetic_tensor == pytest.approx(2 * np.pi / 3 * 3.5e7 * 1.5**4 * 3e-3)
    solid = EddyCurrentDamping.solid_sphere(0.5, 3.5e7, field)
    assert solid.magnetic_tensor == pytest.approx(2 * np.pi / 15 * 3.5e7 * 0.5**5)
    # a thin shell is the radial derivative of the solid-sphere tensor times the thickness
    dR = 1e-6
    d_solid = (EddyCurrentDamping.solid_sphere(1.5 + dR, 3.5e7, field).magnetic_tensor
               - EddyCurrentDamping.solid_sphere(1.5 - dR, 3.5e7, field).magnetic_tensor)
    assert d_solid / (2 * dR) * 3e-3 == pytest.approx(shell.magnetic_tensor, rel=1e-7)


def test_tilted_dipole_field():
    R = 6371.2e3
    B0 = 1e-7 * 7.94e22 / R**3
    assert B0 == pytest.approx(3.07e-5, rel=2e-3)
    # untilted: north along the equator, 2 B0 pointing down at the north pole
    for position, expected in (([R, 0, 0], [0, 0, B0]), ([0, -R, 0], [0, 0, B0]),
                               ([0, 0, R], [0, 0, -2 * B0]), ([0, 0, -R], [0, 0, -2 * B0])):
        field = TiltedDipoleField(position, tilt=0.0)
        np.testing.assert_allclose(field(123.0), expected, atol=1e-12 * B0)
    # tilted: at the northern geomagnetic pole the field points straight down, 2 B0; the
    # pole turns with the Earth (rotation angle 0.3 rad at t = 0, rate omega_E)
    tilt, lon, theta0 = np.radians(9.4), np.radians(-72.7), 0.3
    t = 5000.0
    ang = theta0 + 7.292115e-5 * t + lon
    pole = R * np.array([np.sin(tilt) * np.cos(ang), np.sin(tilt) * np.sin(ang), np.cos(tilt)])
    field = TiltedDipoleField(pole, rotation_angle=theta0)
    np.testing.assert_allclose(field(t), -2 * B0 * pole / R, atol=1e-12 * B0)
    # along an orbit: vectorised, 1/r^3, B0..2 B0 on a sphere of radius r
    orbit = KeplerOrbit(MU, 7.0e6, 0.0, i=np.radians(98.0))
    field = TiltedDipoleField(orbit)
    ts = np.linspace(0.0, orbit.period, 500)
    Bn = np.linalg.norm(field(ts), axis=-1)
    scale = 1e-7 * 7.94e22 / 7.0e6**3
    assert Bn.min() >= scale * (1 - 1e-12) and Bn.max() <= 2 * scale * (1 + 1e-12)
    assert Bn.max() > 1.9 * scale


def test_eddy_current_despin_in_orbit_is_monotonic():
    """A spinning shell along a polar orbit in the tilted dipole: dissipative at every point
    of the orbit, and the spin rate only decreases along a propagated arc."""
    orbit = KeplerOrbit(MU, 7.0e6, 0.0, i=np.radians(98.0))
    model = EddyCurrentDamping.spherical_shell(1.0, 2e-3, 3.5e7, TiltedDipoleField(orbit))
    body = att.RigidBody.from_principal_moments([3.0, 3.0, 3.0])
    rng = np.random.default_rng(17)
    t = np.linspace(0.0, orbit.period, 400)
    w = rng.normal(size=(400, 3))
    M = model(t, Rotation.random(400, random_state=rng), w, body)
    assert np.all(np.sum(w * M, axis=1) < 0)
    state = att.AttitudeState(EPOCH, Rotation.identity(), [0.0, 0.01, 0.02])
    t = np.linspace(0.0, 600.0, 13)
    E = att.propagate(body, state, t, torques=[model]).dataset["kinetic_energy"].values
    assert np.all(np.diff(E) < 0) and E[-1] < 0.999 * E[0]


# --- heavy top --------------------------------------------------------------------------

M_TOP, L_TOP, G = 1.0, 0.1, 9.80665
I1, I3 = 0.05, 0.02                                     # about the pivot


def _top_axis(eph):
    z = Rotation.from_quat(eph.dataset["quaternion"].values).apply([0.0, 0.0, 1.0])
    return np.arccos(z[:, 2]), np.unwrap(np.arctan2(z[:, 0], -z[:, 1]))


def test_heavy_top_steady_precession_exact():
    """Symmetric top in steady precession (Goldstein Sec. 5.7): with
    m g l = Omega (I3 w3 - I1 Omega cos theta) the axis stays at theta and precesses at
    Omega exactly; for a fast top Omega ~= m g l / (I3 w3)."""
    body = att.RigidBody.from_principal_moments([I1, I1, I3], mass=M_TOP)
    top = HeavyTopPivot(pivot_to_com=[0.0, 0.0, L_TOP])           # mass from the body
    mgl = M_TOP * G * L_TOP
    theta, w3 = np.radians(30.0), 60.0
    a, b = I1 * np.cos(theta), -I3 * w3
    Omega = (-b - np.sqrt(b * b - 4 * a * mgl)) / (2 * a)         # slow root
    assert mgl == pytest.approx(Omega * (I3 * w3 - I1 * Omega * np.cos(theta)), rel=1e-14)
    assert Omega == pytest.approx(mgl / (I3 * w3), rel=0.05)      # fast-top estimate
    # Euler ZXZ (phi, theta, psi = 0): ω_body = (0, Omega sin theta, w3)
    state = att.AttitudeState(EPOCH, Rotation.from_euler("ZXZ", [0.0, theta, 0.0]),
                              [0.0, Omega * np.sin(theta), w3])
    t = np.linspace(0.0, 1.0, 11)
    eph = att.propagate(body, state, t, torques=[top])
    th, phi = _top_axis(eph)
    np.testing.assert_allclose(th, theta, atol=1e-11)
    np.testing.assert_allclose(phi - phi[0], Omega * t, atol=1e-10)


def test_heavy_top_released_nutation_bounds_and_mean_precession():
    """Released from rest at theta0 with spin w3: the axis nods between u0 = cos theta0 and
    u1 = (a^2 - sqrt(a^4 - 4 beta a^2 u0 + 4 beta^2)) / (2 beta); over one nutation period
    (a quadrature of 1/sqrt(f(u))) it precesses at the quadrature mean of
    phi' = a (u0 - u)/(1 - u^2), close to m g l / (I3 w3) for a fast top."""
    body = att.RigidBody.from_principal_moments([I1, I1, I3])
    top = HeavyTopPivot(M_TOP, {"value": [0.0, 0.0, 10.0], "unit": "cm"})
    theta0, w3 = np.radians(30.0), 100.0
    a, beta, u0 = I3 * w3 / I1, 2 * M_TOP * G * L_TOP / I1, np.cos(theta0)
    u1 = (a**2 - np.sqrt(a**4 - 4 * beta * a**2 * u0 + 4 * beta**2)) / (2 * beta)

    def f(uu):                                         # u'^2 = f(u) (Goldstein Eq. 5.62)
        return (u0 - uu) * (beta * (1 - uu**2) - a**2 * (u0 - uu))

    half, _ = quad(lambda uu: 1 / np.sqrt(f(uu)), u1, u0, limit=200)
    dphi, _ = quad(lambda uu: a * (u0 - uu) / (1 - uu**2) / np.sqrt(f(uu)), u1, u0,
                   limit=200)
    period, mean_rate = 2 * half, dphi / half
    state = att.AttitudeState(EPOCH, Rotation.from_euler("ZXZ", [0.0, theta0, 0.0]),
                              [0.0, 0.0, w3])
    t = np.concatenate([np.linspace(0.0, period, 801), [2 * period]])
    eph = att.propagate(body, state, t, torques=[top])
    th, phi = _top_axis(eph)
    assert th[:-1].max() == pytest.approx(np.arccos(u1), abs=1e-6)   # lowest point
    assert th.min() == pytest.approx(theta0, abs=1e-9)              # highest point
    assert th[400] == pytest.approx(np.arccos(u1), abs=1e-6)        # reached at T/2
    assert (phi[-2] - phi[0]) / period == pytest.approx(mean_rate, rel=1e-7)
    assert (phi[-1] - phi[0]) / (2 * period) == pytest.approx(mean_rate, rel=1e-7)
    assert mean_rate == pytest.approx(M_TOP * G * L_TOP / (I3 * w3), rel=0.02)


def test_heavy_top_needs_a_mass():
    body = att.RigidBody.from_principal_moments([I1, I1, I3])
    with pytest.raises(TorqueConfigError, match="^mass: the body has no mass"):
        HeavyTopPivot(pivot_to_com=[0, 0, 0.1])(0.0, [0, 0, 0, 1], [0, 0, 1.0], body)
    with pytest.raises(TorqueConfigError, match="^up: must be a non-zero vector"):
        HeavyTopPivot(1.0, [0, 0, 0.1], up=[0, 0, 0])


# --- scenario tables -------------------------------------------------------------------


def test_from_config_gravity_gradient():
    gg = from_config({"type": "gravity_gradient", "mu": "3.986004418e14 m3/s2",
                      "orbit": {"a": "7000 km", "e": 0.0, "i": "0 deg", "raan": "0 deg",
                                "argp": "0 deg", "mean_anomaly": "0 deg"}})
    assert isinstance(gg, GravityGradient) and gg.mu == MU
    assert gg.orbit == KeplerOrbit(MU, 7.0e6, 0.0)
    gg = from_config({"type": "gravity_gradient", "mu": {"value": 398600.4418,
                                                         "unit": "km3/s2"},
                      "orbit": {"a": 7.0e6, "e": 0.1, "i": 0.5}})
    assert gg.mu == pytest.approx(MU) and gg.orbit.i == 0.5 and gg.orbit.e == 0.1


def test_from_config_orbit_epoch_shifts_mean_anomaly():
    base = Time("2030-01-01T01:00:00", scale="tdb")
    gg = from_config({"type": "gravity_gradient", "mu": MU,
                      "orbit": {"a": "7000 km", "mean_anomaly": "10 deg",
                                "epoch": "2030-01-01T00:00:00"}}, base_epoch=base)
    n = np.sqrt(MU / 7.0e6**3)
    assert gg.orbit.mean_anomaly == pytest.approx(np.radians(10.0) + n * 3600.0, rel=1e-12)
    with pytest.raises(TorqueConfigError, match="^orbit.epoch: an orbit epoch needs"):
        from_config({"type": "gravity_gradient", "mu": MU,
                     "orbit": {"a": 7e6, "epoch": "2030-01-01T00:00:00"}})


def test_from_config_other_types():
    c = from_config({"type": "constant", "torque": {"value": [0, 0, 1e-6], "unit": "N m"},
                     "frame": "inertial"})
    assert isinstance(c, ConstantTorque) and c.frame == "inertial"
    np.testing.assert_array_equal(c.torque, [0, 0, 1e-6])
    assert from_config({"type": "constant", "torque": [1, 2, 3]}).frame == "body"
    d = from_config({"type": "dissipation", "time_constant": "30 min"})
    assert isinstance(d, EnergyDissipation) and d.time_constant == 1800.0
    e = from_config({"type": "eddy_current",
                     "shell": {"radius": "1.5 m", "thickness": "3 mm",
                               "conductivity": "3.5e7 S/m"},
                     "field": {"model": "dipole", "tilt": "11 deg"},
                     "orbit": {"a": "7000 km", "i": "98 deg"}},
                    base_epoch=Time("2000-01-01T12:00:00", scale="utc"))
    assert isinstance(e, EddyCurrentDamping) and isinstance(e.field, TiltedDipoleField)
    assert e.field.tilt == pytest.approx(np.radians(11.0))
    assert e.field.orbit.mu == MU
    # ERA (IAU 2000; IERS Conventions 2010, eq. 5.15) at UT1 = UTC + 0.355 s (astropy's
    # IERS table for 2000-01-01T12:00 UTC), no longer with UT1 taken as UTC
    d_u = 0.355 / 86400.0
    era = 2.0 * np.pi * (0.7790572732640 + 1.00273781191135448 * d_u)
    assert e.field.rotation_angle == pytest.approx(era, abs=1e-7)
    e = from_config({"type": "eddy_current", "magnetic_tensor": {
        "value": np.diag([1, 2, 3]).tolist(), "unit": "S m4"},
        "field": {"model": "uniform", "vector": {"value": [0, 0, 30000], "unit": "nT"}}})
    np.testing.assert_allclose(e.field(0.0), [0, 0, 3e-5])
    assert from_config({"type": "eddy_current", "sphere": {"radius": 1, "conductivity": 1},
                        "field": {"model": "uniform", "vector": [0, 0, 1e-5]}}
                       ).magnetic_tensor == pytest.approx(2 * np.pi / 15)
    h = from_config({"type": "heavy_top", "mass": "500 g",
                     "pivot_to_com": {"value": [0, 0, 4], "unit": "cm"}, "up": [0, 0, 2]})
    assert isinstance(h, HeavyTopPivot) and h.mass == 0.5
    np.testing.assert_allclose(h.pivot_to_com, [0, 0, 0.04])
    np.testing.assert_array_equal(h.up, [0, 0, 1])


@pytest.mark.parametrize("table, match", [
    ({"type": "gravity_gradient", "mu": MU, "orbit": {"a": 7e6, "e": 1.2}},
     r"^orbit\.e: must be in \[0, 1\), got 1\.2"),
    ({"type": "gravity_gradient", "mu": MU, "orbit": {"a": "-7000 km"}},
     r"^orbit\.a: must be positive"),
    ({"type": "gravity_gradient", "mu": MU, "orbit": {"a": "7000 kg"}},
     r"^orbit\.a: unit 'kg' cannot be converted to 'm'"),
    ({"type": "gravity_gradient", "mu": MU, "orbit": {"a": 7e6, "eccentricity": 0.1}},
     r"^orbit\.eccentricity: unknown key; did you mean 'e'\?"),
    ({"type": "gravity_gradient", "mu": MU, "orbit": {"a": 7e6, "raaan": 0.1}},
     r"^orbit\.raaan: unknown key; did you mean 'raan'\?"),
    ({"type": "gravity_gradient", "mu": MU, "orbit": {"e": 0.1}},
     r"^orbit: give exactly one of a, tle"),
    ({"type": "gravity_gradient", "orbit": {"a": 7e6}}, r"^mu: missing"),
    ({"type": "gravity_gradient", "mu": "3.9e14 km", "orbit": {"a": 7e6}},
     r"^mu: unit 'km' cannot be converted"),
    ({"type": "gravity_gradient", "mu": "lots", "orbit": {"a": 7e6}},
     r"^mu: cannot parse 'lots'"),
    ({"type": "gravity_gradient", "mu": MU, "orbit": "LEO"}, r"^orbit: expected a table"),
    ({"type": "gravity_gradient", "mu": MU, "orbit": {"a": 7e6}, "orbt": {}},
     r"^orbt: unknown key; did you mean 'orbit'\?"),
    ({"type": "gravity_gradiant", "mu": MU}, r"^type: unknown torque type 'gravity_gradiant';"
                                             r" did you mean 'gravity_gradient'\?"),
    ({"mu": MU}, r"^type: missing; choose one of gravity_gradient, constant"),
    ({"type": "constant", "torque": [0, 1]},
     r"^torque: expected 3 numbers \(shape \(3,\)\) in N m, got 2 numbers"),
    ({"type": "constant", "torque": {"value": [0, 0, 1]}},
     r"^torque: a quantity table needs both 'value' and 'unit'"),
    ({"type": "constant", "torque": [0, 0, 1], "frame": "bdy"},
     r"^frame: unknown frame 'bdy'; did you mean 'body'\?"),
    ({"type": "dissipation", "time_constant": "-5 min"}, r"^time_constant: must be positive"),
    ({"type": "dissipation", "tau": "5 min"},
     r"^tau: unknown key; did you mean 'time_constant'\?"),
    ({"type": "dissipation", "time_constant": True}, r"^time_constant: expected a quantity"),
    ({"type": "eddy_current", "magnetic_tensor": 1.0, "sphere": {"radius": 1.0},
      "field": {"model": "uniform", "vector": [0, 0, 1e-5]}}, r"^sphere: give exactly one of"),
    ({"type": "eddy_current", "magnetic_tensor": 1.0, "field": {"model": "dipol"},
      "orbit": {"a": 7e6}}, r"^field\.model: unknown model 'dipol'; did you mean"),
    ({"type": "eddy_current", "magnetic_tensor": 1.0, "field": {"model": "dipole"}},
     r"^orbit: missing"),
    ({"type": "eddy_current", "magnetic_tensor": 1.0, "orbit": {"a": 7e6},
      "field": {"tilt": "9 m"}}, r"^field\.tilt: unit 'm' cannot be converted"),
    ({"type": "eddy_current", "magnetic_tensor": 1.0, "orbit": {"a": 7e6},
      "field": {"moment": "-1 A m2"}}, r"^field\.moment: must be positive"),
    ({"type": "eddy_current", "shell": {"radius": 1.0, "conductivity": 1.0},
      "field": {"model": "uniform", "vector": [0, 0, 1e-5]}}, r"^shell\.thickness: missing"),
    ({"type": "eddy_current", "shell": {"radius": 1.0, "thickness": "-1 mm",
                                        "conductivity": 1.0},
      "field": {"model": "uniform", "vector": [0, 0, 1e-5]}},
     r"^shell\.thickness: must be positive"),
    ({"type": "eddy_current", "magnetic_tensor": [[1, 0], [0, 1]],
      "field": {"model": "uniform", "vector": [0, 0, 1e-5]}},
     r"^magnetic_tensor: expected a single number \(shape \(\)\) or 3x3 numbers"),
    ({"type": "eddy_current", "magnetic_tensor": 1.0, "orbit": {"a": 7e6},
      "field": {"model": "uniform", "vector": [0, 0, 1e-5]}}, r"^orbit: not used"),
    ({"type": "eddy_current", "magnetic_tensor": 1.0, "field": {"model": "uniform"}},
     r"^field\.vector: missing"),
    ({"type": "heavy_top", "mass": 1.0}, r"^pivot_to_com: missing"),
    ({"type": "heavy_top", "pivot_to_com": [0, 0, 1], "l": 1.0},
     r"^l: unknown key; did you mean 'pivot_to_com'\?"),
    ({"type": "heavy_top", "pivot_to_com": [0, 0, 1], "g": "9.8 m/s"},
     r"^g: unit 'm / s' cannot be converted"),
])
def test_from_config_errors(table, match):
    with pytest.raises(TorqueConfigError, match=match) as info:
        from_config(table)
    err = info.value
    assert isinstance(err, ValueError) and isinstance(err, att.AttitudeError)
    assert str(err).startswith(f"{err.key}: ")


def test_torque_model_subclass_protocol():
    """A user model derived from TorqueModel: implement evaluate, get broadcasting and +."""

    class Drag(TorqueModel):
        velocity_dependent = True

        def evaluate(self, t, quaternion, omega_body, body):
            return -0.1 * omega_body

    body = att.RigidBody.from_principal_moments([1.0, 1.0, 1.0])
    model = Drag() + ConstantTorque([0.0, 0.0, 0.1])
    assert model(np.zeros(4), np.tile([0, 0, 0, 1.0], (4, 1)), np.ones((4, 3)),
                 body).shape == (4, 3)
    # terminal spin rate where drag balances the constant torque: ω_z -> 1 rad/s
    state = att.AttitudeState(EPOCH, Rotation.identity(), [0.0, 0.0, 0.0 + 1e-9])
    eph = att.propagate(body, state, [0.0, 50.0], torques=[model])
    w = eph.dataset["angular_velocity"].values[-1]
    assert w[2] == pytest.approx(1 - np.exp(-0.1 * 50.0), rel=1e-9)


def test_gravity_gradient_roll_yaw_libration_matches_linear_theory():
    """Earth-pointing satellite in the Lagrange region (pitch moment largest, yaw moment
    smallest) on a circular orbit, nudged in roll and yaw rate: roll and yaw are the sum
    of the two linear modes s^4 + (1 + 3 k1 + k1 k3) n^2 s^2 + 4 k1 k3 n^4 = 0,
    k1 = (I2 - I3)/I1, k3 = (I2 - I1)/I3 (Hughes, Spacecraft Attitude Dynamics, ch. 9).
    With I = (80, 100, 20) the modes are exactly n and 2n.  A least-squares fit on those
    two frequencies leaves < 1e-3 of the amplitude; frequencies 5 % off leave > 30 %."""
    I1, I2, I3 = 80.0, 100.0, 20.0          # body x = roll, y = pitch, z = yaw
    orbit = KeplerOrbit.from_elements(mu=3.986004418e14, a=7.0e6, e=0.0, i=0.0, raan=0.0,
                                      argp=0.0, mean_anomaly=0.0)
    n = orbit.mean_motion

    def orbit_frame(t):                     # x along track, y = -orbit normal, z nadir
        r, v = orbit.position(t), orbit.velocity(t)
        z = -r / np.linalg.norm(r, axis=-1, keepdims=True)
        h = np.cross(r, v)
        y = -h / np.linalg.norm(h, axis=-1, keepdims=True)
        return Rotation.from_matrix(np.stack([np.cross(y, z), y, z], axis=-1))

    body = att.RigidBody.from_principal_moments([I1, I2, I3])
    eps = 1e-3 * n
    state = att.AttitudeState("2030-01-01", orbit_frame(np.array([0.0]))[0], [eps, -n, eps])
    t = np.linspace(0.0, 15 * 2 * np.pi / n, 15 * 200 + 1)
    eph = att.propagate(body, state, t, torques=[GravityGradient(orbit=orbit)],
                        method="integrator", rtol=1e-11)
    roll, pitch, yaw = (orbit_frame(t).inv() * eph.rotation).as_rotvec().T
    k1, k3 = (I2 - I3) / I1, (I2 - I1) / I3
    w = n * np.sqrt(-np.roots([1.0, 1 + 3 * k1 + k1 * k3, 4 * k1 * k3]).real)
    np.testing.assert_allclose(np.sort(w / n), [1.0, 2.0], rtol=1e-12)

    def misfit(x, freqs):
        M = np.stack([f(fr * t) for fr in freqs for f in (np.cos, np.sin)], axis=1)
        coef = np.linalg.lstsq(M, x, rcond=None)[0]
        return np.max(np.abs(M @ coef - x)) / np.max(np.abs(x))

    for x in (roll, yaw):
        assert np.max(np.abs(x)) > 1e-4             # excited
        assert misfit(x, w) < 1e-3
        assert misfit(x, 1.05 * w) > 0.3
    assert np.max(np.abs(pitch)) < 1e-2 * np.max(np.abs(roll))   # pitch decoupled


#: Names the single module attitude.model.torques offered before it became a package (its
#: public names, and those other modules imported from it): each stays importable from
#: the package and from the public namespace attitude.torques.
SINGLE_MODULE_NAMES = [
    "BuildContext", "ConstantTorque", "EARTH_DIPOLE_MOMENT", "EARTH_DIPOLE_POLE_LONGITUDE",
    "EARTH_DIPOLE_TILT", "EARTH_MU", "EARTH_ROTATION_RATE", "EddyCurrentDamping",
    "EnergyDissipation", "FIELD_SOURCES", "FunctionTorque", "GravityGradient",
    "HeavyTopPivot", "KeplerOrbit", "Key", "MagneticDipole", "ORBIT_SOURCES", "ORBIT_TABLE",
    "OrbitError", "RigidBody", "STANDARD_GRAVITY", "SYMMETRY_RTOL", "SYNONYMS", "SumTorque",
    "TORQUE_TABLES", "TORQUE_TYPES", "Table", "TiltedDipoleField", "TorqueConfigError",
    "TorqueModel", "UniformField", "as_path", "as_torque_model", "damping_timescale",
    "from_config", "internal_rate", "json_schema", "register_torque_type", "to_si",
    "validate",
]


@pytest.mark.parametrize("namespace", ["attitude.model.torques", "attitude.torques"])
def test_the_torques_package_keeps_the_single_modules_names(namespace):
    import importlib

    from attitude.foundations import constants
    from attitude.model.torques import registry

    module = importlib.import_module(namespace)
    assert not [name for name in SINGLE_MODULE_NAMES if not hasattr(module, name)]
    assert module.EARTH_MU is constants.EARTH_MU
    # the registries are the package's own dicts: a wing registering a type is seen by
    # from_config
    assert module.TORQUE_TABLES is registry.TORQUE_TABLES
    assert module.ORBIT_SOURCES is registry.ORBIT_SOURCES

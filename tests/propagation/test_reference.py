"""The reference propagator (DOP853) against conservation laws and closed forms."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from scipy.special import ellipk

import attitude as att
from attitude.propagation.reference import integrate_reference


def polhode_period(moments, omega):
    """T = 4 K(k) / lambda (Landau & Lifshitz, Mechanics, section 37), SAM case,
    written out here independently of the package."""
    A, B, C = moments
    L2 = np.sum((moments * omega) ** 2)
    E2 = np.sum(moments * omega**2)
    assert L2 > E2 * B                    # short-axis mode
    lam = np.sqrt((C - B) * (L2 - E2 * A) / (A * B * C))
    k2 = (B - A) * (E2 * C - L2) / ((C - B) * (L2 - E2 * A))
    return 4 * ellipk(k2) / lam


def test_conserves_L_and_E_over_100_nutation_periods():
    """Issue 2: |L| (inertial vector) and E conserved to better than 1e-10 relative over
    100 nutation periods at default settings."""
    moments = np.array([1.0, 2.0, 3.0])
    omega = np.array([0.4, 0.3, 0.5])
    T = polhode_period(moments, omega)
    body = att.RigidBody.from_principal_moments(moments)
    q0 = Rotation.from_euler("ZXZ", [0.3, 1.0, -0.4]).as_quat()
    t = np.linspace(0.0, 100 * T, 4001)
    q, w = integrate_reference(body, q0, omega, t)
    L = Rotation.from_quat(q).apply(w * moments)
    L0 = Rotation.from_quat(q0).apply(omega * moments)
    E = 0.5 * np.sum(moments * w**2, axis=1)
    E0 = 0.5 * np.sum(moments * omega**2)
    assert np.max(np.linalg.norm(L - L0, axis=1)) / np.linalg.norm(L0) < 1e-10
    assert np.max(np.abs(E - E0)) / E0 < 1e-10
    # the rates are periodic with the polhode period (an independent closed form)
    np.testing.assert_allclose(w[-1], omega, rtol=0, atol=1e-9 * np.linalg.norm(omega))


def test_axisymmetric_regular_precession_closed_form():
    """Oblate body A = B: omega_3 constant, transverse rate turns at
    Omega = (C - A)/A omega_3 in the body frame (free precession)."""
    A, C = 2.0, 3.0
    w0 = np.array([0.2, 0.0, 1.0])
    body = att.RigidBody.from_principal_moments([A, A, C])
    t = np.linspace(0, 50.0, 101)
    _, w = integrate_reference(body, [0, 0, 0, 1.0], w0, t)
    Omega = (C - A) / A * w0[2]
    expected = np.stack([0.2 * np.cos(Omega * t), 0.2 * np.sin(Omega * t),
                         np.full_like(t, 1.0)], axis=1)
    np.testing.assert_allclose(w, expected, atol=1e-11)


def test_backward_and_unsorted_times_match_forward_run():
    body = att.RigidBody.from_principal_moments([1.0, 1.5, 2.0])
    w0 = np.array([0.1, 0.5, 0.2])
    q_fwd, w_fwd = integrate_reference(body, [0, 0, 0, 1.0], w0, [0.0, 10.0, 20.0])
    # start at t = 20 from the forward state and go back: we must recover the start
    q_back, w_back = integrate_reference(body, q_fwd[2], w_fwd[2], [-20.0, 0.0, -10.0])
    np.testing.assert_allclose(w_back[0], w0, atol=1e-11)
    np.testing.assert_allclose(w_back[2], w_fwd[1], atol=1e-11)
    assert (Rotation.from_quat(q_back[0]).inv() * Rotation.identity()).magnitude() < 1e-11


def test_propagate_through_rotated_body_frame_matches_principal_frame():
    """A body given by a full tensor in a rotated frame moves exactly like the same
    body given in its principal frame (a second, independent route)."""
    R = Rotation.from_euler("xyz", [20, -35, 50], degrees=True)
    moments = np.array([1.0, 2.0, 2.5])
    inertia = R.as_matrix() @ np.diag(moments) @ R.as_matrix().T      # body frame
    body_rot = att.RigidBody(inertia)
    body_pr = att.RigidBody.from_principal_moments(moments)
    w_p = np.array([0.3, -0.2, 0.4])
    q_p = Rotation.from_euler("z", 10, degrees=True)
    # the same physical state: body frame b = R p  -> attitude_b = attitude_p R^-1
    s_pr = att.AttitudeState("2030-01-01", q_p, w_p)
    s_rot = att.AttitudeState("2030-01-01", q_p * R.inv(), R.apply(w_p))
    t = np.linspace(0, 30, 7)
    e_pr = att.propagate(body_pr, s_pr, t, method="integrator")
    e_rot = att.propagate(body_rot, s_rot, t, method="integrator")
    np.testing.assert_allclose(e_rot.dataset.angular_momentum, e_pr.dataset.angular_momentum,
                               atol=1e-10)
    mismatch = (e_rot.rotation * R) * e_pr.rotation.inv()
    assert np.max(mismatch.magnitude()) < 1e-10


def test_constant_body_torque_spins_up_a_sphere():
    """A sphere under a constant body-axis torque M about its spin axis: w = w0 + M t / I."""
    body = att.RigidBody.from_principal_moments([2.0, 2.0, 2.0])

    def torque(t, q, w, body):
        return np.array([0.0, 0.0, 0.5])

    state = att.AttitudeState("2030-01-01", Rotation.identity(), [0, 0, 1.0])
    eph = att.propagate(body, state, [0.0, 4.0], torques=[torque])
    assert eph.dataset.angular_velocity.values[-1, 2] == pytest.approx(1.0 + 0.5 * 4 / 2.0,
                                                                      rel=1e-12)

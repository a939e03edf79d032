"""Every vectorised kernel against its scalar use, on random inputs.

Each kernel is run once on a stack of inputs and once per element (the scalar fast
path where one exists, else a stack of one); the two must agree to a tolerance derived
from the computation: ``k`` correctly rounded (or 1-ulp) floating-point operations on
numbers of magnitude ``M`` differ by at most about ``k eps M`` between two evaluation
orders, and a few ulp more where numpy's SIMD loops and libm differ in the last bit.
Never bit equality.  Where an independent reference exists (scipy's ``Rotation``, the
energy and angular momentum computed naively), the result is checked against it too.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from attitude.analysis.diagnostics import invariants, osculating_polhode_period
from attitude.foundations import quaternion as quat
from attitude.foundations.errors import InvalidInertiaError, NearSeparatrixWarning
from attitude.model import freebody as fb
from attitude.model.body import (
    SYMMETRIC_TENSOR_RTOL,
    RigidBody,
    as_bodies,
    check_inertia,
    principal_quaternions,
    to_body_frame,
    to_principal_frame,
)
from attitude.model.freebody import diagnose_many, diagnose_principal
from attitude.model.population import Ensemble
from attitude.model.torques import ConstantTorque
from attitude.propagation.splitting import free_flow, integrate_splitting
from attitude.propagation.torquefree import free_rotation

EPS = np.finfo(float).eps
N = 64


def ulps(k, magnitude=1.0) -> float:
    """Tolerance of ``k`` rounding errors on numbers of (at most) the given magnitude."""
    return float(k * EPS * np.max(magnitude))


@pytest.fixture
def rng():
    return np.random.default_rng(20261125)


def unit_quaternions(rng, n):
    q = rng.normal(size=(n, 4))
    return q / np.linalg.norm(q, axis=1, keepdims=True)


def triaxial_moments(rng, n):
    """Sorted moments A <= B <= C = 1 satisfying A + B >= C, well away from symmetry."""
    a = rng.uniform(0.55, 0.9, n)
    b = a + rng.uniform(0.02, 1.0 - a - 0.01)
    return np.stack([a, b, np.ones(n)], axis=1)


# ===========================================================================
# quaternions
# ===========================================================================
def test_quaternion_ops_stack_equals_scalar_path_and_scipy(rng):
    p, q = unit_quaternions(rng, N), unit_quaternions(rng, N)
    v = rng.normal(size=(N, 3)) * 10.0
    pq = quat.multiply(p, q)
    pv = quat.rotate(p, v)
    pv_inv = quat.rotate(p, v, inverse=True)
    for i in range(N):
        # 1-D inputs take the scalar fast path (plain floats)
        np.testing.assert_allclose(quat.multiply(p[i], q[i]), pq[i], rtol=0, atol=ulps(8))
        np.testing.assert_allclose(quat.rotate(p[i], v[i]), pv[i], rtol=0,
                                   atol=ulps(16, np.abs(v[i]).max()))
        np.testing.assert_allclose(quat.rotate(p[i], v[i], inverse=True), pv_inv[i], rtol=0,
                                   atol=ulps(16, np.abs(v[i]).max()))
    # independent: scipy's composition and rotation
    ref = (Rotation.from_quat(p) * Rotation.from_quat(q)).as_quat()
    np.testing.assert_allclose(quat.canonical(pq), quat.canonical(ref), rtol=0, atol=ulps(16))
    vmax = np.abs(v).max(axis=1, keepdims=True)
    np.testing.assert_allclose(pv, Rotation.from_quat(p).apply(v), rtol=0, atol=ulps(32, vmax))
    np.testing.assert_allclose(pv_inv, Rotation.from_quat(p).inv().apply(v), rtol=0,
                               atol=ulps(32, vmax))
    np.testing.assert_array_equal(quat.conjugate(p)[:, :3], -p[:, :3])   # exact (a negation)


def test_quaternion_component_form_equals_array_form(rng):
    p, q = unit_quaternions(rng, N), unit_quaternions(rng, N)
    v = rng.normal(size=(N, 3))
    parts = quat.multiply_parts(tuple(p.T), tuple(q.T))
    np.testing.assert_allclose(np.stack(parts, axis=-1), quat.multiply(p, q), rtol=0,
                               atol=ulps(8))
    parts = quat.rotate_parts(tuple(p.T), tuple(v.T), inverse=True)
    np.testing.assert_allclose(np.stack(parts, axis=-1), quat.rotate(p, v, inverse=True),
                               rtol=0, atol=ulps(16, 4.0))


def test_quaternion_blocked_array_form_equals_rows(rng):
    """Large inputs run block by block: the blocks join without a seam."""
    q = unit_quaternions(rng, 3 * 7001).reshape(3, 7001, 4)
    p = unit_quaternions(rng, 3 * 7001).reshape(3, 7001, 4)
    v = rng.normal(size=(3, 7001, 3))
    out, prod = quat.rotate(q, v, inverse=True), quat.multiply(p, q)
    for i, j in [(0, 0), (1, 1190), (1, 1191), (2, 2380), (2, 7000)]:   # around 8192-row cuts
        np.testing.assert_allclose(out[i, j], quat.rotate(q[i, j], v[i, j], inverse=True),
                                   rtol=0, atol=ulps(16, 4.0))
        np.testing.assert_allclose(prod[i, j], quat.multiply(p[i, j], q[i, j]), rtol=0,
                                   atol=ulps(8))


def test_quaternion_broadcasting_over_leading_axes(rng):
    q = unit_quaternions(rng, 12).reshape(3, 4, 4)
    v = rng.normal(size=(4, 3))
    out = quat.rotate(q, v)
    for i in range(3):
        for j in range(4):
            np.testing.assert_allclose(out[i, j], quat.rotate(q[i, j], v[j]), rtol=0,
                                       atol=ulps(16, 4.0))


# ===========================================================================
# free-body invariants and attitude helpers
# ===========================================================================
def test_invariants_stack_equals_floats_and_the_naive_energy(rng):
    I = triaxial_moments(rng, N)
    w = rng.normal(size=(N, 3))
    lam = rng.uniform(size=N) < 0.5
    Ik = fb.kernel_moments(I[:, 0], I[:, 1], I[:, 2], lam)
    wk = fb.kernel_vector(w[:, 0], w[:, 1], w[:, 2], lam)
    inv = fb.invariants(*Ik, *wk)
    jac = fb.jacobi_parameters(*Ik, *inv[:6])
    nu = fb.characteristic(*Ik)
    for i in range(N):
        Ii = fb.kernel_moments(*(float(x) for x in I[i]), bool(lam[i]))
        wi = fb.kernel_vector(*(float(x) for x in w[i]), bool(lam[i]))
        one = fb.invariants(*Ii, *wi)
        assert all(isinstance(x, float) for x in one)          # the scalar path
        scale = np.sum(np.asarray(Ii) * np.asarray(wi) ** 2) * max(Ii)
        for a, b in zip(one, (x[i] for x in inv)):
            assert abs(a - b) <= ulps(8, max(abs(a), scale, 1.0))
        for a, b in zip(fb.jacobi_parameters(*Ii, *one[:6]), (x[i] for x in jac)):
            assert abs(a - b) <= ulps(16, abs(a))
        assert abs(fb.characteristic(*Ii) - nu[i]) <= ulps(8, abs(nu[i]))
    # independent: the naive energy and momentum (cancellation bounded by their size)
    A, B, C = I.T
    L2 = np.sum((I * w) ** 2, axis=1)
    E2 = np.sum(I * w * w, axis=1)
    Q1s, Q3s, Ds = fb.invariants(A, B, C, *w.T)[3:6]
    np.testing.assert_allclose(Q1s, 2 * (E2 / 2) * C - L2, rtol=0, atol=ulps(16, L2 * 2))
    np.testing.assert_allclose(Q3s, L2 - E2 * A, rtol=0, atol=ulps(16, L2 * 2))
    np.testing.assert_allclose(Ds, L2 - E2 * B, rtol=0, atol=ulps(16, L2 * 2))
    # m + m1 = 1 (d21 Q1 + d31 D = d32 Q3): each has a few ulp, plus the rounding of D,
    # whose terms are C (C - B) w3^2 and A (B - A) w1^2
    m, m1, _ = fb.jacobi_parameters(A, B, C, *fb.invariants(A, B, C, *w.T)[:6])
    terms = C * (C - B) * w[:, 2] ** 2 + A * (B - A) * w[:, 0] ** 2
    bound = 8 * EPS + 4 * EPS * (C - A) * terms / np.abs((C - B) * Q3s)
    assert np.all(np.abs(m + m1 - 1.0) <= bound)


def test_half_theta_and_euler313_stack_equals_floats_and_scipy(rng):
    Lv = rng.normal(size=(N, 3))
    phi, psi = rng.uniform(-10, 10, N), rng.uniform(-10, 10, N)
    ct, st = fb.half_theta(*Lv.T)
    qs = np.stack(fb.euler313_quaternion(ct, st, phi, psi), axis=-1)
    for i in range(N):
        c1, s1 = fb.half_theta(*(float(x) for x in Lv[i]))
        assert abs(c1 - ct[i]) <= ulps(8) and abs(s1 - st[i]) <= ulps(8)
        q1 = fb.euler313_quaternion(c1, s1, float(phi[i]), float(psi[i]))
        np.testing.assert_allclose(q1, qs[i], rtol=0, atol=ulps(16))
    # independent: theta from the dot product, the rotation from scipy
    theta = np.arccos(Lv[:, 2] / np.linalg.norm(Lv, axis=1))
    np.testing.assert_allclose(2 * np.arctan2(st, ct), theta, rtol=0, atol=1e-7)
    ref = Rotation.from_euler("ZXZ", np.stack([phi, 2 * np.arctan2(st, ct), psi], 1)).as_quat()
    np.testing.assert_allclose(quat.canonical(qs), quat.canonical(ref), rtol=0, atol=ulps(64))


# ===========================================================================
# the exact flow: closed form and splitting free flow
# ===========================================================================
def test_free_rotation_batch_equals_single_bodies(rng):
    I = triaxial_moments(rng, 16)
    I[0, 1] = I[0, 0]                     # an oblate body (precession branch)
    q0 = unit_quaternions(rng, 16)
    w0 = rng.normal(size=(16, 3)) * 0.1
    w0[1] = [0.0, 0.0, 0.2]               # a principal-axis spin
    t = np.linspace(-200.0, 2000.0, 37)
    q, w = free_rotation(I, q0, w0, t)
    for i in range(16):
        qi, wi = free_rotation(I[i], q0[i], w0[i], t)
        # O(1) quaternions: phases of |omega| t <= ~1e3 rad, so ~1e3 ulp of the phase
        tol_q = ulps(32, 1.0 + np.abs(w0[i]).max() * np.abs(t).max())
        np.testing.assert_allclose(qi, q[i], rtol=0, atol=tol_q)
        np.testing.assert_allclose(wi, w[i], rtol=0, atol=tol_q * np.abs(w0[i]).max() * 4)


def test_free_flow_batch_equals_one_body_path(rng):
    """The splitting free flow's vectorised path (a batch) and its plain-float one-body
    path (a single body) over the same steps."""
    n = 8
    I = triaxial_moments(rng, n)
    q0 = unit_quaternions(rng, n)
    w0 = rng.normal(size=(n, 3)) * 0.05
    t = np.linspace(0.0, 400.0, 9)
    torque = ConstantTorque([1e-4, -2e-4, 5e-5])
    bodies = [RigidBody.from_principal_moments(m) for m in I]
    qb, wb = integrate_splitting(bodies, q0, w0, t, torques=[torque], step=5.0)
    for i in range(n):
        qi, wi = integrate_splitting(bodies[i], q0[i], w0[i], t, torques=[torque], step=5.0)
        # 80 steps of O(10) operations each on O(1) numbers
        tol = ulps(80 * 16, 1.0 + 400.0 * np.abs(w0[i]).max())
        np.testing.assert_allclose(qi, qb[i], rtol=0, atol=tol)
        np.testing.assert_allclose(wi, wb[i], rtol=0, atol=tol * np.abs(wb[i]).max())
    # and one free step against the closed form (independent method)
    qf, wf = free_flow(I, q0, w0, 37.0)
    qr, wr = free_rotation(I, q0, w0, [37.0])
    np.testing.assert_allclose(quat.canonical(qf), quat.canonical(qr[:, 0]), rtol=0, atol=1e-13)
    np.testing.assert_allclose(wf, wr[:, 0], rtol=0, atol=1e-13 * np.abs(w0).max())


# ===========================================================================
# diagnostics
# ===========================================================================
def test_diagnostics_invariants_and_polhode_period_stack_equals_rows(rng):
    I = triaxial_moments(rng, 1)[0]
    w = rng.normal(size=(N, 3))
    inv = invariants(w, I)
    P = osculating_polhode_period(w, I)
    for i in range(N):
        one = invariants(w[i], I)
        for key, value in inv.items():
            a, b = float(one[key]), float(value[i])
            assert (np.isnan(a) and np.isnan(b)) or abs(a - b) <= ulps(16, max(abs(a), 1.0)), key
        assert abs(float(osculating_polhode_period(w[i], I)) - P[i]) <= ulps(64, P[i])


def test_diagnose_many_equals_diagnose_principal(rng):
    I = triaxial_moments(rng, N)
    w = rng.normal(size=(N, 3))
    d = diagnose_many(I, w)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", NearSeparatrixWarning)
        for i in range(N):
            one = diagnose_principal(I[i], w[i])
            assert one.regime == d["regime"][i]
            for key, value in one.periods.items():
                assert abs(value - d[key][i]) <= ulps(64, value), key
            assert abs(one.separatrix_distance - d["separatrix_distance"][i]) <= ulps(64)


# ===========================================================================
# inertia validation and the body <-> principal frames
# ===========================================================================
def random_tensors(rng, n):
    I = triaxial_moments(rng, n) * rng.uniform(0.1, 1e4, (n, 1))
    R = Rotation.random(n, random_state=rng).as_matrix()
    return R @ (I[:, :, None] * np.eye(3)) @ R.transpose(0, 2, 1)


def test_check_inertia_stack_equals_rigid_body(rng):
    T = random_tensors(rng, 12)
    T[3] = np.diag([1.0, 1.0, 3.0])                          # triangle inequality
    T[5, 0, 1] += 1e-3 * np.abs(T[5]).max()                   # not symmetric
    T[7] = np.diag([-1.0, 2.0, 2.0])                          # not positive-definite
    T[9, 2, 2] = np.nan                                       # not finite
    moments, axes, invalid = check_inertia(T)
    assert sorted(invalid) == [3, 5, 7, 9]
    for i in range(12):
        if i in invalid:
            with pytest.raises(InvalidInertiaError) as err:
                RigidBody(T[i])
            assert str(err.value) == invalid[i]             # one validator, one message
            continue
        body = RigidBody(T[i])
        scale = np.abs(T[i]).max()
        np.testing.assert_allclose(body.principal_moments, moments[i], rtol=0,
                                   atol=ulps(32, scale))
        # the axes agree up to the sign of each axis (eigenvectors): compare projectors
        for k in range(3):
            a, b = body.principal_axes[:, k], axes[i][:, k]
            np.testing.assert_allclose(np.outer(a, a), np.outer(b, b), rtol=0, atol=1e-10)
        # independent: the tensor is rebuilt from its principal frame
        np.testing.assert_allclose(axes[i] @ np.diag(moments[i]) @ axes[i].T, T[i], rtol=0,
                                   atol=ulps(64, scale))
        assert np.linalg.det(axes[i]) > 0


def test_one_symmetry_tolerance_for_bodies_and_ensemble_rows():
    """A tensor asymmetric by 1e-11 (relative) is a valid RigidBody and a valid ensemble
    row; by 10 x SYMMETRIC_TENSOR_RTOL it is invalid for both."""
    base = np.diag([1.0, 2.0, 2.5])
    for rel, ok in ((1e-11, True), (10 * SYMMETRIC_TENSOR_RTOL, False)):
        T = base.copy()
        T[0, 1] = rel * 2.5
        invalid_row = Ensemble(T[None], [[0, 0, 0, 1.0]], [[0, 0, 1.0]], epoch="2029-04-13",
                               on_invalid="report") if ok else None
        if ok:
            RigidBody(T)
            assert not invalid_row.invalid
        else:
            with pytest.raises(InvalidInertiaError, match="not symmetric"):
                RigidBody(T)
            with pytest.warns(Warning):
                ens = Ensemble(T[None], [[0, 0, 0, 1.0]], [[0, 0, 1.0]], epoch="2029-04-13")
            assert "not symmetric" in ens.invalid[0]


def test_principal_frames_stack_equals_rows_and_scipy(rng):
    T = random_tensors(rng, N)
    bodies = [RigidBody(x) for x in T]
    batch, single = as_bodies(bodies)
    assert not single and len(batch) == N
    q_bp = principal_quaternions(np.stack([b.principal_axes for b in bodies]))
    np.testing.assert_allclose(q_bp, batch.body_to_principal, rtol=0, atol=0)  # same call
    q = unit_quaternions(rng, N)
    w = rng.normal(size=(N, 3))
    qp, wp = to_principal_frame(q, w, q_bp)
    qb, wb = to_body_frame(qp, wp, q_bp)
    for i in range(N):
        ref_bp = bodies[i].body_to_principal
        np.testing.assert_allclose(quat.canonical(q_bp[i]), quat.canonical(ref_bp.as_quat()),
                                   rtol=0, atol=ulps(16))
        qpi, wpi = to_principal_frame(q[i], w[i], q_bp[i])          # scalar path
        np.testing.assert_allclose(qpi, qp[i], rtol=0, atol=ulps(8))
        np.testing.assert_allclose(wpi, wp[i], rtol=0, atol=ulps(16, np.abs(w[i]).max()))
        # independent: scipy's composition R_p2i = R_b2i R_bp^-1, w_p = R_bp w_b
        ref = (Rotation.from_quat(q[i]) * ref_bp.inv()).as_quat()
        np.testing.assert_allclose(quat.canonical(qpi), quat.canonical(ref), rtol=0,
                                   atol=ulps(32))
        np.testing.assert_allclose(wpi, ref_bp.apply(w[i]), rtol=0,
                                   atol=ulps(32, np.abs(w[i]).max()))
    # the round trip
    np.testing.assert_allclose(qb, q, rtol=0, atol=ulps(16))
    np.testing.assert_allclose(wb, w, rtol=0, atol=ulps(32, np.abs(w).max()))

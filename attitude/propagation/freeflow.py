r"""The exact torque-free flow of rigid bodies over one step: the free part ``F`` of the
splitting integrator (:mod:`attitude.propagation.splitting`).

Jacobi elliptic functions for the rates and an elliptic integral of the third kind for
the precession angle (Celledoni, Fassò, Säfström & Zanna 2008); the formulas, numbered
(S1)-(S5), are in :func:`free_flow`.

References
----------
.. [1] Celledoni, E., Fassò, F., Säfström, N. & Zanna, A. (2008). The exact
   computation of the free rigid body motion and its use in splitting methods.
   *SIAM J. Sci. Comput.* 30, 2084-2112.
.. [2] Carlson, B. C. (1995). Numerical computation of real or complex elliptic
   integrals. *Numer. Algorithms* 10, 13-26; DLMF §19.25, §22.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import special as sp

from ..foundations import quaternion as quat
from ..model import freebody as fb
from ..model.freebody import EQUAL_MOMENTS_RTOL, PURE_SPIN_TOL_UNSCALED
from . import compiled

__all__ = ["free_flow"]

# The free flow's tolerances are those of attitude.freebody: EQUAL_MOMENTS_RTOL (a
# spherical body rotates uniformly) and PURE_SPIN_TOL_UNSCALED (a principal-axis spin
# rotates uniformly; this kernel works on unscaled rates, see its comment there).


#: scipy.special.ellipj (Cephes) switches to its expansion about m = 1 from this m on; the
#: expansion fails past the first quarter period (sn > 1, cn ~ -3e5 at u = 40,
#: m = 1 - 1e-11), so there the free flow takes compiled.ellipj (Landen from 1 - m).
_CEPHES_NEAR1 = 0.9999999999


class FreeConstants:
    """Per-body constants of the free flow: principal moments scaled to O(1) by a power
    of two (exact), the symmetry flags and the characteristics ``nu`` of both kernel
    frames."""

    def __init__(self, moments: np.ndarray):
        moments = np.atleast_2d(np.asarray(moments, dtype=float))
        _, e = np.frexp(moments[:, 2])
        m = moments / np.ldexp(1.0, e)[:, None]            # exact power-of-two scaling
        A, B, C = m[:, 0].copy(), m[:, 1].copy(), m[:, 2].copy()
        self.A, self.B, self.C = A, B, C
        self.spherical = (C - A) <= EQUAL_MOMENTS_RTOL * C
        # on the separatrix (L^2 = 2EB exactly) take the kernel frame with the larger
        # gap I3 - I2 (a prolate body spinning in its B-C plane goes to LAM)
        self.lam_on_tie = (C - B) < (B - A)
        with np.errstate(divide="ignore", invalid="ignore"):
            self.nu_sam = fb.characteristic(A, B, C)        # kernel moments (A, B, C)
            self.nu_lam = fb.characteristic(C, B, A)        # kernel moments (C, B, A)

    def row(self, i: int) -> tuple:
        """Plain-float constants of body ``i`` (for the one-body kernel)."""
        return (float(self.A[i]), float(self.B[i]), float(self.C[i]),
                bool(self.spherical[i]), bool(self.lam_on_tie[i]),
                float(self.nu_sam[i]), float(self.nu_lam[i]))


def free_flow_batch(c: FreeConstants, q: np.ndarray, w: np.ndarray, h: float):
    """Exact free flow of ``N`` bodies over ``h`` (vectorised); see :func:`free_flow`.

    ``q`` (N, 4) principal -> inertial, ``w`` (N, 3) principal rates; new arrays out.
    """
    A, B, C = c.A, c.B, c.C
    o1, o2, o3 = w[:, 0], w[:, 1], w[:, 2]
    with np.errstate(all="ignore"):
        # kernel frame: SAM (A, B, C), or LAM (C, B, A) along (e3, -e2, e1)      (S1)
        delta = fb.separatrix_gap(A, B, C, o1, o3)                     # L^2 - 2EB
        lam = (delta < 0) | ((delta == 0) & c.lam_on_tie)
        I1, I2, I3 = fb.kernel_moments(A, B, C, lam)
        w1, w2, w3 = fb.kernel_vector(o1, o2, o3, lam)
        nu = np.where(lam, c.nu_lam, c.nu_sam)
        d21, d32, d31, Q1, Q3, Dk, Lsq = fb.invariants(I1, I2, I3, w1, w2, w3)
        L1, L2, L3 = I1 * w1, I2 * w2, I3 * w3
        L = np.sqrt(Lsq)
        w2s = w2 * w2
        m, m1, lam2 = fb.jacobi_parameters(I1, I2, I3, d21, d32, d31, Q1, Q3, Dk)
        m = np.minimum(np.maximum(m, 0.0), 1.0)
        m1 = np.minimum(np.maximum(m1, 0.0), 1.0)
        # u = u0 + lambda t with dn(u) = w3 / a3 > 0: lambda has the sign of w3 (I3 - I2)
        s = np.where(w3 < 0, -1.0, 1.0)
        lamb = np.where(lam, -s, s) * np.sqrt(lam2)
        v = lamb * h
        sn, cn, dn, _ = sp.ellipj(v, m)
        for i in np.flatnonzero(m >= _CEPHES_NEAR1):
            sn[i], cn[i], dn[i] = compiled.ellipj(float(v[i]), float(m[i]))
        snl = sn / lamb
        # rates by the addition theorems, no amplitude in a denominator          (S2)
        D = 1.0 - (I2 * d21 / Q3) * w2s * (sn * sn)
        n1 = (w1 * cn - (d32 / I1) * w2 * w3 * snl * dn) / D
        n2 = (w2 * cn * dn + (d31 / I2) * w1 * w3 * snl) / D
        n3 = (w3 * dn - (d21 / I3) * w1 * w2 * snl * cn) / D
        # precession angle about L                                               (S3)
        a1 = np.sqrt(Q1 / (I1 * d31))
        a2 = np.sqrt(Q1 / (I2 * d32))
        a3 = s * np.sqrt(Q3 / (I3 * d31))
        sn0 = np.minimum(np.maximum(w2 / a2, -1.0), 1.0)
        cn0 = np.minimum(np.maximum(w1 / a1, -1.0), 1.0)
        dn0 = np.minimum(w3 / a3, 1.0)
        sn1 = np.minimum(np.maximum(n2 / a2, -1.0), 1.0)
        cn1 = np.minimum(np.maximum(n1 / a1, -1.0), 1.0)
        dn1 = np.minimum(n3 / a3, 1.0)
        nu3 = nu / 3.0
        S0 = nu3 * sn0 ** 3 * sp.elliprj(cn0 * cn0, dn0 * dn0, 1.0, 1.0 + nu * sn0 * sn0)
        S1 = nu3 * sn1 ** 3 * sp.elliprj(cn1 * cn1, dn1 * dn1, 1.0, 1.0 + nu * sn1 * sn1)
        S0 = np.where(nu == 0, 0.0, S0)
        S1 = np.where(nu == 0, 0.0, S1)
        p0 = cn0 >= 0                                 # parity of the half-period window
        p1 = cn1 >= 0
        dwin = np.where(p0 == p1, 0.0, np.where(v >= 0, 1.0, -1.0))
        far = np.abs(v) >= math.pi                    # 2K >= pi: may span > 1 window
        if far.any():
            K = sp.elliprf(0.0, m1, 1.0)
            uh = sn0 * sp.elliprf(cn0 * cn0, dn0 * dn0, 1.0)
            u0 = np.where(p0, uh, np.copysign(2.0 * K, sn0) - uh)
            general = np.rint((u0 + v) / (2.0 * K)) - np.rint(u0 / (2.0 * K))
            dwin = np.where(far & (m1 > 0), general, dwin)
        dJ = np.where(p1, S1, -S1) - np.where(p0, S0, -S0)
        if (dwin != 0).any():
            JK = nu3 * sp.elliprj(0.0, m1, 1.0, 1.0 + nu)
            dJ = dJ + np.where(dwin == 0, 0.0, 2.0 * dwin * JK)
        c1 = L * d31 / (I1 * I3)
        dphi = h * (L / I3 + c1) - c1 * dJ / lamb
        # attitude: q(t+h) = q(t) E0^-1 E1, E = Rz(phi) Rx(theta) Rz(psi)       (S4)
        ct0, st0 = fb.half_theta(L1, L2, L3)
        M1, M2, M3 = I1 * n1, I2 * n2, I3 * n3
        ct1, st1 = fb.half_theta(M1, M2, M3)
        e = fb.euler313_quaternion(ct0, st0, 0.0, np.arctan2(L1, L2))
        f = fb.euler313_quaternion(ct1, st1, dphi, np.arctan2(M1, M2))
        gx, gy, gz, gw = quat.multiply_parts(quat.conjugate_parts(e), f)
        gx, gy, gz = fb.kernel_vector(gx, gy, gz, lam)      # the step in principal axes
        p1_, p2_, p3_ = fb.kernel_vector(n1, n2, n3, lam)
        # uniform rotation: spherical body, principal-axis spin, rest, lambda = 0 (S5)
        mid = np.maximum(np.minimum(np.abs(L1), np.abs(L2)),
                         np.minimum(np.maximum(np.abs(L1), np.abs(L2)), np.abs(L3)))
        uniform = (c.spherical | (mid <= PURE_SPIN_TOL_UNSCALED * L) | ~(lam2 > 0)
                   | ~np.isfinite(gx + gy + gz + gw + p1_ + p2_ + p3_))
        if uniform.any():
            wn = np.sqrt(o1 * o1 + o2 * o2 + o3 * o3)
            half = 0.5 * wn * h
            sh = np.where(wn > 0, np.sin(half) / wn, 0.0)
            gx = np.where(uniform, sh * o1, gx)
            gy = np.where(uniform, sh * o2, gy)
            gz = np.where(uniform, sh * o3, gz)
            gw = np.where(uniform, np.cos(half), gw)
            p1_ = np.where(uniform, o1, p1_)
            p2_ = np.where(uniform, o2, p2_)
            p3_ = np.where(uniform, o3, p3_)
    out = quat.multiply(q, np.stack([gx, gy, gz, gw], axis=-1))
    out /= np.sqrt(np.sum(out * out, axis=1, keepdims=True))
    wout = np.empty_like(w)
    wout[:, 0], wout[:, 1], wout[:, 2] = p1_, p2_, p3_
    return out, wout


def _uniform1(q, o1, o2, o3, h):
    wn = math.sqrt(o1 * o1 + o2 * o2 + o3 * o3)
    half = 0.5 * wn * h
    sh = math.sin(half) / wn if wn > 0 else 0.0
    return qmul_unit(q, (sh * o1, sh * o2, sh * o3, math.cos(half))), (o1, o2, o3)


def qmul_unit(q, g):
    """Normalised product ``q g`` of component quaternions (plain floats)."""
    nx, ny, nz, nw = quat.multiply_parts(q, g)
    r = 1.0 / math.sqrt(nx * nx + ny * ny + nz * nz + nw * nw)
    return (nx * r, ny * r, nz * r, nw * r)


def _clip1(x, lo, hi):
    return lo if x < lo else (hi if x > hi else x)


def free_flow_tuple(k: tuple, q: tuple, w: tuple, h: float):
    """The same step as :func:`free_flow_batch` for one body in plain floats (a numpy
    call on one element costs as much as ~20 float operations)."""
    A, B, C, spherical, lam_on_tie, nu_sam, nu_lam = k
    o1, o2, o3 = w
    if spherical:
        return _uniform1(q, o1, o2, o3, h)
    delta = fb.separatrix_gap(A, B, C, o1, o3)
    lam = delta < 0 or (delta == 0 and lam_on_tie)
    I1, I2, I3 = fb.kernel_moments(A, B, C, lam)
    w1, w2, w3 = fb.kernel_vector(o1, o2, o3, lam)
    nu = nu_lam if lam else nu_sam
    d21, d32, d31, Q1, Q3, Dk, Lsq = fb.invariants(I1, I2, I3, w1, w2, w3)
    L1, L2, L3 = I1 * w1, I2 * w2, I3 * w3
    L = math.sqrt(Lsq)
    a_, b_, c_ = abs(L1), abs(L2), abs(L3)
    mid = max(min(a_, b_), min(max(a_, b_), c_))
    w2s = w2 * w2
    if mid <= PURE_SPIN_TOL_UNSCALED * L or not d32 * Q3 > 0:
        return _uniform1(q, o1, o2, o3, h)
    m, m1, lam2 = fb.jacobi_parameters(I1, I2, I3, d21, d32, d31, Q1, Q3, Dk)
    m = _clip1(m, 0.0, 1.0)
    m1 = _clip1(m1, 0.0, 1.0)
    s = -1.0 if w3 < 0 else 1.0
    lamb = (-s if lam else s) * math.sqrt(lam2)
    v = lamb * h
    if m >= _CEPHES_NEAR1:
        sn, cn, dn = compiled.ellipj(float(v), float(m))
    else:
        sn, cn, dn, _ = sp.ellipj(v, m)
        sn, cn, dn = float(sn), float(cn), float(dn)
    snl = sn / lamb
    D = 1.0 - (I2 * d21 / Q3) * w2s * (sn * sn)
    n1 = (w1 * cn - (d32 / I1) * w2 * w3 * snl * dn) / D
    n2 = (w2 * cn * dn + (d31 / I2) * w1 * w3 * snl) / D
    n3 = (w3 * dn - (d21 / I3) * w1 * w2 * snl * cn) / D
    a1 = math.sqrt(Q1 / (I1 * d31))
    a2 = math.sqrt(Q1 / (I2 * d32))
    a3 = s * math.sqrt(Q3 / (I3 * d31))
    sn0 = _clip1(w2 / a2, -1.0, 1.0)
    cn0 = _clip1(w1 / a1, -1.0, 1.0)
    dn0 = min(w3 / a3, 1.0)
    sn1 = _clip1(n2 / a2, -1.0, 1.0)
    cn1 = _clip1(n1 / a1, -1.0, 1.0)
    dn1 = min(n3 / a3, 1.0)
    if nu == 0:
        S0 = S1 = 0.0
    else:
        nu3 = nu / 3.0
        S0 = nu3 * sn0 ** 3 * float(sp.elliprj(cn0 * cn0, dn0 * dn0, 1.0, 1.0 + nu * sn0 * sn0))
        S1 = nu3 * sn1 ** 3 * float(sp.elliprj(cn1 * cn1, dn1 * dn1, 1.0, 1.0 + nu * sn1 * sn1))
    p0, p1 = cn0 >= 0, cn1 >= 0
    dwin = 0.0 if p0 == p1 else (1.0 if v >= 0 else -1.0)
    if abs(v) >= math.pi and m1 > 0:
        K = float(sp.elliprf(0.0, m1, 1.0))
        uh = sn0 * float(sp.elliprf(cn0 * cn0, dn0 * dn0, 1.0))
        u0 = uh if p0 else math.copysign(2.0 * K, sn0) - uh
        dwin = float(round((u0 + v) / (2.0 * K)) - round(u0 / (2.0 * K)))
    dJ = (S1 if p1 else -S1) - (S0 if p0 else -S0)
    if dwin != 0:
        dJ += 2.0 * dwin * (nu / 3.0) * float(sp.elliprj(0.0, m1, 1.0, 1.0 + nu))
    c1 = L * d31 / (I1 * I3)
    dphi = h * (L / I3 + c1) - c1 * dJ / lamb
    ct0, st0 = fb.half_theta(L1, L2, L3)
    M1, M2, M3 = I1 * n1, I2 * n2, I3 * n3
    ct1, st1 = fb.half_theta(M1, M2, M3)
    e = fb.euler313_quaternion(ct0, st0, 0.0, math.atan2(L1, L2))
    f = fb.euler313_quaternion(ct1, st1, dphi, math.atan2(M1, M2))
    gx, gy, gz, gw = quat.multiply_parts(quat.conjugate_parts(e), f)
    gx, gy, gz = fb.kernel_vector(gx, gy, gz, lam)          # the step in principal axes
    wn = fb.kernel_vector(n1, n2, n3, lam)
    if not math.isfinite(gx + gy + gz + gw + wn[0] + wn[1] + wn[2]):
        return _uniform1(q, o1, o2, o3, h)
    return qmul_unit(q, (gx, gy, gz, gw)), wn


def free_flow(moments, quat, omega, h):
    r"""Exact torque-free motion of rigid bodies over one interval ``h``.

    Parameters
    ----------
    moments : (N, 3) or (3,) array
        Principal moments, sorted ``A <= B <= C`` (any unit).
    quat : (N, 4) or (4,) array
        Principal -> inertial quaternions, scalar-last, unit.
    omega : (N, 3) or (3,) array
        Principal-frame rates, rad/s.
    h : float
        Interval, s (any sign).

    Returns
    -------
    quat, omega : arrays of the input shapes, at ``t + h``.

    Notes
    -----
    (S1) Kernel frame: the principal axes ``(A, B, C)`` when ``L^2 >= 2EB`` (SAM), else
    ``(C, B, A)`` along ``(e3, -e2, e1)`` (LAM, right-handed), with moments
    ``I1, I2, I3`` and signed differences ``d_ij = I_i - I_j``.  There
    ``omega = (a1 cn u, a2 sn u, a3 dn u)`` with ``u = u0 + lambda t``,
    ``m = d21 (2E I3 - L^2) / (d32 (L^2 - 2E I1))``,
    ``lambda^2 = d32 (L^2 - 2E I1) / (I1 I2 I3)``.

    (S2) The addition theorems of ``sn, cn, dn`` with ``v = lambda h`` give the new
    rates without dividing by an amplitude::

        D   = 1 - I2 d21 / (L^2 - 2E I1) * w2^2 sn^2 v
        w1' = (w1 cn v - d32/I1 w2 w3 sn v/lambda dn v) / D
        w2' = (w2 cn v dn v + d31/I2 w1 w3 sn v/lambda) / D
        w3' = (w3 dn v - d21/I3 w1 w2 sn v/lambda cn v) / D

    (S3) With the 3-1-3 angles ``(phi, theta, psi)`` of the body relative to a frame
    whose z axis is L, ``theta`` and ``psi`` are algebraic in the body components of L
    and ``phi' = L/I3 + c1 / (1 + nu sn^2 u)``, ``c1 = L d31 / (I1 I3)``,
    ``nu = I3 d21 / (I1 d32)``, so

    .. math::

        \Delta\phi = h\,(L/I_3 + c_1) - \frac{c_1}{\lambda}\,[J(u_0 + v) - J(u_0)],
        \qquad J(u) = \int_0^u \frac{\nu\,\mathrm{sn}^2}{1 + \nu\,\mathrm{sn}^2}\,du ,

    with ``J(u) = (nu/3) sn^3 R_J(cn^2, dn^2, 1, 1 + nu sn^2)`` for ``|u| <= K``
    (DLMF 19.25.14) and ``J(u + 2K) = J(u) + 2 J(K)``: the half-period window of ``u``
    has the parity of the sign of ``cn``, so a step with ``|v| < 2K`` crosses a window
    boundary exactly when ``cn`` changes sign; longer steps locate ``u0`` with
    ``R_F`` (DLMF 19.25.5).

    (S4) ``q(t+h) = q(t) E(t)^-1 E(t+h)`` with ``E = Rz(phi) Rx(theta) Rz(psi)``.

    (S5) Spherical bodies, pure principal-axis spins (transverse L below 1e-100
    relative) and bodies at rest rotate uniformly about ``omega``.

    Accuracy: a few ulp per step (tested against
    :func:`attitude.propagation.torquefree.free_rotation` in ``tests/test_splitting.py``);
    near the separatrix the motion itself is ill-conditioned and ``scipy.special.ellipj``
    loses ~``eps / m1`` relative.

    Examples
    --------
    >>> import numpy as np
    >>> from attitude.propagation.splitting import free_flow
    >>> from attitude.propagation.torquefree import free_rotation
    >>> I, q0, w0 = np.array([1.0, 2.0, 3.0]), np.array([0, 0, 0, 1.0]), np.array([0.1, 0.2, 1.0])
    >>> q1, w1 = free_flow(I, q0, w0, 2.5)
    >>> q2, w2 = free_rotation(I, q0, w0, [2.5])
    >>> bool(np.allclose(w1, w2[0], rtol=0, atol=1e-14) and abs(abs(q1 @ q2[0]) - 1) < 1e-14)
    True
    """
    moments = np.asarray(moments, dtype=float)
    quat = np.asarray(quat, dtype=float)
    omega = np.asarray(omega, dtype=float)
    single = quat.ndim == 1
    q, w = free_flow_batch(FreeConstants(moments), np.atleast_2d(quat),
                          np.atleast_2d(omega), float(h))
    return (q[0], w[0]) if single else (q, w)


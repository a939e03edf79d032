r"""Splitting integrators: the exact free rigid-body flow composed with torque kicks.

Euler's equations with a torque split into two vector fields,

.. math::

    \underbrace{\dot q = \tfrac12 q\otimes\omega,\;
    I\dot\omega = I\omega\times\omega}_{\text{free rigid body } F}
    \;+\;
    \underbrace{\dot q = 0,\; I\dot\omega = M(t, q, \omega)}_{\text{kick } K} ,

each of which is solved on its own: the free flow :math:`\varphi^F_h` *exactly*
(Jacobi elliptic functions and an elliptic integral of the third kind, see
:func:`free_flow`), the kick with the attitude frozen.  For a torque that depends on
the attitude only (gravity gradient, constant, heavy-top pivot:
``velocity_dependent = False``) the kick is exact, ``omega += h I^-1 M(t, q)``, and is
the flow of the potential energy: every composition of these flows is a Lie–Poisson
(symplectic) map, and a symmetric composition is time-reversible.  Velocity-dependent
torques (eddy currents) are integrated inside the kick by a Runge–Kutta step with the
attitude frozen (explicit midpoint for order 2, classical RK4 otherwise).  Internal
torques (``internal = True``: dissipation) turn ``L`` in the body frame only: their kick
also turns the attitude, at ``(M x L)/L^2``, and ends by restoring the inertial ``L``, so
that it does not drift (``_System.internal_kick``).

Compositions (``order=`` / ``scheme=``; ``K(b h) F(a h) K(...) ...``):

=======================  =====  =====================================================
scheme                   order  free flows per step (kicks merge between steps)
=======================  =====  =====================================================
``"strang"``             2      1  (Strang 1968; Touma & Wisdom 1994 for the rigid body)
``"yoshida4"``           4      3  (Yoshida 1990 triple jump: cheap, large error)
``"blanes-moan"``        4      6  (Blanes & Moan 2002, S6: any splitting)
``"blanes-moan-rkn"``    4      6  (Blanes & Moan 2002, SRKN6b: attitude-only torques)
``"yoshida6"``           6      7  (Yoshida 1990, solution A)
=======================  =====  =====================================================

``order=4`` (the default) takes ``"blanes-moan-rkn"`` when every torque depends on the
attitude only (its order conditions use ``[K, [K, [K, F]]] = 0``, true for such kicks
as for ``p^2/2 + V(q)``; ~10x smaller error than S6 at the same cost), else
``"blanes-moan"``.  With velocity-dependent torques the order is ``min(order, 4)`` (the
RK sub-step is of order 2 for Strang, 4 otherwise; the limit shows only when the damping
is fast on the step).  With no torque at all every scheme is the exact solution to
round-off.  The default step is :func:`choose_step`: set by the torques' own time scales
(:meth:`attitude.model.torques.TorqueModel.characteristic_rate`) and by how fast each torque
changes along the free motion, not by the spin.  ``docs/integrators.md`` has the
formulas, the measured orders, accuracy and timings, and which method to use when.

Time is carried in the extended phase space: the free flow advances ``t``, the kick is
evaluated at the current ``t`` (so orbit-dependent torques keep the order of the
scheme, and symmetric schemes remain time-reversible).

References
----------
.. [1] Touma, J. & Wisdom, J. (1994). Lie-Poisson integrators for rigid body dynamics
   in the solar system. *Astron. J.* 107, 1189-1202.
.. [2] Celledoni, E., Fassò, F., Säfström, N. & Zanna, A. (2008). The exact
   computation of the free rigid body motion and its use in splitting methods.
   *SIAM J. Sci. Comput.* 30, 2084-2112.
.. [3] McLachlan, R. I. & Quispel, G. R. W. (2002). Splitting methods. *Acta Numerica*
   11, 341-434.
.. [4] Yoshida, H. (1990). Construction of higher order symplectic integrators.
   *Phys. Lett. A* 150, 262-268.
.. [5] Blanes, S. & Moan, P. C. (2002). Practical symplectic partitioned Runge-Kutta and
   Runge-Kutta-Nyström methods. *J. Comput. Appl. Math.* 142, 313-330.
.. [6] Carlson, B. C. (1995). Numerical computation of real or complex elliptic
   integrals. *Numer. Algorithms* 10, 13-26; DLMF §19.25, §22.
"""

from __future__ import annotations

import math
import sys
import time as _time
from collections.abc import Sequence

import numpy as np
from scipy import special as sp

from ..deprecation import moved_attribute
from ..foundations import quaternion as quat
from ..foundations.errors import InvalidStateError, PropagationError
from ..model import freebody as fb
from ..model.body import RigidBody, as_bodies, to_body_frame, to_principal_frame
from ..model.freebody import EQUAL_MOMENTS_RTOL, PURE_SPIN_TOL_UNSCALED
from ..model.torques import as_torque_model
from . import compiled, compiled_loop
from .compiled_torques import compile_torques
from .reference import checked_rtol

__all__ = [
    "integrate_splitting",
    "free_flow",
    "choose_step",
    "SCHEMES",
    "DEFAULT_SCHEME",
    "STEPS_PER_PERIOD",
    "step_count",
]

# The free flow's tolerances are those of attitude.freebody: EQUAL_MOMENTS_RTOL (a
# spherical body rotates uniformly) and PURE_SPIN_TOL_UNSCALED (a principal-axis spin
# rotates uniformly; this kernel works on unscaled rates, see its comment there).


#: scipy.special.ellipj (Cephes) switches to its expansion about m = 1 from this m on; the
#: expansion fails past the first quarter period (sn > 1, cn ~ -3e5 at u = 40,
#: m = 1 - 1e-11), so there the free flow takes compiled.ellipj (Landen from 1 - m).
_CEPHES_NEAR1 = 0.9999999999


def __getattr__(name):
    # names that moved to another module: a DeprecationWarning naming the new home
    return moved_attribute(__name__, name)


# ===========================================================================
# the exact free flow over one step
# ===========================================================================
class _FreeConstants:
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


def _free_flow_vec(c: _FreeConstants, q: np.ndarray, w: np.ndarray, h: float):
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
    return _qmul1(q, (sh * o1, sh * o2, sh * o3, math.cos(half))), (o1, o2, o3)


def _qmul1(q, g):
    """Normalised product ``q g`` of component quaternions (plain floats)."""
    nx, ny, nz, nw = quat.multiply_parts(q, g)
    r = 1.0 / math.sqrt(nx * nx + ny * ny + nz * nz + nw * nw)
    return (nx * r, ny * r, nz * r, nw * r)


def _clip1(x, lo, hi):
    return lo if x < lo else (hi if x > hi else x)


def _free_flow1(k: tuple, q: tuple, w: tuple, h: float):
    """The same step as :func:`_free_flow_vec` for one body in plain floats (a numpy
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
    return _qmul1(q, (gx, gy, gz, gw)), wn


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
    q, w = _free_flow_vec(_FreeConstants(moments), np.atleast_2d(quat),
                          np.atleast_2d(omega), float(h))
    return (q[0], w[0]) if single else (q, w)


# ===========================================================================
# compositions
# ===========================================================================
def _strang_chain(w: Sequence[float]) -> tuple:
    """Kick/free coefficients of a composition of Strang steps ``S(w_i h)``."""
    ops = []
    for wi in w:
        ops += [("K", wi / 2), ("F", wi), ("K", wi / 2)]
    return tuple(ops)


def _alternating(first: str, coefficients: Sequence[float]) -> tuple:
    other = "F" if first == "K" else "K"
    return tuple((first if i % 2 == 0 else other, c) for i, c in enumerate(coefficients))


_CBRT2 = 2.0 ** (1.0 / 3.0)
_Y1 = 1.0 / (2.0 - _CBRT2)
_Y0 = -_CBRT2 / (2.0 - _CBRT2)
# Yoshida (1990), Table 1, solution A
_W6 = (0.784513610477560, 0.235573213359357, -1.17767998417887)
_W6_0 = 1.0 - 2.0 * sum(_W6)
# Blanes & Moan (2002), Table 2, S6 (order 4, 6 stages): a_1..a_4 and b_1..b_3
_BM_A = (0.0792036964311957, 0.353172906049774, -0.0420650803577195)
_BM_B = (0.209515106613362, -0.143851773179818)
_BM_A4 = 1.0 - 2.0 * sum(_BM_A)
_BM_B3 = 0.5 - sum(_BM_B)
_BM = (_BM_A[0], _BM_B[0], _BM_A[1], _BM_B[1], _BM_A[2], _BM_B3, _BM_A4, _BM_B3,
       _BM_A[2], _BM_B[1], _BM_A[1], _BM_B[0], _BM_A[0])
# Blanes & Moan (2002), Table 3, SRKN_6^b (order 4, 6 stages) for splittings whose kick
# part B satisfies [B, [B, [B, A]]] = 0: true here for attitude-only torques (the kick
# is a momentum translation by a function of the attitude and time, the free part a
# kinetic energy quadratic in the momenta, as in H = p^2/2 + V(q)).
_RKN_B = (0.0829844064174052, 0.396309801498368, -0.0390563049223486)
_RKN_A = (0.245298957184271, 0.604872665711080)
_RKN_B4 = 1.0 - 2.0 * sum(_RKN_B)
_RKN_A3 = 0.5 - sum(_RKN_A)
_RKN = (_RKN_B[0], _RKN_A[0], _RKN_B[1], _RKN_A[1], _RKN_B[2], _RKN_A3, _RKN_B4, _RKN_A3,
        _RKN_B[2], _RKN_A[1], _RKN_B[1], _RKN_A[0], _RKN_B[0])

#: Compositions: name -> (order, ops), ops a tuple of ``("K" | "F", coefficient)``
#: applied left to right (kick = torque, free = exact free flow; ``sum`` of each kind
#: is 1).  All are symmetric.
SCHEMES: dict[str, tuple[int, tuple]] = {
    "strang": (2, _strang_chain([1.0])),
    "yoshida4": (4, _strang_chain([_Y1, _Y0, _Y1])),
    "blanes-moan": (4, _alternating("K", _BM)),
    "blanes-moan-rkn": (4, _alternating("K", _RKN)),
    "yoshida6": (6, _strang_chain([_W6[0], _W6[1], _W6[2], _W6_0, _W6[2], _W6[1],
                                   _W6[0]])),
}
#: Default scheme of each order (order 4 uses ``"blanes-moan-rkn"`` instead when every
#: torque depends on the attitude only).
DEFAULT_SCHEME = {2: "strang", 4: "blanes-moan", 6: "yoshida6"}
#: Schemes that need attitude-only kicks (their order conditions assume
#: ``[B, [B, [B, A]]] = 0``).
RKN_SCHEMES = ("blanes-moan-rkn",)


def _merge(ops) -> list:
    out = []
    for kind, cc in ops:
        if out and out[-1][0] == kind:
            out[-1] = (kind, out[-1][1] + cc)
        else:
            out.append((kind, cc))
    return out


def _resolve_scheme(order, scheme, attitude_only: bool = False) -> tuple[str, int, tuple]:
    if scheme is None and order is None:
        order = 4
    if scheme is None:
        if order not in DEFAULT_SCHEME:
            raise InvalidStateError(f"order={order!r} is not available; choose one of "
                                    f"{sorted(DEFAULT_SCHEME)}")
        scheme = DEFAULT_SCHEME[order]
        if order == 4 and attitude_only:
            scheme = "blanes-moan-rkn"
    if scheme not in SCHEMES:
        raise InvalidStateError(f"scheme {scheme!r} is unknown; choose one of "
                                f"{tuple(SCHEMES)}")
    sorder, ops = SCHEMES[scheme]
    if order is not None and order != sorder:
        raise InvalidStateError(f"scheme {scheme!r} is of order {sorder}, not {order}")
    return scheme, sorder, ops


# ===========================================================================
# bodies, torques and the kick
# ===========================================================================
def _terms(torques) -> list:
    """Flatten torque models (sums included) into their terms."""
    if torques is None:
        return []
    if callable(torques) and not isinstance(torques, (list, tuple)):
        torques = [torques]
    out = []
    for model in torques:
        if not callable(model):
            raise InvalidStateError(f"torques: expected callables torque(t, quaternion, "
                                    f"omega_body, body), got {type(model).__name__}")
        sub = getattr(model, "terms", None)
        out.extend(_terms(list(sub)) if isinstance(sub, tuple) else [model])
    return out


def _is_conservative(model) -> bool:
    """Attitude-only torque (declared ``velocity_dependent = False``)?  Plain functions
    without the attribute are treated as velocity-dependent (the safe choice)."""
    return getattr(model, "velocity_dependent", True) is False


def _is_internal(model) -> bool:
    """A torque between parts of the body (``internal = True``): it keeps the inertial
    angular momentum (:attr:`attitude.model.torques.TorqueModel.internal`)."""
    return getattr(model, "internal", False) is True


class _System:
    """Everything the stepping loop needs about the bodies and torques."""

    def __init__(self, bodies: list[RigidBody], torques):
        self.bodies = bodies
        self.n = len(bodies)
        batch, _ = as_bodies(bodies)
        self.body_arg = bodies[0] if self.n == 1 else batch
        terms = _terms(torques)
        self.terms = terms
        self.internal_terms = [m for m in terms if _is_internal(m)]
        self.kick_terms = [m for m in terms if _is_conservative(m) and not _is_internal(m)]
        self.drag_terms = [m for m in terms
                           if not _is_conservative(m) and not _is_internal(m)]
        self.moments = batch.principal_moments
        self.inv_moments = 1.0 / self.moments
        self.q_bp = batch.body_to_principal
        self.identity = bool(np.all(self.q_bp == np.array([0.0, 0.0, 0.0, 1.0])))
        self.free = _FreeConstants(self.moments)

    # --- frames ----------------------------------------------------------------------
    def to_principal(self, q_b: np.ndarray, w_b: np.ndarray):
        """Body-frame quaternions (N, 4) and rates (N, 3) -> principal frame."""
        if self.identity:
            return q_b.copy(), w_b.copy()
        return to_principal_frame(q_b, w_b, self.q_bp)

    def to_body(self, q_p: np.ndarray, w_p: np.ndarray):
        if self.identity:
            return q_p.copy(), w_p.copy()
        return to_body_frame(q_p, w_p, self.q_bp)

    # --- torques -----------------------------------------------------------------------
    def _torque(self, models, t, q_p, w_p):
        """Summed body-frame torque of ``models`` -> principal angular acceleration."""
        q_b, w_b = self.to_body(q_p, w_p)
        total = None
        if self.n == 1:
            for model in models:
                out = np.asarray(model(t, q_b[0], w_b[0], self.body_arg), dtype=float)
                total = out if total is None else total + out
            total = np.reshape(total, (1, 3)) if total.size == 3 else total
        else:
            for model in models:
                out = np.asarray(model(t, q_b, w_b, self.body_arg), dtype=float)
                total = out if total is None else total + out
        if total.shape != (self.n, 3):
            try:
                total = np.broadcast_to(total, (self.n, 3))
            except ValueError:
                raise InvalidStateError(f"a torque model returned shape {total.shape}; "
                                        f"expected ({self.n}, 3) body-frame N m") from None
        if not self.identity:
            total = quat.rotate(self.q_bp, total)
        return total * self.inv_moments

    def accel_kick(self, t, q_p, w_p):
        return self._torque(self.kick_terms, t, q_p, w_p)

    def accel_drag(self, t, q_p, w_p):
        return self._torque(self.drag_terms, t, q_p, w_p)

    def internal_kick(self, t, q, w, tau, rk_order, anchor=None):
        """The kick with internal torques, over ``tau`` at the frozen time ``t``.

        The vector field is ``dL/dt = M_ext(q, w) + M_int(w)`` in the principal frame with
        the attitude moving at the extra rate ``(M_int x L)/L^2`` only (the rigid rotation
        at ``w`` is the free flow's).  Explicit midpoint (``rk_order = 2``) or RK4 on
        ``(w, p, L_ext)``, ``p`` the attitude increment (``q(s) = q p(s)``) and
        ``L_ext`` the inertial angular momentum given by the external torques alone;
        then the new body-frame ``L`` is set to ``q'^-1 (L_inertial(0) + L_ext)``: with
        internal torques only, ``anchor`` is the inertial ``L`` of the start of the run,
        restored to round-off at every kick (no drift accumulates); with external
        torques too, ``L`` changes only by theirs.
        """
        moments = self.moments
        external = self.kick_terms + self.drag_terms
        one = np.zeros_like(q)
        one[:, 3] = 1.0

        def field(wv, p):
            qs = quat.multiply(q, p)
            qs = qs / np.sqrt(np.sum(qs * qs, axis=1, keepdims=True))
            L = wv * moments
            a_int = self._torque(self.internal_terms, t, qs, wv)
            m_int = a_int * moments
            L2 = np.sum(L * L, axis=1, keepdims=True)
            extra = np.where(L2 > 0, _cross(m_int, L) / np.where(L2 > 0, L2, 1.0), 0.0)
            dp = 0.5 * quat.multiply(p, np.concatenate([extra, np.zeros((len(p), 1))], axis=1))
            if external:
                a_ext = self._torque(external, t, qs, wv)
                return a_int + a_ext, dp, quat.rotate(qs, a_ext * moments)
            return a_int, dp, None

        def step(y, k, c):
            wv, p, le = y
            return (wv + c * k[0], p + c * k[1], None if k[2] is None else le + c * k[2])

        y0 = (w, one, np.zeros_like(w))
        k1 = field(w, one)
        if rk_order == 2:
            k2 = field(*step(y0, k1, 0.5 * tau)[:2])
            w1, p1, le1 = step(y0, k2, tau)
        else:
            y = step(y0, k1, 0.5 * tau)
            k2 = field(y[0], y[1])
            y = step(y0, k2, 0.5 * tau)
            k3 = field(y[0], y[1])
            y = step(y0, k3, tau)
            k4 = field(y[0], y[1])
            incr = tuple(None if k1[i] is None else
                         k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i] for i in range(3))
            w1, p1, le1 = step(y0, incr, tau / 6.0)
        q1 = quat.multiply(q, p1)
        q1 = q1 / np.sqrt(np.sum(q1 * q1, axis=1, keepdims=True))
        if anchor is not None and le1 is None:
            L_in = anchor
        else:
            L_in = quat.rotate(q, w * moments)
            if le1 is not None:
                L_in = L_in + le1
        w1 = quat.rotate(quat.conjugate(q1), L_in) / moments
        return q1, w1


def _cross(a, b):
    return np.stack([a[:, 1] * b[:, 2] - a[:, 2] * b[:, 1],
                     a[:, 2] * b[:, 0] - a[:, 0] * b[:, 2],
                     a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]], axis=1)


# ===========================================================================
# step size
# ===========================================================================
#: Default number of steps per shortest time scale (``2 pi / rate``) of each order
#: (see :func:`choose_step` and docs/integrators.md for the calibration).
STEPS_PER_PERIOD = {2: 1000, 4: 300, 6: 200}


def _own_rates(model, system: _System, t0: float, q_p, w_p) -> np.ndarray:
    """The model's own rate (``TorqueModel.characteristic_rate``), rad/s, per body."""
    q_b, w_b = system.to_body(q_p, w_p)
    model = as_torque_model(model)
    if system.n == 1:
        rate = model.characteristic_rate(t0, q_b[0], w_b[0], system.body_arg)
    else:
        rate = model.characteristic_rate(t0, q_b, w_b, system.body_arg)
    return np.broadcast_to(np.asarray(rate, dtype=float), (system.n,))


def _variation_rates(model, system: _System, t0: float, q_p, w_p, order: int
                     ) -> np.ndarray:
    """How fast the model's torque, in inertial axes, varies along the exact free flow
    (time frozen), rad/s, per body: ``max_j (|d^j M / ds^j| / |M|)^(1/j)`` for
    ``j = 1, 2`` and, above order 2, 4, from central differences over the free flow at
    spacing ``0.05 / |omega|``.  Differences at the level of their rounding count as
    zero: a relative variation below ~1e-7 of the torque is not resolved, and need not
    be (sampled at any step it moves the result by about that fraction of the torque's
    effect)."""
    spin = np.sqrt(np.sum(w_p * w_p, axis=1))
    moving = spin > 0
    delta = np.where(moving, 0.05 / np.where(moving, spin, 1.0), 0.0)
    torque = {}
    for k in (-2, -1, 0, 1, 2):
        if k == 0:
            qk, wk = q_p, w_p
        else:
            qk, wk = _free_flow_vec(system.free, q_p, w_p, k * delta)
        m = system._torque([model], t0, qk, wk) * system.moments
        torque[k] = quat.rotate(qk, m)
    scale = np.max([np.sqrt(np.sum(m * m, axis=1)) for m in torque.values()], axis=0)
    ok = moving & (scale > 0)
    d = np.where(ok, delta, 1.0)
    sc = np.where(ok, scale, 1.0)

    def rel(x, weight):
        # above the rounding of the differences (|coefficients| * a generous 64 eps)
        size = np.sqrt(np.sum(x * x, axis=1)) / sc
        return np.maximum(size - 64.0 * np.finfo(float).eps * weight, 0.0)

    nu = np.maximum(rel(torque[1] - torque[-1], 2.0) / (2.0 * d),
                    np.sqrt(rel(torque[1] - 2.0 * torque[0] + torque[-1], 4.0)) / d)
    if order > 2:
        d4 = torque[2] - 4.0 * torque[1] + 6.0 * torque[0] - 4.0 * torque[-1] + torque[-2]
        nu = np.maximum(nu, rel(d4, 16.0) ** 0.25 / d)
    return np.where(ok, np.minimum(nu, spin), 0.0)


def _step_rates(system: _System, q_p, w_p, order: int = 4, t0: float = 0.0
                ) -> np.ndarray:
    """``max over models of max(omega_M, (nu^2 omega_M)^(1/3))`` per body (see
    :func:`choose_step`)."""
    rate = np.zeros(system.n)
    for model in system.terms:
        own = _own_rates(model, system, t0, q_p, w_p)
        nu = _variation_rates(model, system, t0, q_p, w_p, order)
        rate = np.maximum(rate, np.maximum(own, np.cbrt(nu * nu * own)))
    return rate


def choose_step(bodies, quat0, omega0, torques=(), *, order: int = 4,
                steps_per_period: float | None = None, t0: float = 0.0) -> float:
    r"""The default step of :func:`integrate_splitting`, s: set by the torques' own time
    scales, not by the spin, which the exact free flow carries.

    ``h = 2 pi / (N * rate)``, ``N = STEPS_PER_PERIOD[order]`` (1000, 300, 200 for
    orders 2, 4, 6), with, over the torque models and the bodies of a batch,

    .. math::

        \mathrm{rate} = \max\big(\omega_M,\ (\nu^2 \omega_M)^{1/3}\big)

    * ``omega_M`` is the model's own rate, :meth:`~attitude.torques.TorqueModel.characteristic_rate`
      at ``(t0, quat0, omega0)`` (gravity gradient: ``sqrt(3 mu / r_p^3)`` or the
      orbital rate at periapsis; dissipation: ``1 / time_constant``; eddy currents: the
      damping rate; heavy top: the pendulum frequency; a user model: from its torque);
    * ``nu`` is how fast the model's torque, seen in inertial axes, changes along the
      exact free flow itself: measured by the integrator from central differences of
      the torque over the free flow (``j = 1, 2, 4``-th derivatives,
      ``max_j (|M^(j)| / |M|)^(1/j)``), at most the spin rate ``|omega0|``.

    A splitting with the exact free flow makes errors only through the commutators of
    the kick with the free flow, which grow with the torque's rate of change *along* the
    free motion, not with the spin: a spin about the axis of a symmetric top, or about
    a principal axis under eddy currents in a uniform field, leaves the inertial torque
    (nearly) unchanged, and the step is that of the torque alone.  For a triaxial
    tumbler under gravity gradient (the inertial torque turns at up to twice the spin)
    ``nu`` reaches the spin and the rule is the previous one, ``(Omega^2
    omega_M)^(1/3)``, for which ``N`` was calibrated (~1e-10 relative accuracy over a
    few orbits at order 4 and 6, ~1e-6 at order 2; docs/integrators.md has the
    measurements).  Only the protocol of :class:`~attitude.model.torques.TorqueModel` is used
    (``characteristic_rate`` and the call), so a user's model is treated like the
    built-in ones.  Returns ``inf`` without torques (the free flow is exact in one
    step).

    Examples
    --------
    >>> import math
    >>> from attitude.propagation.splitting import choose_step, STEPS_PER_PERIOD
    >>> from attitude.model.torques import EnergyDissipation
    >>> h = choose_step([1.0, 2.0, 3.0], [0, 0, 0, 1], [0.0, 0.0, 5.0],  # pure spin about C
    ...                 [EnergyDissipation(600.0)])
    >>> bool(math.isclose(h, 2 * math.pi * 600.0 / STEPS_PER_PERIOD[4]))
    True
    >>> choose_step([1.0, 2.0, 3.0], [0, 0, 0, 1], [0.1, 0.2, 0.3])   # no torque
    inf
    """
    body_list, _ = as_bodies(bodies)
    system = _System(body_list, torques)
    q0 = np.atleast_2d(np.asarray(quat0, dtype=float))
    w0 = np.atleast_2d(np.asarray(omega0, dtype=float))
    q_p, w_p = system.to_principal(np.broadcast_to(q0, (system.n, 4)).copy(),
                                   np.broadcast_to(w0, (system.n, 3)).copy())
    return _choose_step(system, q_p, w_p, order, steps_per_period, float(t0))


def _choose_step(system, q_p, w_p, order, steps_per_period, t0: float = 0.0) -> float:
    per = STEPS_PER_PERIOD[order] if steps_per_period is None else float(steps_per_period)
    if not system.terms:
        return math.inf
    rate = float(np.max(_step_rates(system, q_p, w_p, order, t0)))
    if not rate > 0 or not math.isfinite(rate):
        return math.inf
    return 2.0 * math.pi / (per * rate)


# ===========================================================================
# progress
# ===========================================================================
class _Progress:
    """``tqdm`` when installed, else a one-line stderr counter (at most every 0.5 s);
    counts simulated seconds."""

    def __init__(self, total: float, enabled: bool):
        self.total = max(float(total), 1e-300)
        self.done = 0.0
        self.bar = None
        self.enabled = enabled
        self.t0 = self.last = _time.monotonic()
        if not enabled:
            return
        try:
            from tqdm.auto import tqdm  # optional (a progress bar when installed)
        except ImportError:
            return
        self.bar = tqdm(total=self.total, unit="s", unit_scale=True, desc="splitting",
                        leave=False)

    def update(self, dt: float) -> None:
        if not self.enabled:
            return
        self.done += dt
        if self.bar is not None:
            self.bar.update(dt)
            return
        now = _time.monotonic()
        if now - self.last >= 0.5 or self.done >= self.total * (1 - 1e-12):
            self.last = now
            pct = 100.0 * min(self.done / self.total, 1.0)
            sys.stderr.write(f"\rsplitting: {pct:5.1f}% ({self.done:.6g} of {self.total:.6g}"
                             f" s simulated, {now - self.t0:.1f} s)")
            sys.stderr.flush()

    def close(self) -> None:
        if not self.enabled:
            return
        if self.bar is not None:
            self.bar.close()
        else:
            sys.stderr.write("\n")
            sys.stderr.flush()


# ===========================================================================
# stepping
# ===========================================================================
class _Batch:
    """State operations on (N, 4) / (N, 3) principal-frame arrays."""

    def __init__(self, system: _System):
        self.s = system

    def free(self, q, w, h):
        return _free_flow_vec(self.s.free, q, w, h)

    def acc_kick(self, t, q, w):
        return self.s.accel_kick(t, q, w)

    def acc_drag(self, t, q, w):
        return self.s.accel_drag(t, q, w)

    def internal(self, t, q, w, tau, rk_order, anchor):
        return self.s.internal_kick(t, q, w, tau, rk_order, anchor)

    @staticmethod
    def axpy(w, tau, a):
        return w + tau * a

    @staticmethod
    def add(a, b):
        return a + b

    def store(self, out_q, out_w, j, q, w):
        out_q[:, j] = q
        out_w[:, j] = w


class _One:
    """The same operations for one body on tuples of floats (numpy costs ~1 us per call
    on one element: the one-body path would otherwise be dominated by call overhead)."""

    def __init__(self, system: _System):
        self.s = system
        self.k = system.free.row(0)
        self.inv = tuple(float(x) for x in system.inv_moments[0])
        self.identity = system.identity
        self.q_bp_t = tuple(system.q_bp[0].tolist())
        self.body = system.body_arg

    def free(self, q, w, h):
        return _free_flow1(self.k, q, w, h)

    def _acc(self, models, t, q, w):
        if self.identity:
            q_b, w_b = np.array(q), np.array(w)
        else:
            q_b = np.array(_qmul1(q, self.q_bp_t))
            w_b = np.array(quat.rotate_parts(self.q_bp_t, w, inverse=True))
        total = None
        for model in models:
            out = np.asarray(model(t, q_b, w_b, self.body), dtype=float)
            total = out if total is None else total + out
        if total.size != 3:
            raise InvalidStateError(f"a torque model returned shape {total.shape}; "
                                    "expected (3,) body-frame N m")
        m = total.ravel().tolist()
        if not self.identity:
            m = quat.rotate_parts(self.q_bp_t, m)
        i1, i2, i3 = self.inv
        return (m[0] * i1, m[1] * i2, m[2] * i3)

    def acc_kick(self, t, q, w):
        return self._acc(self.s.kick_terms, t, q, w)

    def acc_drag(self, t, q, w):
        return self._acc(self.s.drag_terms, t, q, w)

    def internal(self, t, q, w, tau, rk_order, anchor):
        """:meth:`_System.internal_kick` in plain floats (see there)."""
        external = self.s.kick_terms + self.s.drag_terms
        if external:                      # rare: the array version is good enough
            q1, w1 = self.s.internal_kick(t, np.array([q]), np.array([w]), tau, rk_order,
                                          anchor)
            return tuple(q1[0].tolist()), tuple(w1[0].tolist())
        I1, I2, I3 = (float(x) for x in self.s.moments[0])

        def field(wv, p):
            qs = _qmul1(q, p)
            a = self._acc(self.s.internal_terms, t, qs, wv)
            m0, m1, m2 = a[0] * I1, a[1] * I2, a[2] * I3
            L0, L1, L2 = wv[0] * I1, wv[1] * I2, wv[2] * I3
            LL = L0 * L0 + L1 * L1 + L2 * L2
            if LL > 0:
                ex = (m1 * L2 - m2 * L1) / LL
                ey = (m2 * L0 - m0 * L2) / LL
                ez = (m0 * L1 - m1 * L0) / LL
            else:
                ex = ey = ez = 0.0
            px, py, pz, pw = p                         # dp = p (extra, 0) / 2
            dp = (0.5 * (pw * ex + py * ez - pz * ey), 0.5 * (pw * ey - px * ez + pz * ex),
                  0.5 * (pw * ez + px * ey - py * ex), -0.5 * (px * ex + py * ey + pz * ez))
            return a, dp

        def ax(y, c, k):
            return tuple(yi + c * ki for yi, ki in zip(y, k))

        one = (0.0, 0.0, 0.0, 1.0)
        k1 = field(w, one)
        if rk_order == 2:
            k2 = field(ax(w, 0.5 * tau, k1[0]), ax(one, 0.5 * tau, k1[1]))
            w1, p1 = ax(w, tau, k2[0]), ax(one, tau, k2[1])
        else:
            k2 = field(ax(w, 0.5 * tau, k1[0]), ax(one, 0.5 * tau, k1[1]))
            k3 = field(ax(w, 0.5 * tau, k2[0]), ax(one, 0.5 * tau, k2[1]))
            k4 = field(ax(w, tau, k3[0]), ax(one, tau, k3[1]))
            p1 = tuple(o + tau / 6.0 * (a + 2.0 * b + 2.0 * c + d)
                       for o, a, b, c, d in zip(one, k1[1], k2[1], k3[1], k4[1]))
            w1 = tuple(o + tau / 6.0 * (a + 2.0 * b + 2.0 * c + d)
                       for o, a, b, c, d in zip(w, k1[0], k2[0], k3[0], k4[0]))
        q1 = _qmul1(q, p1)                                   # normalised
        del w1                                   # superseded by the restored L
        L_in = (anchor[0] if anchor is not None
                else quat.rotate(np.array(q), np.array(w) * self.s.moments[0]))
        Lb = quat.rotate(quat.conjugate(np.array(q1)), L_in).tolist()
        return q1, (Lb[0] / I1, Lb[1] / I2, Lb[2] / I3)

    @staticmethod
    def axpy(w, tau, a):
        return (w[0] + tau * a[0], w[1] + tau * a[1], w[2] + tau * a[2])

    @staticmethod
    def add(a, b):
        return (a[0] + b[0], a[1] + b[1], a[2] + b[2])

    def store(self, out_q, out_w, j, q, w):
        out_q[0, j] = q
        out_w[0, j] = w


def _kick(ops, t, q, w, tau, cached, has_kick: bool, has_drag: bool, rk_order: int):
    """Advance ``w`` by the torques over ``tau`` with the attitude and time frozen.

    Attitude-only torques: the exact flow ``w += tau a``; with velocity-dependent
    torques: explicit midpoint (``rk_order = 2``) or classical RK4 on
    ``dw/dt = a + a_drag(w)``.  Returns ``(w, cached)``, ``cached`` the attitude-only
    acceleration at ``(t, q)`` for reuse.
    """
    a = None
    if has_kick:
        a = cached if cached is not None else ops.acc_kick(t, q, w)
        cached = a
        if not has_drag:
            return ops.axpy(w, tau, a), cached

    def f(wv):
        d = ops.acc_drag(t, q, wv)
        return d if a is None else ops.add(a, d)

    k1 = f(w)
    if rk_order == 2:
        return ops.axpy(w, tau, f(ops.axpy(w, 0.5 * tau, k1))), cached
    k2 = f(ops.axpy(w, 0.5 * tau, k1))
    k3 = f(ops.axpy(w, 0.5 * tau, k2))
    k4 = f(ops.axpy(w, tau, k3))
    incr = ops.add(ops.add(k1, k4), ops.axpy(k2, 1.0, k3))
    incr = ops.axpy(incr, 1.0, ops.axpy(k2, 1.0, k3))     # k1 + 2 k2 + 2 k3 + k4
    return ops.axpy(w, tau / 6.0, incr), cached


def _segments(t: np.ndarray) -> list[np.ndarray]:
    """Indices of the outputs, per direction (t >= 0, then t < 0), in order of |t|."""
    out = []
    for sign in (1.0, -1.0):
        idx = np.flatnonzero(t >= 0) if sign > 0 else np.flatnonzero(t < 0)
        if idx.size:
            out.append(idx[np.argsort(sign * t[idx], kind="stable")])
    return out


def step_count(dt: float, h_max: float) -> int:
    """Number of equal steps no longer than ``h_max`` that cover ``dt``.

    Examples
    --------
    >>> step_count(10.0, 3.0), step_count(9.0, 3.0), step_count(0.0, 3.0)
    (4, 3, 0)
    """
    if dt == 0.0:
        return 0
    if not math.isfinite(h_max):
        return 1
    return max(1, math.ceil(abs(dt) / h_max * (1.0 - 1e-12)))


#: Embedded composition of each scheme for the error estimate of ``rtol=`` (see
#: :func:`integrate_splitting`): a cheaper scheme of the same or lower order whose
#: difference from the step estimates the local error.
EMBEDDED = {"strang": "lie", "yoshida4": "strang", "blanes-moan": "yoshida4",
            "blanes-moan-rkn": "yoshida4", "yoshida6": "blanes-moan"}
_LIE = (1, (("K", 1.0), ("F", 1.0), ("K", 0.0)))      # Lie-Trotter, order 1
#: Relative distance of an output time to a step boundary below which the step is
#: stretched to end on the output (a change of the step at the level of its rounding).
SNAP = 1e-9


class _Scheme:
    """A symmetric composition as kick coefficients ``b[0..m]`` and free-flow
    coefficients ``a[0..m-1]``: ``K(b0 h) F(a0 h) K(b1 h) ... F(a_{m-1} h) K(b_m h)``."""

    def __init__(self, order: int, ops):
        merged = _merge(ops)
        if merged[0][0] != "K":
            merged = [("K", 0.0)] + merged
        if merged[-1][0] != "K":
            merged = merged + [("K", 0.0)]
        self.order = order
        self.b = tuple(c for kind, c in merged if kind == "K")
        self.a = tuple(c for kind, c in merged if kind == "F")


class _Stepper:
    """One composition step of the splitting over ``h``, and the state between steps.

    The loop keeps the state just after the last free flow, ``(q, w)`` at time ``t``,
    and the *pending* kick ``tau`` that closes the step (the last kick of a step and
    the first of the next act at the same time and attitude, so they merge).  The state
    at the step boundary, needed only for outputs and the error estimate, is that state
    with the pending kick applied (:meth:`boundary`).
    """

    def __init__(self, ops, scheme: _Scheme, has_kick, has_drag, has_internal, rk_order,
                 anchor):
        self.ops = ops
        self.scheme = scheme
        self.has_kick, self.has_drag = has_kick, has_drag
        self.has_internal = has_internal
        self.rk_order = rk_order
        self.anchor = anchor
        self.free_flows = 0

    def kick(self, t, q, w, tau, cached):
        if tau == 0.0:
            return q, w, cached
        if self.has_internal:
            q, w = self.ops.internal(t, q, w, tau, self.rk_order, self.anchor)
            return q, w, None
        w, cached = _kick(self.ops, t, q, w, tau, cached, self.has_kick, self.has_drag,
                          self.rk_order)
        return q, w, cached

    def boundary(self, t, q, w, pending, cached):
        """The state at the step boundary ``t``: the pending kick applied."""
        q, w, cached = self.kick(t, q, w, pending, cached)
        return q, w, cached

    def step(self, t, q, w, pending, h, cached, scheme: _Scheme | None = None):
        """One step of ``scheme`` (default the run's) over ``h`` from the state after the
        last free flow with its pending kick: ``(q, w, new pending)`` at ``t + h``."""
        scheme = self.scheme if scheme is None else scheme
        acc = 0.0
        b, a = scheme.b, scheme.a
        for i in range(len(a)):
            q, w, cached = self.kick(t + acc * h, q, w, (pending if i == 0 else 0.0)
                                     + b[i] * h, cached)
            q, w = self.ops.free(q, w, a[i] * h)
            self.free_flows += 1
            cached = None
            acc += a[i]
        return q, w, b[-1] * h


def _rtol_error(w0, q_hi, w_hi, q_lo, w_lo, rtol, w_floor) -> float:
    """Error of a trial step relative to ``rtol``: the larger of ``|dq|`` (the
    quaternion has norm 1; the nearer of ``q`` and ``-q``) and
    ``|dw| / max(|w|, |w'|, w_floor)``, over the bodies."""
    q_hi, q_lo = np.asarray(q_hi, dtype=float), np.asarray(q_lo, dtype=float)
    # q and -q are one attitude: the nearer of the two
    dq = np.minimum(np.sqrt(np.sum((q_hi - q_lo) ** 2, axis=-1)),
                    np.sqrt(np.sum((q_hi + q_lo) ** 2, axis=-1)))
    dw = np.asarray(w_hi, dtype=float) - np.asarray(w_lo, dtype=float)
    w0 = np.asarray(w0, dtype=float)
    w1 = np.asarray(w_hi, dtype=float)
    scale = np.maximum(np.maximum(np.sqrt(np.sum(w0 * w0, axis=-1)),
                                  np.sqrt(np.sum(w1 * w1, axis=-1))), w_floor)
    err = np.maximum(dq, np.sqrt(np.sum(dw * dw, axis=-1)) / scale)
    return float(np.max(err)) / rtol


def _controller_exponent(scheme: _Scheme, embedded: _Scheme) -> float:
    """Exponent of the step controller ``h (1/err)^expo``: ``1/(p+1)`` with ``p`` the
    lower order of the pair, whose error the estimate measures; ``1/5`` for two order-4
    compositions (the difference is then of order 5)."""
    if embedded.order == scheme.order:
        return 0.2
    return 1.0 / (min(scheme.order, embedded.order) + 1.0)


def _march(stepper: _Stepper, q, w, t0: float, times, store, h: float, *, mode: str,
           rtol: float | None = None, embedded: _Scheme | None = None, expo: float = 0.0,
           w_floor: float = 0.0, h_limit: float = math.inf, bar=None) -> None:
    """Advance one direction of a run and hand every output to ``store(j, q, w)``.

    ``times``: ``(index, time relative to t0)`` pairs in order of increasing ``|time|``,
    all of one sign.  Modes: ``"dense"`` (steps of ``h`` from ``t0``, outputs inside a
    step by a partial step from its start), ``"cut"`` (each interval between outputs
    cut into equal steps no longer than ``h``) and ``"rtol"`` (steps chosen by the
    error estimate, outputs as in ``"dense"``; ``expo`` is the controller's exponent,
    :func:`_controller_exponent`).
    """
    if not times:
        return
    sign = 1.0 if times[-1][1] >= 0 else -1.0
    pending, cached, t_now, k = 0.0, None, 0.0, 0
    tol = SNAP * (abs(h) if math.isfinite(h) else abs(times[-1][1]))
    j = 0
    while j < len(times):
        idx, tj = times[j]
        if abs(tj - t_now) <= tol or tj == t_now:
            qb, wb, cached = stepper.boundary(t0 + t_now, q, w, pending, cached)
            store(idx, qb, wb)
            j += 1
            continue
        if mode == "cut":
            n = step_count(tj - t_now, h)
            hh = (tj - t_now) / n
            for i in range(n):
                q, w, pending = stepper.step(t0 + t_now + i * hh, q, w, pending, hh, cached)
                cached = None
            if bar is not None:
                bar.update(abs(tj - t_now))
            t_now = tj
            continue
        if mode == "dense":
            t_next = sign * (k + 1) * h if math.isfinite(h) else times[-1][1]
            if abs(t_next - times[-1][1]) <= tol:
                t_next = times[-1][1]
        else:                                            # rtol: a trial step
            hh = sign * min(h, h_limit)
            t_next = t_now + hh
            last = times[-1][1]
            if sign * (t_next - last) > -tol:             # do not step past the last output
                t_next = last
            # the embedded step starts from the state at the step boundary (one per step)
            q_b, w_b, cached = stepper.boundary(t0 + t_now, q, w, pending, cached)
            while True:
                hh = t_next - t_now
                q_pre, w_pre, pend_new = stepper.step(t0 + t_now, q, w, pending, hh, cached)
                q_hi, w_hi, c_hi = stepper.boundary(t0 + t_next, q_pre, w_pre, pend_new, None)
                ql, wl, pl = stepper.step(t0 + t_now, q_b, w_b, 0.0, hh, cached, embedded)
                q_lo, w_lo, _ = stepper.boundary(t0 + t_next, ql, wl, pl, None)
                err = _rtol_error(w_b, q_hi, w_hi, q_lo, w_lo, rtol, w_floor)
                if err <= 1.0:
                    break
                factor = max(0.2, 0.9 * err ** -expo) if math.isfinite(err) else 0.2
                h = abs(hh) * factor
                if h <= 1e-12 * max(abs(t_now), abs(hh)):
                    raise PropagationError(f"splitting with rtol={rtol:g}: the step fell "
                                           f"below round-off at t = {t0 + t_now:.9g} s; "
                                           "loosen rtol or use method='integrator'",
                                           key="rtol")
                t_next = t_now + sign * h
            grow = 5.0 if err == 0.0 else min(5.0, max(0.2, 0.9 * err ** -expo))
            h = abs(hh) * grow
        # outputs strictly inside (t_now, t_next): partial steps from the step's start
        while j < len(times) and sign * (times[j][1] - t_next) < -tol:
            idx, tj = times[j]
            if abs(tj - t_now) <= tol:
                qb, wb, cached = stepper.boundary(t0 + t_now, q, w, pending, cached)
            else:
                qp, wp, pp = stepper.step(t0 + t_now, q, w, pending, tj - t_now, cached)
                qb, wb, _ = stepper.boundary(t0 + tj, qp, wp, pp, None)
            store(idx, qb, wb)
            j += 1
        if j == len(times):
            break
        if mode == "rtol":
            q, w, pending, cached = q_pre, w_pre, pend_new, c_hi
        else:
            q, w, pending = stepper.step(t0 + t_now, q, w, pending, t_next - t_now, cached)
            cached = None
            k += 1
        if bar is not None:
            bar.update(abs(t_next - t_now))
        t_now = t_next


def _compiled_specs(system: _System, body_list, t0: float, t: np.ndarray, supported: bool):
    """Per body, the compiled forms of the kick, drag and internal torques, or ``None``
    if a model has none (or internal torques act together with external ones)."""
    if not supported or not system.terms:
        return None
    span = (t0 + float(min(0.0, np.min(t))), t0 + float(max(0.0, np.max(t))))
    specs = []
    for body in body_list:
        groups = []
        for models in (system.kick_terms, system.drag_terms, system.internal_terms):
            if not models:
                groups.append((np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64),
                               np.zeros(0)))
                continue
            c = compile_torques(models, body, t_span=span)
            if c is None:
                return None
            groups.append((c.kinds, c.offsets, c.params))
        specs.append(groups)
    return specs


def _run_compiled(system, specs, q_p0, w_p0, t, t0, segments, h, h_limit, expo, mode,
                  rtol, scheme, embedded, rk_order, w_floor, anchor, out_q, out_w, bar):
    """Each body through :func:`attitude.propagation.compiled_loop.march_one`, the
    bodies of a batch on a thread per core (the compiled loop releases the GIL); the
    progress bar moves body by body."""
    flags = (bool(system.kick_terms), bool(system.drag_terms), bool(system.internal_terms))
    coeffs = (np.array(scheme.b), np.array(scheme.a))
    emb = embedded if embedded is not None else scheme
    ecoeffs = (np.array(emb.b), np.array(emb.a))

    def run(i, groups):
        fc = np.array(system.free.row(i), dtype=float)
        frame = (np.ascontiguousarray(system.q_bp[i], dtype=float), system.identity,
                 np.ascontiguousarray(system.inv_moments[i], dtype=float))
        torq = (tuple(groups[0]), tuple(groups[1]), tuple(groups[2]), flags)
        moments = np.ascontiguousarray(system.moments[i], dtype=float)
        anc = (np.ascontiguousarray(anchor[i], dtype=float) if anchor is not None
               else np.zeros(3))
        for idx in segments:
            times = np.ascontiguousarray(t[idx], dtype=float)
            oq = np.empty((idx.size, 4))
            ow = np.empty((idx.size, 3))
            code = compiled_loop.march_one(
                fc, torq, frame, moments, anc, coeffs, ecoeffs,
                np.ascontiguousarray(q_p0[i]), np.ascontiguousarray(w_p0[i]), t0, times,
                float(h), compiled_loop.MODES[mode], float(rtol or 0.0), expo, w_floor,
                h_limit, SNAP, rk_order, oq, ow)
            if code < 0:
                raise PropagationError(
                    f"splitting with rtol={rtol:g}: the step fell below round-off before "
                    f"t = {t0 + times[-code - 1]:.9g} s; loosen rtol or use "
                    "method='integrator'", key="rtol")
            out_q[i, idx] = oq
            out_w[i, idx] = ow
        return sum(abs(float(t[idx][-1])) for idx in segments) / len(specs)

    for done in compiled.each_on_cores(lambda i: run(i, specs[i]), len(specs)):
        bar.update(done)


def integrate_splitting(bodies, quat0, omega0, t, *, torques=(), step: float | None = None,
                        order: int | None = None, scheme: str | None = None,
                        progress: bool = False, steps_per_period: float | None = None,
                        t0: float = 0.0, rtol: float | None = None,
                        dense: bool = True, compiled: bool | None = None
                        ) -> tuple[np.ndarray, np.ndarray]:
    """Propagate rigid bodies under torques with a splitting method.

    The exact free rigid-body flow alternates with torque kicks (see the module
    docstring); all bodies of a batch advance together, vectorised, with one common
    step.

    Parameters
    ----------
    bodies : RigidBody, sequence of RigidBody, or principal moments (3,) / (N, 3)
        Moments mean bodies whose frame is their principal frame.
    quat0 : (4,) or (N, 4) array
        Body -> inertial quaternions at ``t = 0``, scalar-last.
    omega0 : (3,) or (N, 3) array
        Body-frame rates at ``t = 0``, rad/s.
    t : (T,) array
        Output times, s since the epoch, any order, may be negative (integrated
        backwards from 0).
    torques : sequence of torque models (or one model)
        ``torque(t, quaternion, omega_body, body) -> body-frame N m``
        (:mod:`attitude.model.torques`).  Models with ``velocity_dependent = False`` are
        exact kicks; the others are integrated inside the kick.  In a batch a model is
        called once per kick with arrays ``(N, 4)``, ``(N, 3)`` and a
        :class:`attitude.model.body.BodyBatch`; for one body with ``(4,)``, ``(3,)`` and the
        :class:`~attitude.model.body.RigidBody` (like the reference integrator).
    step : float, optional
        Step, s (with ``rtol``: the longest step).  Default: :func:`choose_step`.
    order : {2, 4, 6}, optional
        Order of the composition (default 4, or that of ``scheme``; if both are given
        they must agree).
    scheme : str, optional
        One of :data:`SCHEMES` (default :data:`DEFAULT_SCHEME` of the order).
    progress : bool
        Show a progress bar (``tqdm`` if installed, else a line on stderr).
    steps_per_period : float, optional
        ``N`` of the default step rule (:func:`choose_step`).
    t0 : float
        Time of ``quat0`` / ``omega0``, s since the epoch (default 0); ``t`` stays in
        seconds since the epoch (used to restart from an intermediate state).
    rtol : float, optional
        Error control: each step is accepted when the estimated local error is at most
        ``rtol`` (relative to the unit quaternion and to ``|omega|``), the estimate
        being the difference from a cheaper composition on the same step
        (:data:`EMBEDDED`: Yoshida's triple jump for the order-4 schemes), and the next
        step follows the usual controller ``h (1/err)^(1/(p+1))`` (factor 0.9, between
        0.2 and 5).  Like DOP853's ``rtol``, it bounds the local error estimate per
        step; the propagated solution is the more accurate one.  Variable steps are
        not symplectic: for long conservative runs prefer the fixed default step.
    dense : bool
        Outputs do not set the steps (default): the steps run on the grid
        ``t0 + k h`` and an output inside a step is one partial step of the same
        composition from the step's start (its error is that of one step).  With
        ``False`` each interval between outputs is cut into equal steps no longer than
        ``step`` (every output then lies on a step boundary).
    compiled : bool, optional
        Run the compiled loop (:mod:`attitude.propagation.compiled_loop`, numba): each
        body on its own, a few microseconds per step.  Default: when numba is installed
        and every torque model has a compiled form
        (:func:`attitude.propagation.compiled_torques.compile_torques`; a user's Python
        torque has none).  ``False`` forces the numpy path (bodies of a batch
        vectorised, one common step), which gives the same results to round-off;
        ``True`` raises if a torque has no compiled form (without numba it runs the
        same scalar loop as Python: slow, for tests).  With ``rtol`` the compiled loop
        controls the error of each body separately (the numpy path: the worst body).

    Returns
    -------
    quaternion : (N, T, 4) array, or (T, 4) for one body
        Body -> inertial, scalar-last, unit norm.
    omega : (N, T, 3) array, or (T, 3) for one body
        Body-frame rates, rad/s.

    Examples
    --------
    >>> import numpy as np
    >>> from attitude.propagation.splitting import integrate_splitting
    >>> from attitude.model.torques import GravityGradient
    >>> gg = GravityGradient(3.986004418e14, [7.0e6, 0.0, 0.0])
    >>> q, w = integrate_splitting([1.0, 2.0, 3.0], [0, 0, 0, 1], [1e-3, 2e-3, 3e-3],
    ...                            np.linspace(0.0, 600.0, 7), torques=[gg], step=10.0)
    >>> q.shape, w.shape
    ((7, 4), (7, 3))
    """
    body_list, single = as_bodies(bodies)
    system = _System(body_list, torques)
    n = system.n
    attitude_only = not (system.drag_terms or system.internal_terms)
    name, sorder, ops_step = _resolve_scheme(order, scheme, attitude_only)
    if name in RKN_SCHEMES and not attitude_only:
        raise InvalidStateError(f"scheme {name!r} needs attitude-only torques (its order "
                                "conditions assume them); with velocity-dependent torques "
                                "use 'blanes-moan', 'strang', 'yoshida4' or 'yoshida6'")
    q0 = np.asarray(quat0, dtype=float)
    w0 = np.asarray(omega0, dtype=float)
    if q0.shape[-1:] != (4,) or w0.shape[-1:] != (3,) or q0.ndim > 2 or w0.ndim > 2:
        raise InvalidStateError(f"quat0 / omega0: expected (N, 4) / (N, 3) (or (4,) / (3,)),"
                                f" got {q0.shape} / {w0.shape}")
    try:
        q0 = np.broadcast_to(q0, (n, 4)).astype(float)
        w0 = np.broadcast_to(w0, (n, 3)).astype(float)
    except ValueError:
        raise InvalidStateError(f"quat0 / omega0: {q0.shape} / {w0.shape} do not match "
                                f"{n} bodies") from None
    if not (np.all(np.isfinite(q0)) and np.all(np.isfinite(w0))):
        raise InvalidStateError("quat0 and omega0 must be finite")
    norm = np.linalg.norm(q0, axis=1, keepdims=True)
    if np.any(norm == 0):
        raise InvalidStateError("quat0 must be a non-zero quaternion")
    q0 = q0 / norm
    t = np.atleast_1d(np.asarray(t, dtype=float))
    if t.ndim != 1 or not np.all(np.isfinite(t)):
        raise InvalidStateError("t: expected a 1-D array of finite times (s)")
    if rtol is not None:
        checked_rtol(rtol)
    t0 = float(t0)
    t = t - t0
    q_p0, w_p0 = system.to_principal(q0, w0)

    if step is None:
        h_max = h_rule = _choose_step(system, q_p0, w_p0, sorder, steps_per_period, t0)
    else:
        h_max = float(step)
        if not (h_max > 0 and math.isfinite(h_max)):
            raise InvalidStateError(f"step: expected a positive number of seconds, got "
                                    f"{step!r}")
        h_rule = h_max
    has_kick = bool(system.kick_terms)
    has_drag = bool(system.drag_terms)
    has_internal = bool(system.internal_terms)
    run_scheme = _Scheme(sorder, ops_step)
    mode = "dense" if dense else "cut"
    if not (has_kick or has_drag or has_internal):
        run_scheme = _Scheme(sorder, (("F", 1.0),))   # no torque: the free flow is exact
        h_max, mode = math.inf, "dense"
    elif rtol is not None:
        mode = "rtol"
    rk_order = 2 if sorder == 2 else 4
    embedded = None
    if mode == "rtol":
        emb = EMBEDDED[name]
        if emb == "blanes-moan" and attitude_only:
            emb = "blanes-moan-rkn"
        embedded = _Scheme(*_LIE) if emb == "lie" else _Scheme(*SCHEMES[emb])
    # the loop's settings, the same for the numpy and the compiled loop: the first step
    # (with rtol: the rule's, at most step=), the longest step, the controller's exponent
    h_start = h_max if mode != "rtol" else min(h_rule, h_max)
    h_limit = math.inf if step is None else h_max
    expo = _controller_exponent(run_scheme, embedded) if mode == "rtol" else 0.0

    out_q = np.empty((n, t.size, 4))
    out_w = np.empty((n, t.size, 3))
    ops = _One(system) if n == 1 else _Batch(system)
    # internal torques alone keep the inertial L: every kick restores the initial one
    anchor = (quat.rotate(q_p0, w_p0 * system.moments)
              if has_internal and not (has_kick or has_drag) else None)
    stepper = _Stepper(ops, run_scheme, has_kick, has_drag, has_internal, rk_order, anchor)
    spin0 = float(np.max(np.sqrt(np.sum(w_p0 * w_p0, axis=1))))
    w_floor = 1e-3 * max(spin0, 1.0 / h_rule if math.isfinite(h_rule) else 0.0)
    w_floor = w_floor if w_floor > 0 else np.finfo(float).tiny
    specs = None
    torqued = has_kick or has_drag or has_internal
    if torqued and (compiled or (compiled is None and compiled_loop.NUMBA)):
        specs = _compiled_specs(system, body_list, t0, t, anchor is not None or not has_internal)
        if compiled and specs is None:
            raise InvalidStateError("compiled=True: a torque model has no compiled form (a "
                                    "Python function or model), or internal torques act "
                                    "together with external ones; use compiled=None",
                                    key="compiled")
    segments = _segments(t)
    bar = _Progress(sum(float(np.max(np.abs(t[idx]))) for idx in segments), progress)

    def store(j, q, w):
        ops.store(out_q, out_w, j, q, w)

    try:
        if specs is not None:
            _run_compiled(system, specs, q_p0, w_p0, t, t0, segments, h_start, h_limit,
                          expo, mode, rtol, run_scheme, embedded, rk_order, w_floor, anchor,
                          out_q, out_w, bar)
            segments = []
        for idx in segments:
            if n == 1:
                q, w = tuple(q_p0[0].tolist()), tuple(w_p0[0].tolist())
            else:
                q, w = q_p0.copy(), w_p0.copy()
            _march(stepper, q, w, t0, [(int(j), float(t[j])) for j in idx], store, h_start,
                   mode=mode, rtol=rtol, embedded=embedded, expo=expo, w_floor=w_floor,
                   h_limit=h_limit, bar=bar)
    finally:
        bar.close()
    if system.identity:
        qb, wb = out_q, out_w
    else:
        qb, wb = to_body_frame(out_q, out_w, system.q_bp[:, None, :])
    if single:
        return qb[0], wb[0]
    return qb, wb

r"""The algebra of the free rigid body: the kernel frame, the invariants, the angles of
the body relative to L, and the tolerances, one name and one value each.

Part of :mod:`attitude.model.freebody` (which re-exports every name and gives the
overview): the formulas here are pure arithmetic on components (plain floats or arrays
of one shape), in whatever precision they are given, so that the vectorised kernels,
the one-body splitting path and its compiled twins share them
(``docs/torquefree.md``, TF 3-14).

Examples
--------
>>> d21, d32, d31, Q1, Q3, D, L2 = invariants(1.0, 2.0, 3.0, 0.3, 0.0, 1.0)
>>> m, m1, lam2 = jacobi_parameters(1.0, 2.0, 3.0, d21, d32, d31, Q1, Q3, D)
>>> round(m + m1, 15), round(lam2, 6)
(1.0, 1.0)
"""

from __future__ import annotations

import math

import numpy as np

__all__ = [
    "EQUAL_MOMENTS_RTOL",
    "PURE_SPIN_TOL",
    "PURE_SPIN_TOL_UNSCALED",
    "SEPARATRIX_M1_TOL",
    "NEAR_SEPARATRIX_WARN",
    "LAM_FRAME",
    "kernel_moments",
    "kernel_vector",
    "kernel_attitude",
    "invariants",
    "separatrix_gap",
    "jacobi_parameters",
    "characteristic",
    "half_theta",
    "half_theta_scalar",
    "half_angles",
    "euler313_quaternion",
]

_EPS = float(np.finfo(float).eps)

# ===========================================================================
# tolerances (one name, one value each; docs/torquefree.md "Branches")
# ===========================================================================
#: "Equal moments" for the propagators: two principal moments are equal (axisymmetric
#: or spherical body) when they differ by at most ``EQUAL_MOMENTS_RTOL * C`` (4 ulp).
#: Above it the triaxial formulas are used; they stay exact and continuous down to it
#: (tested), so the solver's limit is set by rounding alone.
EQUAL_MOMENTS_RTOL = 4.0 * _EPS
# "Equal moments" for the regime *labels* (``diagnose``, ``RigidBody.symmetry``,
# ``attitude.analysis.diagnostics``) is attitude.body.SYMMETRY_RTOL (1e-12).  A second value is
# needed: moments given by a user are rounded data (a tensor diagonalised by ``eigh``,
# a shape model), and a body whose moments agree to 1e-12 should be *called*
# axisymmetric, while its motion is still computed exactly from the moments as given
# (with EQUAL_MOMENTS_RTOL).
#: "Pure spin" for the closed form: a principal-axis spin (uniform rotation) when the
#: two smaller body components of L are at most ``PURE_SPIN_TOL * |L|``.  The closed
#: form scales moments and rates to O(1) by exact powers of two, so the elliptic
#: formulas stay in the normal range down to here (below ~1e-150 they would square
#: amplitudes into subnormals); the uniform rotation differs from the motion by
#: O(PURE_SPIN_TOL) relative.
PURE_SPIN_TOL = 1e-150
#: "Pure spin" for one step of the splitting free flow, which works on the rates as
#: given (not scaled): the squares of the transverse rates of a slow spin (``|omega|`` ~
#: 1e-8 rad/s) must stay normal numbers, so the margin is 1e-100 rather than
#: :data:`PURE_SPIN_TOL`.  Both are far below any physical wobble: the uniform rotation
#: differs from the motion by O(1e-100) relative.
PURE_SPIN_TOL_UNSCALED = 1e-100
#: Separatrix branch of the closed form: used when the complementary parameter
#: ``m1 = 1 - k^2`` is at most this (including ``L^2 = 2EB`` exactly).  Between it and 0
#: the heteroclinic closed form equals the elliptic solution to
#: ``O(m1 exp(2 lambda |t|))``, i.e. for ``lambda |t| < 200``.
SEPARATRIX_M1_TOL = 1e-200
#: ``diagnose`` warns (:class:`~attitude.foundations.errors.NearSeparatrixWarning`) when
#: ``0 < |m1| <`` this: the periods then change by more than 1e-6 relative under a
#: 1-ulp change of input.
NEAR_SEPARATRIX_WARN = 1e-10

_S = math.sqrt(0.5)
#: Quaternion ``q_M`` (scalar-last) of the LAM kernel frame: the rotation by pi about
#: ``(e1 + e3)/sqrt 2`` taking the kernel axes ``(e3, -e2, e1)`` to the principal axes,
#: so that ``q_principal->inertial = q_kernel->inertial (x) q_M^-1`` (TF 9).
LAM_FRAME = (_S, 0.0, _S, 0.0)


# ===========================================================================
# the kernel frame (TF 9)
# ===========================================================================
def kernel_moments(A, B, C, lam):
    """Kernel-frame moments ``(I1, I2, I3)``: ``(A, B, C)`` (SAM) or ``(C, B, A)`` (LAM).

    ``lam`` is a bool (plain floats) or a boolean array (broadcasting).

    Examples
    --------
    >>> kernel_moments(1.0, 2.0, 3.0, True)
    (3.0, 2.0, 1.0)
    """
    if isinstance(lam, (bool, np.bool_)):
        return (C, B, A) if lam else (A, B, C)
    return np.where(lam, C, A), B, np.where(lam, A, C)


def kernel_vector(x1, x2, x3, lam):
    """Principal components of a vector -> kernel-frame components: unchanged (SAM) or
    ``(x3, -x2, x1)`` (LAM).  The map is an involution, so it also maps back.

    Examples
    --------
    >>> kernel_vector(1.0, 2.0, 3.0, True)
    (3.0, -2.0, 1.0)
    >>> kernel_vector(*kernel_vector(1.0, 2.0, 3.0, True), True)
    (1.0, 2.0, 3.0)
    """
    if isinstance(lam, (bool, np.bool_)):
        return (x3, -x2, x1) if lam else (x1, x2, x3)
    return np.where(lam, x3, x1), np.where(lam, -x2, x2), np.where(lam, x1, x3)


def kernel_attitude(q):
    """``q (x) q_M`` for component quaternions ``q = (x, y, z, w)``: the attitude of the
    LAM kernel frame from that of the principal frame (or, for ``q`` of the kernel
    frame relative to something, the same relative to the principal frame; TF 9).

    Examples
    --------
    >>> [round(c, 15) for c in kernel_attitude((0.0, 0.0, 0.0, 1.0))]
    [0.707106781186548, 0.0, 0.707106781186548, 0.0]
    """
    ex, ey, ez, ew = q
    return (_S * (ew + ey), _S * (ez - ex), _S * (ew - ey), -_S * (ex + ez))


# ===========================================================================
# invariants (TF 3-10)
# ===========================================================================
def invariants(I1, I2, I3, w1, w2, w3):
    """The gaps of the energy from the principal-axis spins, without cancellation.

    Parameters
    ----------
    I1, I2, I3 : float or array
        Kernel-frame moments, monotonic (``I1 <= I2 <= I3``, or the reverse in the LAM
        frame).
    w1, w2, w3 : float or array
        Kernel-frame rates (rad/s).

    Returns
    -------
    tuple ``(d21, d32, d31, Q1, Q3, D, L2)``
        Signed moment gaps ``d21 = I2 - I1, d32 = I3 - I2, d31 = I3 - I1``;
        ``Q1 = 2E I3 - L^2``, ``Q3 = L^2 - 2E I1``, ``D = L^2 - 2E I2`` (all three from
        the rate components: ``Q1``, ``Q3`` carry full relative precision, the sign of
        ``D`` decides the side of the separatrix) and ``L2 = |L|^2``.  In the LAM frame
        the gaps, ``Q1`` and ``Q3`` are negative: the ratios below do not depend on the
        orientation.

    Examples
    --------
    >>> invariants(1.0, 2.0, 3.0, 1.0, 0.0, 0.0)      # spin about the long axis
    (1.0, 1.0, 2.0, 2.0, 0.0, -1.0, 1.0)
    """
    d21, d32, d31 = I2 - I1, I3 - I2, I3 - I1
    w1s, w2s, w3s = w1 * w1, w2 * w2, w3 * w3
    Q1 = I1 * d31 * w1s + I2 * d32 * w2s                  # 2E I3 - L^2   (TF 3)
    Q3 = I2 * d21 * w2s + I3 * d31 * w3s                  # L^2 - 2E I1   (TF 3)
    D = separatrix_gap(I1, I2, I3, w1, w3)                # L^2 - 2E I2   (TF 5)
    L2 = (I1 * w1) ** 2 + (I2 * w2) ** 2 + (I3 * w3) ** 2
    return d21, d32, d31, Q1, Q3, D, L2


def separatrix_gap(I1, I2, I3, w1, w3):
    """``D = L^2 - 2E I2 = I3 (I3 - I2) w3^2 - I1 (I2 - I1) w1^2``: its sign tells the side
    of the separatrix (> 0: about the third axis, SAM in principal axes); the same
    value in the SAM and the LAM frame (TF 5).

    Examples
    --------
    >>> separatrix_gap(1.0, 2.0, 3.0, 1.0, 1.0)      # 3 - 1
    2.0
    """
    return I3 * (I3 - I2) * (w3 * w3) - I1 * (I2 - I1) * (w1 * w1)


def jacobi_parameters(I1, I2, I3, d21, d32, d31, Q1, Q3, D):
    """Jacobi parameter, its complement and the squared frequency of the polhode.

    The arguments are those of :func:`invariants` (signed, or all as magnitudes: the
    ratios are the same).

    Returns
    -------
    tuple ``(m, m1, lam2)``
        ``m = k^2 = d21 Q1 / (d32 Q3)``, ``m1 = 1 - k^2 = d31 D / (d32 Q3)`` (no
        cancellation: from ``D``, not from ``1 - m``) and
        ``lambda^2 = d32 Q3 / (I1 I2 I3)``; the rates are ``(a1 cn, a2 sn, a3 dn)`` of
        ``lambda t + u0`` (TF 4, 6).

    Examples
    --------
    >>> d21, d32, d31, Q1, Q3, D, L2 = invariants(1.0, 2.0, 3.0, 0.3, 0.0, 1.0)
    >>> jacobi_parameters(1.0, 2.0, 3.0, d21, d32, d31, Q1, Q3, D)
    (0.03, 0.97, 1.0)
    """
    den = d32 * Q3
    return d21 * Q1 / den, d31 * D / den, den / (I1 * I2 * I3)


def characteristic(I1, I2, I3):
    """``nu = I3 (I2 - I1) / (I1 (I3 - I2))``: minus the characteristic of the elliptic
    integral of the third kind in the precession angle (TF 10).

    Examples
    --------
    >>> characteristic(1.0, 2.0, 3.0)
    3.0
    """
    return I3 * (I2 - I1) / (I1 * (I3 - I2))


# ===========================================================================
# the angles of the body relative to L (TF 13, 14)
# ===========================================================================
def half_theta(L1, L2, L3):
    """``cos(theta/2), sin(theta/2)`` of the angle ``theta`` between the third axis and L,
    from the body components of L, without cancellation (TF 13).

    Plain floats take a scalar fast path (``math``); arrays broadcast.  NaN for
    ``L = 0``.

    Examples
    --------
    >>> [round(x, 15) for x in half_theta(0.0, 1.0, 0.0)]     # theta = 90 deg
    [0.707106781186548, 0.707106781186548]
    """
    if isinstance(L3, float) and isinstance(L1, float) and isinstance(L2, float):
        return half_theta_scalar(L1, L2, L3)
    with np.errstate(invalid="ignore", divide="ignore"):
        h, o = half_angles(L1, L2, L3)
    pos = L3 >= 0
    return np.where(pos, h, o), np.where(pos, o, h)


def half_theta_scalar(L1, L2, L3):
    """:func:`half_theta` of plain floats, as floats: the one source of its scalar form
    (numba compiles it as it is for the kernels of :mod:`attitude.propagation.compiled`).

    Examples
    --------
    >>> half_theta_scalar(0.0, 0.0, -1.0)         # L along -z: theta = 180 deg
    (0.0, 1.0)
    """
    if L1 == 0.0 and L2 == 0.0 and L3 == 0.0:
        return math.nan, math.nan
    h, o = half_angles(L1, L2, L3)
    h, o = float(h), float(o)
    return (h, o) if L3 >= 0 else (o, h)


def half_angles(L1, L2, L3):
    """The larger and the smaller of ``cos(theta/2), sin(theta/2)`` (:func:`half_theta`,
    whose one source this is: in numpy's ufuncs on floats or arrays, which numba
    compiles on floats for the kernels of :mod:`attitude.propagation.compiled`).

    Examples
    --------
    >>> [round(float(x), 15) for x in half_angles(0.0, 1.0, 1.0)]     # theta = 45 deg
    [0.923879532511287, 0.38268343236509]
    """
    rho = np.hypot(L1, L2)
    Lt = np.hypot(rho, L3)
    h = np.sqrt((Lt + np.abs(L3)) / (2.0 * Lt))
    return h, rho / (2.0 * Lt * h)


def euler313_quaternion(ct, st, phi, psi):
    """Quaternion ``(x, y, z, w)`` of ``Rz(phi) Rx(theta) Rz(psi)`` from
    ``cos(theta/2), sin(theta/2)`` (TF 14).

    Plain floats take a scalar fast path (``math``); arrays broadcast.

    Examples
    --------
    >>> from scipy.spatial.transform import Rotation
    >>> import numpy as np
    >>> q = euler313_quaternion(np.cos(0.2), np.sin(0.2), 0.3, -0.5)
    >>> r = Rotation.from_euler("ZXZ", [0.3, 0.4, -0.5])
    >>> bool(np.allclose(q, r.as_quat()))
    True
    """
    hp = 0.5 * (phi + psi)
    hm = 0.5 * (phi - psi)
    if isinstance(hp, float) and isinstance(hm, float):
        return (st * math.cos(hm), st * math.sin(hm), ct * math.sin(hp), ct * math.cos(hp))
    return (st * np.cos(hm), st * np.sin(hm), ct * np.sin(hp), ct * np.cos(hp))

r"""The algebra of the free rigid body, shared by every kernel that uses it.

The closed-form solution (:mod:`attitude.propagation.torquefree`), both paths of the
splitting integrator's exact free flow (vectorised and one-body,
:mod:`attitude.propagation.splitting`), the analytic diagnosis (``diagnose``) and the
osculating quantities of an ephemeris (:mod:`attitude.analysis.diagnostics`) all use the
definitions of this module, so that each exists once:

- the **kernel frame**: the principal axes ``(A, B, C)`` on the short-axis side of the
  separatrix (SAM, ``L^2 >= 2EB``), the relabelled right-handed frame
  ``(e3, -e2, e1)`` with moments ``(C, B, A)`` on the long-axis side (LAM), so that one
  set of formulas covers both (:func:`kernel_moments`, :func:`kernel_vector`,
  :func:`kernel_attitude`);
- the **invariants** in that frame (:func:`invariants`, :func:`jacobi_parameters`,
  :func:`characteristic`)::

      d21 = I2 - I1, d32 = I3 - I2, d31 = I3 - I1                  (signed)
      Q1 = 2E I3 - L^2 = I1 d31 w1^2 + I2 d32 w2^2
      Q3 = L^2 - 2E I1 = I2 d21 w2^2 + I3 d31 w3^2
      D  = L^2 - 2E I2 = I3 d32 w3^2 - I1 d21 w1^2
      m = k^2 = d21 Q1 / (d32 Q3),  m1 = 1 - k^2 = d31 D / (d32 Q3)
      lambda^2 = d32 Q3 / (I1 I2 I3),  nu = I3 d21 / (I1 d32)

  formed from the rate components, so that the only cancellation is in ``D`` (the
  distance to the separatrix) and none in ``Q1``, ``Q3``, ``m`` or ``m1`` (Landau &
  Lifshitz §37; ``docs/torquefree.md``, TF 3-10);
- the **attitude helpers**: ``cos, sin`` of half the angle between L and the third
  kernel axis without cancellation (:func:`half_theta`), and the quaternion of the 3-1-3
  rotation ``Rz(phi) Rx(theta) Rz(psi)`` from them (:func:`euler313_quaternion`);
- the **tolerances**, one name and one value for each idea (below);
- the per-body constants of the closed form: the branch of each body
  (:func:`branches`) and the elliptic constants of a triaxial body
  (:func:`elliptic_constants`: ``K``, the Landen chain, the precession rates), which
  the closed form evaluates over time (:mod:`attitude.propagation.torquefree`);
- the **analytic diagnosis** from them, without propagating: :func:`diagnose`
  (``att.diagnose``), :func:`diagnose_principal`, :func:`diagnose_many` and
  :func:`branch_of`.

Every helper takes components (plain floats or arrays of one shape) and returns
components: the vectorised kernels pass arrays, the one-body splitting path plain
floats (its scalar fast path).  The invariants are pure arithmetic and run in whatever
precision they are given (the closed form passes ``longdouble``).

Examples
--------
>>> d21, d32, d31, Q1, Q3, D, L2 = invariants(1.0, 2.0, 3.0, 0.3, 0.0, 1.0)
>>> m, m1, lam2 = jacobi_parameters(1.0, 2.0, 3.0, d21, d32, d31, Q1, Q3, D)
>>> round(m + m1, 15), round(lam2, 6)
(1.0, 1.0)
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field

import numpy as np
from scipy import special as sp

from ..foundations import elliptic as el
from ..foundations import quaternion as quat
from ..foundations.errors import InvalidInertiaError, InvalidStateError, NearSeparatrixWarning
from .body import SYMMETRY_RTOL, to_principal_frame
from .regimes import PERIOD_KEYS, REGIMES

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
    "half_angles",
    "euler313_quaternion",
    "check_inputs",
    "unit_scales",
    "discriminant",
    "kernel_invariants",
    "BRANCHES",
    "branches",
    "elliptic_constants",
    "Diagnosis",
    "diagnose",
    "diagnose_principal",
    "diagnose_many",
    "branch_of",
]

_EPS = float(np.finfo(float).eps)
_LD = el.LD
_TWO_PI = 2.0 * math.pi

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
        if L1 == 0.0 and L2 == 0.0 and L3 == 0.0:
            return math.nan, math.nan
        h, o = (float(x) for x in half_angles(L1, L2, L3))
        return (h, o) if L3 >= 0 else (o, h)
    with np.errstate(invalid="ignore", divide="ignore"):
        h, o = half_angles(L1, L2, L3)
    pos = L3 >= 0
    return np.where(pos, h, o), np.where(pos, o, h)


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


# ===========================================================================
# inputs, scales, discriminant and branches of the closed form (TF 5, 30)
# ===========================================================================
def check_inputs(moments, quat0, omega0, t):
    """Check and flatten the inputs of the closed form (:func:`free_rotation
    <attitude.propagation.torquefree.free_rotation>`).

    Returns
    -------
    batch : tuple
        The broadcast leading shape.
    I, w : (n, 3) ndarray
        Moments and rates, one row per body.
    q : (n, 4) ndarray
        Unit quaternions.
    tt : (1, T) or (n, T) ndarray
        Times, shared or per body.

    Raises
    ------
    InvalidInertiaError, InvalidStateError
        Non-finite, unsorted or non-positive moments; non-finite rates, quaternions
        or times; shapes that do not broadcast.

    Examples
    --------
    >>> batch, I, w, q, tt = check_inputs([1.0, 2.0, 3.0], [0, 0, 0, 2.0], [0, 0, 1.0],
    ...                                   [0.0, 1.0])
    >>> batch, q.tolist(), tt.shape
    ((), [[0.0, 0.0, 0.0, 1.0]], (1, 2))
    """
    moments = np.asarray(moments, dtype=np.float64)
    omega0 = np.asarray(omega0, dtype=np.float64)
    quat0 = np.asarray(quat0, dtype=np.float64)
    t = np.atleast_1d(np.asarray(t, dtype=np.float64))
    if moments.shape[-1:] != (3,) or omega0.shape[-1:] != (3,) or quat0.shape[-1:] != (4,):
        raise InvalidStateError(
            f"free_rotation: expected moments (..., 3), quat0 (..., 4), omega0 (..., 3); got "
            f"{moments.shape}, {quat0.shape}, {omega0.shape}")
    batch = np.broadcast_shapes(moments.shape[:-1], omega0.shape[:-1], quat0.shape[:-1])
    if t.ndim > 1:
        batch = np.broadcast_shapes(batch, t.shape[:-1])
    if not np.all(np.isfinite(moments)) or np.any(moments <= 0):
        raise InvalidInertiaError(f"principal moments must be finite and > 0, got {moments}")
    if np.any(np.diff(moments, axis=-1) < 0):
        raise InvalidInertiaError(f"principal moments must be sorted A <= B <= C, got {moments}")
    if not np.all(np.isfinite(omega0)):
        raise InvalidStateError(f"omega0 must be finite, got {omega0}")
    if not np.all(np.isfinite(t)):
        raise InvalidStateError("times must be finite")
    qn = np.linalg.norm(quat0, axis=-1, keepdims=True)
    if not np.all(np.isfinite(quat0)) or np.any(qn == 0):
        raise InvalidStateError(f"quat0 must be a finite non-zero quaternion, got {quat0}")
    n = int(np.prod(batch)) if batch else 1
    I = np.broadcast_to(moments, batch + (3,)).reshape(n, 3)
    w = np.broadcast_to(omega0, batch + (3,)).reshape(n, 3)
    q = np.broadcast_to(quat0 / qn, batch + (4,)).reshape(n, 4)
    T = t.shape[-1]
    tt = t.reshape(1, T) if t.ndim == 1 else np.broadcast_to(t, batch + (T,)).reshape(n, T)
    return batch, I, w, q, tt


def unit_scales(I, w):
    """Exact power-of-two scales of the moments (by C) and rates (by the largest
    component) of (N, 3) inputs, so that the kernels work on O(1) numbers.

    Examples
    --------
    >>> unit_scales(np.array([[100.0, 200.0, 300.0]]), np.array([[0.0, 0.0, 3.0]]))
    (array([512.]), array([4.]))
    """
    _, eI = np.frexp(I[:, 2])
    sI = np.ldexp(1.0, eI)
    wmax = np.max(np.abs(w), axis=1)
    _, ew = np.frexp(np.where(wmax > 0, wmax, 1.0))
    sw = np.ldexp(1.0, ew)
    return sI, sw


def discriminant(I, w):
    """``Delta = L^2 - 2EB = C(C-B) w3^2 - A(B-A) w1^2`` in double-double (TF 5).

    Computed from the rate components so the only cancellation is the final
    subtraction, done on operands exact to ~eps**2: the result carries full
    relative precision down to ``|Delta| ~ 1e-16 |terms|`` and beyond.

    Parameters
    ----------
    I, w : (N, 3) ndarray
        Principal moments ``A <= B <= C`` and principal-frame rates.

    Returns
    -------
    hi, lo : (N,) ndarray
        ``Delta = hi + lo`` (> 0 on the SAM side).

    Examples
    --------
    >>> hi, lo = discriminant(np.array([[1.0, 2.0, 3.0]]), np.array([[1.0, 0.0, 1.0]]))
    >>> float(hi[0] + lo[0])                      # 3 (3 - 2) - 1 (2 - 1)
    2.0
    """
    A, B, C = I[:, 0], I[:, 1], I[:, 2]
    w1, w3 = w[:, 0], w[:, 2]
    d32 = el.two_sum(C, -B)
    d21 = el.two_sum(B, -A)
    t3 = el.dd_mul_dd(el.dd_mul_d(el.two_prod(w3, w3), C), d32)
    t1 = el.dd_mul_dd(el.dd_mul_d(el.two_prod(w1, w1), A), d21)
    return el.dd_add(t3, (-t1[0], -t1[1]))


def kernel_invariants(I, w):
    """Kernel-frame invariants in longdouble for moments ``I = (I1, I2, I3)`` that
    are monotonic (either order) and rates ``w`` in that frame (TF 3-8).

    Returns
    -------
    dict of (N,) longdouble arrays
        ``I1, I2, I3, w1, w2, w3`` and the magnitudes ``d21, d32, d31, Q1, Q3`` of
        :func:`invariants`, ``L2`` and ``L``.

    Examples
    --------
    >>> v = kernel_invariants(np.array([[1.0, 2.0, 3.0]]), np.array([[1.0, 0.0, 0.0]]))
    >>> float(v["Q1"][0]), float(v["L"][0])       # 2E I3 - L^2 = 3 - 1
    (2.0, 1.0)
    """
    I = I.astype(_LD)
    w = w.astype(_LD)
    I1, I2, I3 = I[:, 0], I[:, 1], I[:, 2]
    w1, w2, w3 = w[:, 0], w[:, 1], w[:, 2]
    # magnitudes (the LAM frame's gaps, Q1 and Q3 are negative; negation is exact)
    d21, d32, d31, Q1, Q3, _, L2 = (np.abs(x) for x in invariants(I1, I2, I3, w1, w2, w3))
    return dict(I1=I1, I2=I2, I3=I3, w1=w1, w2=w2, w3=w3, d21=d21, d32=d32, d31=d31,
                Q1=Q1, Q3=Q3, L2=L2, L=np.sqrt(L2))


# ===========================================================================
# branch selection
# ===========================================================================
#: Propagation branches of the closed form, by code (:func:`branches`).
BRANCHES = ("precession", "separatrix", "SAM", "LAM")
BRANCH_PRECESSION, BRANCH_SEPARATRIX, BRANCH_SAM, BRANCH_LAM = 0, 1, 2, 3


def branches(I, w):
    """Propagation branch of each body (scaled inputs, :func:`unit_scales`) and the
    double-double discriminant (TF 30).

    The branch is precession (axisymmetric or spherical within
    :data:`EQUAL_MOMENTS_RTOL`, principal-axis spin within :data:`PURE_SPIN_TOL`, rest),
    separatrix (``m1 <=`` :data:`SEPARATRIX_M1_TOL`), else SAM or LAM by the sign of
    :func:`discriminant`.

    Returns
    -------
    codes : (N,) int8
        Indices into :data:`BRANCHES`.
    hi, lo : (N,) ndarray
        The discriminant ``L^2 - 2EB`` in double-double.

    Examples
    --------
    >>> codes, hi, lo = branches(np.array([[0.5, 0.75, 1.0], [0.5, 0.75, 1.0]]),
    ...                          np.array([[0.1, 0.0, 1.0], [1.0, 0.0, 0.1]]))
    >>> [BRANCHES[c] for c in codes]
    ['SAM', 'LAM']
    """
    A, B, C = I[:, 0], I[:, 1], I[:, 2]
    Lb = np.abs(I * w)
    Ls = np.sort(Lb, axis=1)
    Lnorm = np.sqrt(np.sum(Lb * Lb, axis=1))
    tol = EQUAL_MOMENTS_RTOL * C
    prec = ((C - A) <= tol) | ((B - A) <= tol) | ((C - B) <= tol)
    prec |= Ls[:, 1] <= PURE_SPIN_TOL * Lnorm  # pure principal-axis spin, or omega = 0
    br = np.full(I.shape[0], BRANCH_PRECESSION, dtype=np.int8)
    tri = ~prec
    dhi, dlo = discriminant(I, w)
    if tri.any():
        sam = tri & (dhi > 0)
        lam = tri & (dhi < 0)
        br[sam] = BRANCH_SAM
        br[lam] = BRANCH_LAM
        br[tri & (dhi == 0)] = BRANCH_SEPARATRIX
        # complementary parameter m1 (TF 6) decides the separatrix branch
        idx = np.nonzero(sam | lam)[0]
        if idx.size:
            m1 = _m1_of(I[idx], w[idx], dhi[idx], dlo[idx], br[idx] == BRANCH_LAM)
            br[idx[m1 <= SEPARATRIX_M1_TOL]] = BRANCH_SEPARATRIX
    return br, dhi, dlo


def _kernel_frame(I, w, lam):
    """(N, 3) moments and rates in the kernel frame (:mod:`attitude.model.freebody`, TF 9)."""
    Ik = np.stack(kernel_moments(I[:, 0], I[:, 1], I[:, 2], lam), axis=1)
    wk = np.stack(kernel_vector(w[:, 0], w[:, 1], w[:, 2], lam), axis=1)
    return Ik, wk


_JACOBI_ARGS = ("I1", "I2", "I3", "d21", "d32", "d31", "Q1", "Q3")


def _m1_of(I, w, dhi, dlo, lam):
    Ik, wk = _kernel_frame(I, w, lam)
    v = kernel_invariants(Ik, wk)
    D = np.abs(dhi.astype(_LD) + dlo.astype(_LD))
    return jacobi_parameters(*(v[k] for k in _JACOBI_ARGS), D)[1].astype(
        np.float64)


# ===========================================================================
# the elliptic constants of a triaxial body (TF 3-12, 15, 31)
# ===========================================================================
def elliptic_constants(I, w, dhi, dlo, lam: bool) -> dict:
    """Per-body constants of the elliptic solution in the kernel frame (TF 3-12, 15).

    Parameters
    ----------
    I, w : (N, 3) ndarray
        Scaled principal moments and rates (:func:`unit_scales`) of triaxial bodies
        of one side of the separatrix.
    dhi, dlo : (N,) ndarray
        Their :func:`discriminant`.
    lam : bool
        The side: LAM (kernel frame relabelled) or SAM.

    Returns
    -------
    dict of (N,) arrays (longdouble where precision matters)
        The kernel invariants (``I1..I3, d21, d32, d31, Q1, Q3, L``), ``Dl = |L^2 - 2EB|``,
        ``m``, ``m1``, ``lamb`` (lambda), ``nu``, ``N`` and ``omN = 1 - N`` (the shifted
        characteristic), the Landen chain ``g, omg, scale, mu`` and ``K``, ``kp``, the
        amplitudes ``a1, a2, a3``, the sign ``s`` of the third rate, the precession
        rates ``w_lin`` (linear part) and ``kappa_j`` (per half-period), ``kappa_r``,
        ``beta``, ``sigma`` (+1 SAM, -1 LAM) and the initial phase ``v0 = u0 - K``.

    Examples
    --------
    >>> I, w = np.array([[0.5, 0.75, 1.0]]), np.array([[0.1, 0.0, 1.0]])
    >>> x = elliptic_constants(I, w, *discriminant(I, w), False)
    >>> bool(abs(float(x["m"][0] + x["m1"][0]) - 1.0) < 1e-15)
    True
    """
    n = I.shape[0]
    Ik, wk = _kernel_frame(I, w, np.full(n, lam))
    v = kernel_invariants(Ik, wk)
    I1, I2, I3 = v["I1"], v["I2"], v["I3"]
    d21, d32, d31, Q1, Q3, L = v["d21"], v["d32"], v["d31"], v["Q1"], v["Q3"], v["L"]
    Dl = np.abs(dhi.astype(_LD) + dlo.astype(_LD))  # |L^2 - 2EB|          (TF 5)
    # k^2, 1 - k^2 and lambda^2                                             (TF 4, 6)
    m, m1, lam2 = jacobi_parameters(I1, I2, I3, d21, d32, d31, Q1, Q3, Dl)
    lamb = np.sqrt(lam2)  # lambda                                           (TF 4)
    nu = characteristic(I1, I2, I3)  # -n, characteristic of Pi              (TF 10)
    onu = 1 + nu
    N = (m + nu) / onu  # shifted characteristic                             (TF 11)
    omN = m1 / onu  # 1 - N
    g, omg, scale, mu = el.landen_chain(m, m1)
    K = el.k_from_chain(scale, mu)
    kp = np.sqrt(m1)
    a1 = np.sqrt(Q1 / (I1 * d31))  # amplitudes                              (TF 3)
    a2 = np.sqrt(Q1 / (I2 * d32))
    a3 = np.sqrt(Q3 / (I3 * d31))
    s = np.where(wk[:, 2] < 0, -1.0, 1.0)
    c1 = L * d31 / (I1 * I3)
    if not lam:  # SAM: phi' = L/I3 + c1/(1 + nu sn^2)                          (TF 15)
        KG = el.cel(kp, onu, 1, 1)
        w_lin = L / I3
        kappa_j = 2 * c1 * KG / lamb
        kappa_r = c1 / (lamb * onu)
        beta = nu * omN / 3
        sigma = 1.0
    else:  # LAM: phi' = L/I1 + c1 nu sn^2/(1 + nu sn^2)                        (TF 15')
        KG2 = el.cel(kp, onu, 0, nu)
        w_lin = L / I1
        kappa_j = -2 * c1 * KG2 / lamb
        kappa_r = -c1 * nu / (lamb * onu)
        beta = -omN / 3
        sigma = -1.0
    # initial phase u0 = F(am u0 | m) through Carlson's RF                    (TF 12)
    cn0sq = (I1 * d31 * wk[:, 0] ** 2 / Q1).astype(np.float64)
    dn0sq = (I3 * d31 * wk[:, 2] ** 2 / Q3).astype(np.float64)
    sn0abs = np.sqrt((I2 * d32 * wk[:, 1] ** 2 / Q1).astype(np.float64))
    f = sn0abs * sp.elliprf(cn0sq, dn0sq, 1.0)
    Kd = K.astype(np.float64)
    sgn_sn0 = np.where(s * wk[:, 1] < 0, -1.0, 1.0)
    u0 = sgn_sn0 * np.where(wk[:, 0] >= 0, f, 2.0 * Kd - f)
    v0 = u0 - Kd  # phase of the shifted variable v = u - K                  (TF 16)
    return dict(m=m, m1=m1, lamb=lamb, K=K, L=L, nu=nu, N=N, omN=omN, w_lin=w_lin,
                kappa_j=kappa_j, kappa_r=kappa_r, beta=beta, sigma=sigma, Q1=Q1, Q3=Q3,
                Dl=Dl, I1=I1, I2=I2, I3=I3, d21=d21, d32=d32, d31=d31, s=s, g=g, omg=omg,
                scale=scale, mu=mu, kp=kp, a1=a1, a2=a2, a3=a3, v0=v0)


# ===========================================================================
# analytic diagnostics
# ===========================================================================
@dataclass(frozen=True)
class Diagnosis:
    """Analytic torque-free quantities of one body and state (no propagation).

    Attributes
    ----------
    regime : str
        One of ``"PA-short"``, ``"PA-long"``, ``"SAM"``, ``"LAM"``, ``"separatrix"``,
        ``"axisymmetric"``, ``"spherical"``, ``"at-rest"`` (:data:`attitude.model.regimes.REGIMES`).
    periods : dict
        Seconds, keys from :data:`attitude.model.regimes.PERIOD_KEYS`.  ``polhode`` (period of
        omega in the body frame, ``4K/lambda``), ``precession`` (mean period ``P_phi`` of
        the reference axis about L), ``rotation`` (``P_psi``, period of the rotation
        angle about the reference axis; equal to the polhode period), ``spin``
        (``2 pi/|omega|``, principal-axis spin).  Keys whose period does not exist for
        the regime are absent.
    angular_momentum : float
        ``|L|`` (kg m^2/s).
    kinetic_energy : float
        ``E`` (J).
    dynamic_inertia : float
        ``L^2 / 2E`` (kg m^2); NaN at rest.
    separatrix_distance : float
        Signed complementary Jacobi parameter ``m1 = 1 - k^2`` (dimensionless, in
        [-1, 1]): ``(C-A)(L^2-2EB) / ((C-B)(L^2-2EA))`` > 0 on the SAM side,
        ``-(C-A)(2EB-L^2) / ((B-A)(2EC-L^2))`` < 0 on the LAM side; 0 on the
        separatrix, +-1 for principal-axis spin about C / A.  NaN when undefined
        (spherical body, rest).
    nutation_range : tuple of float or None
        ``(theta_min, theta_max)`` (rad): range of the angle between L and the
        reference axis (:attr:`reference_axis`); ``None`` at rest.
    stable : bool or None
        Lyapunov stability of a principal-axis spin (False for the intermediate axis
        and for transverse spin of an axisymmetric body); ``None`` otherwise.
    reference_axis : int or None
        Principal axis (1 = A, 3 = C, ...) of the Euler angles: C for SAM and the
        separatrix, A for LAM, the symmetry axis of an axisymmetric body, the spin axis.
    k2 : float or None
        Jacobi parameter ``m = k^2`` (SAM/LAM; 1 on the separatrix).
    lam : float or None
        Jacobi frequency ``lambda`` (rad/s); rates are functions of ``lambda t``.
    mean_precession_rate : float or None
        ``<d phi/dt>`` (rad/s).
    excitation : float
        ``(E - E_min)/(E_max - E_min)`` at fixed L, with ``E_min = L^2/2C`` and
        ``E_max = L^2/2A`` (0: spin about C, 1: spin about A); NaN if undefined.
    energy_ratio : float
        ``E / E0`` with ``E0 = L^2/2C`` (Pravec et al. 2014); NaN at rest.
    branch : str
        Propagation branch used by :func:`free_rotation` (``"elliptic"``,
        ``"separatrix"``, ``"precession"``); can differ from the label because the
        label uses the looser ``rtol_symmetry``.
    omega_principal, angular_momentum_principal : ndarray (3,)
        Rates and L in principal components.
    angular_momentum_inertial : ndarray (3,) or None
        L in the inertial frame (from :func:`diagnose`).

    Examples
    --------
    >>> d = diagnose_principal([0.61, 0.965, 1.0], [0.02, 0.0, 0.1])
    >>> d.regime, round(d.separatrix_distance, 6)         # short-axis mode, m1 > 0
    ('SAM', 0.752514)
    >>> bool(0.965 < d.dynamic_inertia < 1.0)             # B < L^2/2E < C
    True
    >>> diagnose_principal([0.61, 0.965, 1.0], [0.0, 0.0, 1.0]).regime
    'PA-short'
    """

    regime: str
    periods: dict
    angular_momentum: float
    kinetic_energy: float
    dynamic_inertia: float
    separatrix_distance: float
    nutation_range: tuple | None
    stable: bool | None
    reference_axis: int | None = None
    k2: float | None = None
    lam: float | None = None
    mean_precession_rate: float | None = None
    excitation: float = math.nan
    energy_ratio: float = math.nan
    branch: str = ""
    omega_principal: np.ndarray = field(default=None, repr=False)
    angular_momentum_principal: np.ndarray = field(default=None, repr=False)
    angular_momentum_inertial: np.ndarray | None = field(default=None, repr=False)

    def __post_init__(self):
        if self.regime not in REGIMES:  # pragma: no cover - internal consistency
            raise ValueError(f"unknown regime {self.regime!r}")
        if not set(self.periods) <= set(PERIOD_KEYS):  # pragma: no cover
            raise ValueError(f"unknown period keys {sorted(self.periods)}")


def branch_of(moments, omega0):
    """Propagation branch names (``"precession"``, ``"separatrix"``, ``"SAM"``,
    ``"LAM"``) that :func:`free_rotation` uses, for (..., 3) inputs.

    Examples
    --------
    >>> import numpy as np
    >>> omega = np.array([[0.02, 0.0, 0.1], [0.1, 0.0, 0.02], [0.0, 0.0, 1.0]])
    >>> branch_of(np.array([0.61, 0.965, 1.0]), omega).tolist()
    ['SAM', 'LAM', 'precession']
    """
    moments = np.asarray(moments, dtype=float)
    omega0 = np.asarray(omega0, dtype=float)
    batch, I, w, _, _ = check_inputs(moments, [0.0, 0.0, 0.0, 1.0], omega0, [0.0])
    sI, sw = unit_scales(I, w)
    br, _, _ = branches(I / sI[:, None], w / sw[:, None])
    out = np.array(BRANCHES)[br]
    return out.reshape(batch) if batch else str(out[0])


def _atan2_sqrt(s2, c2):
    return float(np.arctan2(np.sqrt(np.float64(s2)), np.sqrt(np.float64(c2))))


def diagnose_principal(moments, omega0, *, rtol_symmetry=None, rtol_spin=None,
                       quat0=None) -> Diagnosis:
    """Analytic diagnosis from principal moments and principal-frame rates.

    Parameters
    ----------
    moments : (3,) array_like
        ``A <= B <= C`` (kg m^2).
    omega0 : (3,) array_like
        Principal-frame angular velocity (rad/s).
    rtol_symmetry : float, optional
        Moments within ``rtol_symmetry * C`` are equal for the *label* (default
        ``attitude.model.body.SYMMETRY_RTOL``, 1e-12, the tolerance of
        ``RigidBody.symmetry``).  Propagation itself uses :data:`EQUAL_MOMENTS_RTOL`.
    rtol_spin : float, optional
        The state is labelled principal-axis spin (``PA-short``, ``PA-long``, or
        ``separatrix`` for the intermediate axis) when the two smaller body components
        of L are at most ``rtol_spin * |L|`` (default: ``rtol_symmetry``), so that the
        1e-16 wobble left by rotating a spin into the principal frame does not turn it
        into SAM/LAM.  Propagation itself uses :data:`PURE_SPIN_TOL`.
    quat0 : (4,) array_like, optional
        Principal -> inertial quaternion; gives ``angular_momentum_inertial``.

    Returns
    -------
    Diagnosis

    Notes
    -----
    Periods (Landau & Lifshitz §37; Samarasinha & A'Hearn 1991; Kaasalainen 2001):
    ``P_polhode = P_psi = 4 K(m) / lambda`` and ``P_phi = 2 pi / <phi'>`` with, for SAM,
    ``<phi'> = L/C + L (C-A)/(A C) * Pi(-nu | m) / K(m)``, ``nu = C(B-A)/(A(C-B))``,
    and for LAM the same with A and C exchanged (docs/torquefree.md, TF 31-33).

    Examples
    --------
    >>> import math
    >>> d = diagnose_principal([1.0, 1.0, 2.0], [0.1, 0.0, 1.0])    # axisymmetric
    >>> d.regime
    'axisymmetric'
    >>> L = math.hypot(0.1, 2.0)                # precession period 2 pi A / |L|
    >>> bool(math.isclose(d.periods["precession"], 2 * math.pi / L, rel_tol=1e-14))
    True
    >>> d = diagnose_principal([0.61, 0.965, 1.0], [0.1, 0.0, 0.02])
    >>> d.regime, d.separatrix_distance < 0     # long-axis mode: m1 < 0
    ('LAM', True)
    """
    if rtol_symmetry is None:
        rtol_symmetry = SYMMETRY_RTOL
    rtol_symmetry = max(float(rtol_symmetry), EQUAL_MOMENTS_RTOL)  # never finer than the solver
    rtol_spin = max(float(rtol_symmetry if rtol_spin is None else rtol_spin), PURE_SPIN_TOL)
    _, I, w, _, _ = check_inputs(moments, [0.0, 0.0, 0.0, 1.0], omega0, [0.0])
    if I.shape[0] != 1:
        raise InvalidStateError("diagnose_principal takes one body; use branch_of for batches")
    A, B, C = (float(x) for x in I[0])
    wv = w[0].copy()
    Lp = I[0] * wv
    L = float(np.sqrt(np.sum(Lp.astype(_LD) ** 2)))
    E2 = float(np.sum(I[0].astype(_LD) * wv.astype(_LD) ** 2))
    E = 0.5 * E2
    Lin = None
    if quat0 is not None:
        q = np.asarray(quat0, dtype=float)
        Lin = quat.rotate(q / np.linalg.norm(q), Lp)
    base = dict(angular_momentum=L, kinetic_energy=E, omega_principal=wv,
                angular_momentum_principal=Lp, angular_momentum_inertial=Lin)
    if L == 0.0:
        return Diagnosis(regime="at-rest", periods={}, dynamic_inertia=math.nan,
                         separatrix_distance=math.nan, nutation_range=None, stable=None,
                         branch="precession", **base)
    wn = float(np.linalg.norm(wv))
    D = L * L / E2
    sI, sw = unit_scales(I, w)
    Is, ws = I / sI[:, None], w / sw[:, None]
    br, dhi, dlo = branches(Is, ws)
    bname = {BRANCH_PRECESSION: "precession", BRANCH_SEPARATRIX: "separatrix"}.get(
        int(br[0]), "elliptic")
    # excitation (E - E_min)/(E_max - E_min) from 2EC - L^2 = A(C-A)w1^2 + B(C-B)w2^2
    q1c = float(invariants(A, B, C, *(float(x) for x in wv))[3])      # 2EC - L^2
    exc = min(1.0, float(A * q1c / (L * L * (C - A)))) if C > A else math.nan
    base.update(dynamic_inertia=D, excitation=exc, energy_ratio=float(1.0 + q1c / (L * L)),
                branch=bname)
    tol = rtol_symmetry * C
    spin = {"spin": _TWO_PI / wn}
    Labs = np.abs(Lp)
    k = int(np.argmax(Labs))
    pure = np.sort(Labs)[1] <= rtol_spin * L

    def theta_of(axis):
        c = Lp[axis] / L
        s = math.sqrt(max(0.0, float(np.sum(np.delete(Lp, axis) ** 2)))) / L
        return math.atan2(s, c)

    if C - A <= tol:
        th = theta_of(2)
        return Diagnosis(regime="spherical", periods=dict(spin), separatrix_distance=math.nan,
                         nutation_range=(th, th), stable=None, reference_axis=3, **base)
    oblate = B - A <= tol
    prolate = C - B <= tol
    if pure:
        sign = 1.0 if Lp[k] > 0 else -1.0
        nut = (0.0, 0.0) if sign > 0 else (math.pi, math.pi)
        if oblate or prolate:
            sym = 2 if oblate else 0
            if k == sym:
                regime = "PA-short" if oblate else "PA-long"
                return Diagnosis(regime=regime, periods=dict(spin), separatrix_distance=(
                    1.0 if oblate else -1.0), nutation_range=nut, stable=True,
                    reference_axis=k + 1, **base)
            th = theta_of(sym)
            return Diagnosis(regime="axisymmetric", periods=dict(spin, precession=spin["spin"]),
                             separatrix_distance=0.0, nutation_range=(th, th), stable=False,
                             reference_axis=sym + 1, **base)
        regime = {2: "PA-short", 0: "PA-long", 1: "separatrix"}[k]
        dist = {2: 1.0, 0: -1.0, 1: 0.0}[k]
        return Diagnosis(regime=regime, periods=dict(spin), separatrix_distance=dist,
                         nutation_range=nut, stable=(k != 1), reference_axis=k + 1, **base)
    if oblate or prolate:
        sym = 2 if oblate else 0
        Is_ = C if oblate else A
        It = 0.5 * (A + B) if oblate else 0.5 * (B + C)
        Om = float(wv[sym] * (It - Is_) / It)
        th = theta_of(sym)
        periods = {"precession": _TWO_PI * It / L}
        if Om != 0.0:
            periods["polhode"] = periods["rotation"] = _TWO_PI / abs(Om)
            dist = 1.0 if oblate else -1.0
        else:
            periods["spin"] = _TWO_PI / wn
            dist = 0.0
        return Diagnosis(regime="axisymmetric", periods=periods, separatrix_distance=dist,
                         nutation_range=(th, th), stable=None if Om != 0.0 else False,
                         reference_axis=sym + 1, mean_precession_rate=L / It, **base)
    # triaxial
    if int(br[0]) in (BRANCH_SEPARATRIX, BRANCH_PRECESSION):
        # separatrix closed form, SAM labels: theta from theta_min to pi/2 (asymptote)
        v = kernel_invariants(Is, ws)
        s2 = v["I1"] * v["Q1"] / (v["d31"] * v["L2"])
        c2 = v["I3"] * v["Q3"] / (v["d31"] * v["L2"])
        th = _atan2_sqrt(s2[0], c2[0])
        nut = (th, 0.5 * math.pi) if wv[2] >= 0 else (0.5 * math.pi, math.pi - th)
        lamb = float(np.sqrt(v["d32"] * v["Q3"] / (v["I1"] * v["I2"] * v["I3"]))[0]) * sw[0]
        return Diagnosis(regime="separatrix", periods={}, separatrix_distance=0.0,
                         nutation_range=nut, stable=None, reference_axis=3, k2=1.0,
                         lam=float(lamb), **base)
    lam_side = int(br[0]) == BRANCH_LAM
    x = elliptic_constants(Is, ws, dhi, dlo, lam_side)
    m1 = float(x["m1"][0])
    if m1 < NEAR_SEPARATRIX_WARN:
        warnings.warn(f"state is {m1:.1e} from the separatrix (1 - k^2): periods and regime "
                      "are ill-conditioned; the motion itself is still computed exactly",
                      NearSeparatrixWarning, stacklevel=2)
    lamb = x["lamb"][0] * _LD(sw[0])
    K = x["K"][0]
    P_pol = float(4 * K / lamb)
    # mean precession rate (TF 31): linear rate + kappa_j * (dj/dt)
    phidot = (x["w_lin"][0] + x["kappa_j"][0] * x["sigma"] * x["lamb"][0] / (2 * K)) * _LD(sw[0])
    L2 = x["L"][0] ** 2
    s2min = x["I1"][0] * x["Q1"][0] / (x["d31"][0] * L2)  # nutation extremes (TF 34)
    c2min = x["I3"][0] * x["Q3"][0] / (x["d31"][0] * L2)
    s2max = x["I2"][0] * x["Q1"][0] / (x["d32"][0] * L2)
    c2max = x["I3"][0] * x["Dl"][0] / (x["d32"][0] * L2)
    tmin, tmax = _atan2_sqrt(s2min, c2min), _atan2_sqrt(s2max, c2max)
    if x["s"][0] < 0:
        tmin, tmax = math.pi - tmax, math.pi - tmin
    return Diagnosis(
        regime="LAM" if lam_side else "SAM",
        periods={"polhode": P_pol, "precession": float(_TWO_PI / abs(phidot)),
                 "rotation": P_pol},
        separatrix_distance=-m1 if lam_side else m1,
        nutation_range=(tmin, tmax), stable=None, reference_axis=1 if lam_side else 3,
        k2=float(x["m"][0]), lam=float(lamb), mean_precession_rate=float(phidot), **base)


def diagnose(body, state, *, rtol_symmetry=None, rtol_spin=None) -> Diagnosis:
    """Analytic torque-free diagnosis of a body in a state (``att.diagnose``).

    Parameters
    ----------
    body : attitude.RigidBody
        Uses ``principal_moments`` and ``body_to_principal``.
    state : attitude.AttitudeState
        Uses ``omega_body`` (rad/s, body frame) and ``attitude`` (body -> inertial).
    rtol_symmetry, rtol_spin : float, optional
        Label tolerances, see :func:`diagnose_principal`.

    Returns
    -------
    Diagnosis

    Examples
    --------
    >>> import attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> body = att.RigidBody.from_principal_moments([0.61, 0.965, 1.0])
    >>> state = att.AttitudeState("2029-04-13", Rotation.identity(), [0.2, 0.0, 3.0])
    >>> d = att.diagnose(body, state)
    >>> d.regime, sorted(d.periods)
    ('SAM', ['polhode', 'precession', 'rotation'])
    """
    q_p2i, w_p = to_principal_frame(state.attitude.as_quat(), state.omega_body,
                                    body.body_to_principal.as_quat())
    return diagnose_principal(body.principal_moments, w_p, rtol_symmetry=rtol_symmetry,
                              rtol_spin=rtol_spin, quat0=q_p2i)


def diagnose_many(moments, omega0, *, rtol_symmetry=None, rtol_spin=None) -> dict:
    """:func:`diagnose_principal` for a batch, vectorised over bodies.

    Parameters
    ----------
    moments : (N, 3) array_like
        Principal moments ``A <= B <= C`` (kg m^2) of each body.
    omega0 : (N, 3) array_like
        Principal-frame angular velocities (rad/s).
    rtol_symmetry, rtol_spin : float, optional
        Label tolerances, as in :func:`diagnose_principal`.

    Returns
    -------
    dict of (N,) arrays
        ``regime`` (str), ``polhode``, ``precession``, ``rotation``, ``spin`` (s; NaN
        where the period does not exist for the regime), ``energy_ratio`` (E/E0),
        ``separatrix_distance``, ``nutation_min`` and ``nutation_max`` (rad).

    Notes
    -----
    Triaxial SAM and LAM states (the bulk of any sampled population) are evaluated
    together with the same formulas as :func:`diagnose_principal`; the rare special
    cases (rest, principal-axis spin, axisymmetric or spherical bodies, the separatrix and
    states within :data:`NEAR_SEPARATRIX_WARN` of it) are delegated to it one by one, so
    the two agree (tested to 1e-13 relative).

    Examples
    --------
    >>> d = diagnose_many([[0.61, 0.965, 1.0], [1.0, 2.0, 3.0]], [[0.2, 0.0, 3.0], [0, 0, 1]])
    >>> d["regime"].tolist()
    ['SAM', 'PA-short']
    """
    if rtol_symmetry is None:
        rtol_symmetry = SYMMETRY_RTOL
    rtol_symmetry = max(float(rtol_symmetry), EQUAL_MOMENTS_RTOL)
    rtol_spin_ = max(float(rtol_symmetry if rtol_spin is None else rtol_spin), PURE_SPIN_TOL)
    moments = np.atleast_2d(np.asarray(moments, dtype=float))
    omega0 = np.atleast_2d(np.asarray(omega0, dtype=float))
    _, I, w, _, _ = check_inputs(moments, [0.0, 0.0, 0.0, 1.0], omega0, [0.0])
    n = I.shape[0]
    keys = ("polhode", "precession", "rotation", "spin", "energy_ratio",
            "separatrix_distance", "nutation_min", "nutation_max")
    out = {k: np.full(n, np.nan) for k in keys}
    regime = np.empty(n, dtype=object)
    A, B, C = I[:, 0], I[:, 1], I[:, 2]
    Lp = I * w
    L = np.sqrt(np.sum(Lp * Lp, axis=1))
    tol = rtol_symmetry * C
    pure = np.sort(np.abs(Lp), axis=1)[:, 1] <= rtol_spin_ * L
    generic = (L > 0) & ((B - A) > tol) & ((C - B) > tol) & ~pure
    sI, sw = unit_scales(I, w)
    Is, ws = I / sI[:, None], w / sw[:, None]
    br, dhi, dlo = branches(Is, ws)
    generic &= (br == BRANCH_SAM) | (br == BRANCH_LAM)
    for lam_side, code in ((False, BRANCH_SAM), (True, BRANCH_LAM)):
        idx = np.nonzero(generic & (br == code))[0]
        if idx.size == 0:
            continue
        x = elliptic_constants(Is[idx], ws[idx], dhi[idx], dlo[idx], lam_side)
        m1 = x["m1"].astype(np.float64)
        far = m1 >= NEAR_SEPARATRIX_WARN
        generic[idx[~far]] = False
        # per-body arrays along the last axis (the Landen chain has its level axis first)
        idx, x = idx[far], {k: (v[..., far] if np.ndim(v) else v) for k, v in x.items()}
        s_w = sw[idx].astype(_LD)
        lamb = x["lamb"] * s_w
        K = x["K"]
        P_pol = (4 * K / lamb).astype(np.float64)
        phidot = ((x["w_lin"] + x["kappa_j"] * x["sigma"] * x["lamb"] / (2 * K)) * s_w)
        L2 = x["L"] ** 2
        tmin = np.arctan2(np.sqrt((x["I1"] * x["Q1"] / (x["d31"] * L2)).astype(np.float64)),
                          np.sqrt((x["I3"] * x["Q3"] / (x["d31"] * L2)).astype(np.float64)))
        tmax = np.arctan2(np.sqrt((x["I2"] * x["Q1"] / (x["d32"] * L2)).astype(np.float64)),
                          np.sqrt((x["I3"] * x["Dl"] / (x["d32"] * L2)).astype(np.float64)))
        flip = x["s"] < 0
        tmin, tmax = np.where(flip, np.pi - tmax, tmin), np.where(flip, np.pi - tmin, tmax)
        regime[idx] = "LAM" if lam_side else "SAM"
        out["polhode"][idx] = out["rotation"][idx] = P_pol
        out["precession"][idx] = (_TWO_PI / np.abs(phidot)).astype(np.float64)
        out["separatrix_distance"][idx] = -m1[far] if lam_side else m1[far]
        out["nutation_min"][idx], out["nutation_max"][idx] = tmin, tmax
        q1c = invariants(A[idx], B[idx], C[idx], *w[idx].T)[3]            # 2EC - L^2
        out["energy_ratio"][idx] = 1.0 + q1c / L[idx] ** 2
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", NearSeparatrixWarning)
        for i in np.nonzero(~generic)[0]:
            d = diagnose_principal(I[i], w[i], rtol_symmetry=rtol_symmetry,
                                   rtol_spin=rtol_spin)
            regime[i] = d.regime
            for k, v in d.periods.items():
                out[k][i] = v
            out["energy_ratio"][i] = d.energy_ratio
            out["separatrix_distance"][i] = d.separatrix_distance
            if d.nutation_range is not None:
                out["nutation_min"][i], out["nutation_max"][i] = d.nutation_range
    out["regime"] = regime.astype(str)
    return out

r"""Compiled scalar kernels of the splitting integrator's one-body path (numba, optional).

The one-body step of :mod:`attitude.propagation.splitting` costs ~470 us of Python and
numpy dispatch (issue 18), ~11 us of it in each exact free flow.  This module holds that
flow and the special functions it needs as *scalar* functions written so that numba
compiles them (``nopython``, no allocation), and so that they still run as plain Python
when numba is absent or disabled:

- :data:`NUMBA` is True when numba is installed and ``ATTITUDE_NO_NUMBA=1`` is not set;
- :func:`jit` is ``numba.njit(cache=True, nogil=True, error_model="numpy")`` then, else the
  identity (numba is imported on the first call of a kernel, not with this module).  No
  ``fastmath``: the compiled path must round as IEEE arithmetic does, so that it agrees
  with the numpy fallback to round-off (``tests/test_compiled.py``);
- :func:`ellipj` (Jacobi ``sn, cn, dn``), :func:`elliprf` and :func:`elliprj`
  (Carlson's symmetric integrals): the algorithms of ``scipy.special`` (Cephes' AGM
  for ``ellipj``, Carlson's duplication for ``R_F``, ``R_J``), as scalar code;
- :func:`free_flow_one`: ``splitting._free_flow1`` (the exact free flow of one body
  over one step) on arrays updated in place;
- :func:`jit_formula`: a formula of the model layer (written on floats or arrays)
  compiled as it is, with the package's functions it calls: the free-body invariants,
  half angles and frames here, the torque formulas in :mod:`.compiled_torques` (one
  source per formula, docs/architecture.md).

The special functions here are plain-arithmetic twins of scipy's; the tests run
each one compiled and as plain Python (the module loaded with ``ATTITUDE_NO_NUMBA=1``)
against scipy, mpmath and the splitting module.

The one deliberate difference from scipy is :func:`ellipj` at ``1 - m <= 1e-10``: Cephes
switches there to the expansion in ``1 - m`` about ``m = 1`` (A&S 16.15), which holds
only well inside the first quarter period; beyond it scipy returns values that are not
elliptic functions at all (``sn > 1``, ``cn = -2.9e5`` at ``u = 40``, ``m = 1 - 1e-11``).
Here the expansion is used only where its next term is below the rounding error, and
elsewhere the descending Landen transformation from ``1 - m`` (as the closed form does,
:func:`attitude.foundations.elliptic.landen_sncndn`) on the argument reduced to ``[0, K/2]``;
``splitting`` takes this function there too.

References
----------
.. [1] Abramowitz, M. & Stegun, I. A. (1964). *Handbook of Mathematical Functions*,
   16.4 (the AGM scale), 16.13 (m near 0), 16.15 (m near 1); DLMF 22.20(ii).
.. [2] Moshier, S. L. (1989). *Methods and Programs for Mathematical Functions*
   (Cephes ``ellpj``, as in ``scipy.special.ellipj``).
.. [3] Carlson, B. C. (1995). Numerical computation of real or complex elliptic
   integrals. *Numer. Algorithms* 10, 13-26; DLMF 19.36.1-2.
"""

from __future__ import annotations

import functools
import math

import numpy as np

from ..foundations import elliptic as el
from ..foundations import quaternion as quat
from ..model import freebody as fb
from .jit import (
    COMPILE_NOTICE,
    KERNEL_MODULES,
    KERNEL_SOURCES,
    NUMBA,
    each_on_cores,
    jit,
    jit_formula,
    quiet_compiles,
    set_compile_notice,
)

#: The numba machinery (:mod:`.jit`) is re-exported here, where the kernels' callers have
#: always found it.
__all__ = ["NUMBA", "jit", "jit_formula", "set_compile_notice", "quiet_compiles",
           "COMPILE_NOTICE", "KERNEL_MODULES", "KERNEL_SOURCES", "each_on_cores", "ellipj",
           "elliprf", "elliprj", "free_flow_one", "free_flow_bodies", "free_step"]

#: Unit roundoff of float64 (half the spacing of 1.0): the AGM's stopping test (Cephes'
#: MACHEP) and Carlson's ``r``.
_U = 2.0 ** -53
#: Carlson's (1995) stopping factors ``(3 r)^(-1/6)`` for R_F and ``(r / 4)^(-1/6)`` for
#: R_J, with ``r`` the unit roundoff (constants here: numba folds module globals).
_RF_Q = (3.0 * _U) ** (-1.0 / 6.0)
_RJ_Q = (0.25 * _U) ** (-1.0 / 6.0)


# ===========================================================================
# Jacobi elliptic functions
# ===========================================================================
#: Cephes' switch to the expansions about m = 0 and m = 1 (A&S 16.13, 16.15).
_M_SMALL = 1e-9
_M1_SMALL = 1e-10
#: The expansion about m = 1 is used while ``(1 - m) cosh(u)^2`` is at most this: its
#: relative error is of the order of the square of that number (the next term of
#: A&S 16.15), here below the unit roundoff.
_NEAR1_MAX = 1e-8


@jit
def _amplitude(a, b, c, twon, u):
    """``(phi_i, phi_{i+1})`` of the AGM's backward recurrence from level ``i``
    (``a_i, b_i, c_i``, ``twon = 2^i``) down to convergence (A&S 16.4.3): recursive, so
    that the levels live on the call stack (no array, any number of levels)."""
    if abs(c / a) <= _U or twon >= 2.0 ** 40:
        phi = twon * a * u
        return phi, phi
    a1 = (a + b) / 2.0
    c1 = (a - b) / 2.0
    b1 = math.sqrt(a * b)
    phi1, _ = _amplitude(a1, b1, c1, 2.0 * twon, u)
    return (math.asin(c1 * math.sin(phi1) / a1) + phi1) / 2.0, phi1


#: The descending Landen chain ends where the parameter is below this (its base level
#: is then the expansion about m = 0, A&S 16.13, to O(mu^2)); as attitude.elliptic.
_MU_BASE = 1e-10


# the base level and the steps of the chain: attitude.foundations.elliptic's, compiled
_landen_base = jit(el.landen_base)
_landen_ascend = jit(el.landen_ascend)
_landen_descend = jit(el.landen_descend)


@jit
def _landen(x, kp, omk):
    """``sn, cn, dn (x | m)`` for ``m = 1 - kp^2``, ``omk = 1 - kp`` (formed without
    cancellation), by the descending Landen transformation (A&S 16.12.2-4), each level
    without cancellation (``dn = ((1 - g) + g c^2) / (1 + g s^2)``); recursive, one
    level per call (attitude.foundations.elliptic.landen_sncndn, in scalar float64, on
    its base level and step)."""
    g = omk / (1.0 + kp)
    omg = 2.0 * kp / (1.0 + kp)
    xs = x / (1.0 + g)
    mu = g * g
    if mu < _MU_BASE:
        s, c, d = _landen_base(xs, mu)
    else:
        s, c, d = _landen(xs, *_landen_descend(kp, omk))
    return _landen_ascend(s, c, d, g, omg)


@jit
def _ellipj_near1(u, m, m1):
    """``sn, cn, dn`` for ``m`` near 1 beyond the expansion about ``m = 1``: ``u`` reduced
    to ``[0, K/2]`` by the periods and the quarter-period reflection (DLMF 22.4.3,
    22.4(iii)), where :func:`_landen` keeps ``cn`` and ``dn`` (``>= m1^(1/4)`` there)
    to full relative precision; ``K`` from the same Landen chain (A&S 17.5)."""
    kp = math.sqrt(m1)
    omk = m / (1.0 + kp)
    scale = 1.0
    k, o = kp, omk
    while True:
        g = o / (1.0 + k)
        scale *= 1.0 + g
        if g * g < _MU_BASE:
            break
        k, o = _landen_descend(k, o)
    mu = g * g
    K = scale * (math.pi / 2.0) * (1.0 + mu / 4.0 + 9.0 * mu * mu / 64.0)
    n = math.floor(u / (2.0 * K) + 0.5)
    x = u - 2.0 * K * n                              # in [-K, K]; sn, cn change sign
    sgn = -1.0 if n % 2.0 != 0.0 else 1.0
    ax = abs(x)
    if ax <= 0.5 * K:
        s, c, d = _landen(ax, kp, omk)
    else:                                            # reflection about the quarter period
        s1, c1, d1 = _landen(K - ax, kp, omk)
        s, c, d = c1 / d1, kp * s1 / d1, kp / d1
    return math.copysign(s, x) * sgn, c * sgn, d


@jit
def ellipj(u, m):
    """Jacobi elliptic functions ``sn, cn, dn`` of real ``u`` and parameter ``0 <= m <= 1``.

    Cephes' algorithm (``scipy.special.ellipj``): the expansion about ``m = 0`` below
    ``m = 1e-9`` (A&S 16.13), the AGM scale and its backward recurrence for the
    amplitude (A&S 16.4, DLMF 22.20(ii)), ``dn = cos(phi) / cos(phi - phi_1)`` unless
    that cosine is small (then ``sqrt(1 - m sn^2)``), and the expansion about ``m = 1``
    above ``m = 1 - 1e-10`` (A&S 16.15), the latter only where it holds (module notes):
    beyond, the descending Landen transformation from ``1 - m`` on the argument reduced
    to ``[0, K/2]`` (within ~10 ulp of ``|f| + |u f'|``, where scipy fails).

    Parameters
    ----------
    u : float
        Argument.
    m : float
        Parameter ``k^2`` in ``[0, 1]``; NaN outside (and for an infinite ``u``).

    Returns
    -------
    sn, cn, dn : float

    Examples
    --------
    >>> from scipy import special
    >>> from attitude.propagation.compiled import ellipj
    >>> sn, cn, dn = ellipj(0.7, 0.3)
    >>> [bool(abs(x - y) < 1e-15) for x, y in zip((sn, cn, dn), special.ellipj(0.7, 0.3)[:3])]
    [True, True, True]
    """
    if not (0.0 <= m <= 1.0 and math.isfinite(u)):
        return math.nan, math.nan, math.nan
    if m < _M_SMALL:
        t = math.sin(u)
        b = math.cos(u)
        ai = 0.25 * m * (u - t * b)
        return t - ai * b, b + ai * t, 1.0 - 0.5 * m * t * t
    m1 = 1.0 - m
    if m1 <= _M1_SMALL:
        au = abs(u)
        if m1 == 0.0:                  # sn = tanh, cn = dn = sech (no overflow in cosh)
            e = math.exp(-au)
            sech = 2.0 * e / (1.0 + e * e)
            return math.tanh(u), sech, sech
        if au < 20.0:
            b = math.cosh(u)
            if m1 * b * b <= _NEAR1_MAX:
                ai = 0.25 * m1
                t = math.tanh(u)
                phi = 1.0 / b
                twon = b * math.sinh(u)
                sn = t + ai * (twon - u) / (b * b)
                ai *= t * phi
                return sn, phi - ai * (twon - u), phi + ai * (twon + u)
        return _ellipj_near1(u, m, m1)
    phi, phi1 = _amplitude(1.0, math.sqrt(m1), math.sqrt(m), 1.0, u)
    sn = math.sin(phi)
    cn = math.cos(phi)
    dnfac = math.cos(phi - phi1)
    if abs(dnfac) < 0.1:               # dn near a quarter period (after DLMF 22.20.5)
        dn = math.sqrt(1.0 - m * sn * sn)
    else:
        dn = cn / dnfac
    return sn, cn, dn


# ===========================================================================
# Carlson's symmetric elliptic integrals (Carlson 1995; DLMF 19.36.1-2)
# ===========================================================================
@jit
def elliprf(x, y, z):
    """Carlson's ``R_F(x, y, z)`` for ``x, y, z >= 0``, at most one of them zero.

    Duplication (Carlson 1995, algorithm 1, ``r`` = the unit roundoff) and the fifth-
    order series of DLMF 19.36.1.  ``inf`` when two arguments are zero, NaN for a
    negative or NaN argument.

    Examples
    --------
    >>> from scipy import special
    >>> from attitude.propagation.compiled import elliprf
    >>> bool(abs(elliprf(0.0, 0.25, 1.0) - special.elliprf(0.0, 0.25, 1.0)) < 1e-15)
    True
    """
    if not (x >= 0.0 and y >= 0.0 and z >= 0.0):
        return math.nan
    if x + y == 0.0 or x + z == 0.0 or y + z == 0.0:
        return math.inf
    if x == math.inf or y == math.inf or z == math.inf:
        return 0.0
    a0 = (x + y + z) / 3.0
    q = max(abs(a0 - x), abs(a0 - y), abs(a0 - z)) * _RF_Q
    a = a0
    x0, y0 = x, y
    f = 1.0                                           # 4^-n
    while f * q >= abs(a):
        sx, sy, sz = math.sqrt(x), math.sqrt(y), math.sqrt(z)
        lam = sx * sy + sx * sz + sy * sz
        x = (x + lam) / 4.0
        y = (y + lam) / 4.0
        z = (z + lam) / 4.0
        a = (a + lam) / 4.0
        f /= 4.0
    X = (a0 - x0) * f / a
    Y = (a0 - y0) * f / a
    Z = -(X + Y)
    e2 = X * Y - Z * Z
    e3 = X * Y * Z
    s = (1.0 - e2 / 10.0 + e3 / 14.0 + e2 * e2 / 24.0 - 3.0 * e2 * e3 / 44.0
         - 5.0 * e2 * e2 * e2 / 208.0 + 3.0 * e3 * e3 / 104.0 + e2 * e2 * e3 / 16.0)
    return s / math.sqrt(a)


@jit
def _rc1(e):
    """``R_C(1, 1 + e)`` for ``e > -1`` (DLMF 19.2.19-20): ``atan(sqrt e)/sqrt e``, or
    ``atanh(sqrt(-e))/sqrt(-e)`` for ``e < 0``."""
    if e > 0.0:
        s = math.sqrt(e)
        return math.atan(s) / s
    if e < 0.0:
        s = math.sqrt(-e)
        return math.atanh(s) / s
    return 1.0


@jit
def elliprj(x, y, z, p):
    """Carlson's ``R_J(x, y, z, p)`` for ``x, y, z >= 0`` (at most one zero) and ``p > 0``.

    Duplication (Carlson 1995, algorithm 3, with ``d_m``, ``e_m`` and ``R_C(1, 1 + e_m)``
    of DLMF 19.36.2) and the series of DLMF 19.36.2.  ``inf`` when two of ``x, y, z``
    are zero, 0 for ``p = inf``, NaN for other arguments out of range.

    Examples
    --------
    >>> from scipy import special
    >>> from attitude.propagation.compiled import elliprj
    >>> v = special.elliprj(0.3, 0.64, 1.0, 1.5)
    >>> bool(abs(elliprj(0.3, 0.64, 1.0, 1.5) - v) < 4e-16 * v)
    True
    """
    if not (x >= 0.0 and y >= 0.0 and z >= 0.0 and p > 0.0):
        return math.nan
    if x + y == 0.0 or x + z == 0.0 or y + z == 0.0:
        return math.inf
    if p == math.inf or x == math.inf or y == math.inf or z == math.inf:
        return 0.0
    a0 = (x + y + z + 2.0 * p) / 5.0
    delta = (p - x) * (p - y) * (p - z)
    q = max(abs(a0 - x), abs(a0 - y), abs(a0 - z), abs(a0 - p)) * _RJ_Q
    a = a0
    x0, y0, z0 = x, y, z
    f = 1.0                                           # 4^-n
    f3 = 1.0                                          # 4^-3n
    total = 0.0
    while f * q >= abs(a):
        sx, sy, sz, sp = math.sqrt(x), math.sqrt(y), math.sqrt(z), math.sqrt(p)
        lam = sx * sy + sx * sz + sy * sz
        d = (sp + sx) * (sp + sy) * (sp + sz)
        total += f / d * _rc1(f3 * delta / (d * d))
        x = (x + lam) / 4.0
        y = (y + lam) / 4.0
        z = (z + lam) / 4.0
        p = (p + lam) / 4.0
        a = (a + lam) / 4.0
        f /= 4.0
        f3 /= 64.0
    X = (a0 - x0) * f / a
    Y = (a0 - y0) * f / a
    Z = (a0 - z0) * f / a
    P = -(X + Y + Z) / 2.0
    xyz = X * Y * Z
    e2 = X * Y + X * Z + Y * Z - 3.0 * P * P
    e3 = xyz + 2.0 * e2 * P + 4.0 * P * P * P
    e4 = (2.0 * xyz + e2 * P + 3.0 * P * P * P) * P
    e5 = xyz * P * P
    s = (1.0 - 3.0 * e2 / 14.0 + e3 / 6.0 + 9.0 * e2 * e2 / 88.0 - 3.0 * e4 / 22.0
         - 9.0 * e2 * e3 / 52.0 + 3.0 * e5 / 26.0)
    return f * s / (a * math.sqrt(a)) + 6.0 * total


# ===========================================================================
# the exact free flow over one step: one source (free_step), compiled and as numpy
# ===========================================================================
# The formulas of the free flow are written once, in free_step, in arithmetic that runs
# on plain floats and on numpy arrays alike (numpy's ufuncs, which numba compiles on
# floats).  Where the scalar and the array code must differ, free_step calls one of the
# primitives bound here: a branch (``_select``, ``_any``), a special function, or a
# freebody helper whose float branch numba cannot type.  With numba they are the scalar
# kernels of this module, and free_step is compiled for one body (free_flow_one, and
# free_flow_bodies over a batch: a compiled loop, faster than numpy's passes over the
# arrays); without numba, numpy's and scipy's, and free_step is the vectorised numpy
# path of attitude.propagation.freeflow (a Python loop over the bodies would be ~100x
# slower).  So each formula has one source, and both paths round alike (the tests
# compare them to a few ulp).
#: scipy.special.ellipj (Cephes) switches to its expansion about m = 1 from this m on; the
#: expansion fails past the first quarter period (sn > 1, cn ~ -3e5 at u = 40,
#: m = 1 - 1e-11), so the numpy path takes :func:`ellipj` there (Landen from 1 - m).
CEPHES_NEAR1 = 0.9999999999
_PURE_SPIN_TOL = fb.PURE_SPIN_TOL_UNSCALED
# the freebody and quaternion helpers that numba compiles as they are (their float
# branch chosen by isinstance; jit_formula compiles the helpers they call with them);
# without numba, they are the functions themselves
_separatrix_gap = jit_formula(fb.separatrix_gap)
_jacobi_parameters = jit_formula(fb.jacobi_parameters)
_kernel_moments = jit_formula(fb.kernel_moments)
_kernel_vector = jit_formula(fb.kernel_vector)
_euler313_quaternion = jit_formula(fb.euler313_quaternion)
_multiply_parts = jit_formula(quat.multiply_parts)
_conjugate_parts = jit_formula(quat.conjugate_parts)
_invariants = jit_formula(fb.invariants)
_half_theta = jit_formula(fb.half_theta_scalar)


@jit
def _round_half_even(x):
    """Python's ``round(x)`` of a float (ties to even), as a float."""
    r = math.floor(x)
    d = x - r                                        # exact, in [0, 1)
    if d > 0.5 or (d == 0.5 and r % 2.0 != 0.0):
        r += 1.0
    return r


@jit
def _select_scalar(c, a, b):
    return a if c else b


@jit
def _any_scalar(c):
    return c


def _ellipj_numpy(u, m):
    """``sn, cn, dn`` by scipy.special.ellipj, by :func:`ellipj` from ``m >= CEPHES_NEAR1``
    on (module notes)."""
    from scipy import special as sp  # costly: only the numpy path (numba absent) needs it

    sn, cn, dn, _ = sp.ellipj(u, m)
    near = np.atleast_1d(m >= CEPHES_NEAR1)
    if near.any():
        sn, cn, dn = np.atleast_1d(sn).copy(), np.atleast_1d(cn).copy(), np.atleast_1d(dn).copy()
        uu = np.broadcast_to(np.atleast_1d(u), near.shape)
        mm = np.broadcast_to(np.atleast_1d(m), near.shape)
        for i in np.flatnonzero(near):
            sn[i], cn[i], dn[i] = ellipj(float(uu[i]), float(mm[i]))
        if np.ndim(u) == 0 and np.ndim(m) == 0:
            sn, cn, dn = sn[0], cn[0], dn[0]
    return sn, cn, dn


if NUMBA:
    _select, _any, _rint = _select_scalar, _any_scalar, _round_half_even
    _ellipj, _elliprf, _elliprj = ellipj, elliprf, elliprj
    _half_theta_any, _invariants_any = _half_theta, _invariants
else:
    def _elliprf(x, y, z):
        from scipy import special as sp  # costly: only the numpy path needs it

        return sp.elliprf(x, y, z)

    def _elliprj(x, y, z, p):
        from scipy import special as sp  # costly: only the numpy path needs it

        return sp.elliprj(x, y, z, p)

    def _select(c, a, b):
        """np.where, or a branch on one body's flag (no 0-d array: ~5x faster)."""
        if isinstance(c, (bool, np.bool_)):
            return a if c else b
        return np.where(c, a, b)

    def _any(c):
        return bool(c) if isinstance(c, (bool, np.bool_)) else bool(c.any())

    _rint = np.rint
    _ellipj = _ellipj_numpy
    _half_theta_any, _invariants_any = fb.half_theta, fb.invariants


@jit
def free_step(A, B, C, spherical, lam_on_tie, nu_sam, nu_lam, o1, o2, o3, h):
    """The step of the exact free flow over ``h``: the rotation ``g`` it applies in
    principal axes (``q(t + h) = q(t) g``) and the new principal rates.

    One body (floats; compiled with numba) or many (arrays of one shape; numpy): the
    single source of the free flow (the module notes above).  The formulas and their
    numbering (S1-S5) are those of :func:`attitude.propagation.freeflow.free_flow`.

    Parameters
    ----------
    A, B, C : float or array
        Principal moments scaled by a power of two (:class:`~attitude.propagation.
        freeflow.FreeConstants`).
    spherical, lam_on_tie : bool or bool array
        Rotation is uniform; the kernel frame on the separatrix is the LAM one.
    nu_sam, nu_lam : float or array
        The characteristic ``nu`` of both kernel frames.
    o1, o2, o3 : float or array
        Principal-frame rates, rad/s.
    h : float or array
        Interval, s (any sign).

    Returns
    -------
    gx, gy, gz, gw, p1, p2, p3
        The rotation's quaternion components (scalar last, unit to round-off) and the
        rates at ``t + h``.

    Examples
    --------
    >>> from attitude.propagation.compiled import free_step
    >>> g = free_step(0.25, 0.5, 0.75, False, False, 3.0, 1 / 3, 0.0, 0.0, 1.0, 0.5)
    >>> [round(float(x), 12) for x in g]     # pure spin about C: half a radian about z
    [0.0, 0.0, 0.247403959255, 0.968912421711, 0.0, 0.0, 1.0]
    """
    # kernel frame: SAM (A, B, C), or LAM (C, B, A) along (e3, -e2, e1)          (S1)
    delta = _separatrix_gap(A, B, C, o1, o3)                            # L^2 - 2EB
    lam = np.logical_or(delta < 0, np.logical_and(delta == 0, lam_on_tie))
    I1, I2, I3 = _kernel_moments(A, B, C, lam)
    w1, w2, w3 = _kernel_vector(o1, o2, o3, lam)
    nu = _select(lam, nu_lam, nu_sam)
    d21, d32, d31, Q1, Q3, Dk, Lsq = _invariants_any(I1, I2, I3, w1, w2, w3)
    L1, L2, L3 = I1 * w1, I2 * w2, I3 * w3
    L = np.sqrt(Lsq)
    m, m1, lam2 = _jacobi_parameters(I1, I2, I3, d21, d32, d31, Q1, Q3, Dk)
    m = np.minimum(np.maximum(m, 0.0), 1.0)
    m1 = np.minimum(np.maximum(m1, 0.0), 1.0)
    # u = u0 + lambda t with dn(u) = w3 / a3 > 0: lambda has the sign of w3 (I3 - I2)
    s = _select(w3 < 0, -1.0, 1.0)
    lamb = _select(lam, -s, s) * np.sqrt(lam2)
    v = lamb * h
    sn, cn, dn = _ellipj(v, m)
    snl = sn / lamb
    # rates by the addition theorems, no amplitude in a denominator              (S2)
    D = 1.0 - (I2 * d21 / Q3) * (w2 * w2) * (sn * sn)
    n1 = (w1 * cn - (d32 / I1) * w2 * w3 * snl * dn) / D
    n2 = (w2 * cn * dn + (d31 / I2) * w1 * w3 * snl) / D
    n3 = (w3 * dn - (d21 / I3) * w1 * w2 * snl * cn) / D
    # precession angle about L                                                   (S3)
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
    S0 = nu3 * sn0 ** 3 * _elliprj(cn0 * cn0, dn0 * dn0, 1.0, 1.0 + nu * sn0 * sn0)
    S1 = nu3 * sn1 ** 3 * _elliprj(cn1 * cn1, dn1 * dn1, 1.0, 1.0 + nu * sn1 * sn1)
    S0 = _select(nu == 0, 0.0, S0)
    S1 = _select(nu == 0, 0.0, S1)
    p0 = cn0 >= 0                                     # parity of the half-period window
    p1 = cn1 >= 0
    dwin = _select(p0 == p1, 0.0, _select(v >= 0, 1.0, -1.0))
    far = np.abs(v) >= math.pi                        # 2K >= pi: may span > 1 window
    if _any(far):
        K = _elliprf(0.0, m1, 1.0)
        uh = sn0 * _elliprf(cn0 * cn0, dn0 * dn0, 1.0)
        u0 = _select(p0, uh, np.copysign(2.0 * K, sn0) - uh)
        general = _rint((u0 + v) / (2.0 * K)) - _rint(u0 / (2.0 * K))
        dwin = _select(np.logical_and(far, m1 > 0), general, dwin)
    dJ = _select(p1, S1, -S1) - _select(p0, S0, -S0)
    if _any(dwin != 0):
        JK = nu3 * _elliprj(0.0, m1, 1.0, 1.0 + nu)
        dJ = dJ + _select(dwin == 0, 0.0, 2.0 * dwin * JK)
    c1 = L * d31 / (I1 * I3)
    dphi = h * (L / I3 + c1) - c1 * dJ / lamb
    # attitude: q(t+h) = q(t) E0^-1 E1, E = Rz(phi) Rx(theta) Rz(psi)           (S4)
    ct0, st0 = _half_theta_any(L1, L2, L3)
    M1, M2, M3 = I1 * n1, I2 * n2, I3 * n3
    ct1, st1 = _half_theta_any(M1, M2, M3)
    e = _euler313_quaternion(ct0, st0, 0.0, np.arctan2(L1, L2))
    f = _euler313_quaternion(ct1, st1, dphi, np.arctan2(M1, M2))
    gx, gy, gz, gw = _multiply_parts(_conjugate_parts(e), f)
    gx, gy, gz = _kernel_vector(gx, gy, gz, lam)          # the step in principal axes
    p1_, p2_, p3_ = _kernel_vector(n1, n2, n3, lam)
    # uniform rotation: spherical body, principal-axis spin, rest, lambda = 0     (S5)
    aL1, aL2, aL3 = np.abs(L1), np.abs(L2), np.abs(L3)
    mid = np.maximum(np.minimum(aL1, aL2), np.minimum(np.maximum(aL1, aL2), aL3))
    uniform = np.logical_or(
        np.logical_or(spherical, mid <= _PURE_SPIN_TOL * L),
        np.logical_not(np.logical_and(lam2 > 0, np.isfinite(gx + gy + gz + gw + p1_ + p2_
                                                            + p3_))))
    if _any(uniform):
        wn = np.sqrt(o1 * o1 + o2 * o2 + o3 * o3)
        half = 0.5 * wn * h
        sh = _select(wn > 0, np.sin(half) / wn, 0.0)
        gx = _select(uniform, sh * o1, gx)
        gy = _select(uniform, sh * o2, gy)
        gz = _select(uniform, sh * o3, gz)
        gw = _select(uniform, np.cos(half), gw)
        p1_ = _select(uniform, o1, p1_)
        p2_ = _select(uniform, o2, p2_)
        p3_ = _select(uniform, o3, p3_)
    return gx, gy, gz, gw, p1_, p2_, p3_


@jit
def _rotate_by(q, gx, gy, gz, gw):
    """``q <- q g / |q g|`` in place."""
    nx, ny, nz, nw = _multiply_parts((q[0], q[1], q[2], q[3]), (gx, gy, gz, gw))
    r = 1.0 / math.sqrt(nx * nx + ny * ny + nz * nz + nw * nw)
    q[0] = nx * r
    q[1] = ny * r
    q[2] = nz * r
    q[3] = nw * r


@jit
def free_flow_one(c, q, w, h):
    """Exact torque-free motion of one body over ``h``, in place: :func:`free_step`.

    Parameters
    ----------
    c : float64 array (7,), like ``q`` and ``w`` C-contiguous (each other layout or
        dtype compiles once more)
        ``[A, B, C, spherical, lam_on_tie, nu_sam, nu_lam]``: the moments scaled by a
        power of two and the flags (0 or 1) and characteristics of
        :class:`attitude.propagation.freeflow.FreeConstants` (its ``row``).
    q : float64 array (4,)
        Principal -> inertial quaternion, scalar-last, unit; overwritten with ``q(t + h)``.
    w : float64 array (3,)
        Principal-frame rates, rad/s; overwritten with ``omega(t + h)``.
    h : float
        Interval, s (any sign).

    Notes
    -----
    The formulas and their numbering (S1-S5) are those of
    :func:`attitude.propagation.freeflow.free_flow`; the special functions are
    :func:`ellipj`, :func:`elliprf` and :func:`elliprj` of this module (scipy's without
    numba).

    Examples
    --------
    >>> import numpy as np
    >>> from attitude.propagation.compiled import free_flow_one
    >>> from attitude.propagation.splitting import free_flow
    >>> q, w = np.array([0.0, 0.0, 0.0, 1.0]), np.array([0.1, 0.2, 1.0])
    >>> qr, wr = free_flow([0.25, 0.5, 0.75], q, w, 2.5)
    >>> free_flow_one(np.array([0.25, 0.5, 0.75, 0, 0, 3.0, 1 / 3]), q, w, 2.5)
    >>> bool(np.allclose(q, qr, rtol=0, atol=1e-15) and np.allclose(w, wr, rtol=0, atol=1e-15))
    True
    """
    gx, gy, gz, gw, p1, p2, p3 = free_step(c[0], c[1], c[2], c[3] != 0.0, c[4] != 0.0,
                                           c[5], c[6], w[0], w[1], w[2], h)
    _rotate_by(q, gx, gy, gz, gw)
    w[0] = p1
    w[1] = p2
    w[2] = p3


if not NUMBA:
    def _quietly(function):
        """``function`` under ``np.errstate(all="ignore")``: as plain Python, free_step
        divides by zero and takes square roots of negatives where numba (its numpy error
        model) does so silently, in the branches that the selections then discard."""
        @functools.wraps(function)
        def quiet(*args):
            with np.errstate(all="ignore"):
                return function(*args)
        return quiet

    free_step, free_flow_one = _quietly(free_step), _quietly(free_flow_one)


@jit
def free_flow_bodies(c, q, w, h):
    """:func:`free_flow_one` of each body of a batch, in place: ``c`` (N, 7) rows of
    constants, ``q`` (N, 4), ``w`` (N, 3), ``h`` (N,) intervals (the compiled
    vectorised free flow).

    Examples
    --------
    >>> import numpy as np
    >>> from attitude.propagation.compiled import free_flow_bodies, free_flow_one
    >>> c = np.array([[0.25, 0.5, 0.75, 0, 0, 3.0, 1 / 3]] * 2)
    >>> q, w = np.array([[0, 0, 0, 1.0]] * 2), np.array([[0.1, 0.2, 1.0]] * 2)
    >>> free_flow_bodies(c, q, w, np.array([2.5, -2.5]))           # each body its own h
    >>> q1, w1 = np.array([0, 0, 0, 1.0]), np.array([0.1, 0.2, 1.0])
    >>> free_flow_one(c[1], q1, w1, -2.5)
    >>> bool(np.array_equal(q[1], q1) and np.array_equal(w[1], w1))
    True
    """
    for i in range(q.shape[0]):
        free_flow_one(c[i], q[i], w[i], h[i])

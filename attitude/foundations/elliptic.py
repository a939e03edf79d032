"""Private numerical kernels for the exact torque-free solution.

Everything here is vectorised numpy; nothing loops over epochs or bodies in
Python (the only loops run over a handful of Landen / AGM levels).

Contents
--------
* error-free transformations and double-double helpers (Dekker 1971,
  Knuth TAOCP vol. 2 §4.2.2) used to carry phases past the 53-bit limit and to
  form the separatrix discriminant without cancellation;
* the descending Landen (Gauss) transformation for Jacobi ``sn, cn, dn``
  evaluated from the *complementary* parameter ``m1 = 1 - m``
  (Abramowitz & Stegun 16.12.2-4, 16.13.1-3; DLMF 22.7.1-3);
* Bulirsch's general complete elliptic integral ``cel`` (Bulirsch 1969,
  Numer. Math. 13, 305; Numerical Recipes 2nd ed. §6.11), evaluated in
  ``numpy.longdouble``.
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "LD",
    "PI_LD",
    "two_sum",
    "fast_two_sum",
    "split",
    "two_prod",
    "dd_mul_d",
    "dd_mul_dd",
    "dd_add",
    "ld_to_dd",
    "landen_chain",
    "k_from_chain",
    "landen_sncndn",
    "landen_base",
    "landen_ascend",
    "landen_descend",
    "cel",
]

#: pi in extended precision
PI_LD = np.longdouble("3.14159265358979323846264338327950288")

#: extended precision used for per-body constants (80-bit on x86-64 Linux; on
#: platforms where it is plain double the code still works, a few ulp less exact)
LD = np.longdouble

_SPLITTER = 134217729.0  # 2**27 + 1, Veltkamp splitting constant


# --------------------------------------------------------------------------
# error-free transformations (float64)
# --------------------------------------------------------------------------
def two_sum(a, b):
    """``s + e == a + b`` exactly, ``s = fl(a + b)`` (Knuth).

    Examples
    --------
    >>> s, e = two_sum(1.0, 1e-17)     # 1e-17 is lost in fl(1 + 1e-17), kept in e
    >>> s, e
    (1.0, 1e-17)
    """
    s = a + b
    bb = s - a
    e = (a - (s - bb)) + (b - bb)
    return s, e


def fast_two_sum(a, b):
    """``s + e == a + b`` exactly, valid for ``|a| >= |b|`` (Dekker).

    Examples
    --------
    >>> fast_two_sum(1.0, 2.0 ** -60)       # |a| >= |b|
    (1.0, 8.673617379884035e-19)
    """
    s = a + b
    e = b - (s - a)
    return s, e


def split(a):
    """Veltkamp split ``a = hi + lo`` with ``hi`` holding 26 significant bits.

    For ``|a| > ~1e291`` (where ``2**27 a`` overflows) the split degrades gracefully
    to ``(a, 0)``: products then lose their exact error term, nothing worse.

    Examples
    --------
    >>> from fractions import Fraction as F
    >>> hi, lo = split(0.1)
    >>> hi + lo == 0.1, F(hi) * F(hi) == F(hi * hi)   # hi * hi is exact: hi has 26 bits
    (True, True)
    """
    with np.errstate(over="ignore", invalid="ignore"):
        c = _SPLITTER * a
        hi = c - (c - a)
    if not np.all(np.isfinite(hi)):
        hi = np.where(np.isfinite(hi), hi, a)
    return hi, a - hi


def two_prod(a, b, b_split=None):
    """``p + e == a * b`` exactly (Dekker's product; no FMA in numpy).

    Examples
    --------
    >>> p, e = two_prod(0.1, 0.1)        # 0.1 * 0.1 = p + e exactly
    >>> p, e
    (0.010000000000000002, -8.326672684688674e-19)
    >>> from fractions import Fraction as F
    >>> F(p) + F(e) == F(0.1) * F(0.1)
    True
    """
    p = a * b
    ah, al = split(a)
    bh, bl = split(b) if b_split is None else b_split
    e = ((ah * bh - p) + ah * bl + al * bh) + al * bl
    return p, e


def dd_mul_d(x, b):
    """double-double times double, relative error ~ 2 eps**2.

    Examples
    --------
    >>> x = two_sum(1.0, 1e-20)            # the double-double 1 + 1e-20
    >>> dd_mul_d(x, 3.0)
    (3.0, 3e-20)
    """
    p, e = two_prod(x[0], b)
    e = e + x[1] * b
    return fast_two_sum(p, e)


def dd_mul_dd(x, y):
    """double-double times double-double, relative error ~ 4 eps**2.

    Examples
    --------
    >>> x = two_sum(1.0, 1e-20)
    >>> dd_mul_dd(x, x)                    # (1 + 1e-20)^2 = 1 + 2e-20 + 1e-40
    (1.0, 2e-20)
    """
    p, e = two_prod(x[0], y[0])
    e = e + (x[0] * y[1] + x[1] * y[0])
    return fast_two_sum(p, e)


def dd_add(x, y):
    """double-double sum (Bailey's "sloppy" add; exact when no cancellation
    of the low parts matters, always correct to ~eps**2 of the operands).

    Examples
    --------
    >>> dd_add((1.0, 1e-20), (-1.0, 1e-20))    # the low parts survive the cancellation
    (2e-20, 0.0)
    """
    s, e = two_sum(x[0], y[0])
    e = e + (x[1] + y[1])
    return fast_two_sum(s, e)


def ld_to_dd(x):
    """Split a ``longdouble`` array into float64 ``(hi, lo)``.

    Examples
    --------
    >>> third = np.longdouble(1) / 3
    >>> hi, lo = ld_to_dd(third)
    >>> float(hi), bool(np.longdouble(hi) + np.longdouble(lo) == third)
    (0.3333333333333333, True)
    """
    x = np.asarray(x, dtype=LD)
    hi = x.astype(np.float64)
    lo = (x - hi.astype(LD)).astype(np.float64)
    return hi, lo


# --------------------------------------------------------------------------
# Jacobi elliptic functions by descending Landen transformation, from m1
# --------------------------------------------------------------------------
#: the chain stops when the base parameter mu drops below this; the first-order
#: small-parameter expansion (A&S 16.13) then errs by O(mu**2) < 1e-20
MU_BASE_MAX = 1e-10


def landen_chain(m, m1):
    """Descending Landen chain from the parameter ``m`` and its complement ``m1``.

    Both ``m`` and ``m1 = 1 - m`` are passed (each computed without
    cancellation by the caller), so ``k' = sqrt(m1)`` keeps full relative
    precision however close ``m`` is to 1 (the separatrix).

    Parameters
    ----------
    m, m1 : array_like of longdouble, shape (n,)

    Returns
    -------
    g : ndarray (levels, n) float64
        ``sqrt(mu_{i+1}) = (1 - k'_i) / (1 + k'_i)`` for each level.
    omg : ndarray (levels, n) float64
        ``1 - g`` formed without cancellation, ``2 k'_i / (1 + k'_i)``.
    scale : ndarray (n,) longdouble
        ``prod(1 + g_i)``; ``K(m) = scale * K(mu_base)`` (A&S 17.5.x).
    mu : ndarray (n,) longdouble
        Base parameter ``mu_base`` (``< MU_BASE_MAX``).

    Examples
    --------
    >>> from scipy.special import ellipk
    >>> m = np.array([0.5, 0.99])
    >>> g, omg, scale, mu = landen_chain(m, 1 - m)
    >>> g.shape[1], bool(np.all(mu < MU_BASE_MAX))
    (2, True)
    >>> K = k_from_chain(scale, mu)               # K(m) = scale * K(mu_base)
    >>> bool(np.allclose(K.astype(float), ellipk(m), rtol=4e-16, atol=0))
    True
    """
    m = np.asarray(m, dtype=LD)
    m1 = np.asarray(m1, dtype=LD)
    kp = np.sqrt(m1)
    omk = m / (1 + kp)  # 1 - k', no cancellation
    gs, omgs = [], []
    scale = np.ones_like(kp)
    while True:
        g = omk / (1 + kp)
        omg = 2 * kp / (1 + kp)
        gs.append(g)
        omgs.append(omg)
        scale = scale * (1 + g)
        mu = g * g
        if not np.any(mu >= MU_BASE_MAX) or len(gs) > 40:
            break
        kp, omk = landen_descend(kp, omk)
    g = np.array(gs, dtype=LD)
    omg = np.array(omgs, dtype=LD)
    return g.astype(np.float64), omg.astype(np.float64), scale, mu


def k_from_chain(scale, mu):
    """Complete integral ``K(m) = scale * K(mu)``, ``K(mu)`` from its series
    (A&S 17.3.11) to O(mu**3).

    Examples
    --------
    >>> from scipy.special import ellipk
    >>> m = np.array([0.2, 0.999999])
    >>> g, omg, scale, mu = landen_chain(m, 1 - m)
    >>> K = k_from_chain(scale, mu).astype(float)
    >>> bool(np.allclose(K, ellipk(m), rtol=1e-15, atol=0))
    True
    """
    return scale * (PI_LD / 2) * (1 + mu / 4 + 9 * mu * mu / 64)


def landen_sncndn(x, g, omg, inv_scale, mu):
    """``sn, cn, dn (x | m)`` for ``0 <= x <= K/2`` by descending Landen.

    ``x`` and the per-body constants broadcast together; ``g`` and ``omg`` have
    a leading level axis.  On ``[0, K/2]`` every returned function is bounded
    away from 0 in the relative sense needed (``dn >= m1**(1/4)``), and each
    level is evaluated without cancellation::

        D  = 1 + g s^2
        sn = (1 + g) s / D
        cn = c d / D
        dn = ((1 - g) + g c^2) / D      # = (1 - g s^2)/D, A&S 16.12.4 rearranged

    where ``s, c, d`` are the functions of the next (smaller) parameter at
    argument ``x / prod(1 + g)``; the base level uses A&S 16.13.1-3.

    Examples
    --------
    >>> from scipy.special import ellipj
    >>> m = np.array([0.5, 0.99])
    >>> g, omg, scale, mu = landen_chain(m, 1 - m)
    >>> x = 0.3 * k_from_chain(scale, mu).astype(float)          # inside [0, K/2]
    >>> s, c, d = landen_sncndn(x, g, omg, (1 / scale).astype(float), mu.astype(float))
    >>> sj, cj, dj, _ = ellipj(x, m)
    >>> bool(np.allclose([s, c, d], [sj, cj, dj], rtol=0, atol=1e-15))
    True
    >>> bool(np.allclose(s**2 + c**2, 1.0, rtol=0, atol=4e-16))
    True
    """
    s, c, d = landen_base(x * inv_scale, mu)
    for lev in range(g.shape[0] - 1, -1, -1):
        s, c, d = landen_ascend(s, c, d, g[lev], omg[lev])
    return s, c, d


# The three formulas of the chain, each once, in numpy's ufuncs on floats or arrays: numba
# compiles them on floats for the scalar kernels (attitude.propagation.compiled._landen).
def landen_base(v, mu):
    """``sn, cn, dn (v | mu)`` at the base of the chain, ``mu < MU_BASE_MAX``: the
    expansion about ``m = 0`` to ``O(mu)`` (A&S 16.13.1-3).

    Examples
    --------
    >>> [round(float(f), 12) for f in landen_base(0.5, 0.0)]     # sin, cos, 1
    [0.479425538604, 0.87758256189, 1.0]
    """
    s0 = np.sin(v)
    c0 = np.cos(v)
    corr = (0.25 * mu) * (v - s0 * c0)
    return s0 - corr * c0, c0 + corr * s0, 1.0 - (0.5 * mu) * (s0 * s0)


def landen_descend(kp, omk):
    """One level down the chain: ``k'`` and ``1 - k'`` of the next (smaller) parameter
    from those of a level, ``k'_{i+1} = 2 sqrt(k') / (1 + k')`` and
    ``1 - k'_{i+1} = (1 - sqrt k')^2 / (1 + k')`` with ``1 - sqrt k' = (1 - k') / (1 +
    sqrt k')`` (no cancellation).

    Examples
    --------
    >>> [float(x) for x in landen_descend(0.25, 0.75)]
    [0.8, 0.2]
    """
    sq = np.sqrt(kp)
    return 2.0 * sq / (1.0 + kp), (omk / (1.0 + sq)) ** 2 / (1.0 + kp)


def landen_ascend(s, c, d, g, omg):
    """One level up the chain: ``sn, cn, dn`` of a level from those ``s, c, d`` of the
    next (smaller) parameter at the argument divided by ``1 + g`` (A&S 16.12.2-4, each
    without cancellation; ``omg = 1 - g``, formed without it).

    Examples
    --------
    >>> landen_ascend(0.0, 1.0, 1.0, 0.25, 0.75)                  # u = 0
    (0.0, 1.0, 1.0)
    """
    inv_d = 1.0 / (1.0 + g * (s * s))
    return ((1.0 + g) * inv_d) * s, (c * d) * inv_d, (omg + g * (c * c)) * inv_d


# --------------------------------------------------------------------------
# Bulirsch's general complete elliptic integral
# --------------------------------------------------------------------------
def cel(kc, p, a, b):
    r"""Bulirsch's ``cel(kc, p, a, b)`` for ``kc > 0, p > 0`` in longdouble.

    .. math::
        \mathrm{cel}(k_c,p,a,b) = \int_0^{\pi/2}
        \frac{a\cos^2\theta + b\sin^2\theta}
             {(\cos^2\theta + p\sin^2\theta)\sqrt{\cos^2\theta + k_c^2\sin^2\theta}}
        \,d\theta

    so ``K = cel(k', 1, 1, 1)`` and ``Pi(n|m) = cel(k', 1 - n, 1, 1)``.  The
    complementary modulus enters directly, so nothing cancels near ``m = 1``;
    convergence is quadratic (Bulirsch 1969; Numerical Recipes §6.11).

    Examples
    --------
    >>> from scipy.special import ellipk
    >>> m = np.array([0.5, 0.99])
    >>> K = cel(np.sqrt(1 - m), 1, 1, 1)            # K(m) = cel(k', 1, 1, 1)
    >>> bool(np.allclose(K.astype(float), ellipk(m), rtol=4e-16, atol=0))
    True
    """
    kc, p, a, b = np.broadcast_arrays(*(np.asarray(z, dtype=LD) for z in (kc, p, a, b)))
    qc = np.abs(kc).copy()
    a = a.copy()
    p = np.sqrt(p)
    b = b / p
    e = qc.copy()
    em = np.ones_like(qc)
    done = np.zeros(qc.shape, dtype=bool)
    ca = LD(1e-10) if np.finfo(LD).eps < 1e-17 else LD(1e-8)
    for _ in range(60):
        f = a
        a_n = a + b / p
        g = e / p
        b_n = 2 * (b + f * g)
        p_n = g + p
        g = em
        em_n = em + qc
        conv = np.abs(g - qc) <= g * ca
        upd = ~done
        a = np.where(upd, a_n, a)
        b = np.where(upd, b_n, b)
        p = np.where(upd, p_n, p)
        em = np.where(upd, em_n, em)
        done = done | conv
        if done.all():
            break
        qc_n = 2 * np.sqrt(e)
        e_n = qc_n * em
        qc = np.where(done, qc, qc_n)
        e = np.where(done, e, e_n)
    return (PI_LD / 2) * (b + a * em) / (em * (em + p))

r"""Exact torque-free rotation of a rigid body (Euler–Poinsot), vectorised.

The closed-form solution of Euler's equations

.. math::
    A\dot\omega_1 = (B - C)\,\omega_2\omega_3,\quad
    B\dot\omega_2 = (C - A)\,\omega_3\omega_1,\quad
    C\dot\omega_3 = (A - B)\,\omega_1\omega_2 ,\qquad A \le B \le C

with the attitude carried by 3-1-3 Euler angles ``(phi, theta, psi)`` of the body
relative to a fixed frame whose z axis is the (constant) angular momentum L.  The
method, formulas, tolerances and measured accuracy are in ``docs/torquefree.md``;
equation numbers ``(TF n)`` in comments refer to that document.

Sources: Landau & Lifshitz, *Mechanics* §37; Whittaker, *Analytical Dynamics* §69;
Samarasinha & A'Hearn 1991 (Icarus 93, 194); Kaasalainen 2001 (A&A 376, 302);
Abramowitz & Stegun ch. 16-17; DLMF §19.25, §22.7; Carlson 1995 (Numer. Algorithms
10, 13); Bulirsch 1969 (Numer. Math. 13, 305).

Conventions: principal moments sorted ``A <= B <= C``; quaternions scalar-last
``(x, y, z, w)`` mapping principal-frame vectors to the inertial frame; ``omega`` in
principal-frame components (rad/s); time in seconds since the initial epoch.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field

import numpy as np
from scipy import special as sp

from .. import freebody as fb
from .. import quaternion as quat
from ..body import SYMMETRY_RTOL, to_principal_frame
from ..errors import InvalidInertiaError, InvalidStateError, NearSeparatrixWarning
from ..freebody import (
    EQUAL_MOMENTS_RTOL,
    NEAR_SEPARATRIX_WARN,
    PURE_SPIN_TOL,
    SEPARATRIX_M1_TOL,
)
from ..regimes import PERIOD_KEYS, REGIMES
from . import elliptic as el

__all__ = [
    "free_rotation",
    "exact_arrays",
    "Diagnosis",
    "diagnose",
    "diagnose_principal",
    "diagnose_many",
    "branch_of",
    "RTOL_AXISYMMETRIC",
    "PURE_SPIN_TOL",
    "SEPARATRIX_M1_TOL",
    "NEAR_SEPARATRIX_WARN",
]

#: The branch tolerances (:data:`PURE_SPIN_TOL`, :data:`SEPARATRIX_M1_TOL`,
#: :data:`NEAR_SEPARATRIX_WARN`) live in :mod:`attitude.freebody` with their reasons.
#: ``RTOL_AXISYMMETRIC`` is this module's earlier name of
#: :data:`attitude.freebody.EQUAL_MOMENTS_RTOL` (the same value), kept for its users.
RTOL_AXISYMMETRIC = EQUAL_MOMENTS_RTOL

_BLOCK = 1 << 15  # elements per evaluation block (fits L2 cache)
_TWO_PI = 2.0 * math.pi
_FOUR_PI_LD = 4 * el.PI_LD
_LD = el.LD


# ===========================================================================
# small helpers
# ===========================================================================
def _lin_turns(tsp, t, c, add=None):
    """``t * c (+ add)`` as an unevaluated sum ``p + e`` (double-double).

    ``c = (h1, h2, lo, hi)``: ``hi = h1 + h2`` is Veltkamp-split so its product with
    the split time ``tsp`` is error-free (Dekker 1971); ``lo`` is the longdouble
    residual of the constant (TF 20).
    """
    th, tl = tsp
    ch, cl, clo, chi = c
    p = t * chi
    e = ((th * ch - p) + th * cl + tl * ch) + tl * cl + t * clo
    if add is not None:
        p, e2 = el.two_sum(p, add)
        e = e + e2
    return p, e


def _frac_turns(tsp, t, c, j=None, cj=None):
    """Fractional part (turns, ``|F| <= 1/2``) of ``t * c (+ j * cj)``.

    Each product is formed error-free and reduced modulo 1 on its own before the
    parts are added, so the result has absolute error ~1e-16 however many turns
    ``t * c`` and ``j * cj`` hold (up to ~1e15 turns).
    """
    p, e = _lin_turns(tsp, t, c)
    f = p - np.rint(p)
    if j is not None:
        jh, jl = el.split(j)
        ch, cl, clo, chi = cj
        p2 = j * chi
        e = e + (((jh * ch - p2) + jh * cl + jl * ch) + jl * cl + j * clo)
        f = f + (p2 - np.rint(p2))
    F = f + e
    return F - np.rint(F)


def _turn_const(x_ld):
    """Per-body constant (longdouble, turns per unit time) -> split triple."""
    hi, lo = el.ld_to_dd(x_ld)
    h1, h2 = el.split(hi)
    return (h1, h2, lo, hi)


def _blocks(nrows, ncols):
    """Row/column slices of ~_BLOCK elements covering an (nrows, ncols) grid."""
    if ncols >= _BLOCK or nrows == 1:
        step = max(_BLOCK, 1)
        for r in range(nrows):
            for c0 in range(0, ncols, step):
                yield slice(r, r + 1), slice(c0, min(c0 + step, ncols))
    else:
        rstep = max(1, _BLOCK // max(ncols, 1))
        for r0 in range(0, nrows, rstep):
            yield slice(r0, min(r0 + rstep, nrows)), slice(0, ncols)


def _sub(consts, rows):
    """Slice every per-body constant (leading body axis; Landen arrays have a level
    axis first) to the rows of a block."""
    out = {}
    for k, v in consts.items():
        if isinstance(v, tuple):
            out[k] = tuple(x[rows] for x in v)
        elif isinstance(v, np.ndarray) and v.ndim == 3:
            out[k] = v[:, rows]
        elif isinstance(v, np.ndarray):
            out[k] = v[rows]
        else:
            out[k] = v
    return out


def _col(x):
    """(n,) -> (n, 1) float64 for broadcasting against (n, T)."""
    return np.asarray(x, dtype=np.float64).reshape(-1, 1)


# ===========================================================================
# discriminant and per-body invariants
# ===========================================================================
def _discriminant_dd(I, w):
    """``2EB - L^2 = C(C-B) w3^2 - A(B-A) w1^2`` with sign flipped, i.e.
    ``Delta = L^2 - 2EB``, in double-double (TF 5).

    Computed from the rate components so the only cancellation is the final
    subtraction, done on operands exact to ~eps**2: the result carries full
    relative precision down to ``|Delta| ~ 1e-16 |terms|`` and beyond.
    """
    A, B, C = I[:, 0], I[:, 1], I[:, 2]
    w1, w3 = w[:, 0], w[:, 2]
    d32 = el.two_sum(C, -B)
    d21 = el.two_sum(B, -A)
    t3 = el.dd_mul_dd(el.dd_mul_d(el.two_prod(w3, w3), C), d32)
    t1 = el.dd_mul_dd(el.dd_mul_d(el.two_prod(w1, w1), A), d21)
    return el.dd_add(t3, (-t1[0], -t1[1]))


def _invariants_ld(I, w):
    """Kernel-frame invariants in longdouble for moments ``I = (I1, I2, I3)`` that
    are monotonic (either order) and rates ``w`` in that frame (TF 3-8)."""
    I = I.astype(_LD)
    w = w.astype(_LD)
    I1, I2, I3 = I[:, 0], I[:, 1], I[:, 2]
    w1, w2, w3 = w[:, 0], w[:, 1], w[:, 2]
    # magnitudes (the LAM frame's gaps, Q1 and Q3 are negative; negation is exact)
    d21, d32, d31, Q1, Q3, _, L2 = (np.abs(x) for x in fb.invariants(I1, I2, I3, w1, w2, w3))
    return dict(I1=I1, I2=I2, I3=I3, w1=w1, w2=w2, w3=w3, d21=d21, d32=d32, d31=d31,
                Q1=Q1, Q3=Q3, L2=L2, L=np.sqrt(L2))


# ===========================================================================
# branch selection
# ===========================================================================
_BR_PREC, _BR_SEP, _BR_SAM, _BR_LAM = 0, 1, 2, 3


def _branches(I, w):
    """Propagation branch of each body (scaled inputs) and the double-double
    discriminant.  Tolerances: module constants (TF 30)."""
    A, B, C = I[:, 0], I[:, 1], I[:, 2]
    Lb = np.abs(I * w)
    Ls = np.sort(Lb, axis=1)
    Lnorm = np.sqrt(np.sum(Lb * Lb, axis=1))
    tol = RTOL_AXISYMMETRIC * C
    prec = ((C - A) <= tol) | ((B - A) <= tol) | ((C - B) <= tol)
    prec |= Ls[:, 1] <= PURE_SPIN_TOL * Lnorm  # pure principal-axis spin, or omega = 0
    br = np.full(I.shape[0], _BR_PREC, dtype=np.int8)
    tri = ~prec
    dhi, dlo = _discriminant_dd(I, w)
    if tri.any():
        sam = tri & (dhi > 0)
        lam = tri & (dhi < 0)
        br[sam] = _BR_SAM
        br[lam] = _BR_LAM
        br[tri & (dhi == 0)] = _BR_SEP
        # complementary parameter m1 (TF 6) decides the separatrix branch
        idx = np.nonzero(sam | lam)[0]
        if idx.size:
            m1 = _m1_of(I[idx], w[idx], dhi[idx], dlo[idx], br[idx] == _BR_LAM)
            br[idx[m1 <= SEPARATRIX_M1_TOL]] = _BR_SEP
    return br, dhi, dlo


def _kernel_frame(I, w, lam):
    """(N, 3) moments and rates in the kernel frame (:mod:`attitude.freebody`, TF 9)."""
    Ik = np.stack(fb.kernel_moments(I[:, 0], I[:, 1], I[:, 2], lam), axis=1)
    wk = np.stack(fb.kernel_vector(w[:, 0], w[:, 1], w[:, 2], lam), axis=1)
    return Ik, wk


_JACOBI_ARGS = ("I1", "I2", "I3", "d21", "d32", "d31", "Q1", "Q3")


def _m1_of(I, w, dhi, dlo, lam):
    Ik, wk = _kernel_frame(I, w, lam)
    v = _invariants_ld(Ik, wk)
    D = np.abs(dhi.astype(_LD) + dlo.astype(_LD))
    return fb.jacobi_parameters(*(v[k] for k in _JACOBI_ARGS), D)[1].astype(
        np.float64)


# ===========================================================================
# triaxial (SAM / LAM) branch
# ===========================================================================
def _triaxial_setup(I, w, dhi, dlo, lam):
    """Per-body constants of the elliptic solution in the kernel frame (TF 3-12, 16-22).

    ``lam`` is a scalar bool: the whole group is LAM (kernel frame relabelled) or SAM.
    """
    n = I.shape[0]
    Ik, wk = _kernel_frame(I, w, np.full(n, lam))
    v = _invariants_ld(Ik, wk)
    I1, I2, I3 = v["I1"], v["I2"], v["I3"]
    d21, d32, d31, Q1, Q3, L = v["d21"], v["d32"], v["d31"], v["Q1"], v["Q3"], v["L"]
    Dl = np.abs(dhi.astype(_LD) + dlo.astype(_LD))  # |L^2 - 2EB|          (TF 5)
    # k^2, 1 - k^2 and lambda^2                                             (TF 4, 6)
    m, m1, lam2 = fb.jacobi_parameters(I1, I2, I3, d21, d32, d31, Q1, Q3, Dl)
    lamb = np.sqrt(lam2)  # lambda                                           (TF 4)
    nu = fb.characteristic(I1, I2, I3)  # -n, characteristic of Pi           (TF 10)
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
    twoK = 2 * K
    c = dict(
        vt=_turn_const(sigma * lamb / twoK),  # v / 2K advances at this rate
        v0t=_col(v0 / (2.0 * Kd)),
        twoK=_col(twoK), K=_col(K), Kh=_col(K / 2),
        g=g.astype(np.float64)[:, :, None], omg=omg.astype(np.float64)[:, :, None],
        inv_scale=_col(1 / scale), mu=_col(mu),
        kp=_col(kp), N=_col(N), omN=_col(omN), beta=_col(beta),
        a1=_col(a1), a2s=_col(s * a2), a3s=_col(s * a3),
        alp=_col(I1 * a1), bet=_col(I2 * a2), s=_col(s),
        I1=_col(I1), I2=_col(I2), I3=_col(I3),
        ph=_turn_const(w_lin / _FOUR_PI_LD),
        pj=_turn_const(kappa_j / _FOUR_PI_LD),
        kr=_col(kappa_r), C0=np.zeros((n, 1)),
        QL=tuple(np.zeros((n, 1)) for _ in range(4)), lam=lam,
        tiny=bool(np.any(m1 < 1e-60)),
    )
    for k in ("vt", "ph", "pj"):
        c[k] = tuple(_col(x) for x in c[k])
    # integration constant and L-frame orientation from t = 0            (TF 23)
    zero = np.zeros((n, 1))
    phi0, ct0, st0, psi0 = _triaxial_eval(c, zero, angles_only=True)
    c["C0"] = phi0
    E0 = fb.euler313_quaternion(ct0, st0, 0.0, psi0)
    c["E0"] = E0
    extra = dict(m=m, m1=m1, lamb=lamb, K=K, L=L, nu=nu, N=N, w_lin=w_lin, kappa_j=kappa_j,
                 sigma=sigma, Q1=Q1, Q3=Q3, Dl=Dl, I1=I1, I2=I2, I3=I3, d21=d21, d32=d32,
                 d31=d31, s=s)
    return c, extra


#: below this largest argument, RJ(x, y, 1, p) is taken from its z -> infinity limit
_RJ_ASYMPTOTIC_MAX = 1e-40


def _rj_small_args(x, y, p, rj):
    """Replace ``RJ(x, y, 1, p)`` where ``x, y, p <= 1e-40`` by its limit (TF 22')::

        RJ(x, y, 1, p) = 3 RC((sqrt(xy) + p)^2, p (sqrt x + sqrt y)^2) (1 + O(d log 1/d))

    with ``d = max(x, y, p)`` (from ``RJ = 3/2 int dt / ((t+p) sqrt((t+x)(t+y)(t+1)))``
    with ``t + 1 -> 1``, integrated exactly).  scipy's ``elliprj`` loses accuracy, then
    returns NaN, once its arguments span more than ~1e150, which only the elliptic
    branch with ``m1 < 1e-100`` reaches.
    """
    d = np.maximum(np.maximum(x, y), p)
    small = d <= _RJ_ASYMPTOTIC_MAX
    if not small.any():
        return rj
    xs, ys, ps = x[small] / d[small], y[small] / d[small], p[small] / d[small]
    rxy = np.sqrt(xs * ys)
    rc = sp.elliprc((rxy + ps) ** 2, ps * (np.sqrt(xs) + np.sqrt(ys)) ** 2)
    rj = rj.copy()
    rj[small] = 3.0 * rc / d[small]
    return rj


def _triaxial_eval(c, t, angles_only=False):
    """Evaluate the elliptic solution on a block: ``t`` (nb|1, Tb) scaled time."""
    tsp = el.split(t)
    # phase v = sigma lambda t + v0 in half-periods 2K: v = 2K (j + fr)       (TF 16)
    p, e = _lin_turns(tsp, t, c["vt"], add=c["v0t"])
    j = np.rint(p)
    r = ((p - j) + e) * c["twoK"]  # reduced argument, |r| <= K
    a = np.abs(r)
    refl = a > c["Kh"]
    x = np.where(refl, c["K"] - a, a)  # 0 <= x <= K/2                         (TF 17)
    sx, cx, dx = el.landen_sncndn(x, c["g"], c["omg"], c["inv_scale"], c["mu"])
    idx = 1.0 / dx
    cdx = cx * idx
    kpsd = c["kp"] * sx * idx
    kpnd = c["kp"] * idx
    sg = np.copysign(1.0, r)
    # functions of r (TF 18) and of u = r + K before the (-1)^j flip (TF 19)
    sn_r = sg * np.where(refl, cdx, sx)
    cn_r = np.where(refl, kpsd, cx)
    dn_r = np.where(refl, kpnd, dx)
    snK = np.where(refl, sx, cdx)
    cnK = -sg * np.where(refl, cx, kpsd)
    dnK = np.where(refl, dx, kpnd)
    half = 0.5 * j
    par = 1.0 - 4.0 * (half - np.floor(half))  # (-1)^j
    w1 = c["a1"] * par * cnK
    w2 = c["a2s"] * par * snK
    w3 = c["a3s"] * dnK
    # precession angle: linear part in double-double, periodic part through RJ (TF 20-22)
    cn2 = cn_r * cn_r
    dn2 = dn_r * dn_r
    pj = c["omN"] + c["N"] * cn2
    rj = sp.elliprj(cn2, dn2, 1.0, pj)
    if c["tiny"]:  # m1 < 1e-60 in this block: guard scipy's RJ for tiny arguments (TF 22')
        rj = _rj_small_args(cn2, dn2, pj, rj)
    per = r + c["beta"] * (sn_r * sn_r * sn_r) * rj
    F = _frac_turns(tsp, t, c["ph"], j, c["pj"])
    phi = (4.0 * math.pi) * F + c["kr"] * per - c["C0"]
    L1 = c["I1"] * w1
    L2 = c["I2"] * w2
    L3 = c["I3"] * w3
    ct, st = fb.half_theta(L1, L2, L3)
    chi = np.arctan2(c["bet"] * snK, c["alp"] * cnK)  # in [0, pi]
    jm4 = j - 4.0 * np.floor(0.25 * j)
    psi = 0.5 * math.pi - c["s"] * (math.pi * jm4 + chi)  # unwrapped mod 4 pi (TF 13)
    if angles_only:
        return phi, ct, st, psi
    E = fb.euler313_quaternion(ct, st, phi, psi)
    if c["lam"]:  # E (x) q_M and the rates back in principal axes              (TF 9)
        E = fb.kernel_attitude(E)
        w1, w2, w3 = fb.kernel_vector(w1, w2, w3, True)
    q = quat.multiply_parts(c["QL"], E)
    return q, (w1, w2, w3)


# ===========================================================================
# separatrix branch (heteroclinic closed form)
# ===========================================================================
def _separatrix_setup(I, w):
    """Per-body constants of the separatrix solution, principal labels (TF 24-26)."""
    n = I.shape[0]
    v = _invariants_ld(I, w)
    I1, I2, I3 = v["I1"], v["I2"], v["I3"]
    d21, d32, d31, Q1, Q3, L = v["d21"], v["d32"], v["d31"], v["Q1"], v["Q3"], v["L"]
    lamb = np.sqrt(0.5 * (d32 * Q3 + d21 * Q1) / (I1 * I2 * I3))  # (TF 24)
    a1 = np.sqrt(Q1 / (I1 * d31)).astype(np.float64)
    a2 = np.sqrt(Q1 / (I2 * d32)).astype(np.float64)
    a3 = np.sqrt(Q3 / (I3 * d31)).astype(np.float64)
    w1, w2, w3 = w[:, 0], w[:, 1], w[:, 2]
    s1 = np.where(w1 < 0, -1.0, 1.0)
    s3 = np.where(w3 < 0, -1.0, 1.0)
    s2 = s1 * s3
    rho0 = np.minimum(np.maximum(np.abs(w1) / a1, np.abs(w3) / a3), 1.0)  # sech(tau0)
    tau0 = np.arcsinh(s2 * w2 / (a2 * rho0))
    nu = fb.characteristic(I1, I2, I3)
    sq_nu = np.sqrt(nu)
    c1 = L * d31 / (I1 * I3)
    kappa = (c1 / (lamb * (1 + nu)) * sq_nu).astype(np.float64)
    c = dict(
        lamb=_col(lamb), tau0=_col(tau0), a1=_col(s1 * a1), a2=_col(s2 * a2), a3=_col(s3 * a3),
        sqnu=_col(sq_nu), kappa=_col(kappa),
        ph=tuple(_col(x) for x in _turn_const(L / I2 / _FOUR_PI_LD)),
        I1=_col(I1), I2=_col(I2), I3=_col(I3), C0=np.zeros((n, 1)),
        QL=tuple(np.zeros((n, 1)) for _ in range(4)),
    )
    zero = np.zeros((n, 1))
    phi0, ct0, st0, psi0 = _separatrix_eval(c, zero, angles_only=True)
    c["C0"] = phi0
    c["E0"] = fb.euler313_quaternion(ct0, st0, 0.0, psi0)
    return c, dict(lamb=lamb, L=L, nu=nu)


def _separatrix_eval(c, t, angles_only=False):
    tau = c["lamb"] * t + c["tau0"]
    at = np.abs(tau)
    e2 = np.exp(-2.0 * at)
    th = np.copysign(-np.expm1(-2.0 * at) / (1.0 + e2), tau)  # tanh, no overflow
    sech = 2.0 * np.exp(-at) / (1.0 + e2)
    w1 = c["a1"] * sech
    w2 = c["a2"] * th
    w3 = c["a3"] * sech
    # phi = (L/B) t + kappa sqrt(nu) atan(sqrt(nu) tanh tau) - C0             (TF 26)
    F = _frac_turns(el.split(t), t, c["ph"])
    phi = (4.0 * math.pi) * F + c["kappa"] * np.arctan(c["sqnu"] * th) - c["C0"]
    L1 = c["I1"] * w1
    L2 = c["I2"] * w2
    L3 = c["I3"] * w3
    ct, st = fb.half_theta(L1, L2, L3)
    psi = np.arctan2(L1, L2)
    if angles_only:
        return phi, ct, st, psi
    q = quat.multiply_parts(c["QL"], fb.euler313_quaternion(ct, st, phi, psi))
    return q, (w1, w2, w3)


# ===========================================================================
# regular precession / uniform rotation branch
# ===========================================================================
def _precession_setup(I, w, q0):
    """Axisymmetric, spherical, principal-axis spin and rest (TF 27-29)::

        R(t) = Rot(L_hat_inertial, L t / I_t) R0 Rot(e_s, Omega t),
        omega(t) = Rot(e_s, -Omega t) omega0,   Omega = omega_s (I_t - I_s) / I_t
    """
    n = I.shape[0]
    A, B, C = I[:, 0], I[:, 1], I[:, 2]
    tol = RTOL_AXISYMMETRIC * C
    Lb = I * w
    Labs = np.abs(Lb)
    L = np.sqrt(np.sum(Lb.astype(_LD) ** 2, axis=1))
    k = np.argmax(Labs, axis=1)
    Ls = np.sort(Labs, axis=1)
    pure = Ls[:, 1] <= PURE_SPIN_TOL * L.astype(np.float64)
    sph = (C - A) <= tol
    obl = ~sph & ((B - A) <= tol)
    pro = ~sph & ~obl & ((C - B) <= tol)
    axis = np.where(obl, 2, 0)
    It = np.where(obl, 0.5 * (A + B), np.where(pro, 0.5 * (B + C), B))
    Is = np.where(obl, C, np.where(pro, A, B))
    use_pure = pure & ~obl & ~pro | pure & sph
    It = np.where(use_pure, I[np.arange(n), k], It)
    Is = np.where(use_pure, It, Is)
    axis = np.where(use_pure, k, axis)
    es = np.zeros((n, 3))
    es[np.arange(n), axis] = 1.0
    ws = w[np.arange(n), axis]
    It_ld = It.astype(_LD)
    Om = ws.astype(_LD) * (It_ld - Is.astype(_LD)) / It_ld
    Om = np.where(use_pure | sph, 0.0, Om)
    w_par = es * ws[:, None]
    w_perp = w - w_par
    e_x_wp = np.cross(es, w_perp)
    Lin = quat.rotate(q0, Lb)
    Lf = L.astype(np.float64)
    with np.errstate(invalid="ignore", divide="ignore"):
        Lhat = np.where(Lf[:, None] > 0, Lin / np.where(Lf > 0, Lf, 1.0)[:, None], 0.0)
    c = dict(
        rate=tuple(_col(x) for x in _turn_const(L / It_ld / _FOUR_PI_LD)),
        om=tuple(_col(x) for x in _turn_const(Om / _FOUR_PI_LD)),
        Lhat=tuple(_col(Lhat[:, i]) for i in range(3)),
        es=tuple(_col(es[:, i]) for i in range(3)),
        q0=tuple(_col(q0[:, i]) for i in range(4)),
        wpar=tuple(_col(w_par[:, i]) for i in range(3)),
        wperp=tuple(_col(w_perp[:, i]) for i in range(3)),
        exw=tuple(_col(e_x_wp[:, i]) for i in range(3)),
    )
    return c, dict(L=L, It=It, Is=Is, Om=Om, axis=axis, pure=use_pure, sph=sph, obl=obl,
                   pro=pro)


def _precession_eval(c, t):
    tsp = el.split(t)
    ha = _TWO_PI * _frac_turns(tsp, t, c["rate"])  # half of L t / I_t
    hb = _TWO_PI * _frac_turns(tsp, t, c["om"])  # half of Omega t
    sa, ca = np.sin(ha), np.cos(ha)
    sb, cb = np.sin(hb), np.cos(hb)
    qL = (c["Lhat"][0] * sa, c["Lhat"][1] * sa, c["Lhat"][2] * sa, ca)
    qs = (c["es"][0] * sb, c["es"][1] * sb, c["es"][2] * sb, cb)
    q = quat.multiply_parts(quat.multiply_parts(qL, c["q0"]), qs)
    cO = 1.0 - 2.0 * sb * sb  # cos(Omega t)
    sO = 2.0 * sb * cb  # sin(Omega t)
    w = tuple(c["wpar"][i] + cO * c["wperp"][i] - sO * c["exw"][i] for i in range(3))
    return q, w


# ===========================================================================
# public kernel
# ===========================================================================
def _validate(moments, quat0, omega0, t):
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


def _scales(I, w):
    """Exact power-of-two scales so the kernel works on O(1) numbers."""
    _, eI = np.frexp(I[:, 2])
    sI = np.ldexp(1.0, eI)
    wmax = np.max(np.abs(w), axis=1)
    _, ew = np.frexp(np.where(wmax > 0, wmax, 1.0))
    sw = np.ldexp(1.0, ew)
    return sI, sw


def _quaternion_then_omega(quat0, omega0, name: str):
    """Accept the earlier ``(omega, quaternion)`` order of the kernels, with a warning:
    the last axes (3 and 4) tell the two apart."""
    if np.shape(quat0)[-1:] == (3,) and np.shape(omega0)[-1:] == (4,):
        warnings.warn(f"{name}(moments, omega0, quat0, ...) is deprecated: give "
                      f"{name}(moments, quat0, omega0, ...), the order (moments, quaternion, "
                      "omega) of every kernel", DeprecationWarning, stacklevel=3)
        return omega0, quat0
    return quat0, omega0


def free_rotation(moments, quat0, omega0, t):
    """Exact torque-free attitude and body rates of rigid bodies.

    The bodies' frames are their principal frames (``attitude.propagate`` maps any body
    frame to them and back).

    Parameters
    ----------
    moments : array_like, shape (..., 3)
        Principal moments sorted ``A <= B <= C`` (kg m^2; any consistent unit).
    quat0 : array_like, shape (..., 4)
        Scalar-last quaternion principal (body) -> inertial at ``t = 0`` (normalised
        here).
    omega0 : array_like, shape (..., 3)
        Angular velocity at ``t = 0`` in principal-frame components (rad/s).
    t : array_like, shape (T,) or (..., T)
        Seconds since the initial epoch (any sign, any order), shared by all bodies
        or per body.

    Returns
    -------
    quat : ndarray, shape (..., T, 4)
        Scalar-last quaternions principal -> inertial.  Their sign is continuous in
        time within each regime (useful for interpolation); ``quat[..., 0, :]``
        equals ``quat0`` for ``t = 0``.
    omega : ndarray, shape (..., T, 3)
        Principal-frame angular velocity (rad/s).

    Notes
    -----
    The branch (regime) of every body is chosen from the documented tolerances
    :data:`RTOL_AXISYMMETRIC`, :data:`PURE_SPIN_TOL` and :data:`SEPARATRIX_M1_TOL`;
    bodies of one branch are evaluated together with numpy (no Python loop per body
    or per epoch).  Work is O(1) per epoch: one Landen-transformed ``sn, cn, dn``
    evaluation, one Carlson ``RJ`` and a handful of trigonometric functions.
    See ``docs/torquefree.md`` for formulas and measured accuracy.

    Examples
    --------
    >>> import numpy as np
    >>> q, w = free_rotation([0.61, 0.965, 1.0], [0, 0, 0, 1], [0.002, 0.0, 0.05],
    ...                      np.linspace(0.0, 1e5, 5))
    >>> q.shape, w.shape
    ((5, 4), (5, 3))

    The order of earlier releases, ``free_rotation(moments, omega0, quat0, t)``, still
    works (told apart by the shapes) and warns with a :class:`DeprecationWarning`.
    """
    quat0, omega0 = _quaternion_then_omega(quat0, omega0, "free_rotation")
    batch, I, w, q0, tt = _validate(moments, quat0, omega0, t)
    q, w = _evaluate(I, q0, w, tt)
    T = tt.shape[-1]
    return q.reshape(batch + (T, 4)), w.reshape(batch + (T, 3))


def _evaluate(I, q0, w, tt, b2p=None):
    """The closed form of (n, 3) bodies at (1|n, T) times, as (n, T, 4) and (n, T, 3)
    arrays: in the principal frames, or in body frames given the body -> principal
    quaternions ``b2p`` (n, 4), mapped block by block (:func:`exact_arrays`)."""
    n, T = I.shape[0], tt.shape[-1]
    sI, sw = _scales(I, w)
    Is = I / sI[:, None]  # exact: powers of two
    ws = w / sw[:, None]
    out_q = np.empty((n, T, 4))
    out_w = np.empty((n, T, 3))
    br, dhi, dlo = _branches(Is, ws)
    for code in (_BR_PREC, _BR_SEP, _BR_SAM, _BR_LAM):
        idx = np.nonzero(br == code)[0]
        if idx.size == 0:
            continue
        Ig, wg, qg = Is[idx], ws[idx], q0[idx]
        if code == _BR_PREC:
            c, _ = _precession_setup(Ig, wg, qg)
            ev = _precession_eval
        elif code == _BR_SEP:
            c, _ = _separatrix_setup(Ig, wg)
            ev = _separatrix_eval
        else:
            c, _ = _triaxial_setup(Ig, wg, dhi[idx], dlo[idx], code == _BR_LAM)
            ev = _triaxial_eval
        if code != _BR_PREC:
            # Q_L = q0 (x) q_M^-1 (x) E0^-1 : L-frame -> inertial             (TF 23)
            qg_t = tuple(_col(qg[:, i]) for i in range(4))
            E0 = c.pop("E0")
            if code == _BR_LAM:
                qg_t = quat.multiply_parts(qg_t, quat.conjugate_parts(fb.LAM_FRAME))
            c["QL"] = quat.multiply_parts(qg_t, quat.conjugate_parts(E0))
        if b2p is not None:       # to the body frames: q b2p, b2p^-1 w b2p   (body.py)
            c["b2p"] = tuple(_col(b2p[idx, i]) for i in range(4))
        _run_group(ev, c, idx, tt, sw, out_q, out_w)
    return out_q, out_w


def exact_arrays(moments, b2p, q0, w0, t):
    """Torque-free closed form of N bodies given principal moments (N, 3), body ->
    principal quaternions (N, 4), attitudes (N, 4) and body rates (N, 3): ``q (N, T, 4),
    w (N, T, 3)`` in the body frames."""
    q0p, w0p = to_principal_frame(q0, w0, b2p)                         # principal -> inertial
    b2p = np.asarray(b2p, dtype=float).reshape(-1, 4)
    _, I, w, q, tt = _validate(moments, q0p, w0p, t)
    return _evaluate(I, q, w, tt, b2p / np.linalg.norm(b2p, axis=1, keepdims=True))


def _run_group(ev, c, idx, tt, sw, out_q, out_w):
    """Evaluate one branch group block by block and scatter into the outputs.

    ``tt`` is (1, T) shared or (n, T) per body, in seconds; each body's time is
    scaled by its exact power-of-two rate unit ``sw``.
    """
    shared = tt.shape[0] == 1
    T = tt.shape[-1]
    swg = sw[idx]
    ng = idx.size
    contiguous = ng == 0 or (idx[-1] - idx[0] == ng - 1)
    if contiguous:  # write straight into the output (basic slicing, a view)
        buf_q = out_q[idx[0]:idx[0] + ng]
        buf_w = out_w[idx[0]:idx[0] + ng]
    else:  # one scatter per group at the end
        buf_q = np.empty((ng, T, 4))
        buf_w = np.empty((ng, T, 3))
    tg = tt if shared else tt[idx]
    for rows, cols in _blocks(ng, T):
        cb = _sub(c, rows)
        swr = swg[rows][:, None]
        tb = (tg[:, cols] if shared else tg[rows, cols]) * swr
        q, wv = ev(cb, tb)
        if "b2p" in cb:           # the frame map of to_body_frame, on the block
            q = quat.multiply_parts(q, cb["b2p"])
            wv = quat.rotate_parts(cb["b2p"], wv, inverse=True)
        oq = buf_q[rows, cols]
        ow = buf_w[rows, cols]
        for k in range(4):
            oq[..., k] = q[k]
        for k in range(3):
            ow[..., k] = wv[k] * swr
    if not contiguous:
        out_q[idx] = buf_q
        out_w[idx] = buf_w


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
        ``"axisymmetric"``, ``"spherical"``, ``"at-rest"`` (:data:`attitude.regimes.REGIMES`).
    periods : dict
        Seconds, keys from :data:`attitude.regimes.PERIOD_KEYS`.  ``polhode`` (period of
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
    ``"LAM"``) that :func:`free_rotation` uses, for (..., 3) inputs."""
    moments = np.asarray(moments, dtype=float)
    omega0 = np.asarray(omega0, dtype=float)
    batch, I, w, _, _ = _validate(moments, [0.0, 0.0, 0.0, 1.0], omega0, [0.0])
    sI, sw = _scales(I, w)
    br, _, _ = _branches(I / sI[:, None], w / sw[:, None])
    names = np.array(["precession", "separatrix", "SAM", "LAM"])
    out = names[br]
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
        ``attitude.body.SYMMETRY_RTOL``, 1e-12, the tolerance of
        ``RigidBody.symmetry``).  Propagation itself uses :data:`RTOL_AXISYMMETRIC`.
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
    """
    if rtol_symmetry is None:
        rtol_symmetry = SYMMETRY_RTOL
    rtol_symmetry = max(float(rtol_symmetry), RTOL_AXISYMMETRIC)  # never finer than the solver
    rtol_spin = max(float(rtol_symmetry if rtol_spin is None else rtol_spin), PURE_SPIN_TOL)
    _, I, w, _, _ = _validate(moments, [0.0, 0.0, 0.0, 1.0], omega0, [0.0])
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
    sI, sw = _scales(I, w)
    Is, ws = I / sI[:, None], w / sw[:, None]
    br, dhi, dlo = _branches(Is, ws)
    bname = {_BR_PREC: "precession", _BR_SEP: "separatrix"}.get(int(br[0]), "elliptic")
    # excitation (E - E_min)/(E_max - E_min) from 2EC - L^2 = A(C-A)w1^2 + B(C-B)w2^2
    q1c = float(fb.invariants(A, B, C, *(float(x) for x in wv))[3])      # 2EC - L^2
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
    if int(br[0]) in (_BR_SEP, _BR_PREC):
        # separatrix closed form, SAM labels: theta from theta_min to pi/2 (asymptote)
        v = _invariants_ld(Is, ws)
        s2 = v["I1"] * v["Q1"] / (v["d31"] * v["L2"])
        c2 = v["I3"] * v["Q3"] / (v["d31"] * v["L2"])
        th = _atan2_sqrt(s2[0], c2[0])
        nut = (th, 0.5 * math.pi) if wv[2] >= 0 else (0.5 * math.pi, math.pi - th)
        lamb = float(np.sqrt(v["d32"] * v["Q3"] / (v["I1"] * v["I2"] * v["I3"]))[0]) * sw[0]
        return Diagnosis(regime="separatrix", periods={}, separatrix_distance=0.0,
                         nutation_range=nut, stable=None, reference_axis=3, k2=1.0,
                         lam=float(lamb), **base)
    lam_side = int(br[0]) == _BR_LAM
    _, x = _triaxial_setup(Is, ws, dhi, dlo, lam_side)
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
    rtol_symmetry = max(float(rtol_symmetry), RTOL_AXISYMMETRIC)
    rtol_spin_ = max(float(rtol_symmetry if rtol_spin is None else rtol_spin), PURE_SPIN_TOL)
    moments = np.atleast_2d(np.asarray(moments, dtype=float))
    omega0 = np.atleast_2d(np.asarray(omega0, dtype=float))
    _, I, w, _, _ = _validate(moments, [0.0, 0.0, 0.0, 1.0], omega0, [0.0])
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
    sI, sw = _scales(I, w)
    Is, ws = I / sI[:, None], w / sw[:, None]
    br, dhi, dlo = _branches(Is, ws)
    generic &= (br == _BR_SAM) | (br == _BR_LAM)
    for lam_side, code in ((False, _BR_SAM), (True, _BR_LAM)):
        idx = np.nonzero(generic & (br == code))[0]
        if idx.size == 0:
            continue
        _, x = _triaxial_setup(Is[idx], ws[idx], dhi[idx], dlo[idx], lam_side)
        m1 = x["m1"].astype(np.float64)
        far = m1 >= NEAR_SEPARATRIX_WARN
        generic[idx[~far]] = False
        idx, x = idx[far], {k: (v[far] if np.ndim(v) else v) for k, v in x.items()}
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
        q1c = fb.invariants(A[idx], B[idx], C[idx], *w[idx].T)[3]            # 2EC - L^2
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

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

import numpy as np
from scipy import special as sp

from ..deprecation import moved_attribute
from ..foundations import elliptic as el
from ..foundations import quaternion as quat
from ..model import freebody as fb
from ..model.body import to_principal_frame
from ..model.freebody import (
    EQUAL_MOMENTS_RTOL,
    NEAR_SEPARATRIX_WARN,
    PURE_SPIN_TOL,
    SEPARATRIX_M1_TOL,
)

__all__ = [
    "free_rotation",
    "exact_arrays",
    "RTOL_AXISYMMETRIC",
    "PURE_SPIN_TOL",
    "SEPARATRIX_M1_TOL",
    "NEAR_SEPARATRIX_WARN",
]

#: The branch tolerances (:data:`PURE_SPIN_TOL`, :data:`SEPARATRIX_M1_TOL`,
#: :data:`NEAR_SEPARATRIX_WARN`) live in :mod:`attitude.model.freebody` with their reasons.
#: ``RTOL_AXISYMMETRIC`` is this module's earlier name of
#: :data:`attitude.model.freebody.EQUAL_MOMENTS_RTOL` (the same value), kept for its users.
RTOL_AXISYMMETRIC = EQUAL_MOMENTS_RTOL


def __getattr__(name):
    # the analytic diagnosis moved to attitude.freebody: a DeprecationWarning naming it
    return moved_attribute(__name__, name)

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
def _triaxial_setup(I, w, dhi, dlo, lam):
    """Evaluation constants of the elliptic solution (TF 16-23) from the per-body
    constants of :func:`attitude.model.freebody.elliptic_constants`.

    ``lam`` is a scalar bool: the whole group is LAM (kernel frame relabelled) or SAM.
    """
    n = I.shape[0]
    x = fb.elliptic_constants(I, w, dhi, dlo, lam)
    K, m1, s = x["K"], x["m1"], x["s"]
    Kd = K.astype(np.float64)
    twoK = 2 * K
    c = dict(
        vt=_turn_const(x["sigma"] * x["lamb"] / twoK),  # v / 2K advances at this rate
        v0t=_col(x["v0"] / (2.0 * Kd)),
        twoK=_col(twoK), K=_col(K), Kh=_col(K / 2),
        g=x["g"].astype(np.float64)[:, :, None], omg=x["omg"].astype(np.float64)[:, :, None],
        inv_scale=_col(1 / x["scale"]), mu=_col(x["mu"]),
        kp=_col(x["kp"]), N=_col(x["N"]), omN=_col(x["omN"]), beta=_col(x["beta"]),
        a1=_col(x["a1"]), a2s=_col(s * x["a2"]), a3s=_col(s * x["a3"]),
        alp=_col(x["I1"] * x["a1"]), bet=_col(x["I2"] * x["a2"]), s=_col(s),
        I1=_col(x["I1"]), I2=_col(x["I2"]), I3=_col(x["I3"]),
        ph=_turn_const(x["w_lin"] / _FOUR_PI_LD),
        pj=_turn_const(x["kappa_j"] / _FOUR_PI_LD),
        kr=_col(x["kappa_r"]), C0=np.zeros((n, 1)),
        QL=tuple(np.zeros((n, 1)) for _ in range(4)), lam=lam,
        tiny=bool(np.any(m1 < 1e-60)),
    )
    for k in ("vt", "ph", "pj"):
        c[k] = tuple(_col(v) for v in c[k])
    # integration constant and L-frame orientation from t = 0            (TF 23)
    zero = np.zeros((n, 1))
    phi0, ct0, st0, psi0 = _triaxial_eval(c, zero, angles_only=True)
    c["C0"] = phi0
    c["E0"] = fb.euler313_quaternion(ct0, st0, 0.0, psi0)
    return c, x


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
    v = fb.kernel_invariants(I, w)
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
    batch, I, w, q0, tt = fb.check_inputs(moments, quat0, omega0, t)
    q, w = _evaluate(I, q0, w, tt)
    T = tt.shape[-1]
    return q.reshape(batch + (T, 4)), w.reshape(batch + (T, 3))


def _evaluate(I, q0, w, tt, b2p=None):
    """The closed form of (n, 3) bodies at (1|n, T) times, as (n, T, 4) and (n, T, 3)
    arrays: in the principal frames, or in body frames given the body -> principal
    quaternions ``b2p`` (n, 4), mapped block by block (:func:`exact_arrays`)."""
    n, T = I.shape[0], tt.shape[-1]
    sI, sw = fb.unit_scales(I, w)
    Is = I / sI[:, None]  # exact: powers of two
    ws = w / sw[:, None]
    out_q = np.empty((n, T, 4))
    out_w = np.empty((n, T, 3))
    br, dhi, dlo = fb.branches(Is, ws)
    for code in (fb.BRANCH_PRECESSION, fb.BRANCH_SEPARATRIX, fb.BRANCH_SAM, fb.BRANCH_LAM):
        idx = np.nonzero(br == code)[0]
        if idx.size == 0:
            continue
        Ig, wg, qg = Is[idx], ws[idx], q0[idx]
        if code == fb.BRANCH_PRECESSION:
            c, _ = _precession_setup(Ig, wg, qg)
            ev = _precession_eval
        elif code == fb.BRANCH_SEPARATRIX:
            c, _ = _separatrix_setup(Ig, wg)
            ev = _separatrix_eval
        else:
            c, _ = _triaxial_setup(Ig, wg, dhi[idx], dlo[idx], code == fb.BRANCH_LAM)
            ev = _triaxial_eval
        if code != fb.BRANCH_PRECESSION:
            # Q_L = q0 (x) q_M^-1 (x) E0^-1 : L-frame -> inertial             (TF 23)
            qg_t = tuple(_col(qg[:, i]) for i in range(4))
            E0 = c.pop("E0")
            if code == fb.BRANCH_LAM:
                qg_t = quat.multiply_parts(qg_t, quat.conjugate_parts(fb.LAM_FRAME))
            c["QL"] = quat.multiply_parts(qg_t, quat.conjugate_parts(E0))
        if b2p is not None:       # to the body frames: q b2p, b2p^-1 w b2p   (body.py)
            c["b2p"] = tuple(_col(b2p[idx, i]) for i in range(4))
        _run_group(ev, c, idx, tt, sw, out_q, out_w)
    return out_q, out_w


def exact_arrays(moments, b2p, q0, w0, t):
    """Torque-free closed form of N bodies given principal moments (N, 3), body ->
    principal quaternions (N, 4), attitudes (N, 4) and body rates (N, 3): ``q (N, T, 4),
    w (N, T, 3)`` in the body frames.

    Examples
    --------
    >>> import numpy as np
    >>> moments = np.array([[0.61, 0.965, 1.0]])
    >>> identity = np.array([[0.0, 0.0, 0.0, 1.0]])
    >>> q, w = exact_arrays(moments, identity, identity, np.array([[0.02, 0.0, 0.1]]),
    ...                     np.linspace(0.0, 100.0, 5))
    >>> q.shape, w.shape
    ((1, 5, 4), (1, 5, 3))
    >>> E = 0.5 * np.sum(moments[:, None] * w**2, axis=-1)    # kinetic energy is conserved
    >>> bool(np.allclose(E, E[:, :1], rtol=4e-16, atol=0))
    True
    """
    q0p, w0p = to_principal_frame(q0, w0, b2p)                         # principal -> inertial
    b2p = np.asarray(b2p, dtype=float).reshape(-1, 4)
    _, I, w, q, tt = fb.check_inputs(moments, q0p, w0p, t)
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

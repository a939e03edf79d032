"""The per-body constants of the closed-form torque-free solution: the inputs checked
and flattened, exact power-of-two scales, the discriminant ``L^2 - 2EB`` in
double-double, the propagation branch of each body and the elliptic constants of a
triaxial body (``K``, the Landen chain, the precession rates; ``docs/torquefree.md``,
TF 3-12, 15, 30, 31).

Part of :mod:`attitude.model.freebody` (which re-exports every name): the closed form
(:mod:`attitude.propagation.torquefree`) evaluates these constants over time, and the
analytic diagnosis (:mod:`.freebody_diagnosis`) reads them without propagating.
"""

from __future__ import annotations

import numpy as np
from scipy import special as sp

from ..foundations import elliptic as el
from ..foundations.errors import InvalidInertiaError, InvalidStateError
from .freebody_algebra import (
    EQUAL_MOMENTS_RTOL,
    PURE_SPIN_TOL,
    SEPARATRIX_M1_TOL,
    characteristic,
    invariants,
    jacobi_parameters,
    kernel_moments,
    kernel_vector,
)

__all__ = [
    "check_inputs",
    "unit_scales",
    "discriminant",
    "kernel_invariants",
    "BRANCHES",
    "BRANCH_PRECESSION",
    "BRANCH_SEPARATRIX",
    "BRANCH_SAM",
    "BRANCH_LAM",
    "branches",
    "elliptic_constants",
]

_LD = el.LD


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

"""High-precision references for the torque-free solution (mpmath, 30+ digits).

Two references, sharing no code with ``attitude`` (this module imports only
mpmath and numpy):

``taylor_solution``
    A high-order Taylor-series integrator of Euler's equations *and* the
    quaternion kinematics ``q' = q (x) (omega, 0) / 2`` in mpmath.  Nothing of the
    closed form enters: it is the most independent check, and is used for short
    spans, every edge regime, and to validate the closed-form reference below.

``closed_form_solution``
    The textbook solution (Landau & Lifshitz §37) evaluated with mpmath's own
    Jacobi functions and incomplete integrals (``ellipfun``, ``ellipf``,
    ``ellippi``) at 40 digits, so it is cheap over 50 polhode periods.  It is
    derived independently of the fast path: original principal labels (no
    relabelling for LAM), the signs and initial phase found by checking Euler's
    equations numerically, the precession rate of the reference axis written as
    ``(alpha + beta sn^2)/(gamma + delta sn^2)`` from the amplitudes, and the
    attitude rebuilt from a nodal frame (no Euler angles).

Inputs are converted from their float64 values *exactly*, so both references
solve the very problem the fast path is given.
"""

from __future__ import annotations

import functools

import mpmath as mp
import numpy as np

__all__ = ["taylor_solution", "closed_form_solution", "attitude_error", "rate_error",
           "polhode_period", "separatrix_m1"]


def _mpf_vec(x):
    return [mp.mpf(float(v)) for v in x]


def _quat_to_float(q):
    n = mp.sqrt(mp.fsum(c * c for c in q))
    return np.array([float(c / n) for c in q])


# ---------------------------------------------------------------------------
# Taylor-series integrator
# ---------------------------------------------------------------------------
def _taylor_coeffs(I, w, q, order):
    A, B, C = I
    kA, kB, kC = (B - C) / A, (C - A) / B, (A - B) / C
    W = [[w[i]] for i in range(3)]
    Q = [[q[i]] for i in range(4)]
    half = mp.mpf(1) / 2
    for k in range(order):
        w1, w2, w3 = W
        x, y, z, s = Q
        r1 = list(reversed(w1[: k + 1]))
        r2 = list(reversed(w2[: k + 1]))
        r3 = list(reversed(w3[: k + 1]))
        inv = mp.mpf(1) / (k + 1)
        W[0].append(kA * mp.fdot(w2[: k + 1], r3) * inv)
        W[1].append(kB * mp.fdot(w3[: k + 1], r1) * inv)
        W[2].append(kC * mp.fdot(w1[: k + 1], r2) * inv)
        xs, ys, zs, ss = x[: k + 1], y[: k + 1], z[: k + 1], s[: k + 1]
        h = half * inv
        Q[0].append(h * (mp.fdot(ss, r1) + mp.fdot(ys, r3) - mp.fdot(zs, r2)))
        Q[1].append(h * (mp.fdot(ss, r2) - mp.fdot(xs, r3) + mp.fdot(zs, r1)))
        Q[2].append(h * (mp.fdot(ss, r3) + mp.fdot(xs, r2) - mp.fdot(ys, r1)))
        Q[3].append(h * (-mp.fdot(xs, r1) - mp.fdot(ys, r2) - mp.fdot(zs, r3)))
    return W, Q


def _horner(c, h):
    acc = mp.mpf(0)
    for a in reversed(c):
        acc = acc * h + a
    return acc


def taylor_solution(moments, omega0, quat0, times, dps=34, order=36):
    """Integrate Euler's equations and quaternion kinematics by Taylor series.

    Parameters
    ----------
    moments, omega0, quat0 : float arrays (principal frame, scalar-last quaternion
        principal -> inertial).
    times : float array, sorted ascending, >= 0.
    dps : decimal digits of the arithmetic.
    order : Taylor order; the step is chosen so the last two terms are below
        ``10**-(dps+2)`` of the state (Jorba & Zou 2005, Exp. Math. 14, 99).

    Returns
    -------
    quat (T, 4), omega (T, 3) float64; also the conserved |L| and 2E relative
    drifts of the oracle itself (for self-checks) as a dict.
    """
    return _taylor_cached(tuple(map(float, moments)), tuple(map(float, omega0)),
                          tuple(map(float, quat0)), tuple(map(float, times)), dps, order)


@functools.cache
def _taylor_cached(moments, omega0, quat0, times, dps, order):
    with mp.workdps(dps):
        I = _mpf_vec(moments)
        w = _mpf_vec(omega0)
        q = _mpf_vec(quat0)
        nq = mp.sqrt(mp.fsum(c * c for c in q))
        q = [c / nq for c in q]
        tol = mp.mpf(10) ** (-(dps + 2))
        t = mp.mpf(0)
        out_q, out_w = [], []
        L0 = mp.sqrt(mp.fsum((I[i] * w[i]) ** 2 for i in range(3)))
        E0 = mp.fsum(I[i] * w[i] ** 2 for i in range(3))
        ti = 0
        T = [mp.mpf(x) for x in times]
        while ti < len(T) and T[ti] <= 0:
            out_q.append(_quat_to_float(q))
            out_w.append(np.array([float(v) for v in w]))
            ti += 1
        while ti < len(T):
            W, Q = _taylor_coeffs(I, w, q, order)
            scale = max(mp.mpf(1), max(abs(v) for v in w), max(abs(v) for v in q))
            h = mp.inf
            for k in (order - 1, order):
                nk = max(max(abs(W[i][k]) for i in range(3)), max(abs(Q[i][k]) for i in range(4)))
                if nk > 0:
                    h = min(h, (tol * scale / nk) ** (mp.mpf(1) / k))
            if h == mp.inf:  # polynomial (e.g. at rest): any step is exact
                h = T[-1] - t
            t_next = t + h
            while ti < len(T) and T[ti] <= t_next:
                dt = T[ti] - t
                qq = [_horner(Q[i], dt) for i in range(4)]
                ww = [_horner(W[i], dt) for i in range(3)]
                out_q.append(_quat_to_float(qq))
                out_w.append(np.array([float(v) for v in ww]))
                ti += 1
            w = [_horner(W[i], h) for i in range(3)]
            q = [_horner(Q[i], h) for i in range(4)]
            t = t_next
        L1 = mp.sqrt(mp.fsum((I[i] * w[i]) ** 2 for i in range(3)))
        E1 = mp.fsum(I[i] * w[i] ** 2 for i in range(3))
        drift = {"L": float(abs(L1 / L0 - 1)) if L0 else 0.0,
                 "E": float(abs(E1 / E0 - 1)) if E0 else 0.0}
    return np.array(out_q), np.array(out_w), drift


# ---------------------------------------------------------------------------
# Closed form in mpmath (Landau & Lifshitz §37, original labels)
# ---------------------------------------------------------------------------
def _jacobi(u, m):
    if m == 1:
        return mp.tanh(u), mp.sech(u), mp.sech(u)
    return (mp.ellipfun("sn", u, m=m), mp.ellipfun("cn", u, m=m), mp.ellipfun("dn", u, m=m))


def _am(u, m, K):
    """Unwrapped Jacobi amplitude."""
    sn, cn, _ = _jacobi(u, m)
    a = mp.atan2(sn, cn)
    if m == 1:
        return a
    k = mp.nint((u - mp.ellipf(a, m)) / (4 * K))
    return a + 2 * mp.pi * k


def _setup(moments, omega0):
    A, B, C = I = _mpf_vec(moments)
    w = _mpf_vec(omega0)
    L2 = mp.fsum((I[i] * w[i]) ** 2 for i in range(3))
    E2 = mp.fsum(I[i] * w[i] ** 2 for i in range(3))
    if not (A < B < C):
        raise ValueError("closed_form_solution needs a triaxial body (use taylor_solution)")
    if L2 >= E2 * B:  # SAM (and the separatrix itself): forms (cn, sn, dn)
        lam = mp.sqrt((C - B) * (L2 - E2 * A) / (A * B * C))
        m = (B - A) * (E2 * C - L2) / ((C - B) * (L2 - E2 * A))
        amp = [mp.sqrt((E2 * C - L2) / (A * (C - A))), mp.sqrt((E2 * C - L2) / (B * (C - B))),
               mp.sqrt((L2 - E2 * A) / (C * (C - A)))]
        forms = ("cn", "sn", "dn")
        ref = 2
    else:  # LAM: forms (dn, sn, cn)
        lam = mp.sqrt((B - A) * (E2 * C - L2) / (A * B * C))
        m = (C - B) * (L2 - E2 * A) / ((B - A) * (E2 * C - L2))
        amp = [mp.sqrt((E2 * C - L2) / (A * (C - A))), mp.sqrt((L2 - E2 * A) / (B * (B - A))),
               mp.sqrt((L2 - E2 * A) / (C * (C - A)))]
        forms = ("dn", "sn", "cn")
        ref = 0
    return I, w, L2, E2, lam, m, amp, forms, ref


def _rates(u, m, lam, amp, forms, signs):
    sn, cn, dn = _jacobi(u, m)
    f = {"sn": sn, "cn": cn, "dn": dn}
    return [signs[i] * amp[i] * f[forms[i]] for i in range(3)]


def _find_signs_and_phase(I, w, m, lam, amp, forms):
    """Signs and initial phase such that the formulas satisfy Euler's equations
    (checked numerically at a generic phase) and reproduce omega0."""
    A, B, C = I
    sn_i = forms.index("sn")
    other = [i for i in range(3) if forms[i] == "cn"][0]
    best = None
    for s0 in (1, -1):
        for s1 in (1, -1):
            for s2 in (1, -1):
                signs = (s0, s1, s2)
                # Euler's equations at a generic phase, analytic derivatives
                u = mp.mpf("0.3183098861837907")
                sn, cn, dn = _jacobi(u, m)
                d = {"sn": cn * dn, "cn": -sn * dn, "dn": -m * sn * cn}
                ww = _rates(u, m, lam, amp, forms, signs)
                dw = [signs[i] * amp[i] * lam * d[forms[i]] for i in range(3)]
                res = max(abs(A * dw[0] - (B - C) * ww[1] * ww[2]),
                          abs(B * dw[1] - (C - A) * ww[2] * ww[0]),
                          abs(C * dw[2] - (A - B) * ww[0] * ww[1]))
                if res > mp.mpf(10) ** (-mp.mp.dps + 8) * (1 + max(abs(x) for x in ww)) ** 2:
                    continue
                # initial phase from the sn and cn components
                snv = w[sn_i] / (signs[sn_i] * amp[sn_i]) if amp[sn_i] else mp.mpf(0)
                cnv = w[other] / (signs[other] * amp[other]) if amp[other] else mp.mpf(1)
                a0 = mp.atan2(snv, cnv)
                u0 = mp.ellipf(a0, m)
                err = max(abs(x - y) for x, y in zip(_rates(u0, m, lam, amp, forms, signs), w))
                if best is None or err < best[0]:
                    best = (err, signs, u0)
    if best is None or best[0] > mp.mpf(10) ** (-mp.mp.dps + 10) * max(abs(x) for x in w):
        raise RuntimeError(f"oracle: no consistent sign/phase found ({best and best[0]})")
    return best[1], best[2]


def _nodal(Lb, ref):
    """Rows of the body -> nodal-frame matrix: z along L, x along the projection of
    the reference body axis onto the plane normal to L."""
    Ln = mp.sqrt(mp.fsum(c * c for c in Lb))
    z = [c / Ln for c in Lb]
    e = [mp.mpf(0)] * 3
    e[ref] = mp.mpf(1)
    dz = z[ref]
    x = [e[i] - dz * z[i] for i in range(3)]
    xn = mp.sqrt(mp.fsum(c * c for c in x))
    x = [c / xn for c in x]
    y = [z[1] * x[2] - z[2] * x[1], z[2] * x[0] - z[0] * x[2], z[0] * x[1] - z[1] * x[0]]
    return mp.matrix([x, y, z])


def _quat_to_matrix(q):
    x, y, z, w = q
    return mp.matrix([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])


def _matrix_to_quat(R):
    tr = R[0, 0] + R[1, 1] + R[2, 2]
    cands = [tr, R[0, 0], R[1, 1], R[2, 2]]
    i = max(range(4), key=lambda k: cands[k])
    if i == 0:
        s = mp.sqrt(1 + tr) * 2
        return [(R[2, 1] - R[1, 2]) / s, (R[0, 2] - R[2, 0]) / s, (R[1, 0] - R[0, 1]) / s, s / 4]
    if i == 1:
        s = mp.sqrt(1 + R[0, 0] - R[1, 1] - R[2, 2]) * 2
        return [s / 4, (R[0, 1] + R[1, 0]) / s, (R[0, 2] + R[2, 0]) / s, (R[2, 1] - R[1, 2]) / s]
    if i == 2:
        s = mp.sqrt(1 + R[1, 1] - R[0, 0] - R[2, 2]) * 2
        return [(R[0, 1] + R[1, 0]) / s, s / 4, (R[1, 2] + R[2, 1]) / s, (R[0, 2] - R[2, 0]) / s]
    s = mp.sqrt(1 + R[2, 2] - R[0, 0] - R[1, 1]) * 2
    return [(R[0, 2] + R[2, 0]) / s, (R[1, 2] + R[2, 1]) / s, s / 4, (R[1, 0] - R[0, 1]) / s]


def closed_form_solution(moments, omega0, quat0, times, dps=40):
    """Closed-form reference for a triaxial body (SAM, LAM or the separatrix).

    Returns quat (T, 4), omega (T, 3) as float64 (rounded from ``dps`` digits).
    """
    return _closed_cached(tuple(map(float, moments)), tuple(map(float, omega0)),
                          tuple(map(float, quat0)), tuple(map(float, times)), dps)


@functools.cache
def _closed_cached(moments, omega0, quat0, times, dps):
    with mp.workdps(dps):
        I, w, L2, E2, lam, m, amp, forms, ref = _setup(moments, omega0)
        L = mp.sqrt(L2)
        signs, u0 = _find_signs_and_phase(I, w, m, lam, amp, forms)
        K = mp.ellipk(m) if m != 1 else mp.inf
        # precession rate of the reference axis about L:
        #   phi' = (L.w - (L.e)(e.w)) / (1 - (L.e)^2)  =  L (al + be s^2) / (ga + de s^2)
        j, k = [i for i in range(3) if i != ref]
        sq = {"sn": (0, 1), "cn": (1, -1), "dn": (1, -m)}  # f^2 = p + q sn^2
        al = be = ga = de = mp.mpf(0)
        for i in (j, k):
            p, qq = sq[forms[i]]
            a2 = amp[i] ** 2
            al += I[i] * a2 * p
            be += I[i] * a2 * qq
            ga += I[i] ** 2 * a2 * p
            de += I[i] ** 2 * a2 * qq
        n = -de / ga
        c_lin = L * be / de
        c_pi = L * (al / ga - be / de) / lam
        am0 = _am(u0, m, K)
        Pi0 = mp.ellippi(n, am0, m)
        q0 = _mpf_vec(quat0)
        nq = mp.sqrt(mp.fsum(c * c for c in q0))
        R0 = _quat_to_matrix([c / nq for c in q0])
        N0 = _nodal([I[i] * w[i] for i in range(3)], ref)
        RL = R0 * N0.T
        out_q, out_w = [], []
        for tf in times:
            t = mp.mpf(tf)
            u = lam * t + u0
            ww = _rates(u, m, lam, amp, forms, signs)
            phi = c_lin * t + c_pi * (mp.ellippi(n, _am(u, m, K), m) - Pi0)
            cp, sp_ = mp.cos(phi), mp.sin(phi)
            Rz = mp.matrix([[cp, -sp_, 0], [sp_, cp, 0], [0, 0, 1]])
            R = RL * Rz * _nodal([I[i] * ww[i] for i in range(3)], ref)
            out_q.append(_quat_to_float(_matrix_to_quat(R)))
            out_w.append(np.array([float(x) for x in ww]))
    return np.array(out_q), np.array(out_w)


def polhode_period(moments, omega0, dps=40):
    """4K/lambda in mpmath (the period of omega in the body frame)."""
    with mp.workdps(dps):
        _, _, _, _, lam, m, _, _, _ = _setup(moments, omega0)
        return float(4 * mp.ellipk(m) / lam)


def separatrix_m1(moments, omega0, dps=50):
    """Signed ``1 - k^2`` (+ on the SAM side), exact from the float inputs."""
    with mp.workdps(dps):
        A, B, C = _mpf_vec(moments)
        w1, w2, w3 = _mpf_vec(omega0)
        L2 = (A * w1) ** 2 + (B * w2) ** 2 + (C * w3) ** 2
        E2 = A * w1 ** 2 + B * w2 ** 2 + C * w3 ** 2
        if L2 >= E2 * B:
            return float((C - A) * (L2 - E2 * B) / ((C - B) * (L2 - E2 * A)))
        return -float((C - A) * (E2 * B - L2) / ((B - A) * (E2 * C - L2)))


# ---------------------------------------------------------------------------
# error measures
# ---------------------------------------------------------------------------
def attitude_error(q, q_ref):
    """Rotation angle (rad) between two stacks of scalar-last quaternions."""
    q = np.asarray(q, dtype=float)
    r = np.asarray(q_ref, dtype=float)
    # vector part of conj(r) (x) q
    rx, ry, rz, rw = -r[..., 0], -r[..., 1], -r[..., 2], r[..., 3]
    qx, qy, qz, qw = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    vx = rw * qx + rx * qw + ry * qz - rz * qy
    vy = rw * qy - rx * qz + ry * qw + rz * qx
    vz = rw * qz + rx * qy - ry * qx + rz * qw
    sw = rw * qw - rx * qx - ry * qy - rz * qz
    return 2.0 * np.arctan2(np.sqrt(vx * vx + vy * vy + vz * vz), np.abs(sw))


def rate_error(w, w_ref):
    """max |w - w_ref| / |w_ref| over epochs (relative to the rate magnitude)."""
    w = np.asarray(w, dtype=float)
    r = np.asarray(w_ref, dtype=float)
    scale = np.max(np.linalg.norm(r, axis=-1))
    return float(np.max(np.linalg.norm(w - r, axis=-1)) / scale) if scale > 0 else float(
        np.max(np.abs(w)))

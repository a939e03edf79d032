"""The LGVI's step loop of a family of binaries, compiled with numba.

The same map as :func:`attitude.binary.lgvi.integrate_lgvi_batch` (read
:mod:`attitude.binary.lgvi` for the method), run member by member, each member's whole
step loop inside compiled code: the implicit rotations by Newton on the Cayley
parameters, the compensated sums of the state, and the mutual force and torques of
:mod:`attitude.binary.mutual` at every step.  The series is not written out here: the
kernels walk the tables of :func:`attitude.binary.mutual.series_tables` (the recurrence of
``1/R``'s derivatives, the degree pairs with their coefficients, the generators of
rotation) and of :func:`attitude.binary.integrals.tensor_maps` (each degree's integrals
as a symmetric tensor, turned with the body), the ones the numpy path uses.

Without numba (or with ``ATTITUDE_NO_NUMBA=1``) these functions would run as plain Python
(correct, but far slower than numpy over many members): :data:`NUMBA` is False then and
:mod:`attitude.binary.lgvi` runs its numpy path.  Every array is float64 and contiguous;
no ``fastmath`` (the compiled path rounds as IEEE arithmetic does and agrees with the
numpy path to round-off, ``tests/binary/test_compiled.py``).
"""

from __future__ import annotations

import math
from functools import cache

import numpy as np

from attitude.binary.integrals import tensor_maps
from attitude.binary.mutual import series_tables
from attitude.propagation.jit import NUMBA, jit

__all__ = []

#: Whether the kernels run compiled (numba present and not disabled); re-exported.
COMPILED = NUMBA

#: The unit round-off (Newton's stop at the round-off floor, as the numpy path's).
_EPS = float(np.finfo(float).eps)


@cache
def kernel_tables(order: int) -> tuple:
    """The tables the kernels read, as a tuple of contiguous arrays: the series'
    (:func:`attitude.binary.mutual.series_tables`) and, per degree ``k >= 2``, the
    tensor maps of :func:`attitude.binary.integrals.tensor_maps` (``full`` from
    ``full_start[k]``; ``first`` from the degree's offset)."""
    s = series_tables(order)
    fulls = [np.zeros(0, np.int64)] * 2 + [tensor_maps(k)[0] for k in range(2, order + 1)]
    firsts = [np.arange((k + 1) * (k + 2) // 2, dtype=np.int64) for k in range(2)] + \
        [tensor_maps(k)[1] for k in range(2, order + 1)]
    full_start = np.concatenate([[0], np.cumsum([f.size for f in fulls])]).astype(np.int64)
    return (np.int64(order), s["offset"], s["one"], s["two"], s["factorials"], s["pair_k"],
            s["pair_l"], s["pair_start"], s["index"], s["coef"], s["force_index"],
            s["generator_start"], s["generators"], full_start,
            np.ascontiguousarray(np.concatenate(fulls)),
            np.ascontiguousarray(np.concatenate(firsts)))


@jit
def _rotate(T, A, out, offset, order, full_start, full, first, work):
    """The integrals ``T`` (all degrees 0..order, flat) of a body turned by ``A``
    (body -> inertial) into ``out``: degree ``k`` as a ``3^k`` tensor, each index turned
    (``k`` passes that turn the first index and move it last, as
    :func:`attitude.binary.integrals.rotated`)."""
    for i in range(offset[2]):
        out[i] = T[i]
    for k in range(2, order + 1):
        size = 3 ** k
        rest = size // 3
        a = work[0:size]
        b = work[size:2 * size]
        base = full_start[k]
        for i in range(size):
            a[i] = T[offset[k] + full[base + i]]
        for _ in range(k):
            for r in range(rest):
                for i in range(3):
                    b[r * 3 + i] = (A[i, 0] * a[r] + A[i, 1] * a[rest + r]) \
                        + A[i, 2] * a[2 * rest + r]
            for i in range(size):
                a[i] = b[i]
        n = offset[k + 1] - offset[k]
        for j in range(n):
            out[offset[k] + j] = a[first[offset[k] + j]]


@jit
def _inverse_distance(R, D, offset, order, one, two, factorials):
    """``D_gamma(R)`` for degrees 0..order+1 into ``D`` (flat): the recurrence of the
    Taylor coefficients of ``1/R`` on the tables, then times ``gamma!``."""
    x, y, z = R[0], R[1], R[2]
    r2 = x * x + y * y + z * z
    D[0] = 1.0 / math.sqrt(r2)
    for n in range(1, order + 2):
        prev, size_prev = offset[n - 1], offset[n] - offset[n - 1]
        pp = offset[n - 2] if n >= 2 else 0
        size_pp = offset[n - 1] - offset[n - 2] if n >= 2 else 0
        for j in range(offset[n], offset[n + 1]):
            i0, i1, i2 = one[0, j], one[1, j], one[2, j]
            c0 = D[prev + i0] if i0 < size_prev else 0.0
            c1 = D[prev + i1] if i1 < size_prev else 0.0
            c2 = D[prev + i2] if i2 < size_prev else 0.0
            acc = -(2 * n - 1) * (x * c0 + y * c1 + z * c2)
            if n >= 2:
                k0, k1, k2 = two[0, j], two[1, j], two[2, j]
                d0 = D[pp + k0] if k0 < size_pp else 0.0
                d1 = D[pp + k1] if k1 < size_pp else 0.0
                d2 = D[pp + k2] if k2 < size_pp else 0.0
                acc -= (n - 1) * (d0 + d1 + d2)
            D[j] = acc / (n * r2)
    for j in range(offset[order + 2]):
        D[j] *= factorials[j]


@jit
def _forces(R, T1, T2, G, tables, D, g1, g2, force, torque1, torque2):
    """Force on the secondary and both torques (inertial frame) at ``R`` of the
    integrals ``T1``, ``T2`` (inertial frame, flat): the degree pairs of the tables."""
    order, offset, one, two, factorials = tables[0], tables[1], tables[2], tables[3], \
        tables[4]
    pair_k, pair_l, pair_start, index, coef = tables[5], tables[6], tables[7], tables[8], \
        tables[9]
    force_index, generator_start, generators = tables[10], tables[11], tables[12]
    _inverse_distance(R, D, offset, order, one, two, factorials)
    for j in range(offset[order + 1]):
        g1[j] = 0.0
        g2[j] = 0.0
    F0, F1, F2 = 0.0, 0.0, 0.0
    for p in range(pair_k.size):
        k, l = pair_k[p], pair_l[p]  # noqa: E741 - the series' own letter
        nk, nl = offset[k + 1] - offset[k], offset[l + 1] - offset[l]
        start, size = pair_start[p], nk * nl
        ok, ol, om, of = offset[k], offset[l], offset[k + l], offset[k + l + 1]
        for a in range(nk):
            t2 = T2[ok + a]
            row = 0.0
            for b in range(nl):
                e = start + a * nl + b
                m = D[om + index[e]] * coef[e]
                row += m * T1[ol + b]
                g1[ol + b] += t2 * m
                w = coef[e] * t2 * T1[ol + b]
                F0 += D[of + force_index[3 * start + e - start]] * w
                F1 += D[of + force_index[3 * start + size + e - start]] * w
                F2 += D[of + force_index[3 * start + 2 * size + e - start]] * w
            g2[ok + a] += row
    force[0], force[1], force[2] = G * F0, G * F1, G * F2
    for i in range(3):
        torque1[i] = 0.0
        torque2[i] = 0.0
    for k in range(2, order + 1):
        n = offset[k + 1] - offset[k]
        base = generator_start[k]
        for i in range(3):
            w1, w2 = 0.0, 0.0
            for a in range(n):
                turned1, turned2 = 0.0, 0.0
                for b in range(n):
                    gen = generators[base + (i * n + a) * n + b]
                    turned1 += gen * T1[offset[k] + b]
                    turned2 += gen * T2[offset[k] + b]
                w1 += g1[offset[k] + a] * turned1
                w2 += g2[offset[k] + a] * turned2
            torque1[i] += G * w1
            torque2[i] += G * w2


@jit
def _solve3(m, r, out):
    """``m^-1 r`` by Cramer's rule (as :mod:`attitude.binary.lgvi`)."""
    a, b, c = m[0, 0], m[0, 1], m[0, 2]
    d, e, f = m[1, 0], m[1, 1], m[1, 2]
    g, h, i = m[2, 0], m[2, 1], m[2, 2]
    A, B, C = e * i - f * h, f * g - d * i, d * h - e * g
    det = a * A + b * B + c * C
    out[0] = (r[0] * A + r[1] * (c * h - b * i) + r[2] * (b * f - c * e)) / det
    out[1] = (r[0] * B + r[1] * (a * i - c * g) + r[2] * (c * d - a * f)) / det
    out[2] = (r[0] * C + r[1] * (b * g - a * h) + r[2] * (a * e - b * d)) / det


@jit
def _cayley(u, I, rtol, iterations, f, work, jac, d):
    """Newton on ``u (1 + f.f) = 2 (I f + f x I f)`` from ``f = I^-1 u / 2`` (the
    iteration of :mod:`attitude.binary.lgvi`, same stops); False if it fails."""
    for i in range(3):
        work[i] = 0.5 * u[i]
    _solve3(I, work, f)
    previous = math.inf
    for _ in range(iterations):
        f0, f1, f2 = f[0], f[1], f[2]
        i0 = I[0, 0] * f0 + I[0, 1] * f1 + I[0, 2] * f2
        i1 = I[1, 0] * f0 + I[1, 1] * f1 + I[1, 2] * f2
        i2 = I[2, 0] * f0 + I[2, 1] * f1 + I[2, 2] * f2
        s = 1.0 + f0 * f0 + f1 * f1 + f2 * f2
        work[0] = u[0] * s - 2.0 * (i0 + f1 * i2 - f2 * i1)
        work[1] = u[1] * s - 2.0 * (i1 + f2 * i0 - f0 * i2)
        work[2] = u[2] * s - 2.0 * (i2 + f0 * i1 - f1 * i0)
        for c in range(3):
            si0 = f1 * I[2, c] - f2 * I[1, c]
            si1 = f2 * I[0, c] - f0 * I[2, c]
            si2 = f0 * I[1, c] - f1 * I[0, c]
            sif0 = 0.0 if c == 0 else (-i2 if c == 1 else i1)
            sif1 = i2 if c == 0 else (0.0 if c == 1 else -i0)
            sif2 = -i1 if c == 0 else (i0 if c == 1 else 0.0)
            jac[0, c] = 2.0 * u[0] * f[c] - 2.0 * (I[0, c] + si0 - sif0)
            jac[1, c] = 2.0 * u[1] * f[c] - 2.0 * (I[1, c] + si1 - sif1)
            jac[2, c] = 2.0 * u[2] * f[c] - 2.0 * (I[2, c] + si2 - sif2)
        _solve3(jac, work, d)
        f[0], f[1], f[2] = f0 - d[0], f1 - d[1], f2 - d[2]
        correction = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) ** 0.5
        size = (f[0] * f[0] + f[1] * f[1] + f[2] * f[2]) ** 0.5
        if correction <= rtol * size or (correction <= 64 * _EPS * size
                                          and correction >= 0.5 * previous):
            return True
        if not math.isfinite(size):
            return False
        previous = correction
    return False


@jit
def _cayley_difference(f, out):
    """``F - E = 2 (S + S^2) / (1 + f.f)`` (as :func:`attitude.binary.lgvi.cayley_difference`)."""
    f0, f1, f2 = f[0], f[1], f[2]
    c = 2.0 / (1.0 + f0 * f0 + f1 * f1 + f2 * f2)
    out[0, 0], out[0, 1], out[0, 2] = -c * (f1 * f1 + f2 * f2), c * (f0 * f1 - f2), \
        c * (f0 * f2 + f1)
    out[1, 0], out[1, 1], out[1, 2] = c * (f0 * f1 + f2), -c * (f0 * f0 + f2 * f2), \
        c * (f1 * f2 - f0)
    out[2, 0], out[2, 1], out[2, 2] = c * (f0 * f2 - f1), c * (f1 * f2 + f0), \
        -c * (f0 * f0 + f1 * f1)


@jit
def _add(x, carry, dx, compensated):
    """``x + dx``, compensated (Neumaier) or plain: the new ``(x, carry)``."""
    if not compensated:
        return x + dx, carry
    y = dx + carry
    total = x + y
    if abs(x) >= abs(y):
        return total, (x - total) + y
    return total, (y - total) + x


@jit
def _loads(R, A, T1b, T2b, G, tables, scratch, force, M):
    """Force on the secondary (inertial) and both body-frame torques ``M`` (2, 3) at
    ``R`` and attitudes ``A`` (2, 3, 3) of body-frame integrals ``T1b``, ``T2b``."""
    order, offset, full_start, full, first = tables[0], tables[1], tables[13], tables[14], \
        tables[15]
    T1, T2, D, g1, g2, work, tau = scratch
    _rotate(T1b, A[0], T1, offset, order, full_start, full, first, work)
    _rotate(T2b, A[1], T2, offset, order, full_start, full, first, work)
    _forces(R, T1, T2, G, tables, D, g1, g2, force, tau[0], tau[1])
    for b in range(2):
        for i in range(3):
            M[b, i] = (A[b, 0, i] * tau[b, 0] + A[b, 1, i] * tau[b, 1]) + A[b, 2, i] * tau[b, 2]


@jit
def lgvi_members(R0, p0, A0, Pi0, inertia, mu, T1b, T2b, G, tables, grid, nodes,
                 kick_step, kick_member, kick_body, kick_dp, kick_L, compensated, rtol,
                 iterations, Rs, ps, As, Pis):
    """Every member's LGVI over ``grid`` (the numpy path's map, see
    :func:`attitude.binary.lgvi.integrate_lgvi_batch`), writing the state at the grid
    nodes ``nodes`` into ``Rs`` ``(nodes, n, 3)``, ``ps``, ``As`` ``(nodes, n, 2, 3, 3)``
    and ``Pis`` ``(nodes, n, 2, 3)``.  The kicks (sorted by step) add ``kick_dp`` to
    ``p`` and ``A_b^T kick_L`` to the body's ``Pi`` after their step.  Returns -1, or the
    first member whose implicit rotation failed."""
    offset = tables[1]
    size = offset[tables[0] + 2]
    n_tensor = 2 * 3 ** max(tables[0], 2)
    scratch = (np.empty(size), np.empty(size), np.empty(size), np.empty(size),
               np.empty(size), np.empty(n_tensor), np.empty((2, 3)))
    R, p, cR, cp = np.empty(3), np.empty(3), np.empty(3), np.empty(3)
    A, cA, Pi, cPi = np.empty((2, 3, 3)), np.empty((2, 3, 3)), np.empty((2, 3)), \
        np.empty((2, 3))
    F, F1, M, M1 = np.empty(3), np.empty(3), np.empty((2, 3)), np.empty((2, 3))
    g, u, D = np.empty((2, 3)), np.empty(3), np.empty((2, 3, 3))
    f, work, jac, d = np.empty(3), np.empty(3), np.empty((3, 3)), np.empty(3)
    AD = np.empty((2, 3, 3))
    for m in range(R0.shape[0]):
        R[:] = R0[m]
        p[:] = p0[m]
        A[:] = A0[m]
        Pi[:] = Pi0[m]
        cR[:] = 0.0
        cp[:] = 0.0
        cA[:] = 0.0
        cPi[:] = 0.0
        _loads(R, A, T1b[m], T2b[m], G, tables, scratch, F, M)
        j = 0
        for k in range(grid.size):
            if k > 0:
                h = grid[k] - grid[k - 1]
                for b in range(2):
                    for i in range(3):
                        g[b, i] = Pi[b, i] + 0.5 * h * M[b, i]
                        u[i] = h * g[b, i]
                    if not _cayley(u, inertia[m, b], rtol, iterations, f, work, jac, d):
                        return m
                    _cayley_difference(f, D[b])
                c = h / mu[m]
                for i in range(3):
                    R[i], cR[i] = _add(R[i], cR[i], c * (p[i] + 0.5 * h * F[i]), compensated)
                for b in range(2):
                    for r in range(3):
                        for c in range(3):
                            AD[b, r, c] = (A[b, r, 0] * D[b, 0, c] + A[b, r, 1] * D[b, 1, c]) \
                                + A[b, r, 2] * D[b, 2, c]
                for b in range(2):
                    for r in range(3):
                        for c in range(3):
                            A[b, r, c], cA[b, r, c] = _add(A[b, r, c], cA[b, r, c],
                                                           AD[b, r, c], compensated)
                _loads(R, A, T1b[m], T2b[m], G, tables, scratch, F1, M1)
                for i in range(3):
                    p[i], cp[i] = _add(p[i], cp[i], 0.5 * h * (F[i] + F1[i]), compensated)
                for b in range(2):
                    for i in range(3):
                        turn = (D[b, 0, i] * g[b, 0] + D[b, 1, i] * g[b, 1]) \
                            + D[b, 2, i] * g[b, 2]
                        Pi[b, i], cPi[b, i] = _add(Pi[b, i], cPi[b, i],
                                                   turn + 0.5 * h * (M[b, i] + M1[b, i]),
                                                   compensated)
                F[:] = F1
                M[:] = M1
            for e in range(kick_step.size):
                if kick_step[e] == k and kick_member[e] == m:
                    b = kick_body[e]
                    for i in range(3):
                        p[i] += kick_dp[e, i]
                        Pi[b, i] += (A[b, 0, i] * kick_L[e, 0] + A[b, 1, i] * kick_L[e, 1]) \
                            + A[b, 2, i] * kick_L[e, 2]
            if j < nodes.size and nodes[j] == k:
                Rs[j, m] = R
                ps[j, m] = p
                As[j, m] = A
                Pis[j, m] = Pi
                j += 1
    return -1

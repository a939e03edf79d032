"""The splitting integrator's step loop for one body, compiled with numba.

The same loop as :func:`attitude.propagation.splitting.integrate_splitting` (read its
module docstring for the method): the exact free flow
(:func:`attitude.propagation.compiled.free_flow_one`) composed with the kicks of the
built-in torque models (:mod:`attitude.propagation.compiled_torques`), the outputs
inside a step by a partial step, and the ``rtol`` error control from an embedded
composition, all in plain scalar code.  With numba installed it runs compiled (a step of
the order-4 composition costs a few microseconds instead of ~0.5 ms of Python); without
numba the same functions run as Python and :mod:`~attitude.propagation.splitting` uses its
own numpy path instead.  A user's Python torque has no compiled form: such runs take the
numpy path (``docs/integrators.md`` gives the cost of each path).

Every array is float64; quaternions are scalar-last, the loop works in the principal
frame (``q_p = q_b * q_bp^-1``, ``w_p = R(q_bp) w_b``) like the numpy path.
"""

from __future__ import annotations

import math

import numpy as np

from .compiled import NUMBA, free_flow_one, jit
from .compiled_torques import body_torque

__all__ = ["march_one", "MODES", "NUMBA"]

#: Modes of :func:`march_one`: steps on a grid with outputs inside them, steps cut at
#: the outputs, steps from the error estimate.
MODES = {"dense": 0, "cut": 1, "rtol": 2}


@jit
def _qmul(a, b, out):
    ax, ay, az, aw = a[0], a[1], a[2], a[3]
    bx, by, bz, bw = b[0], b[1], b[2], b[3]
    out[0] = aw * bx + ax * bw + ay * bz - az * by
    out[1] = aw * by - ax * bz + ay * bw + az * bx
    out[2] = aw * bz + ax * by - ay * bx + az * bw
    out[3] = aw * bw - ax * bx - ay * by - az * bz


@jit
def _rotate(q, v, inverse, out):
    """``out = R(q) v`` (or ``R(q)^T v``), q unit scalar-last."""
    x, y, z, s = q[0], q[1], q[2], q[3]
    if inverse:
        x, y, z = -x, -y, -z
    # v + 2 s (u x v) + 2 u x (u x v)
    cx = y * v[2] - z * v[1]
    cy = z * v[0] - x * v[2]
    cz = x * v[1] - y * v[0]
    out[0] = v[0] + 2.0 * (s * cx + y * cz - z * cy)
    out[1] = v[1] + 2.0 * (s * cy + z * cx - x * cz)
    out[2] = v[2] + 2.0 * (s * cz + x * cy - y * cx)


@jit
def _accel(spec, t, q, w, frame, work, out):
    """Principal-frame angular acceleration of the torque models in ``spec`` at
    ``(t, q, w)`` (principal frame): ``out = I^-1 R(q_bp) M_b(t, q_b, w_b)``."""
    kinds, offsets, params = spec
    q_bp, identity, inv_m = frame
    qb = work[0:4]
    wb = work[4:7]
    mb = work[7:10]
    if identity:
        qb[:] = q
        wb[:] = w
    else:
        _qmul(q, q_bp, qb)
        _rotate(q_bp, w, True, wb)
    mb[:] = 0.0
    body_torque(kinds, offsets, params, t, qb, wb, mb)
    if identity:
        out[0], out[1], out[2] = mb[0] * inv_m[0], mb[1] * inv_m[1], mb[2] * inv_m[2]
    else:
        _rotate(q_bp, mb, False, out)
        out[0] *= inv_m[0]
        out[1] *= inv_m[1]
        out[2] *= inv_m[2]


@jit
def _kick(kick, drag, has_kick, has_drag, frame, t, q, w, tau, cache, work, rk_order):
    """``w`` advanced by the torques over ``tau`` at frozen ``(t, q)``, in place.

    ``cache[0:3]`` holds the attitude-only acceleration at ``(t, q)`` when
    ``cache[3] == 1`` (reused by the next kick at the same point)."""
    if tau == 0.0:
        return
    a = cache[0:3]
    if has_kick and cache[3] == 0.0:
        _accel(kick, t, q, w, frame, work, a)
        cache[3] = 1.0
    if not has_drag:
        w[0] += tau * a[0]
        w[1] += tau * a[1]
        w[2] += tau * a[2]
        return
    k = work[10:22]
    y = work[22:25]
    d = work[25:28]
    base = 0.0 if not has_kick else 1.0
    stages = 2 if rk_order == 2 else 4
    c = (0.0, 0.5, 0.5, 1.0) if stages == 4 else (0.0, 0.5, 0.0, 0.0)
    for s in range(stages):
        for i in range(3):
            y[i] = w[i] if s == 0 else w[i] + c[s] * tau * k[3 * (s - 1) + i]
        _accel(drag, t, q, y, frame, work, d)
        for i in range(3):
            k[3 * s + i] = d[i] + base * a[i]
    if stages == 2:
        for i in range(3):
            w[i] += tau * k[3 + i]
    else:
        for i in range(3):
            w[i] += tau / 6.0 * (k[i] + 2.0 * k[3 + i] + 2.0 * k[6 + i] + k[9 + i])


@jit
def _internal_kick(internal, frame, moments, anchor, t, q, w, tau, rk_order, work):
    """The kick of internal torques alone (they keep the inertial ``L``): RK on the rates
    and the attitude increment ``p`` (``dp = p (M x L / L^2, 0) / 2``), then the body
    ``L`` set to ``q'^-1 L_inertial`` (``anchor``), in place on ``q``, ``w``."""
    if tau == 0.0:
        return
    kw = work[30:42]
    kp = work[42:58]
    y = work[58:61]
    p = work[61:65]
    qs = work[65:69]
    a = work[69:72]
    stages = 2 if rk_order == 2 else 4
    c = (0.0, 0.5, 0.5, 1.0) if stages == 4 else (0.0, 0.5, 0.0, 0.0)
    for s in range(stages):
        for i in range(3):
            y[i] = w[i] if s == 0 else w[i] + c[s] * tau * kw[3 * (s - 1) + i]
        for i in range(4):
            one = 1.0 if i == 3 else 0.0
            p[i] = one if s == 0 else one + c[s] * tau * kp[4 * (s - 1) + i]
        _qmul(q, p, qs)
        nq = math.sqrt(qs[0] * qs[0] + qs[1] * qs[1] + qs[2] * qs[2] + qs[3] * qs[3])
        for i in range(4):
            qs[i] /= nq
        _accel(internal, t, qs, y, frame, work, a)
        m0, m1, m2 = a[0] * moments[0], a[1] * moments[1], a[2] * moments[2]
        L0, L1, L2 = y[0] * moments[0], y[1] * moments[1], y[2] * moments[2]
        LL = L0 * L0 + L1 * L1 + L2 * L2
        ex = ey = ez = 0.0
        if LL > 0.0:
            ex = (m1 * L2 - m2 * L1) / LL
            ey = (m2 * L0 - m0 * L2) / LL
            ez = (m0 * L1 - m1 * L0) / LL
        px, py, pz, pw = p[0], p[1], p[2], p[3]
        kp[4 * s + 0] = 0.5 * (pw * ex + py * ez - pz * ey)
        kp[4 * s + 1] = 0.5 * (pw * ey - px * ez + pz * ex)
        kp[4 * s + 2] = 0.5 * (pw * ez + px * ey - py * ex)
        kp[4 * s + 3] = -0.5 * (px * ex + py * ey + pz * ez)
        for i in range(3):
            kw[3 * s + i] = a[i]
    for i in range(4):
        one = 1.0 if i == 3 else 0.0
        if stages == 2:
            p[i] = one + tau * kp[4 + i]
        else:
            p[i] = one + tau / 6.0 * (kp[i] + 2.0 * kp[4 + i] + 2.0 * kp[8 + i] + kp[12 + i])
    _qmul(q, p, qs)
    nq = math.sqrt(qs[0] * qs[0] + qs[1] * qs[1] + qs[2] * qs[2] + qs[3] * qs[3])
    for i in range(4):
        q[i] = qs[i] / nq
    _rotate(q, anchor, True, y)
    w[0], w[1], w[2] = y[0] / moments[0], y[1] / moments[1], y[2] / moments[2]


@jit
def _any_kick(torq, frame, moments, anchor, t, q, w, tau, cache, work, rk_order):
    kick, drag, internal, flags = torq
    if flags[2]:
        _internal_kick(internal, frame, moments, anchor, t, q, w, tau, rk_order, work)
        cache[3] = 0.0
    else:
        _kick(kick, drag, flags[0], flags[1], frame, t, q, w, tau, cache, work, rk_order)


@jit
def _step(fc, torq, frame, moments, anchor, b, a, t, q, w, pending, h, cache, work,
          rk_order):
    """One step of the composition ``(b, a)`` over ``h`` from the state after the last
    free flow with its pending kick, in place; returns the new pending kick."""
    acc = 0.0
    for i in range(a.shape[0]):
        tau = b[i] * h + (pending if i == 0 else 0.0)
        _any_kick(torq, frame, moments, anchor, t + acc * h, q, w, tau, cache, work,
                  rk_order)
        free_flow_one(fc, q, w, a[i] * h)
        cache[3] = 0.0
        acc += a[i]
    return b[a.shape[0]] * h


@jit
def march_one(fc, torq, frame, moments, anchor, scheme, embedded, q0, w0, t0, times,
              h, mode, rtol, expo, w_floor, h_limit, snap, rk_order, out_q, out_w):
    """Advance one body through ``times`` (relative to ``t0``, one sign, increasing
    ``|t|``) and write the principal-frame outputs (the loop of
    :func:`attitude.propagation.splitting.integrate_splitting` for one body).

    Parameters
    ----------
    fc : (7,) array
        Free-flow constants (``[A, B, C, spherical, lam_on_tie, nu_sam, nu_lam]``).
    torq : tuple
        ``(kick, drag, internal, flags)``: three compiled torque specs
        ``(kinds, offsets, params)`` and the booleans ``(has_kick, has_drag, internal)``.
    frame : tuple
        ``(q_bp, identity, inverse moments)``.
    moments, anchor : (3,) arrays
        Principal moments; the inertial ``L`` kept by internal torques.
    scheme, embedded : tuple of arrays
        ``(b, a)`` kick and free coefficients of the composition and of the embedded
        one (``rtol`` mode).
    q0, w0 : (4,), (3,) arrays
        Principal-frame state at ``t0``.
    times : (T,) array
        Output times, s relative to ``t0``.
    h, mode, rtol, expo, w_floor, h_limit, snap, rk_order
        Step (initial step for ``rtol``), :data:`MODES` code, tolerance, controller
        exponent, rate floor of the error norm, longest step, relative snapping
        distance of an output to a step end, RK order of velocity-dependent kicks.
    out_q, out_w : (T, 4), (T, 3) arrays
        Outputs, in the order of ``times``.

    Returns
    -------
    int
        Number of accepted steps (negative if the ``rtol`` step fell below round-off:
        minus the index of the first output not reached).

    Examples
    --------
    >>> import numpy as np
    >>> from attitude.propagation.compiled_loop import march_one
    >>> march_one.__name__
    'march_one'
    """
    b, a = scheme
    eb, ea = embedded
    n_out = times.shape[0]
    q = q0.copy()
    w = w0.copy()
    qt = np.empty(4)
    wt = np.empty(3)
    qe = np.empty(4)
    we = np.empty(3)
    qb = np.empty(4)
    wb = np.empty(3)
    qs = np.empty(4)
    ws = np.empty(3)
    cache = np.zeros(4)
    cache_t = np.zeros(4)
    cache_e = np.zeros(4)
    work = np.empty(80)
    pending = 0.0
    t_now = 0.0
    sign = 1.0 if times[n_out - 1] >= 0 else -1.0
    last = times[n_out - 1]
    tol = snap * (abs(h) if math.isfinite(h) else abs(last))
    k = 0
    j = 0
    steps = 0
    err = 0.0
    pend_new = 0.0
    while j < n_out:
        tj = times[j]
        if abs(tj - t_now) <= tol:
            qb[:] = q
            wb[:] = w
            _any_kick(torq, frame, moments, anchor, t0 + t_now, qb, wb, pending, cache, work,
                      rk_order)
            out_q[j] = qb
            out_w[j] = wb
            j += 1
            continue
        if mode == 1:                                       # cut: equal steps to tj
            n = max(1, math.ceil(abs(tj - t_now) / h * (1.0 - 1e-12))) if math.isfinite(h) else 1
            hh = (tj - t_now) / n
            for i in range(n):
                pending = _step(fc, torq, frame, moments, anchor, b, a,
                                t0 + t_now + i * hh, q, w, pending, hh, cache, work, rk_order)
                steps += 1
            t_now = tj
            continue
        if mode == 0:
            t_next = sign * (k + 1) * h if math.isfinite(h) else last
            if abs(t_next - last) <= tol or (not math.isfinite(h)):
                t_next = last
            pend_new = 0.0
        else:
            t_next = t_now + sign * min(h, h_limit)
            if sign * (t_next - last) > -tol:
                t_next = last
            pend_new = 0.0
            # the embedded step starts from the state at the step boundary (one per step)
            qs[:] = q
            ws[:] = w
            _any_kick(torq, frame, moments, anchor, t0 + t_now, qs, ws, pending, cache, work,
                      rk_order)
            w_scale = math.sqrt(ws[0] * ws[0] + ws[1] * ws[1] + ws[2] * ws[2])
            while True:
                hh = t_next - t_now
                qt[:] = q
                wt[:] = w
                cache_t[:] = cache
                pend_new = _step(fc, torq, frame, moments, anchor, b, a, t0 + t_now, qt, wt,
                                 pending, hh, cache_t, work, rk_order)
                qb[:] = qt
                wb[:] = wt
                cache_t[3] = 0.0
                _any_kick(torq, frame, moments, anchor, t0 + t_next, qb, wb, pend_new,
                          cache_t, work, rk_order)
                qe[:] = qs
                we[:] = ws
                cache_e[:] = cache
                pe = _step(fc, torq, frame, moments, anchor, eb, ea, t0 + t_now, qe, we, 0.0,
                           hh, cache_e, work, rk_order)
                cache_e[3] = 0.0
                _any_kick(torq, frame, moments, anchor, t0 + t_next, qe, we, pe, cache_e, work,
                          rk_order)
                dq = 0.0                     # q and -q are one attitude
                dqs = 0.0
                dw = 0.0
                for i in range(4):
                    dq += (qb[i] - qe[i]) ** 2
                    dqs += (qb[i] + qe[i]) ** 2
                dq = min(dq, dqs)
                for i in range(3):
                    dw += (wb[i] - we[i]) ** 2
                w1 = math.sqrt(wb[0] * wb[0] + wb[1] * wb[1] + wb[2] * wb[2])
                scale = max(max(w_scale, w1), w_floor)
                err = max(math.sqrt(dq), math.sqrt(dw) / scale) / rtol
                if err <= 1.0:
                    break
                factor = max(0.2, 0.9 * err ** -expo) if math.isfinite(err) else 0.2
                h = abs(hh) * factor
                if h <= 1e-12 * max(abs(t_now), abs(hh)):
                    return -j - 1
                t_next = t_now + sign * h
            grow = 5.0 if err == 0.0 else min(5.0, max(0.2, 0.9 * err ** -expo))
            h = abs(t_next - t_now) * grow
        # outputs strictly inside (t_now, t_next): partial steps from the step's start
        while j < n_out and sign * (times[j] - t_next) < -tol:
            tj = times[j]
            qb[:] = q
            wb[:] = w
            if abs(tj - t_now) <= tol:
                _any_kick(torq, frame, moments, anchor, t0 + t_now, qb, wb, pending, cache,
                          work, rk_order)
            else:
                cache_t[:] = cache
                pp = _step(fc, torq, frame, moments, anchor, b, a, t0 + t_now, qb, wb,
                           pending, tj - t_now, cache_t, work, rk_order)
                cache_t[3] = 0.0
                _any_kick(torq, frame, moments, anchor, t0 + tj, qb, wb, pp, cache_t, work,
                          rk_order)
            out_q[j] = qb
            out_w[j] = wb
            j += 1
        if j == n_out:
            break
        if mode == 2:
            q[:] = qt
            w[:] = wt
            pending = pend_new
            cache[3] = 0.0
        else:
            pending = _step(fc, torq, frame, moments, anchor, b, a, t0 + t_now, q, w,
                            pending, t_next - t_now, cache, work, rk_order)
            k += 1
        steps += 1
        t_now = t_next
    return steps

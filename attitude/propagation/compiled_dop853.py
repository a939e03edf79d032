"""The reference integrator's DOP853 for one body, compiled with numba, with events.

The same method, step-size control and dense output as scipy's
``solve_ivp(method="DOP853", t_eval=...)`` (Hairer, Norsett & Wanner, *Solving Ordinary
Differential Equations I*, Sec. II.5 and II.6; scipy's formulation: the error norm
that blends the 5th- and 3rd-order estimates, the initial step of Sec. II.4, the 7th-degree
interpolant from three extra stages), with the Butcher tableau read from scipy itself
(``scipy.integrate._ivp.dop853_coefficients``: nothing is copied), on the right-hand side
of :mod:`attitude.propagation.reference`

.. math::

    I \\dot\\omega = (I\\omega) \\times \\omega + M_e + M_i, \\qquad
    \\dot q = \\tfrac12\\, q \\otimes (\\omega + (M_i \\times L)/L^2, 0)

with the built-in torque models evaluated by
:func:`attitude.propagation.compiled_torques.body_torque` (``M_e`` external, ``M_i``
internal).  A step costs ~12 right-hand sides of a fraction of a microsecond each instead
of ~12 calls of Python torque models; the two paths take the same steps up to the last
bits of the error norm, so they agree to a small multiple of the tolerance (tested against
scipy and against the exact torque-free solution).

Every array is float64; the state is ``(q (4), omega (3))``, body -> inertial quaternion
scalar-last, body-frame rates, as in :func:`attitude.propagation.reference.integrate_reference`.

:func:`dop853_block` runs from a carried state (time, state, its derivative, the next
step size, the event values) until a given time, so that a run in blocks (a progress
bar's) takes the same steps as a run in one, and locates events: the built-in event
functions (:data:`EVENT_KINDS`, each the formula of :mod:`attitude.propagation.events`
compiled by ``jit_formula``) at each accepted step, a sign change bracketing a root on the
step's interpolant, located by the Illinois variant of false position to
:func:`root_tolerance`.  :func:`dop853_one` is one block from ``t = 0`` without events.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.integrate._ivp import dop853_coefficients as _dop

from .compiled import NUMBA, jit, jit_formula
from .compiled_torques import body_torque
from .events import nutation_angle

__all__ = ["dop853_one", "dop853_block", "root_tolerance", "TABLEAU", "NUMBA", "EVENT_KINDS",
           "EVENT_PARAMS", "CARRY", "NO_EVENTS", "DONE", "TERMINAL", "FULL"]

_N = _dop.N_STAGES                  # 12 stages, the 13th is the next step's first (FSAL)
#: ``(A (16, 16), C (16,), B (12,), E3 (13,), E5 (13,), D (4, 16))``: scipy's DOP853
#: tableau with its three extra stages for the dense output.
TABLEAU = tuple(np.ascontiguousarray(x, dtype=float) for x in (
    _dop.A, _dop.C, _dop.B, _dop.E3, _dop.E5, _dop.D))
_SAFETY, _MIN_FACTOR, _MAX_FACTOR = 0.9, 0.2, 10.0
_EXPONENT = -1.0 / 8.0              # -1 / (error estimator order 7 + 1)
_EPS = float(np.finfo(float).eps)


@jit
def _rhs(torques, inertia, inv_inertia, t, y, work, out):
    """``out = dy/dt`` at ``(t, y)``; ``work`` (9,) scratch."""
    ext, internal, has_internal, user, has_user = torques
    w0, w1, w2 = y[4], y[5], y[6]
    q = y[0:4]
    w = y[4:7]
    m = work[0:3]
    mi = work[3:6]
    L0 = inertia[0, 0] * w0 + inertia[0, 1] * w1 + inertia[0, 2] * w2
    L1 = inertia[1, 0] * w0 + inertia[1, 1] * w1 + inertia[1, 2] * w2
    L2 = inertia[2, 0] * w0 + inertia[2, 1] * w1 + inertia[2, 2] * w2
    body_torque(ext[0], ext[1], ext[2], t, q, w, m)
    if has_user:
        # the user's own compiled torque (compiled_torques.user_torque), by its address
        mu = work[6:9]
        user(t, q, w, mu)
        m[0] += mu[0]
        m[1] += mu[1]
        m[2] += mu[2]
    d0 = (L1 * w2 - L2 * w1) + m[0]
    d1 = (L2 * w0 - L0 * w2) + m[1]
    d2 = (L0 * w1 - L1 * w0) + m[2]
    r0, r1, r2 = w0, w1, w2
    if has_internal:
        # torques between parts of the body turn L in the body frame only: the frame
        # turns at w + (M x L)/L^2 so that the inertial L stays fixed
        body_torque(internal[0], internal[1], internal[2], t, q, w, mi)
        d0 += mi[0]
        d1 += mi[1]
        d2 += mi[2]
        LL = L0 * L0 + L1 * L1 + L2 * L2
        if LL > 0.0:
            r0 += (mi[1] * L2 - mi[2] * L1) / LL
            r1 += (mi[2] * L0 - mi[0] * L2) / LL
            r2 += (mi[0] * L1 - mi[1] * L0) / LL
    out[4] = inv_inertia[0, 0] * d0 + inv_inertia[0, 1] * d1 + inv_inertia[0, 2] * d2
    out[5] = inv_inertia[1, 0] * d0 + inv_inertia[1, 1] * d1 + inv_inertia[1, 2] * d2
    out[6] = inv_inertia[2, 0] * d0 + inv_inertia[2, 1] * d1 + inv_inertia[2, 2] * d2
    qx, qy, qz, qw = y[0], y[1], y[2], y[3]
    out[0] = 0.5 * (qw * r0 + qy * r2 - qz * r1)
    out[1] = 0.5 * (qw * r1 - qx * r2 + qz * r0)
    out[2] = 0.5 * (qw * r2 + qx * r1 - qy * r0)
    out[3] = 0.5 * (-qx * r0 - qy * r1 - qz * r2)


@jit
def _rms(x, scale):
    s = 0.0
    for i in range(x.shape[0]):
        v = x[i] / scale[i]
        s += v * v
    return math.sqrt(s / x.shape[0])


@jit
def _initial_step(torques, inertia, inv_inertia, y0, f0, direction, t_bound, rtol, atol,
                  work, scratch):
    """scipy's ``select_initial_step`` (Hairer et al. II.4) for order 7."""
    n = y0.shape[0]
    interval = abs(t_bound)
    scale = scratch[0]
    y1 = scratch[1]
    f1 = scratch[2]
    for i in range(n):
        scale[i] = atol[i] + abs(y0[i]) * rtol
    d0 = _rms(y0, scale)
    d1 = _rms(f0, scale)
    h0 = 1e-6 if (d0 < 1e-5 or d1 < 1e-5) else 0.01 * d0 / d1
    h0 = min(h0, interval)
    for i in range(n):
        y1[i] = y0[i] + h0 * direction * f0[i]
    _rhs(torques, inertia, inv_inertia, h0 * direction, y1, work, f1)
    for i in range(n):
        f1[i] -= f0[i]
    d2 = _rms(f1, scale) / h0
    if d1 <= 1e-15 and d2 <= 1e-15:
        h1 = max(1e-6, h0 * 1e-3)
    else:
        h1 = (0.01 / max(d1, d2)) ** (1.0 / 8.0)
    return min(100.0 * h0, h1, interval)


@jit
def _stage(torques, inertia, inv_inertia, A, C, K, s, t, y, h, work, ys):
    """``K[s] = f(t + c_s h, y + h sum_j a_sj K[j])``."""
    for i in range(y.shape[0]):
        acc = 0.0
        for j in range(s):
            acc += K[j, i] * A[s, j]
        ys[i] = y[i] + acc * h
    _rhs(torques, inertia, inv_inertia, t + C[s] * h, ys, work, K[s])


#: Codes of the built-in event functions the kernel evaluates (:func:`_event_value`):
#: ``nutation`` (numbers: the angle crossed, the principal axis in body axes (3)),
#: :func:`attitude.propagation.events.nutation_angle`.
EVENT_KINDS = {"nutation": 0}
#: Numbers per event in ``event_params`` (the widest kind's).
EVENT_PARAMS = 4
#: Slots of the carried state (``carry``) before the event values: ``t``, the next step
#: size (0: not started), the next output index, ``y`` (7), ``f(t, y)`` (7).
CARRY = 17
#: Status codes of :func:`dop853_block`: the block ended (``t_stop`` passed or every
#: output written), a terminal event stopped the run, the record arrays are full.
DONE, TERMINAL, FULL = 0, 1, 2

_nutation_angle = jit_formula(nutation_angle)


@jit
def _event_value(kind, params, inertia, t, y):
    """The event function ``kind`` at ``(t, y)``: one formula with the Python event's
    (:mod:`attitude.propagation.events`)."""
    if kind == 0:
        return _nutation_angle(inertia, params[1:4], y[4], y[5], y[6]) - params[0]
    return math.nan


@jit
def _crossed(g_old, g_new, direction):
    """Whether an event changed sign over a step in the counted direction (scipy's
    ``find_active_events``: a zero at either end counts)."""
    up = g_old <= 0.0 and g_new >= 0.0
    down = g_old >= 0.0 and g_new <= 0.0
    if direction > 0.0:
        return up
    if direction < 0.0:
        return down
    return up or down


@jit
def _dense(torques, inertia, inv_inertia, A, C, D, K, t, y, y_new, h, work, ys, F):
    """The 7th-degree interpolant of the step ``[t, t + h]``: three more stages, then
    its coefficients ``F`` (7, n)."""
    for s in range(_N + 1, 16):
        _stage(torques, inertia, inv_inertia, A, C, K, s, t, y, h, work, ys)
    for i in range(y.shape[0]):
        dy = y_new[i] - y[i]
        F[0, i] = dy
        F[1, i] = h * K[0, i] - dy
        F[2, i] = 2.0 * dy - h * (K[_N, i] + K[0, i])
        for r in range(4):
            acc = 0.0
            for s in range(16):
                acc += D[r, s] * K[s, i]
            F[3 + r, i] = h * acc


@jit
def _interpolate(F, y, x, out):
    """The interpolant at ``x = (t_out - t) / h`` in ``[0, 1]``."""
    for i in range(y.shape[0]):
        v = 0.0
        for r in range(7):
            v += F[6 - r, i]
            v *= x if r % 2 == 0 else 1.0 - x
        out[i] = v + y[i]


@jit
def _event_at(kind, params, inertia, F, y, t, h, tt, ys):
    """The event function on the interpolant at time ``tt`` of the step."""
    _interpolate(F, y, (tt - t) / h, ys)
    return _event_value(kind, params, inertia, tt, ys)


@jit
def root_tolerance(a, b):
    """Half-width of the bracket :func:`_locate` ends with: ``4 eps max(|a|, |b|)``
    (a few ulps of the event time; the time it returns is within this of the root of the
    event function on the interpolant, plus half an ulp for the midpoint's rounding).

    Examples
    --------
    >>> from attitude.propagation.compiled_dop853 import root_tolerance
    >>> root_tolerance(10.0, 12.0) == 48.0 * 2.0 ** -52
    True
    """
    return 4.0 * _EPS * max(abs(a), abs(b))


@jit
def _locate(kind, params, inertia, F, y, t, h, ga, gb, ys):
    """The root of one event's function on the step's interpolant, between ``t``
    (value ``ga``) and ``t + h`` (``gb``), of opposite signs or one zero.

    The Illinois variant of false position, kept in a bracket: a point within the
    tolerance of an end is moved the tolerance inside (so that a bracket close to the
    root straddles it next), and every third iteration that did not halve the bracket
    is a bisection; it ends at a zero or a bracket at most ``2 root_tolerance`` wide,
    returning its midpoint."""
    a, b = t, t + h
    fa, fb = ga, gb
    if fa == 0.0:
        return a
    if fb == 0.0:
        return b
    tol = root_tolerance(a, b)
    side = 0
    width = abs(b - a)
    for it in range(400):
        if abs(b - a) <= 2.0 * tol:
            break
        if it % 3 == 2:
            if abs(b - a) > 0.5 * width:
                c = a + 0.5 * (b - a)
            else:
                c = b - fb * (b - a) / (fb - fa)
            width = abs(b - a)
        else:
            c = b - fb * (b - a) / (fb - fa)
        lo, hi = min(a, b), max(a, b)
        if not (c > lo + tol):
            c = lo + tol
        if not (c < hi - tol):
            c = hi - tol
        fc = _event_at(kind, params, inertia, F, y, t, h, c, ys)
        if fc == 0.0:
            return c
        if (fc > 0.0) == (fb > 0.0):          # c takes b's place: a stays
            b, fb = c, fc
            if side == -1:
                fa *= 0.5
            side = -1
        else:                                 # c takes a's place: b stays
            a, fa = c, fc
            if side == 1:
                fb *= 0.5
            side = 1
    return a + 0.5 * (b - a)


@jit
def dop853_block(torques, inertia, inv_inertia, times, direction, t_bound, t_stop, rtol,
                 atol, tableau, carry, out, events, records, record_y, n_records):
    """Advance one body from the state in ``carry`` until the step that passes ``t_stop``
    (or the last output, or a terminal event), writing the outputs met on the way and
    the crossings of the events.

    The steps are those of one run from ``t = 0`` to ``t_bound`` whatever the blocks:
    ``carry`` holds the time, the next step size, the next output, the state and its
    derivative (the step's first stage) and the event values, so that a run in blocks
    gives the same bits as a run in one.

    Parameters
    ----------
    torques, inertia, inv_inertia, direction, rtol, atol, tableau
        As for :func:`dop853_one`.
    times : (T,) float64 array
        All the output times, ordered away from 0 (``direction * times`` non-decreasing).
    t_bound : float
        The end of the run (``times[-1]``): steps never pass it.
    t_stop : float
        The block's end: the kernel returns after the step that reaches it.
    carry : (CARRY + E,) float64 array
        Read and updated; ``carry[1] = 0`` on the first call (with ``y`` at
        ``carry[3:10]``, ``t = carry[0] = 0``, ``carry[2] = 0``).
    out : (T, 7) float64 array
        Receives the outputs.
    events : tuple
        ``(kinds (E,) int64, params (E, EVENT_PARAMS), direction (E,), terminal (E,))``;
        ``E = 0``: no events.
    records, record_y : (R, 2) and (R, 7) float64 arrays
        Receive each crossing's time and event index, and the state there.
    n_records : (1,) int64 array
        The number of records written (read and updated).

    Returns
    -------
    int
        :data:`DONE`, :data:`TERMINAL`, :data:`FULL` (fewer than ``E`` free records:
        call again after reading them), or ``-(j + 1)`` if the step fell below round-off
        before output ``j``.

    Examples
    --------
    >>> import numpy as np
    >>> from attitude.propagation import compiled_dop853 as cd
    >>> none = (np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros(0))
    >>> inertia = np.diag([1.0, 2.0, 3.0])
    >>> carry = np.zeros(cd.CARRY)
    >>> carry[3:10] = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.5]          # a spin about z
    >>> times, out = np.array([np.pi / 2, np.pi]), np.empty((2, 7))
    >>> no_events = (np.zeros(0, np.int64), np.zeros((0, 4)), np.zeros(0), np.zeros(0))
    >>> rec, rec_y, n_rec = np.empty((0, 2)), np.empty((0, 7)), np.zeros(1, np.int64)
    >>> from attitude.propagation.compiled_torques import user_torque
    >>> torques = (none, none, False, *user_torque(None))
    >>> args = (torques, inertia, np.linalg.inv(inertia), times, 1.0, np.pi)
    >>> tail = (1e-12, np.full(7, 1e-15), cd.TABLEAU, carry, out, no_events, rec, rec_y,
    ...         n_rec)
    >>> cd.dop853_block(*args, 1.0, *tail), bool(carry[0] >= 1.0)  # a block to t = 1 s
    (0, True)
    >>> cd.dop853_block(*args, np.pi, *tail), int(carry[2])  # the rest
    (0, 2)
    >>> np.round(out[1, :4], 12) + 0.0                           # a quarter turn
    array([0.      , 0.      , 0.707107, 0.707107])
    """
    A, C, B, E3, E5, D = tableau
    ev_kinds, ev_params, ev_direction, ev_terminal = events
    n_events = ev_kinds.shape[0]
    n = 7
    n_out = times.shape[0]
    K = np.empty((16, n))
    F = np.empty((7, n))
    y = carry[3:10].copy()
    y_new = np.empty(n)
    ys = np.empty(n)
    work = np.empty(9)
    scratch = np.empty((3, n))
    g = carry[CARRY:CARRY + n_events]
    g_new = np.empty(n_events)
    found_t = np.empty(n_events)
    t = carry[0]
    j = int(carry[2])
    h_abs = carry[1]
    if h_abs == 0.0:                          # the first call: t = 0
        while j < n_out and times[j] == 0.0:
            out[j, :] = y
            j += 1
        carry[2] = j
        if j == n_out:
            return DONE
        _rhs(torques, inertia, inv_inertia, 0.0, y, work, K[0])
        h_abs = _initial_step(torques, inertia, inv_inertia, y, K[0], direction, t_bound,
                              rtol, atol, work, scratch)
        for e in range(n_events):
            g[e] = _event_value(ev_kinds[e], ev_params[e], inertia, 0.0, y)
    else:
        K[0, :] = carry[10:17]
    status = DONE
    while j < n_out:
        if n_records[0] + n_events > records.shape[0]:
            status = FULL
            break
        min_step = 10.0 * abs(np.nextafter(t, direction * np.inf) - t)
        if h_abs < min_step:
            h_abs = min_step
        rejected = False
        while True:
            if h_abs < min_step:
                carry[2] = j
                return -(j + 1)
            t_new = t + h_abs * direction
            if direction * (t_new - t_bound) > 0.0:
                t_new = t_bound
            h = t_new - t
            h_abs = abs(h)
            for s in range(1, _N):
                _stage(torques, inertia, inv_inertia, A, C, K, s, t, y, h, work, ys)
            for i in range(n):
                acc = 0.0
                for s in range(_N):
                    acc += K[s, i] * B[s]
                y_new[i] = y[i] + h * acc
            _rhs(torques, inertia, inv_inertia, t + h, y_new, work, K[_N])
            # scipy's error norm: the 5th-order estimate, damped by the 3rd-order one
            e5 = 0.0
            e3 = 0.0
            for i in range(n):
                sc = atol[i] + max(abs(y[i]), abs(y_new[i])) * rtol
                a5 = 0.0
                a3 = 0.0
                for s in range(_N + 1):
                    a5 += K[s, i] * E5[s]
                    a3 += K[s, i] * E3[s]
                e5 += (a5 / sc) ** 2
                e3 += (a3 / sc) ** 2
            if e5 == 0.0 and e3 == 0.0:
                error = 0.0
            else:
                error = abs(h) * e5 / math.sqrt((e5 + 0.01 * e3) * n)
            if error < 1.0:
                if error == 0.0:
                    factor = _MAX_FACTOR
                else:
                    factor = min(_MAX_FACTOR, _SAFETY * error ** _EXPONENT)
                if rejected:
                    factor = min(1.0, factor)
                h_abs *= factor
                break
            h_abs *= max(_MIN_FACTOR, _SAFETY * error ** _EXPONENT)
            rejected = True
        dense = False
        t_end = t_new                          # outputs up to here (a terminal event: te)
        stop = False
        if n_events > 0:
            n_found = 0
            for e in range(n_events):
                g_new[e] = _event_value(ev_kinds[e], ev_params[e], inertia, t_new, y_new)
                found_t[e] = math.nan
                if _crossed(g[e], g_new[e], ev_direction[e]):
                    if not dense:
                        _dense(torques, inertia, inv_inertia, A, C, D, K, t, y, y_new, h,
                               work, ys, F)
                        dense = True
                    found_t[e] = _locate(ev_kinds[e], ev_params[e], inertia, F, y, t, h,
                                         g[e], g_new[e], ys)
                    n_found += 1
            # the crossings in time order, up to the first terminal one (scipy's rule)
            while n_found > 0:
                first = -1
                for e in range(n_events):
                    if not math.isnan(found_t[e]) and (
                            first < 0 or direction * (found_t[e] - found_t[first]) < 0.0):
                        first = e
                te = found_t[first]
                found_t[first] = math.nan
                n_found -= 1
                k = n_records[0]
                records[k, 0] = te
                records[k, 1] = first
                _interpolate(F, y, (te - t) / h, record_y[k])
                n_records[0] = k + 1
                if ev_terminal[first] != 0.0:
                    t_end = te
                    stop = True
                    break
            for e in range(n_events):
                g[e] = g_new[e]
        if j < n_out and direction * (times[j] - t_end) <= 0.0:
            if not dense:
                _dense(torques, inertia, inv_inertia, A, C, D, K, t, y, y_new, h, work, ys,
                       F)
                dense = True
            while j < n_out and direction * (times[j] - t_end) <= 0.0:
                _interpolate(F, y, (times[j] - t) / h, out[j])
                j += 1
        t = t_new
        y[:] = y_new
        K[0, :] = K[_N, :]
        if stop:
            status = TERMINAL
            break
        if direction * (t - t_stop) >= 0.0:
            break
    carry[0] = t
    carry[1] = h_abs
    carry[2] = j
    carry[3:10] = y
    carry[10:17] = K[0]
    return status


def dop853_one(torques, inertia, inv_inertia, y0, times, direction, rtol, atol, tableau,
               out):
    """Integrate one body from ``t = 0`` to the output times of one direction.

    Parameters
    ----------
    torques : tuple
        ``(external, internal, has_internal, callback, has_user)``, each of the first two
        a ``(kinds, offsets, params)`` triple of
        :class:`~attitude.propagation.compiled_torques.CompiledTorques`, the last two
        :func:`~attitude.propagation.compiled_torques.user_torque`'s.
    inertia, inv_inertia : (3, 3) float64 arrays
        Body-frame inertia tensor and its inverse.
    y0 : (7,) float64 array
        ``(q, omega)`` at ``t = 0``.
    times : (T,) float64 array
        Output times, all of one sign, ordered away from 0 (``direction * times``
        non-decreasing).
    direction : float
        +1 or -1.
    rtol : float
    atol : (7,) float64 array
    tableau : tuple
        :data:`TABLEAU`.
    out : (T, 7) float64 array
        Receives ``(q, omega)`` at ``times`` (q not normalised, as the integrator
        carries it).

    Returns
    -------
    int
        0, or ``-(j + 1)`` if the step fell below round-off before output ``j``.

    Examples
    --------
    >>> import numpy as np
    >>> from attitude.propagation.compiled_dop853 import TABLEAU, dop853_one
    >>> from attitude.propagation.compiled_torques import user_torque
    >>> none = (np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros(0))
    >>> inertia = np.diag([1.0, 2.0, 3.0])
    >>> y0 = np.array([0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.5])      # a spin about z
    >>> out = np.empty((1, 7))
    >>> torques = (none, none, False, *user_torque(None))       # no torque
    >>> dop853_one(torques, inertia, np.linalg.inv(inertia), y0,
    ...            np.array([np.pi]), 1.0, 1e-12, np.full(7, 1e-15), TABLEAU, out)
    0
    >>> np.round(out[0, :4], 12) + 0.0                           # a quarter turn
    array([0.      , 0.      , 0.707107, 0.707107])
    """
    carry = np.zeros(CARRY)
    carry[3:10] = y0
    n_out = times.shape[0]
    t_bound = times[n_out - 1] if n_out else 0.0
    code = dop853_block(torques, inertia, inv_inertia, times, direction, t_bound, t_bound,
                        rtol, atol, tableau, carry, out, NO_EVENTS, _NO_RECORDS[0],
                        _NO_RECORDS[1], np.zeros(1, np.int64))
    return int(code)


#: ``events`` of :func:`dop853_block` without events.
NO_EVENTS = (np.zeros(0, np.int64), np.zeros((0, 4)), np.zeros(0), np.zeros(0))
_NO_RECORDS = (np.zeros((0, 2)), np.zeros((0, 7)))

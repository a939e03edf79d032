"""Numerical propagation of Euler's equations with quaternion kinematics.

The reference propagator: scipy's ``solve_ivp`` (DOP853, tight tolerances) on

.. math::

    I \\dot\\omega = (I\\omega) \\times \\omega + M(t, q, \\omega), \\qquad
    \\dot q = \\tfrac12\\, q \\otimes (\\omega, 0)

with ``q`` the body -> inertial quaternion (scalar-last) and ``omega`` in body-frame
components.  It is the trusted baseline that faster methods are checked against.

A torque model is any callable ``torque(t, quaternion, omega_body, body)`` returning the
body-frame torque in N m; ``t`` is seconds since the epoch, ``quaternion`` the
body -> inertial quaternion (scalar-last).  A model with ``internal = True`` (a torque
between parts of the body, :class:`attitude.model.torques.EnergyDissipation`) turns ``L`` in
the body frame only: the attitude then turns at ``omega + (M x L)/L^2``, which keeps
the inertial ``L`` fixed.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
from scipy.integrate import solve_ivp

from ..foundations import quaternion as quat
from ..foundations.errors import InvalidStateError, PropagationError
from ..foundations.progress import Progress, duration_text
from ..model.body import RigidBody
from ..model.torques import internal_rate
from . import compiled_dop853
from .compiled import NUMBA, each_on_cores
from .compiled_torques import callback_model, compile_torques_shared, user_torque
from .events import compiled_events, evaluate

__all__ = ["integrate_reference", "integrate_reference_batch", "checked_rtol", "DEFAULT_RTOL",
           "DEFAULT_ATOL_SCALE"]

#: Relative tolerance of the reference integrator.
DEFAULT_RTOL = 1e-13
#: Absolute tolerance per component, as a fraction of the component's scale
#: (1 for quaternions, ``|omega0|`` for rates).
DEFAULT_ATOL_SCALE = 1e-15

Torque = Callable[[float, np.ndarray, np.ndarray, RigidBody], np.ndarray]


def _rhs(body: RigidBody, torques: Sequence[Torque]):
    inertia = body.inertia
    inverse = np.linalg.inv(inertia)
    external = [m for m in torques if getattr(m, "internal", False) is not True]
    internal = [m for m in torques if getattr(m, "internal", False) is True]

    def rhs(t, y):
        q, w = y[:4], y[4:]
        h = inertia @ w
        dw = np.cross(h, w)
        for torque in external:
            dw = dw + np.asarray(torque(t, q, w, body), dtype=float)
        rate = w
        if internal:
            # torques between parts of the body turn L in the body frame only: the frame
            # turns at w + (M x L)/L^2 so that the inertial L stays fixed
            m = sum(np.asarray(torque(t, q, w, body), dtype=float) for torque in internal)
            dw = dw + m
            rate = w + internal_rate(m, w, inertia)
        dw = inverse @ dw
        dq = 0.5 * quat.multiply(q, np.append(rate, 0.0))
        return np.concatenate([dq, dw])

    return rhs


def integrate_reference(body: RigidBody, quat0, omega0, t, *, torques: Sequence[Torque] = (),
                        rtol: float = DEFAULT_RTOL, atol_scale: float = DEFAULT_ATOL_SCALE,
                        method: str = "DOP853", compiled: bool | None = None,
                        progress: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Integrate one body from ``t = 0`` to every requested time.

    Parameters
    ----------
    body : RigidBody
    quat0 : (4,) array
        Body -> inertial quaternion at ``t = 0``, scalar-last.
    omega0 : (3,) array
        Body-frame angular velocity at ``t = 0``, rad/s.
    t : (T,) array
        Output times, seconds since the epoch, any order, may be negative.
    torques : sequence of callables, optional
        Body-frame torque models (see the module docstring).
    rtol, atol_scale : float
        Relative tolerance; absolute tolerance relative to each component's scale.
    method : str
        Any ``solve_ivp`` method (``"DOP853"``, ``"Radau"``, ...).
    compiled : bool, optional
        DOP853 compiled (:mod:`attitude.propagation.compiled_dop853`: scipy's method,
        step control and dense output, the built-in torque models evaluated by
        :func:`~attitude.propagation.compiled_torques.body_torque`): by default when numba
        is installed, ``method="DOP853"`` and every torque model has a compiled form;
        ``False`` runs scipy's ``solve_ivp`` (the independent check); ``True`` raises if
        the compiled path cannot run (without numba it runs as slow plain Python).
    progress : bool
        Report the progress on stderr (:mod:`attitude.foundations.progress`): the
        compiled path runs in blocks of simulated time then (the state and the step size
        carried from block to block: the same steps and results as in one block).

    Returns
    -------
    quaternion : (T, 4) array
        Body -> inertial, scalar-last, unit norm.
    omega : (T, 3) array
        Body-frame rates, rad/s.

    Examples
    --------
    >>> import numpy as np
    >>> from attitude import RigidBody
    >>> from attitude.propagation.reference import integrate_reference
    >>> body = RigidBody.from_principal_moments([1.0, 2.0, 3.0])
    >>> q, w = integrate_reference(body, [0, 0, 0, 1.0], [0.1, 0.2, 1.0], [0.0, 10.0])
    >>> L = body.principal_moments * w                         # body = principal frame
    >>> bool(abs(np.linalg.norm(L[1]) / np.linalg.norm(L[0]) - 1) < 1e-12)
    True
    """
    t = np.asarray(t, dtype=float)
    spec = _compiled_form(body, torques, t, method, compiled)
    with _progress(_simulated(t), progress) as bar:
        return _integrate(body, quat0, omega0, t, torques, rtol, atol_scale, method, spec,
                          bar)


def _simulated(t: np.ndarray) -> float:
    """Simulated seconds of one body's run: forward and backward from 0."""
    return float(max(0.0, np.max(t, initial=0.0)) - min(0.0, np.min(t, initial=0.0)))


def _progress(total: float, enabled: bool) -> Progress:
    """The report of a run (:mod:`attitude.foundations.progress`): simulated time."""
    return Progress(total, "propagation", unit="simulated", show=enabled,
                    amount=duration_text)


def checked_rtol(rtol) -> float:
    """A relative tolerance as a float, or InvalidStateError naming ``rtol`` unless it is
    a number in (0, 1) (the integrator and the splitting's error control).

    Examples
    --------
    >>> from attitude.propagation.reference import checked_rtol
    >>> checked_rtol(1e-8)
    1e-08
    >>> checked_rtol(0.0)
    Traceback (most recent call last):
    ...
    attitude.foundations.errors.InvalidStateError: rtol: expected a number in (0, 1), got 0.0
    """
    if not (isinstance(rtol, (int, float, np.floating)) and 0.0 < float(rtol) < 1.0):
        raise InvalidStateError(f"expected a number in (0, 1), got {rtol!r}",
                                key="rtol")
    return float(rtol)


def _check_rtol(rtol) -> float:
    """:func:`checked_rtol`, raised to 100 eps as scipy's solvers do (silently)."""
    return max(checked_rtol(rtol), 100.0 * np.finfo(float).eps)


def _compiled_form(body: RigidBody, torques, t: np.ndarray, method: str,
                   compiled: bool | None):
    """The torques of :func:`compiled_dop853.dop853_one` (``(external, internal,
    has_internal)``) when the compiled path is chosen and can run, else None."""
    forms = _compiled_forms([body], torques, t, method, compiled)
    return None if forms is None else forms[0]


def _compiled_forms(bodies, torques, t: np.ndarray, method: str, compiled: bool | None):
    """:func:`_compiled_form` for each body, all in one ``params`` array (a path or
    field laid out once for the batch), or None."""
    if compiled is False or (compiled is None and not NUMBA):
        return None
    if method != "DOP853":
        if compiled:
            raise InvalidStateError(f"compiled=True: only DOP853 is compiled, not "
                                    f"{method!r}", key="compiled")
        return None
    span = (float(min(0.0, np.min(t, initial=0.0))), float(max(0.0, np.max(t, initial=0.0))))
    # a user's torque with its own numba function (compiled_torques.user_torque), one
    # external one at most, runs by its callback; the others by their compiled forms
    user = callback_model(torques)
    rest = [m for m in torques if m is not user]
    groups = [[m for m in rest if (getattr(m, "internal", False) is True) == internal]
              for internal in (False, True)]
    shared = compile_torques_shared(groups, bodies, t_span=span)
    if shared is None:
        if compiled:
            raise InvalidStateError("compiled=True: a torque model has no compiled "
                                    "form (a Python function or model without a "
                                    "numba_torque, or more than one with it); use "
                                    "compiled=None", key="compiled")
        return None
    has_internal = any(getattr(m, "internal", False) is True for m in rest)
    callback = user_torque(user)
    return [tuple((c.kinds, c.offsets, c.params) for c in row) + (has_internal, *callback)
            for row in shared]


def _integrate(body, quat0, omega0, t, torques, rtol, atol_scale, method, spec, bar=None):
    rtol = _check_rtol(rtol)
    y0 = np.concatenate([np.asarray(quat0, float), np.asarray(omega0, float)])
    atol = _atol(omega0, atol_scale)
    rhs = _rhs(body, tuple(torques)) if spec is None else None
    out = np.empty((t.size, 7))
    for sign in (1.0, -1.0):
        idx = np.flatnonzero(t >= 0) if sign > 0 else np.flatnonzero(t < 0)
        if idx.size == 0:
            continue
        order = idx[np.argsort(sign * t[idx], kind="stable")]
        t_eval = t[order]
        end = t_eval[-1]
        if end == 0.0:
            out[order] = y0
            continue
        if spec is not None:
            res = np.empty((t_eval.size, 7))
            _run_compiled(body, spec, y0, t_eval, sign, rtol, atol, res, None, bar)
            out[order] = res
            continue
        # solve_ivp wants strictly ordered times: a repeated time is asked for once
        first = np.concatenate([[True], t_eval[1:] != t_eval[:-1]])
        sol = solve_ivp(rhs, (0.0, end), y0, method=method, t_eval=t_eval[first],
                        rtol=rtol, atol=atol)
        if not sol.success:
            reached = f"{sol.t[-1]:.6g} s" if sol.t.size else "the first step"
            raise PropagationError(f"{method} integration failed at {reached}: {sol.message}")
        out[order] = sol.y.T[np.cumsum(first) - 1]
        if bar is not None:
            bar.update(abs(float(end)))
    q = out[:, :4] / np.linalg.norm(out[:, :4], axis=1, keepdims=True)
    return q, out[:, 4:]


def _atol(omega0, atol_scale) -> np.ndarray:
    """Absolute tolerances: rates set that of the rate components; a body at rest (spun up
    by a torque) falls back to 1 rad/s, i.e. atol = atol_scale rad/s."""
    scale = float(np.linalg.norm(omega0)) or 1.0
    return atol_scale * np.array([1.0] * 4 + [scale] * 3)


#: Blocks of a compiled run whose progress is shown (the bar moves block by block; the
#: state and the step size carry over, so the result is the same as in one block).
PROGRESS_BLOCKS = 100
#: Records of event crossings read back per call of the compiled kernel (at least the
#: number of events).
_RECORDS = 256


def _run_compiled(body, spec, y0, t_eval, sign, rtol, atol, res, events, bar):
    """One direction of one body through :func:`compiled_dop853.dop853_block`, in
    :data:`PROGRESS_BLOCKS` blocks of simulated time when ``bar`` is shown (else one);
    ``events``: the kernel's event arrays (or None).  Returns the records
    ``[(t, event_index, y (7,)), ...]`` and whether a terminal event stopped the run."""
    inertia = np.ascontiguousarray(body.inertia, dtype=float)
    inverse = np.linalg.inv(inertia)
    ev = compiled_dop853.NO_EVENTS if events is None else events
    n_events = ev[0].size
    carry = np.zeros(compiled_dop853.CARRY + n_events)
    carry[3:10] = y0
    times = np.ascontiguousarray(t_eval, dtype=float)
    end = float(times[-1])
    size = max(_RECORDS, n_events) if n_events else 0
    records, record_y = np.empty((size, 2)), np.empty((size, 7))
    n_records = np.zeros(1, np.int64)
    blocks = PROGRESS_BLOCKS if bar is not None and bar.shown else 1
    found, done, stopped = [], 0.0, False
    for k in range(1, blocks + 1):
        t_stop = end if k == blocks else end * (k / blocks)
        while True:
            code = compiled_dop853.dop853_block(
                spec, inertia, inverse, times, sign, end, t_stop, float(rtol), atol,
                compiled_dop853.TABLEAU, carry, res, ev, records, record_y, n_records)
            if code < 0:
                raise PropagationError(
                    f"DOP853 integration failed before {times[-code - 1]:.6g} s: the "
                    "step size fell below the spacing of the floating-point times")
            found += [(float(records[i, 0]), int(records[i, 1]), record_y[i].copy())
                      for i in range(int(n_records[0]))]
            n_records[0] = 0
            if code != compiled_dop853.FULL:
                break
        stopped = code == compiled_dop853.TERMINAL
        if bar is not None:
            reached = abs(end) if stopped else min(abs(float(carry[0])), abs(end))
            bar.update(reached - done)
            done = reached
        if stopped or int(carry[2]) == times.size:
            break
    if bar is not None and done < abs(end):
        bar.update(abs(end) - done)
    return found, stopped


def integrate_reference_batch(bodies: Sequence[RigidBody], quat0, omega0, t, **kwargs
                              ) -> tuple[np.ndarray, np.ndarray]:
    """:func:`integrate_reference` for each of N bodies (each with its own adaptive
    steps; on the compiled path on a thread per core, else one after the other):
    ``quat0`` (N, 4), ``omega0`` (N, 3) -> ``(N, T, 4), (N, T, 3)``; ``kwargs`` as for
    :func:`integrate_reference`.

    Examples
    --------
    >>> import numpy as np
    >>> from attitude import RigidBody
    >>> from attitude.propagation.reference import integrate_reference_batch
    >>> bodies = [RigidBody.from_principal_moments(m) for m in ([1, 2, 3], [2, 2.5, 3])]
    >>> q, w = integrate_reference_batch(bodies, [[0, 0, 0, 1.0]] * 2, [[0.1, 0.2, 1.0]] * 2,
    ...                                  [0.0, 5.0, 10.0])
    >>> q.shape, w.shape
    ((2, 3, 4), (2, 3, 3))
    """
    t = np.asarray(t, dtype=float)
    options = {"torques": (), "rtol": DEFAULT_RTOL, "atol_scale": DEFAULT_ATOL_SCALE,
               "method": "DOP853", "compiled": None, "progress": False} | kwargs
    compiled = options.pop("compiled")
    show = options.pop("progress")
    specs = _compiled_forms(list(bodies), options["torques"], t, options["method"], compiled)
    with _progress(len(bodies) * _simulated(t), show) as bar:
        if specs is None:
            # a model without a compiled form: Python torques, one body after the other
            results = [_integrate(b, quat0[i], omega0[i], t, spec=None, bar=bar, **options)
                       for i, b in enumerate(bodies)]
        else:
            # the compiled integrator releases the GIL: the bodies run on all cores
            results = list(each_on_cores(
                lambda i: _integrate(bodies[i], quat0[i], omega0[i], t, spec=specs[i],
                                     bar=bar, **options), len(bodies)))
    return np.stack([r[0] for r in results]), np.stack([r[1] for r in results])


def integrate_reference_events(body: RigidBody, quat0, omega0, t, events, *,
                               torques: Sequence[Torque] = (), rtol: float = DEFAULT_RTOL,
                               atol_scale: float = DEFAULT_ATOL_SCALE,
                               method: str = "DOP853", compiled: bool | None = None,
                               progress: bool = False):
    """:func:`integrate_reference` forward in time with events
    (:mod:`attitude.propagation.events`).

    Compiled (:func:`compiled_dop853.dop853_block`) when the torques have compiled forms
    (as for :func:`integrate_reference`) and every event is a built-in one with a
    compiled form (:func:`attitude.propagation.events.nutation_crossing`): the event
    functions evaluated at each accepted step, a sign change located on the step's
    interpolant to :func:`compiled_dop853.root_tolerance`.  Else (``compiled=False``,
    no numba, a Python torque or a Python event) scipy's ``solve_ivp`` and its own event
    location on the dense output.  The two take the same steps and evaluate the same
    event formula.

    Returns ``(quaternion (T, 4), omega (T, 3), records)``, ``records`` a time-ordered
    list of ``(t_event, event_index, quaternion (4,), omega (3,))``; outputs after a
    terminal event are NaN.

    Examples
    --------
    >>> import numpy as np
    >>> from attitude import RigidBody
    >>> from attitude.propagation.events import nutation_crossing
    >>> from attitude.propagation.reference import integrate_reference_events
    >>> body = RigidBody.from_principal_moments([1.0, 1.2, 1.5])
    >>> wide = nutation_crossing(0.4, "A", terminal=True)
    >>> q, w, rec = integrate_reference_events(body, [0, 0, 0, 1.0], [0.5, 0.1, 0.1],
    ...                                        np.linspace(0.0, 40.0, 5), [wide])
    >>> [(round(te, 6), i) for te, i, _, _ in rec]
    [(2.010986, 0)]
    >>> bool(np.isnan(w[-1, 0]))                 # after the terminal event
    True
    """
    t = np.asarray(t, dtype=float)
    if np.any(t < 0):
        raise PropagationError("events need forward propagation: every time >= 0")
    y0 = np.concatenate([np.asarray(quat0, float), np.asarray(omega0, float)])
    atol = _atol(omega0, atol_scale)
    rtol = _check_rtol(rtol)
    out = np.full((t.size, 7), np.nan)
    order = np.argsort(t, kind="stable")
    end = float(t[order[-1]]) if t.size else 0.0
    if end == 0.0:
        out[:] = y0
        return out[:, :4], out[:, 4:], []
    spec = _compiled_form(body, torques, t, method, compiled)
    forms = None if spec is None else compiled_events(events, body,
                                                      compiled_dop853.EVENT_KINDS)
    if forms is None and compiled:
        raise InvalidStateError("compiled=True: an event has no compiled form (a Python "
                                "function); use compiled=None", key="compiled")
    with _progress(end, progress) as bar:
        if forms is not None:
            res = np.full((t.size, 7), np.nan)
            found, _ = _run_compiled(body, spec, y0, t[order], 1.0, rtol, atol, res, forms,
                                     bar)
            out[order] = res
            records = [(te, i, y[:4] / np.linalg.norm(y[:4]), y[4:].copy())
                       for te, i, y in found]
        else:
            out, records = _scipy_events(body, y0, t, order, end, events, torques, rtol,
                                         atol, method)
            bar.update(end)
    q = out[:, :4] / np.linalg.norm(out[:, :4], axis=1, keepdims=True)
    return q, out[:, 4:], records


def _scipy_events(body, y0, t, order, end, events, torques, rtol, atol, method):
    """scipy's ``solve_ivp`` with its event location: ``(out (T, 7), records)``."""
    rhs = _rhs(body, tuple(torques))

    def wrap(ev):
        def g(tt, y):
            return evaluate(ev, tt, y[:4] / np.linalg.norm(y[:4]), y[4:], body)

        g.terminal = bool(getattr(ev, "terminal", False))
        g.direction = float(getattr(ev, "direction", 0))
        return g

    out = np.full((t.size, 7), np.nan)
    sol = solve_ivp(rhs, (0.0, end), y0, method=method, t_eval=t[order], rtol=rtol,
                    atol=atol, events=[wrap(ev) for ev in events])
    if sol.status < 0:
        reached = f"{sol.t[-1]:.6g} s" if sol.t.size else "the first step"
        raise PropagationError(f"{method} integration failed at {reached}: {sol.message}")
    out[order[:sol.t.size]] = sol.y.T
    records = []
    for i, (te, ye) in enumerate(zip(sol.t_events, sol.y_events)):
        for tk, yk in zip(te, ye):
            records.append((float(tk), i, yk[:4] / np.linalg.norm(yk[:4]), yk[4:].copy()))
    records.sort(key=lambda r: r[0])
    return out, records

"""``propagate``: one entry point for every propagator.

Without torques the exact Euler–Poinsot solution is used
(:mod:`attitude.propagation.torquefree`); with torques the splitting integrator
(:mod:`attitude.propagation.splitting`: exact free flow and torque kicks, 4th order by
default) or the DOP853 integrator (:mod:`attitude.propagation.reference`), as chosen by
``method=`` or, without it, by :mod:`attitude.propagation.choice` (the cheaper for the
case at the default accuracy); populations run in chunks, locally or on dask
(:mod:`attitude.propagation.batch`).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from astropy import units as u
from astropy.time import Time

from ..foundations import quaternion as quat
from ..foundations.errors import InvalidStateError
from ..foundations.lazy import wing_method
from ..foundations.quantities import to_si
from ..model.body import RigidBody, as_bodies
from ..model.ephemeris import Ephemeris
from ..model.population import Ensemble, check_batch
from ..model.state import AttitudeState, stack_states
from .batch import propagate_ensemble
from .choice import choose_method
from .events import as_events, locate, name_of
from .reference import integrate_reference_batch, integrate_reference_events
from .splitting import choose_step, integrate_splitting, step_count
from .torquefree import exact_arrays

__all__ = ["propagate", "METHODS", "elapsed_seconds"]

#: ``method=`` values: the closed form (no torques), the splitting integrator (exact
#: free flow + torque kicks; the default with torques) or the DOP853 reference integrator.
METHODS = ("exact", "splitting", "integrator")


def elapsed_seconds(times, epoch: Time) -> np.ndarray:
    """Output times as float seconds since ``epoch``.

    ``times`` may be plain numbers (seconds), an astropy Quantity with a time unit, or an
    astropy ``Time`` array (converted to the epoch's scale; the difference is taken in
    two-double precision before rounding to float64).

    Examples
    --------
    >>> import astropy.units as u
    >>> from astropy.time import Time
    >>> epoch = Time("2024-01-01", scale="tdb")
    >>> elapsed_seconds([1.0, 2.0] * u.min, epoch)
    array([ 60., 120.])
    >>> elapsed_seconds(Time("2024-01-01T00:00:01.5", scale="tdb"), epoch)
    array([1.5])
    """
    if isinstance(times, Time):
        # difference taken in the epoch's scale: seconds of TDB, not of TT, for a TDB epoch
        t = (getattr(times, epoch.scale) - epoch).to_value(u.s)
    else:   # seconds, a time Quantity, "30 min", {value, unit}: the one quantity reader
        t = to_si(times, "s", key="times", finite=False, error=InvalidStateError)
    t = np.atleast_1d(np.asarray(t, dtype=float))
    if t.ndim != 1:
        raise InvalidStateError(f"times: expected a 1-D array, got shape {t.shape}")
    if not np.all(np.isfinite(t)):
        raise InvalidStateError("times: every time must be finite")
    return t


def _as_batch(body, state):
    """``(bodies (BodyBatch), epoch, frame, q0 (N, 4) body -> inertial, w0 (N, 3), batch)``
    from one body and state or from sequences of them (the batch normalisers of body
    and state)."""
    single = isinstance(body, RigidBody) and isinstance(state, AttitudeState)
    if not single and (isinstance(body, RigidBody) or isinstance(state, AttitudeState)):
        raise InvalidStateError("a batch needs a sequence of bodies and a sequence of states "
                                "of the same length")
    states = [state] if single else list(state)
    if not single and (not states or len(states) != len(body)):
        raise InvalidStateError(f"batch: got {len(body)} bodies and {len(states)} "
                                "states; give one state per body")
    bodies, _ = as_bodies([body] if single else body, moments=False)
    epoch, frame, q0, w0 = stack_states(states, len(bodies))
    return bodies, epoch, frame, q0, w0, not single


def propagate(body, state=None, times=None, *, torques: Sequence | None = None,
              method: str | None = None, rtol: float | None = None,
              step: float | u.Quantity | None = None, order: int | None = None,
              progress: bool = False, events=None, client=None,
              chunks: int | None = None) -> Ephemeris:
    """Propagate the rotation of one body, or of a batch of bodies, to ``times``.

    Parameters
    ----------
    body : RigidBody, sequence of RigidBody, :class:`attitude.Ensemble`, or
        :class:`attitude.BinarySystem`
        With an ensemble, ``state`` is omitted: ``propagate(ensemble, times)``.  A binary
        system (two bodies that torque each other) takes a :class:`attitude.BinaryState`
        and runs :func:`attitude.binary.propagate.propagate_binary`: ``method="lgvi"``
        (the default: the Lie-group variational integrator at ``step``) or
        ``"integrator"`` (DOP853 at ``rtol``), ``events`` a list of
        :class:`attitude.Impulse`; the ephemeris has both bodies and the mutual orbit.
    state : AttitudeState or sequence of AttitudeState (same length, same epoch and frame)
    times : array-like (s since the epoch), Quantity, or astropy Time array
    torques : sequence of torque models, optional
        Callables ``torque(t, quaternion, omega_body, body) -> (3,)`` body-frame N m
        (:mod:`attitude.model.torques`).
    method : {"exact", "splitting", "integrator"}, optional
        ``"exact"``: the closed-form torque-free solution.  ``"splitting"``: the exact
        free flow composed with torque kicks
        (:func:`attitude.propagation.splitting.integrate_splitting`; symplectic for
        attitude-only torques, a whole batch in one vectorised run).
        ``"integrator"``: DOP853 on Euler's equations (the reference; each body with
        its own steps; compiled with numba when every torque model is built in,
        :mod:`attitude.propagation.compiled_dop853`, the bodies of a batch on a thread
        per core; else scipy's ``solve_ivp``).  Default: ``"exact"`` without torques;
        with torques ``"integrator"`` if ``rtol`` is given, ``"splitting"`` if ``step``
        or ``order`` is, and with none of them the cheaper of the two compiled methods
        for the case, each set for the default accuracy, an attitude error of ~1e-8 rad
        over the run (:mod:`attitude.propagation.choice`: DOP853's ``rtol`` and the
        splitting's ``step`` from error models, the cheaper by a count of steps; without
        numba, with a torque of your own, or with an event of your own (a Python
        function), the splitting at its step rule).  The ephemeris attributes
        ``method`` and ``method_reason`` say which method ran and why.
    rtol : float, optional
        Relative tolerance: of the ``"integrator"`` method (default 1e-13), or, with
        ``method="splitting"``, the error control of the splitting (each step's
        estimated local error at most ``rtol`` relative to the unit quaternion and to
        ``|omega|``, like DOP853's; ``step`` is then the longest step).
    step : float (s) or time Quantity, optional
        Longest step of the ``"splitting"`` method; default
        :func:`attitude.propagation.splitting.choose_step` (a fixed fraction of the
        torques' time scales: libration, orbit, damping, and how fast each torque changes
        along the free motion; not the spin, which the exact free flow carries).  The
        output times do not set the steps: an output inside a step is a partial step of
        the same composition from the step's start.
    order : {2, 4, 6}, optional
        Order of the ``"splitting"`` method (default 4).
    progress : bool
        Progress on stderr for the ``"splitting"`` and ``"integrator"`` methods (off by
        default; :mod:`attitude.foundations.progress`).

    events : callable or sequence of callables, optional
        Events ``g(t, quaternion, omega_body, body) -> float`` with optional attributes
        ``terminal`` and ``direction`` like scipy's (:class:`attitude.propagation.events.Event`,
        :func:`attitude.propagation.events.nutation_crossing`).  Crossings are located to ~1e-12
        relative in time on the method's own solution (``"integrator"``: compiled, on
        DOP853's dense output, when every event is built in and numba is installed) and
        recorded in the ephemeris (``event_time``, ``event_name``, ``event_quaternion``,
        ``event_angular_velocity``; :func:`attitude.propagation.events.event_table`); a terminal
        event ends the ephemeris, its last sample being the event; in a batch each
        body stops at its own event (its later samples are NaN).  Times must be >= 0.

    client : dask.distributed.Client or str, optional
        Scale out on dask: the ``body`` dimension is split into chunks that run the
        same numpy kernel as tasks on the cluster: a ``Client``, a scheduler address
        such as ``"tcp://host:8786"`` for a real cluster, or ``"local"`` for a
        ``LocalCluster`` of this machine's cores kept for the session
        (:func:`attitude.ensemble.local_cluster` gives one with a ``with`` block).
        The ephemeris is then backed by dask arrays and computed when written or
        loaded, chunk by chunk.
    chunks : int, optional
        Bodies per chunk; alone (no ``client``) it gives a dask-backed ephemeris run by
        dask's current scheduler.  Default with ``client``: about a million epochs per
        chunk.  A single body (not a sequence) runs in this process: ``client`` and
        ``chunks`` are for batches.

    ``step`` and ``order`` are used only by ``"splitting"``, ``rtol`` by
    ``"integrator"`` and ``"splitting"``; the exact solution ignores them.  An ensemble, or a batch
    with ``client``/``chunks``, has a ``status`` variable per body (0 ok, 1 invalid
    input, 2 propagation failed; such bodies are NaN and do not stop the others).

    Returns
    -------
    Ephemeris
        Dims ``(time, ...)``, or ``(body, time, ...)`` for a batch.

    Examples
    --------
    >>> import numpy as np, astropy.units as u, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> body = att.RigidBody.from_principal_moments([0.61, 0.965, 1.0])
    >>> state = att.AttitudeState("2029-04-13", Rotation.identity(),
    ...                           [0.2, 0.0, 3.0] * u.deg / u.s)
    >>> eph = att.propagate(body, state, np.arange(0.0, 600.0, 60.0))
    >>> eph.conservation()["energy_rel_drift"] < 1e-13
    True
    """
    if getattr(body, "wing_propagator", None):   # a BinarySystem: the binary wing's own
        return wing_method(body.wing_propagator)(body, state, times, method=method, rtol=rtol,
                                                 step=step, events=events, progress=progress)
    if isinstance(body, Ensemble) and times is None:
        state, times = None, state
    if times is None:
        raise InvalidStateError("times: missing; propagate(body, state, times) or "
                                "propagate(ensemble, times)")
    ensemble = None
    if isinstance(body, Ensemble):
        if state is not None:
            raise InvalidStateError("an Ensemble carries its states: call "
                                    "propagate(ensemble, times)")
        ensemble = body
    elif (client is not None or chunks is not None) and not isinstance(body, RigidBody):
        ensemble = Ensemble.from_bodies(*check_batch(body, state))
    if ensemble is not None:
        return _propagate_ensemble(ensemble, times, torques=torques, method=method,
                                   rtol=rtol, step=step, order=order, progress=progress,
                                   events=events, client=client, chunks=chunks)
    bodies, epoch, frame, q0, w0, batch = _as_batch(body, state)
    t = elapsed_seconds(times, epoch)
    torques = list(torques or [])
    method, reason = _choose_method(method, torques, rtol, step, order)
    events = as_events(events)
    if method == "auto" and any(getattr(e, "compiled_form", None) is None for e in events):
        # an event in Python: DOP853 would run it in scipy (not compiled): the splitting
        method, reason = "splitting", ("events given: the splitting at its step rule "
                                       "(DOP853's events run in scipy, not compiled, "
                                       "with an event in Python)")
    elif method == "auto":
        # built-in events run on either compiled method: the cheaper, as without events
        choice = choose_method(bodies, q0, w0, t, torques)
        method, reason, rtol, step = choice.method, choice.reason, choice.rtol, choice.step
    if step is not None:
        step = _step_seconds(step)

    records = None
    if events:
        if np.any(t < 0):
            raise InvalidStateError("events: propagation with events is forward only; "
                                    "give times >= 0")
        t, q, w, records = _with_events(method, bodies, q0, w0, t, events, torques, step,
                                        order, rtol, progress)
    elif method == "exact":
        q, w = _exact(bodies, q0, w0, t)
    elif method == "splitting":
        q, w = integrate_splitting(bodies, q0, w0, t, torques=torques, step=step,
                                   order=4 if order is None else order, progress=progress,
                                   rtol=rtol)
    else:
        kwargs = {} if rtol is None else {"rtol": rtol}
        q, w = integrate_reference_batch(bodies, q0, w0, t, torques=torques,
                                         progress=progress, **kwargs)
    if not batch:
        q, w, bodies = q[0], w[0], bodies[0]
    name = bodies.name if isinstance(bodies, RigidBody) else "batch"
    eph = Ephemeris.from_arrays(
        t, q, w, body=bodies, epoch=epoch, frame=frame,
        title=f"attitude ephemeris{': ' + name if name else ''}",
        source=f"attitude.propagate, method={method}{_DESCRIPTION[method]}")
    if records is not None:
        eph = _record_events(eph, records, events, batch)
    return _with_method(eph, method, reason)


def _with_method(eph: Ephemeris, method: str, reason: str) -> Ephemeris:
    """The ephemeris with the attributes ``method`` (the one that ran) and
    ``method_reason`` (why)."""
    ds = eph.dataset.copy()
    ds.attrs["method"] = method
    ds.attrs["method_reason"] = reason
    return Ephemeris(ds)


def _choose_method(method, torques, rtol, step, order) -> tuple[str, str]:
    """``(method, reason)``; ``"auto"`` when torques come without ``method``, ``rtol``,
    ``step`` or ``order`` (:func:`attitude.propagation.choice.choose_method` then
    decides)."""
    if method is None:
        if rtol is not None and (step is not None or order is not None):
            raise InvalidStateError("rtol= belongs to method='integrator', step= and "
                                    "order= to method='splitting': give one of them, or "
                                    "choose the method")
        if not torques:
            return "exact", "no torques: the closed-form torque-free solution"
        if rtol is not None:
            return "integrator", "rtol= given without method=: DOP853"
        if step is not None or order is not None:
            return "splitting", "step= or order= given without method=: the splitting"
        return "auto", ""
    if method not in METHODS:
        raise InvalidStateError(f"method {method!r} is unknown; choose one of {METHODS}")
    if method == "exact" and torques:
        raise InvalidStateError("method='exact' is the torque-free solution; use "
                                "method='splitting' or method='integrator' with torques")
    return method, f"method={method!r} given"


def _propagate_ensemble(ensemble, times, *, torques, method, rtol, step, order, progress,
                        events, client, chunks) -> Ephemeris:
    if events:
        raise InvalidStateError("events: not available for an ensemble or with client=/"
                                "chunks=; propagate the bodies of interest one by one")
    t = elapsed_seconds(times, ensemble.epoch)
    torques = list(torques or [])
    method, reason = _choose_method(method, torques, rtol, step, order)
    if method == "auto":
        valid = np.flatnonzero(ensemble.valid)
        if valid.size == 0:
            method, reason = "splitting", "no valid body: the splitting (nothing to run)"
        else:
            # the choice on at most _CHOICE_SAMPLE bodies spread over the ensemble
            pick = valid[np.unique(np.linspace(0, valid.size - 1,
                                               min(valid.size, _CHOICE_SAMPLE)).astype(int))]
            choice = choose_method([ensemble.body_at(int(i)) for i in pick],
                                   ensemble.quaternion[pick], ensemble.omega_body[pick],
                                   t, torques)
            method, reason, rtol, step = (choice.method, choice.reason, choice.rtol,
                                          choice.step)
    options = {}
    if method == "splitting":
        options = {"step": None if step is None else _step_seconds(step),
                   "order": 4 if order is None else order,
                   "progress": progress and client is None and chunks is None,
                   "rtol": rtol}
    elif method == "integrator" and rtol is not None:
        options = {"rtol": rtol}
    eph = propagate_ensemble(ensemble, t, method=method, torques=torques, options=options,
                             client=client, chunks=chunks,
                             source=f"attitude.propagate, method={method}"
                                    f"{_DESCRIPTION[method]}")
    return _with_method(eph, method, reason)


#: Bodies of an ensemble on which the automatic method is chosen.
_CHOICE_SAMPLE = 4096


def _record_events(eph: Ephemeris, records: list, events: list, batch: bool) -> Ephemeris:
    """Event variables along an ``event`` dimension (absent when nothing happened)."""
    rows = [(rec, b) for b, recs in enumerate(records) for rec in recs]
    ds = eph.dataset.copy()
    ds.attrs["event_count"] = len(rows)
    ds.attrs["event_names"] = ", ".join(name_of(ev) for ev in events)
    if rows:
        ds["event_time"] = ("event", np.array([r[0] for r, _ in rows]), {
            "long_name": "time of the event", "units": "s",
            "comment": "seconds since the epoch global attribute"})
        ds["event_name"] = ("event", np.array([name_of(events[r[1]]) for r, _ in rows]),
                            {"long_name": "name of the event"})
        ds["event_quaternion"] = (("event", "quaternion_component"), quat.canonical(
            np.stack([r[2] for r, _ in rows])), {
            "long_name": "attitude quaternion at the event", "units": "1"})
        ds["event_angular_velocity"] = (("event", "axis"), np.stack([r[3] for r, _ in rows]),
                                        {"long_name": "body-frame angular velocity at "
                                                      "the event", "units": "rad s-1"})
        if batch:
            ds["event_body"] = ("event", np.array([b for _, b in rows]), {
                "long_name": "body index of the event", "units": "1"})
    return Ephemeris(ds)


def _grid(t: np.ndarray, h: float) -> np.ndarray:
    """0, the output times and equal steps no longer than ``h`` between them."""
    knots = np.unique(np.concatenate([[0.0], t]))
    parts = [knots[:1]]
    for a, b in zip(knots[:-1], knots[1:]):
        n = step_count(b - a, h)
        parts.append(np.linspace(a, b, n + 1)[1:])
    return np.concatenate(parts)


def _scan_step(bodies: list[RigidBody], w0: np.ndarray) -> float:
    """Scan step of the closed form: 1/64 of the fastest body-frame turning period of
    omega (``|omega| C / A``)."""
    rates = [float(np.linalg.norm(w)) * b.principal_moments[2] / b.principal_moments[0]
             for b, w in zip(bodies, w0)]
    rate = max(rates)
    return 2.0 * np.pi / (64.0 * rate) if rate > 0 else np.inf


def _with_events(method, bodies, q0, w0, t, events, torques, step, order, rtol, progress):
    """Propagate with events: ``(t, q (N, T, 4), w (N, T, 3), records per body)``."""
    if method == "integrator":
        kwargs = {} if rtol is None else {"rtol": rtol}
        results = [integrate_reference_events(b, q0[i], w0[i], t, events, torques=torques,
                                              progress=progress, **kwargs)
                   for i, b in enumerate(bodies)]
        q = np.stack([r[0] for r in results])
        w = np.stack([r[1] for r in results])
        records = [r[2] for r in results]
    else:
        if method == "exact":
            grid = _grid(t, _scan_step(bodies, w0))
            qg, wg = _exact(bodies, q0, w0, grid)

            def state_at(i, k, x):
                if x == grid[k]:
                    return qg[i, k], wg[i, k]
                qx, wx = _exact([bodies[i]], q0[i:i + 1], w0[i:i + 1], np.array([x]))
                return qx[0, 0], wx[0, 0]
        else:
            if rtol is not None:
                raise InvalidStateError("events with method='splitting' run on a fixed step "
                                        "grid: give step= (or nothing), not rtol=",
                                        key="rtol")
            order = 4 if order is None else order
            h = step if step is not None else choose_step(bodies, q0, w0, torques,
                                                          order=order)
            if not np.isfinite(h):
                h = _scan_step(bodies, w0)
            grid = _grid(t, h)
            hs = h * (1.0 + 1e-9)
            return _splitting_events(bodies, q0, w0, t, grid, events, torques, hs, order,
                                     progress)
        idx = np.searchsorted(grid, t)
        q, w = qg[:, idx], wg[:, idx]
        records = [locate(events, grid, qg[i], wg[i], b,
                          lambda k, x, i=i: state_at(i, k, x))
                   for i, b in enumerate(bodies)]
    return _truncate(t, q, w, records, events)


#: Steps per chunk of the splitting method with events (a terminal event stops after the
#: chunk that holds it).
_EVENT_CHUNK = 4096


def _splitting_events(bodies, q0, w0, t, grid, events, torques, hs, order, progress):
    """Splitting with events: the step grid in chunks, crossings located on each chunk
    by ``brentq`` over a partial step from the step's start."""
    n, m = len(bodies), grid.size
    qg, wg = np.full((n, m, 4), np.nan), np.full((n, m, 3), np.nan)
    qg[:, 0], wg[:, 0] = q0, w0
    records = [[] for _ in bodies]
    stopped = [False] * n
    start = 0
    while start < m - 1:
        end = min(start + _EVENT_CHUNK, m - 1)
        seg = grid[start:end + 1]
        qs, ws = integrate_splitting(bodies, qg[:, start], wg[:, start], seg[1:],
                                     torques=torques, step=hs, order=order,
                                     progress=progress, t0=seg[0], dense=False)
        qg[:, start + 1:end + 1], wg[:, start + 1:end + 1] = qs, ws

        def state_at(i, k, x, seg=seg, start=start):
            if x == seg[k]:
                return qg[i, start + k], wg[i, start + k]
            qx, wx = integrate_splitting(bodies[i], qg[i, start + k], wg[i, start + k], [x],
                                         torques=torques, step=hs, order=order, t0=seg[k])
            return qx[0], wx[0]

        for i, b in enumerate(bodies):
            if not stopped[i]:
                records[i].extend(locate(events, seg, qg[i, start:end + 1],
                                         wg[i, start:end + 1], b,
                                         lambda k, x, i=i: state_at(i, k, x)))
                stopped[i] = bool(records[i]) and getattr(events[records[i][-1][1]],
                                                          "terminal", False)
        start = end
        if all(stopped):
            break
    idx = np.searchsorted(grid, t)
    return _truncate(t, qg[:, idx], wg[:, idx], records, events)


def _truncate(t, q, w, records, events):
    """Stop each body at its terminal event.  A single body's outputs are cut there (the
    event is the last sample); in a batch, whose bodies share the output times, the
    samples of a body after its terminal event are NaN (its state at the event is in the
    event variables)."""
    def stop(recs):
        return recs[-1][0] if recs and getattr(events[recs[-1][1]], "terminal",
                                               False) else None

    if len(records) == 1 and stop(records[0]) is not None:
        te, _, qe, we = records[0][-1]
        keep = t < te
        t = np.append(t[keep], te)
        q = np.concatenate([q[:, keep], qe[None, None]], axis=1)
        w = np.concatenate([w[:, keep], we[None, None]], axis=1)
    elif len(records) > 1:
        for i, recs in enumerate(records):
            te = stop(recs)
            if te is not None:
                q[i, t > te] = np.nan
                w[i, t > te] = np.nan
    return t, q, w, records


_DESCRIPTION = {
    "exact": " (closed-form Euler-Poinsot solution)",
    "splitting": " (splitting integrator: exact free flow and torque kicks)",
    "integrator": " (DOP853 reference integrator)",
}


def _step_seconds(step) -> float:
    """``step=`` as float seconds (a number, a time Quantity or a string such as
    ``"10 s"``)."""
    return to_si(step, "s", key="step", shape=(), positive=True, error=InvalidStateError)


def _exact(bodies, q0: np.ndarray, w0: np.ndarray, t: np.ndarray):
    """Torque-free closed form, in principal frames, mapped back to body frames."""
    batch, _ = as_bodies(bodies, moments=False)
    return exact_arrays(batch.principal_moments, batch.body_to_principal, q0, w0, t)

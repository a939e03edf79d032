"""Events for :func:`attitude.propagate`: locate (and optionally stop at) the zero
crossings of a scalar function of the state.

An event is a callable ``g(t, quaternion, omega_body, body) -> float`` (``t`` in s since
the epoch, ``quaternion`` body -> inertial scalar-last, ``omega_body`` in rad/s) with
scipy-like attributes ``terminal`` (stop the propagation at the first crossing) and
``direction`` (``+1``: only crossings where ``g`` goes from negative to positive,
``-1``: positive to negative, ``0``: both).  :class:`Event` wraps a plain function;
:func:`nutation_crossing` is ready-made.

Crossings are bracketed between consecutive internal samples (the integrator steps of
``"integrator"`` and ``"splitting"``; a scan grid of the closed form for ``"exact"``)
and located by root finding on the method's own solution (DOP853 dense output,
a partial splitting step, the closed form), to ~1e-12 relative in time.  Two crossings
of one event inside one internal step are not seen.

The propagated ephemeris records every event in the variables ``event_time`` (s since
the epoch), ``event_name``, ``event_quaternion``, ``event_angular_velocity`` (and
``event_body`` for a batch) along an ``event`` dimension; the global attribute
``event_count`` is always set when ``events=`` is given.  :func:`event_table` reads them
back as a list of ``(time_s, name)`` (or ``(time_s, name, body)``).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from scipy.optimize import brentq

from ..foundations.errors import InvalidStateError, PropagationError
from ..foundations.quantities import to_si

__all__ = ["Event", "nutation_crossing", "nutation_angle", "event_table"]


class Event:
    """A propagation event: ``function(t, quaternion, omega_body, body) -> float``.

    Parameters
    ----------
    function : callable
    terminal : bool
        Stop the propagation at the first crossing (default True).
    direction : {-1, 0, 1}
        Crossing direction that counts (default 0: both).
    name : str, optional
        Label recorded in the ephemeris (default: the function's name).
    vectorized : bool
        ``function`` accepts arrays ``t (M,)``, ``quaternion (M, 4)``, ``omega (M, 3)``
        and returns ``(M,)`` (faster event scans).

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> body = att.RigidBody.from_principal_moments([0.61, 0.965, 1.0])
    >>> state = att.AttitudeState("2029-04-13", Rotation.identity(), [0.02, 0.0, 0.1])
    >>> from attitude.propagation.events import Event
    >>> quarter = Event(lambda t, q, w, b: t - 250.0, terminal=True, name="quarter")
    >>> eph = att.propagate(body, state, np.linspace(0.0, 1000.0, 11), events=quarter)
    >>> float(eph.dataset["time"].values[-1])
    250.0
    """

    def __init__(self, function: Callable, terminal: bool = True, direction: int = 0, *,
                 name: str | None = None, vectorized: bool = False):
        if not callable(function):
            raise InvalidStateError(f"Event: expected a callable g(t, quaternion, "
                                    f"omega_body, body), got {type(function).__name__}")
        self.function = function
        self.terminal = terminal
        self.direction = direction
        self.name = name or getattr(function, "__name__", "event")
        self.vectorized = vectorized
        _check(self, "Event")

    def __call__(self, t, quaternion, omega_body, body):
        return self.function(t, quaternion, omega_body, body)

    def __repr__(self) -> str:
        return (f"Event({self.name!r}, terminal={self.terminal}, "
                f"direction={self.direction})")


_AXES = {"A": 0, "B": 1, "C": 2, 0: 0, 1: 1, 2: 2}


def nutation_crossing(angle, axis="C", *, terminal: bool = True, direction: int = 0
                      ) -> Event:
    """Event: the angle between the angular momentum ``L`` and a principal axis of the
    body crosses ``angle``.

    ``g = atan2(|L x a|, L . a) - angle`` with ``L = I omega`` and ``a`` the principal
    axis (``"A"``, ``"B"``, ``"C"``: smallest to largest moment, or 0, 1, 2), both in
    body axes (the angle is that of the inertial ``L = R I omega`` and ``R a``).

    Parameters
    ----------
    angle : float (rad) or angle Quantity, in [0, pi]
    axis : {"A", "B", "C", 0, 1, 2}
    terminal, direction : see :class:`Event`

    Examples
    --------
    >>> import numpy as np
    >>> from attitude.propagation.events import nutation_crossing
    >>> ev = nutation_crossing(np.radians(10.0), "C", terminal=False)
    >>> ev.terminal, ev.direction
    (False, 0)
    """
    value = to_si(angle, "rad", key="angle", shape=(), bounds=(0.0, math.pi),
                  error=InvalidStateError)
    key = axis.upper() if isinstance(axis, str) else axis
    if isinstance(key, bool) or not isinstance(key, (str, int)) or key not in _AXES:
        raise InvalidStateError(f"nutation_crossing: axis {axis!r} is not one of 'A', "
                                "'B', 'C', 0, 1, 2")
    k = _AXES[key]
    cache: list = [None, None, None]           # body, its inertia, its principal axis k

    def nutation(t, quaternion, omega_body, body):
        if cache[0] is not body:
            cache[:] = [body, body.inertia, _principal_axis(body, k)]
        _, inertia, a = cache
        w = np.asarray(omega_body, dtype=float)
        return nutation_angle(inertia, a, w[..., 0], w[..., 1], w[..., 2]) - value

    event = Event(nutation, terminal=terminal, direction=direction,
                  name=f"nutation_{'ABC'[k]}_{value:.9g}", vectorized=True)
    # the compiled DOP853 evaluates the same formula (compiled_dop853.EVENT_KINDS)
    event.compiled_form = lambda body: ("nutation", (value, *_principal_axis(body, k)))
    return event


def _principal_axis(body, k: int) -> np.ndarray:
    """Principal axis ``k`` in body axes: row ``k`` of the body -> principal matrix."""
    return np.ascontiguousarray(body.body_to_principal.as_matrix()[k], dtype=float)


def nutation_angle(inertia, axis, w0, w1, w2):
    """The angle between the angular momentum ``L = I omega`` and a body axis:
    ``atan2(|L x a|, L . a)``, on floats or on arrays of rates alike (one formula for
    the Python event of :func:`nutation_crossing` and for the compiled DOP853's).

    Parameters
    ----------
    inertia : (3, 3) array
        Body-frame inertia tensor.
    axis : (3,) array
        Unit axis ``a`` in body axes.
    w0, w1, w2 : float or arrays
        Body-frame rates, rad/s.

    Returns
    -------
    float or array
        The angle, rad, in ``[0, pi]``.

    Examples
    --------
    >>> import numpy as np
    >>> from attitude.propagation.events import nutation_angle
    >>> inertia, c = np.diag([1.0, 2.0, 3.0]), np.array([0.0, 0.0, 1.0])
    >>> round(float(np.degrees(nutation_angle(inertia, c, 0.0, 1.5, 1.0))), 9)
    45.0
    """
    L0 = inertia[0, 0] * w0 + inertia[0, 1] * w1 + inertia[0, 2] * w2
    L1 = inertia[1, 0] * w0 + inertia[1, 1] * w1 + inertia[1, 2] * w2
    L2 = inertia[2, 0] * w0 + inertia[2, 1] * w1 + inertia[2, 2] * w2
    c0 = L1 * axis[2] - L2 * axis[1]
    c1 = L2 * axis[0] - L0 * axis[2]
    c2 = L0 * axis[1] - L1 * axis[0]
    return np.arctan2(np.sqrt(c0 * c0 + c1 * c1 + c2 * c2),
                      L0 * axis[0] + L1 * axis[1] + L2 * axis[2])


def event_table(ephemeris) -> list[tuple]:
    """The events recorded in an ephemeris: ``[(time_s, name), ...]`` in time order,
    or ``(time_s, name, body_index)`` for a batch.

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> body = att.RigidBody.from_principal_moments([0.61, 0.965, 1.0])
    >>> state = att.AttitudeState("2029-04-13", Rotation.identity(), [0.02, 0.0, 0.1])
    >>> from attitude.propagation.events import Event, event_table
    >>> half = Event(lambda t, q, w, b: t - 500.0, terminal=False, name="half")
    >>> event_table(att.propagate(body, state, [0.0, 1000.0], events=half))
    [(500.0, 'half')]
    """
    ds = ephemeris.dataset if hasattr(ephemeris, "dataset") else ephemeris
    if "event_time" not in ds.variables:
        return []
    names = [v.decode() if isinstance(v, bytes) else str(v) for v in ds["event_name"].values]
    times = [float(x) for x in ds["event_time"].values]
    if "event_body" in ds.variables:
        return [(t, n, int(b)) for t, n, b in zip(times, names, ds["event_body"].values)]
    return list(zip(times, names))


# ---------------------------------------------------------------------------
# internals shared by the propagators
# ---------------------------------------------------------------------------
def _check(event, where: str) -> None:
    if not callable(event):
        raise InvalidStateError(f"{where}: expected a callable g(t, quaternion, "
                                f"omega_body, body) or an attitude.propagation.events.Event, got "
                                f"{type(event).__name__}")
    direction = getattr(event, "direction", 0)
    if direction not in (-1, 0, 1):
        raise InvalidStateError(f"{where}: direction must be -1, 0 or 1, got {direction!r}")
    terminal = getattr(event, "terminal", False)
    if not isinstance(terminal, (bool, np.bool_)):
        raise InvalidStateError(f"{where}: terminal must be True or False, got "
                                f"{terminal!r}")


def as_events(events) -> list:
    """Validate ``events=``: one callable or a sequence of them (plain functions are
    non-terminal, both directions, like scipy)."""
    if events is None:
        return []
    if callable(events):
        events = [events]
    try:
        events = list(events)
    except TypeError:
        raise InvalidStateError(f"events: expected a callable or a sequence of callables, "
                                f"got {type(events).__name__}") from None
    for i, ev in enumerate(events):
        _check(ev, f"events[{i}]")
    return events


def name_of(event) -> str:
    return str(getattr(event, "name", None) or getattr(event, "__name__", "event"))


def evaluate(event, t, q, w, body) -> float:
    """One scalar value of an event function, checked."""
    try:
        value = np.asarray(event(t, q, w, body), dtype=float)
    except (TypeError, ValueError) as exc:
        raise PropagationError(f"event {name_of(event)!r} failed at t = {t:.9g} s: "
                               f"{exc}") from exc
    if value.size != 1 or not np.isfinite(value).all():
        raise PropagationError(f"event {name_of(event)!r} returned {value!r} at "
                               f"t = {t:.9g} s; expected one finite float")
    return float(value.reshape(()))


def evaluate_grid(event, t, q, w, body) -> np.ndarray:
    """Event values on samples ``t (M,)``, ``q (M, 4)``, ``w (M, 3)``."""
    if getattr(event, "vectorized", False):
        values = np.asarray(event(t, q, w, body), dtype=float)
        if values.shape != t.shape or not np.all(np.isfinite(values)):
            raise PropagationError(f"vectorized event {name_of(event)!r} returned shape "
                                   f"{values.shape} (or non-finite values); expected "
                                   f"{t.shape}")
        return values
    return np.array([evaluate(event, float(t[k]), q[k], w[k], body) for k in range(t.size)])


def locate(events, tg, qg, wg, body, state_at) -> list[tuple]:
    """Crossings of ``events`` on one body's samples ``tg`` (increasing), refined by
    ``brentq`` on ``state_at(k, t) -> (q, w)`` (the state at ``t`` in
    ``[tg[k], tg[k+1]]``).  Returns ``[(t, index, q, w), ...]`` sorted by time, cut
    after the first terminal crossing."""
    found = []
    for i, ev in enumerate(events):
        g = evaluate_grid(ev, tg, qg, wg, body)
        direction = getattr(ev, "direction", 0)
        up = (g[:-1] < 0) & (g[1:] >= 0)
        down = (g[:-1] > 0) & (g[1:] <= 0)
        mask = up if direction > 0 else down if direction < 0 else up | down
        for k in np.flatnonzero(mask):
            a, b = float(tg[k]), float(tg[k + 1])
            if g[k + 1] == 0.0:
                te = b
            else:
                def f(x, k=k, ev=ev):
                    return evaluate(ev, x, *state_at(k, x), body)

                te = brentq(f, a, b, xtol=1e-14 * max(abs(b), 1.0), rtol=1e-15,
                            maxiter=200)
            q, w = state_at(k, te)
            found.append((te, i, np.asarray(q, float), np.asarray(w, float)))
            if getattr(ev, "terminal", False):
                break
    found.sort(key=lambda r: r[0])
    out = []
    for rec in found:
        out.append(rec)
        if getattr(events[rec[1]], "terminal", False):
            break
    return out


def compiled_events(events, body, kinds: dict):
    """The ``events`` of :func:`attitude.propagation.compiled_dop853.dop853_block` for
    one body, ``(kinds (E,), params (E, P), direction (E,), terminal (E,))``, or None when
    an event has no compiled form (a Python function: scipy's path runs it).  ``kinds``
    maps a form's name to its code (``compiled_dop853.EVENT_KINDS``)."""
    forms = [getattr(ev, "compiled_form", None) for ev in events]
    if not events or any(f is None for f in forms):
        return None
    rows = [f(body) for f in forms]
    width = max(len(p) for _, p in rows)
    params = np.zeros((len(rows), width))
    for i, (_, p) in enumerate(rows):
        params[i, :len(p)] = p
    return (np.array([kinds[name] for name, _ in rows], dtype=np.int64), params,
            np.array([float(getattr(ev, "direction", 0)) for ev in events]),
            np.array([float(bool(getattr(ev, "terminal", False))) for ev in events]))

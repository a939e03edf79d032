"""Propagate a binary system: both attitudes and the mutual orbit, into one ephemeris.

:func:`propagate_binary` is what ``att.propagate(system, state, times, ...)`` runs for a
:class:`~attitude.binary.system.BinarySystem`.  The ephemeris has a ``body`` dimension
of two (``primary``, ``secondary``) holding each body's quaternion and angular velocity
like any batch ephemeris, plus ``relative_position`` and ``relative_velocity``
``(time, axis)`` (the secondary relative to the primary, inertial frame), and
``total_energy`` and ``total_angular_momentum`` of the system (conserved between
impulses: their drift is the integrator's error).
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from attitude.binary.dynamics import energy_momentum, integrate_dop853, pack, unpack
from attitude.binary.lgvi import default_step, impulse_change, integrate_lgvi, integrate_lgvi_batch
from attitude.binary.system import BODIES, BinaryState, BinarySystem, Impulse
from attitude.foundations import quaternion as quat
from attitude.foundations.errors import BinarySystemError
from attitude.foundations.quantities import to_si
from attitude.model.ephemeris import Ephemeris
from attitude.propagation.propagator import elapsed_seconds

__all__ = ["propagate_binary", "propagate_family", "METHODS", "apply_impulse", "initial_vector"]

#: Methods of :func:`propagate_binary` (the first is the default).
METHODS = ("lgvi", "integrator")


def initial_vector(state: BinaryState) -> np.ndarray:
    """The state vector ``(20,)`` of a :class:`BinaryState` (:mod:`attitude.binary.dynamics`).

    Examples
    --------
    >>> import attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> s = att.BinaryState("2026-12-01", [1190.0, 0, 0], [0, 0.17, 0], Rotation.identity(),
    ...                     [0, 0, 7.7e-4], Rotation.identity(), [0, 0, 1.46e-4])
    >>> initial_vector(s)[[0, 4, 12, 19]].tolist()
    [1190.0, 0.17, 0.00077, 0.000146]
    """
    q1, q2 = state.quaternions
    return pack(state.position, state.velocity, q1, state.primary_omega, q2,
                state.secondary_omega)


def apply_impulse(system: BinarySystem, y: np.ndarray, impulse: Impulse) -> np.ndarray:
    """The state vector just after ``impulse``: the relative velocity changed by the
    body's ``delta_v`` (minus it for the primary), the body's angular momentum by its
    ``angular_impulse`` (inertial frame).

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> ball = att.RigidBody.from_mass_properties(att.MassProperties.solid_sphere(1e9, 50.0))
    >>> system = att.BinarySystem(ball, ball)
    >>> y = pack([500.0, 0, 0], [0, 0.01, 0], [0, 0, 0, 1.0], [0, 0, 0], [0, 0, 0, 1.0],
    ...          [0, 0, 0])
    >>> kick = att.Impulse(0.0, body="primary", delta_v=[0, 0.001, 0])
    >>> unpack(apply_impulse(system, y, kick))[1].tolist()
    [0.0, 0.009, 0.0]
    """
    y = np.array(y, dtype=float)
    R, V, q1, w1, q2, w2 = unpack(y)
    dV, b, angular_impulse = impulse_change(impulse)     # the LGVI's kick, the same change
    V += dV
    q, w, body = (q2, w2, system.secondary) if b else (q1, w1, system.primary)
    if np.any(angular_impulse):
        dH_body = quat.rotate(q, angular_impulse, inverse=True)
        w += np.linalg.solve(body.inertia, dH_body)
    return y


def propagate_binary(system: BinarySystem, state: BinaryState, times, *,
                     method: str | None = None, rtol: float | None = None, step=None,
                     events=None, progress: bool = False) -> Ephemeris:
    """Propagate a binary system from ``state`` to ``times`` (s since the epoch, >= 0).

    Parameters
    ----------
    system : BinarySystem
    state : BinaryState
    times : array-like (s since ``state.epoch``), Quantity, or astropy Time array
    method : {"lgvi", "integrator"}, optional
        ``"lgvi"`` (the default; ``"integrator"`` when only ``rtol`` is given): the
        Lie-group variational integrator (:mod:`attitude.binary.lgvi`) at fixed steps,
        second order, total angular momentum kept to round-off, energy error bounded
        (``O(h^2)``, no drift).  ``"integrator"``: DOP853 at ``rtol`` (default 1e-12).
    rtol : float, optional
        Of ``"integrator"`` only.
    step : float (s), time Quantity or str (``"30 s"``), optional
        Longest step of ``"lgvi"``; default 1/200 of the shortest of the osculating
        orbit period and both spin periods (:func:`attitude.binary.lgvi.default_step`).
        Between consecutive output and impulse times the steps are equal and no longer
        than ``step`` (an output or impulse time inside a step shortens the steps of its
        interval).  Not used by ``"integrator"``.
    events : sequence of :class:`~attitude.binary.system.Impulse`, optional
        Impulses applied at their times (the ephemeris holds the state just after an
        impulse at a sample time).
    progress : bool
        Not used yet.

    Returns
    -------
    Ephemeris
        Dims ``(body, time)`` with ``body = ["primary", "secondary"]``, plus
        ``relative_position``, ``relative_velocity``, ``total_energy``,
        ``total_angular_momentum``.

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> ellipsoid = att.MassProperties.solid_ellipsoid
    >>> system = att.BinarySystem(
    ...     att.RigidBody.from_mass_properties(ellipsoid(5.2e11, [425.0, 410.0, 390.0])),
    ...     att.RigidBody.from_mass_properties(ellipsoid(4.3e9, [103.16, 79.35, 66.13])))
    >>> n = np.sqrt(system.mu / 1190.0**3)
    >>> state = att.BinaryState("2022-09-26", [1190.0, 0, 0], [0, n * 1190.0, 0],
    ...                         Rotation.identity(), [0, 0, 2 * np.pi / 8136.0],
    ...                         Rotation.identity(), [0, 0, n])
    >>> eph = att.propagate(system, state, np.linspace(0.0, 86400.0, 25))
    >>> eph.dataset.quaternion.dims, eph.dataset.body.values.tolist()
    (('body', 'time', 'quaternion_component'), ['primary', 'secondary'])
    >>> L = eph.dataset.total_angular_momentum.values
    >>> bool(np.abs(L - L[0]).max() < 1e-9 * np.linalg.norm(L[0]))
    True
    """
    method, t, impulses, y0 = _prepared(system, state, times, method, rtol, step, events)
    if method == "lgvi":
        h = _step_seconds(step) if step is not None else default_step(system, y0)
        y = integrate_lgvi(system, y0, t, h, impulses)
        return binary_ephemeris(system, state, t, y, method=method, step=h)
    y = _integrate(system, y0, t, impulses, rtol)
    return binary_ephemeris(system, state, t, y, method=method)


def propagate_family(systems, states, times, *, step, events=None) -> list[Ephemeris]:
    """Propagate many binaries of one family (one mutual-potential order and ``G``) with
    the LGVI at a common ``step``, all at once (:func:`attitude.binary.lgvi.
    integrate_lgvi_batch`): the ephemeris of each, as :func:`propagate_binary` gives it,
    except that each member's steps also end at the other members' impulse times.

    Parameters
    ----------
    systems, states : sequences of BinarySystem and BinaryState (same length)
    times : array-like
        s since each state's epoch, sorted, >= 0.
    step : float (s), Quantity or str
    events : sequence of sequences of Impulse, optional
        Each member's impulses.

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> ball = att.RigidBody.from_mass_properties(att.MassProperties.solid_sphere(5e11, 400.0))
    >>> eggs = [att.RigidBody.from_mass_properties(
    ...     att.MassProperties.solid_ellipsoid(4.3e9, [a, 80.0, 66.0])) for a in (95.0, 110.0)]
    >>> systems = [att.BinarySystem(ball, egg) for egg in eggs]
    >>> n = np.sqrt(systems[0].mu / 1190.0**3)
    >>> state = att.BinaryState("2026-12-01", [1190.0, 0, 0], [0, n * 1190.0, 0],
    ...                         Rotation.identity(), [0, 0, 7.7e-4], Rotation.identity(),
    ...                         [0, 0, n])
    >>> ephs = propagate_family(systems, [state, state], np.linspace(0.0, 3600.0, 7),
    ...                         step=30.0)
    >>> len(ephs), ephs[1].dataset.attrs["method"]
    (2, 'lgvi')
    """
    systems, states = list(systems), list(states)
    if len(systems) != len(states) or not systems:
        raise BinarySystemError("systems, states: expected two sequences of one length")
    events = [None] * len(systems) if events is None else list(events)
    if len(events) != len(systems):
        raise BinarySystemError("events: one sequence of impulses per member")
    prepared = [_prepared(sy, st, times, "lgvi", None, step, ev)
                for sy, st, ev in zip(systems, states, events)]
    t = prepared[0][1]
    if any(not np.array_equal(p[1], t) for p in prepared):
        raise BinarySystemError("times: the members of a family share their times")
    h = _step_seconds(step)
    y = integrate_lgvi_batch(systems, np.array([p[3] for p in prepared]), t, h,
                             [p[2] for p in prepared])
    return [binary_ephemeris(sy, st, t, yy, method="lgvi", step=h)
            for sy, st, yy in zip(systems, states, y)]


def _prepared(system, state, times, method, rtol, step, events) -> tuple:
    """The checked inputs of one run: ``(method, t, impulses, y0)``."""
    if not isinstance(system, BinarySystem):
        raise BinarySystemError(f"system: expected a BinarySystem, got {type(system).__name__}")
    if not isinstance(state, BinaryState):
        raise BinarySystemError(f"state: a BinarySystem propagates a BinaryState, got "
                                f"{type(state).__name__}")
    if method is None:
        method = "integrator" if rtol is not None and step is None else METHODS[0]
    if method not in METHODS:
        raise BinarySystemError(f"method: expected one of {', '.join(METHODS)} for a binary "
                                f"system, got {method!r}")
    if method == "lgvi" and rtol is not None:
        raise BinarySystemError("rtol: method='lgvi' runs at a fixed step; give step= "
                                "(or method='integrator' with rtol=)")
    t = np.atleast_1d(np.asarray(elapsed_seconds(times, state.epoch), dtype=float))
    if t.ndim != 1 or not np.all(np.isfinite(t)) or np.any(t < 0) or np.any(np.diff(t) < 0):
        raise BinarySystemError("times: a binary propagates forward: give sorted times >= 0 "
                                "s after the state's epoch")
    impulses = sorted(_impulses(events, state.epoch), key=lambda e: e[0])
    for s, _ in impulses:
        if s < 0:
            raise BinarySystemError("events: an impulse before the state's epoch; the "
                                    "propagation runs forward")
    return method, t, impulses, initial_vector(state)


def _step_seconds(step) -> float:
    """The LGVI's longest step in seconds (float s, time Quantity or ``"30 s"``)."""
    h = to_si(step, "s", key="step", shape=(), positive=True, error=BinarySystemError)
    return float(h)


def _impulses(events, epoch) -> list[tuple[float, Impulse]]:
    out = []
    for e in [] if events is None else list(events):
        if not isinstance(e, Impulse):
            raise BinarySystemError(f"events: expected att.Impulse for a binary, got "
                                    f"{type(e).__name__}")
        out.append((e.seconds_after(epoch), e))
    return out


def _integrate(system, y0, t, impulses, rtol) -> np.ndarray:
    """DOP853 from impulse to impulse; a sample at an impulse's time is taken after it."""
    kwargs = {} if rtol is None else {"rtol": float(rtol)}
    out = np.empty((t.size, 20))
    start, y = 0.0, y0
    for stop, impulse in impulses + [(np.inf, None)]:
        sel = (t >= start) & (t < stop)
        if impulse is None:
            out[sel] = integrate_dop853(system, y, t[sel] - start, **kwargs)
            break
        ys = integrate_dop853(system, y, np.concatenate([t[sel] - start, [stop - start]]),
                              **kwargs)
        out[sel] = ys[:-1]
        y, start = apply_impulse(system, ys[-1], impulse), stop
    return out


def binary_ephemeris(system: BinarySystem, state: BinaryState, t: np.ndarray, y: np.ndarray,
                     *, method: str, step: float | None = None) -> Ephemeris:
    """The ephemeris of a binary from its state vectors ``(T, 20)`` at times ``t``
    (``step``: the LGVI's longest step, s, kept as the attribute ``step``).

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> ball = att.RigidBody.from_mass_properties(att.MassProperties.solid_sphere(1e9, 50.0))
    >>> s = att.BinaryState("2026-12-01", [500.0, 0, 0], [0, 0.01, 0], Rotation.identity(),
    ...                     [0, 0, 0], Rotation.identity(), [0, 0, 0])
    >>> system = att.BinarySystem(ball, ball)
    >>> eph = binary_ephemeris(system, s, np.array([0.0]), initial_vector(s)[None],
    ...                        method="integrator")
    >>> eph.dataset.relative_position.values.tolist()
    [[500.0, 0.0, 0.0]]
    """
    R, V, q1, w1, q2, w2 = unpack(y)
    q = np.stack([q1, q2])
    w = np.stack([w1, w2])
    bodies = [system.primary, system.secondary]
    E, L = energy_momentum(system, y)
    eph = Ephemeris.from_arrays(
        t, q, w, body=bodies, epoch=state.epoch, frame=state.frame,
        title="attitude ephemeris: binary system",
        source=f"attitude.propagate, binary system, method={method}",
        extra_attrs={"system": "binary", "method": method, "mutual_potential_order":
                     system.order, "gravitational_constant": system.G,
                     "masses": system.masses, **({} if step is None else {"step": step})})
    ds = eph.dataset.assign_coords(body=("body", list(BODIES), {"long_name": "body"}))
    ds["relative_position"] = (("time", "axis"), R, {
        "long_name": "secondary's centre of mass relative to the primary's, inertial frame",
        "units": "m"})
    ds["relative_velocity"] = (("time", "axis"), V, {
        "long_name": "secondary's velocity relative to the primary, inertial frame",
        "units": "m s-1"})
    ds["total_energy"] = (("time",), E, {
        "long_name": "orbital and rotational kinetic energy plus the mutual potential",
        "units": "J"})
    ds["total_angular_momentum"] = (("time", "axis"), L, {
        "long_name": "total angular momentum about the system's centre of mass, inertial "
                     "frame", "units": "kg m2 s-1"})
    return Ephemeris(ds)


def is_binary_dataset(ds: xr.Dataset) -> bool:
    """Whether an ephemeris dataset holds a binary system (what
    :func:`binary_ephemeris` writes: the attribute ``system = "binary"`` and the
    ``relative_position``); the one test of the wing and of the pictures' binary page.

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> body = att.RigidBody.from_principal_moments([1.0, 2.0, 3.0])
    >>> state = att.AttitudeState("2030-01-01", Rotation.identity(), [0, 0, 0.1])
    >>> is_binary_dataset(att.propagate(body, state, [0.0, 1.0]).dataset)
    False
    """
    return ds.attrs.get("system") == "binary" and "relative_position" in ds

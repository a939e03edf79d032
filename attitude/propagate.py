"""``propagate``: one entry point for every propagator.

Without torques the exact Euler–Poinsot solution is used (:mod:`attitude.torquefree`);
with torques the splitting integrator (:mod:`attitude.splitting`: exact free flow and
torque kicks, 4th order by default), or, with ``method="integrator"`` (or an ``rtol``),
the DOP853 reference integrator (:mod:`attitude.integrate`).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from astropy import units as u
from astropy.time import Time

from . import _quat
from .body import RigidBody
from .ephemeris import Ephemeris
from .errors import InvalidStateError
from .integrate import integrate_reference
from .state import AttitudeState

__all__ = ["propagate", "METHODS", "elapsed_seconds"]

#: ``method=`` values: the closed form (no torques), the splitting integrator (exact
#: free flow + torque kicks; the default with torques) or the DOP853 reference integrator.
METHODS = ("exact", "splitting", "integrator")


def elapsed_seconds(times, epoch: Time) -> np.ndarray:
    """Output times as float seconds since ``epoch``.

    ``times`` may be plain numbers (seconds), an astropy Quantity with a time unit, or an
    astropy ``Time`` array (converted to the epoch's scale; the difference is taken in
    two-double precision before rounding to float64).
    """
    if isinstance(times, Time):
        # difference taken in the epoch's scale: seconds of TDB, not of TT, for a TDB epoch
        t = (getattr(times, epoch.scale) - epoch).to_value(u.s)
    elif isinstance(times, u.Quantity):
        try:
            t = times.to_value(u.s)
        except u.UnitConversionError:
            raise InvalidStateError(
                f"times: unit '{times.unit}' is not a time unit; give seconds, a time "
                "Quantity or an astropy Time array") from None
    else:
        try:
            t = np.asarray(times, dtype=float)
        except (TypeError, ValueError):
            raise InvalidStateError(
                f"times: expected seconds since the epoch, a Quantity or a Time array, got "
                f"{type(times).__name__}") from None
    t = np.atleast_1d(np.asarray(t, dtype=float))
    if t.ndim != 1:
        raise InvalidStateError(f"times: expected a 1-D array, got shape {t.shape}")
    if not np.all(np.isfinite(t)):
        raise InvalidStateError("times: every time must be finite")
    return t


def _as_batch(body, state) -> tuple[list[RigidBody], list[AttitudeState], bool]:
    if isinstance(body, RigidBody) and isinstance(state, AttitudeState):
        return [body], [state], False
    if isinstance(body, RigidBody) or isinstance(state, AttitudeState):
        raise InvalidStateError("a batch needs a sequence of bodies and a sequence of states "
                                "of the same length")
    bodies, states = list(body), list(state)
    if len(bodies) != len(states) or not bodies:
        raise InvalidStateError(f"batch: got {len(bodies)} bodies and {len(states)} states; "
                                "give one state per body")
    for i, (b, s) in enumerate(zip(bodies, states)):
        if not isinstance(b, RigidBody):
            raise InvalidStateError(f"bodies[{i}]: expected a RigidBody, got {type(b).__name__}")
        if not isinstance(s, AttitudeState):
            raise InvalidStateError(
                f"states[{i}]: expected an AttitudeState, got {type(s).__name__}")
        if s.frame != states[0].frame:
            raise InvalidStateError(f"states[{i}].frame = {s.frame} differs from "
                                    f"states[0].frame = {states[0].frame}")
        if abs((s.epoch - states[0].epoch).to_value(u.s)) > 0:
            raise InvalidStateError(f"states[{i}].epoch differs from states[0].epoch; "
                                    "a batch shares one epoch")
    return bodies, states, True


def propagate(body: RigidBody | Sequence[RigidBody], state: AttitudeState |
              Sequence[AttitudeState], times, *, torques: Sequence | None = None,
              method: str | None = None, rtol: float | None = None,
              step: float | u.Quantity | None = None, order: int | None = None,
              progress: bool = False) -> Ephemeris:
    """Propagate the rotation of one body, or of a batch of bodies, to ``times``.

    Parameters
    ----------
    body : RigidBody or sequence of RigidBody
    state : AttitudeState or sequence of AttitudeState (same length, same epoch and frame)
    times : array-like (s since the epoch), Quantity, or astropy Time array
    torques : sequence of torque models, optional
        Callables ``torque(t, quaternion, omega_body, body) -> (3,)`` body-frame N m
        (:mod:`attitude.torques`).
    method : {"exact", "splitting", "integrator"}, optional
        ``"exact"``: the closed-form torque-free solution.  ``"splitting"``: the exact
        free flow composed with torque kicks (:func:`attitude.splitting.integrate_splitting`;
        symplectic for attitude-only torques, a whole batch in one vectorised run).
        ``"integrator"``: DOP853 on Euler's equations (the reference; one body at a
        time).  Default: ``"exact"`` without torques; with torques ``"splitting"``,
        or ``"integrator"`` if ``rtol`` is given.
    rtol : float, optional
        Relative tolerance of the ``"integrator"`` method (default 1e-13).
    step : float (s) or time Quantity, optional
        Longest step of the ``"splitting"`` method; default
        :func:`attitude.splitting.choose_step` (a fixed fraction of the fastest time
        scale: spin, libration, orbit, damping).  Output times are always hit exactly.
    order : {2, 4, 6}, optional
        Order of the ``"splitting"`` method (default 4).
    progress : bool
        Progress bar for the ``"splitting"`` method (off by default).

    ``step``, ``order`` and ``progress`` are used only by ``"splitting"``, ``rtol``
    only by ``"integrator"``; the exact solution ignores them.

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
    bodies, states, batch = _as_batch(body, state)
    t = elapsed_seconds(times, states[0].epoch)
    torques = list(torques or [])
    if method is None:
        if rtol is not None and (step is not None or order is not None):
            raise InvalidStateError("rtol= belongs to method='integrator', step= and "
                                    "order= to method='splitting': give one of them, or "
                                    "choose the method")
        if not torques:
            method = "exact"
        else:
            method = "integrator" if rtol is not None else "splitting"
    if method not in METHODS:
        raise InvalidStateError(f"method {method!r} is unknown; choose one of {METHODS}")
    if method == "exact" and torques:
        raise InvalidStateError("method='exact' is the torque-free solution; use "
                                "method='splitting' or method='integrator' with torques")
    if step is not None:
        step = _step_seconds(step)

    q0 = np.stack([s.attitude.as_quat() for s in states])             # body -> inertial
    w0 = np.stack([s.omega_body for s in states])
    if method == "exact":
        q, w = _exact(bodies, q0, w0, t)
    elif method == "splitting":
        from .splitting import integrate_splitting

        q, w = integrate_splitting(bodies, q0, w0, t, torques=torques, step=step,
                                   order=4 if order is None else order, progress=progress)
    else:
        kwargs = {} if rtol is None else {"rtol": rtol}
        results = [integrate_reference(b, q0[i], w0[i], t, torques=torques, **kwargs)
                   for i, b in enumerate(bodies)]
        q = np.stack([r[0] for r in results])
        w = np.stack([r[1] for r in results])
    if not batch:
        q, w, bodies = q[0], w[0], bodies[0]
    name = bodies.name if isinstance(bodies, RigidBody) else "batch"
    return Ephemeris.from_arrays(
        t, q, w, body=bodies, epoch=states[0].epoch, frame=states[0].frame,
        title=f"attitude ephemeris{': ' + name if name else ''}",
        source=f"attitude.propagate, method={method}{_DESCRIPTION[method]}")


_DESCRIPTION = {
    "exact": " (closed-form Euler-Poinsot solution)",
    "splitting": " (splitting integrator: exact free flow and torque kicks)",
    "integrator": " (DOP853 reference integrator)",
}


def _step_seconds(step) -> float:
    """``step=`` as float seconds (a number or a time Quantity)."""
    if isinstance(step, u.Quantity):
        try:
            step = step.to_value(u.s)
        except u.UnitConversionError:
            raise InvalidStateError(f"step: unit '{step.unit}' is not a time unit") from None
    try:
        value = float(step)
    except (TypeError, ValueError):
        raise InvalidStateError(f"step: expected seconds or a time Quantity, got "
                                f"{step!r}") from None
    if not (value > 0 and np.isfinite(value)):
        raise InvalidStateError(f"step: expected a positive, finite step, got {step!r}")
    return value


def _exact(bodies: list[RigidBody], q0: np.ndarray, w0: np.ndarray, t: np.ndarray):
    """Torque-free closed form, in principal frames, mapped back to body frames."""
    from .torquefree import free_rotation

    q_bp = np.stack([b.body_to_principal.as_quat() for b in bodies])  # body -> principal
    q_pb = _quat.conjugate(q_bp)
    moments = np.stack([b.principal_moments for b in bodies])
    w0p = _quat.rotate(q_bp, w0)
    q0p = _quat.multiply(q0, q_pb)                                      # principal -> inertial
    qp, wp = free_rotation(moments, w0p, q0p, t)                        # (N, T, 4), (N, T, 3)
    q = _quat.multiply(qp, q_bp[:, None, :])
    w = _quat.rotate(q_pb[:, None, :], wp)
    return q, w

"""Perturbation torques: the hook and the built-in models.

The protocol
------------
A torque model is any callable

.. code-block:: python

    torque(t, quaternion, omega_body, body) -> (..., 3) ndarray   # body frame, N m

with

``t``
    seconds since the epoch (float, or an array for a vectorised call);
``quaternion``
    the attitude, body -> inertial, scalar-last ``(x, y, z, w)``, shape ``(..., 4)``
    (the built-in models also take a scipy ``Rotation`` stack and tolerate a
    quaternion that is not exactly unit: integrators pass their raw stage values);
``omega_body``
    body-frame angular velocity, rad/s, shape ``(..., 3)``;
``body``
    the :class:`~attitude.model.body.RigidBody` (the built-in models also take a sequence
    of bodies, one per leading element, or an inertia array ``(..., 3, 3)``).

Leading axes broadcast: a scalar ``t`` with a ``(4,)`` quaternion gives ``(3,)``; arrays
``(n,)``, ``(n, 4)``, ``(n, 3)`` give ``(n, 3)``.  The integrators add the returned torque
to Euler's equations ``I dω/dt = (I ω) x ω + M``.

A plain Python function with this signature is a valid model.  Models derived from
:class:`TorqueModel` add with ``+`` (``GravityGradient(...) + EnergyDissipation(...)``
is a :class:`SumTorque`); :func:`as_torque_model` wraps a plain function so that it can
take part in a sum.  Each model says whether it depends on the angular velocity
(:attr:`TorqueModel.velocity_dependent`): splitting integrators may treat
velocity-independent (conservative) torques as pure kicks; whether it is internal
(:attr:`TorqueModel.internal`: exerted by one part of the body on another, so that the
integrators keep the inertial angular momentum fixed); its own time scale
(:meth:`TorqueModel.characteristic_rate`, from which the splitting integrator builds its
default step) and how to move its time origin (:meth:`TorqueModel.shifted`, for runs
restarted mid-way).  The integrators and the Lyapunov test use nothing else, so a
user's subclass is treated like the built-in models.

Built-in models
---------------
============================  ========================================================
:class:`GravityGradient`      point-mass primary, ``3 mu / r^5 (r x I r)``
:class:`ConstantTorque`       fixed torque in body or inertial axes
:class:`EnergyDissipation`    internal energy sink (damper, inelastic asteroid): keeps
                              the inertial ``L``, bleeds kinetic energy toward ``L^2 / 2C``
                              in a time constant (:func:`damping_timescale` for asteroids)
:class:`EddyCurrentDamping`   ``(M (ω x B)) x B`` in a uniform or tilted-dipole field
:class:`MagneticDipole`       a body-fixed (residual) magnetic moment: ``m x B``
:class:`HeavyTopPivot`        uniform gravity about a fixed pivot (the heavy top)
============================  ========================================================

:func:`from_config` builds any of them from a scenario ``[[torques]]`` table.
"""

from __future__ import annotations

import dataclasses
import difflib
import math
import warnings
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

import erfa
import numpy as np
from astropy import units as u
from scipy.spatial.transform import Rotation

from ..foundations import quaternion as quat
from ..foundations.errors import OrbitError, TorqueConfigError
from ..foundations.quantities import to_si
from ..foundations.spec import SYNONYMS, Key, Table, json_schema, validate
from .body import SYMMETRY_RTOL, RigidBody
from .orbit import KeplerOrbit, as_path

__all__ = [
    "TorqueModel",
    "SumTorque",
    "FunctionTorque",
    "as_torque_model",
    "GravityGradient",
    "ConstantTorque",
    "EnergyDissipation",
    "internal_rate",
    "damping_timescale",
    "EddyCurrentDamping",
    "MagneticDipole",
    "HeavyTopPivot",
    "UniformField",
    "TiltedDipoleField",
    "from_config",
    "TORQUE_TYPES",
    "BuildContext",
    "register_torque_type",
    "EARTH_MU",
    "EARTH_DIPOLE_MOMENT",
    "EARTH_DIPOLE_TILT",
    "EARTH_DIPOLE_POLE_LONGITUDE",
    "EARTH_ROTATION_RATE",
    "STANDARD_GRAVITY",
]

#: Gravitational parameter of the Earth (EGM2008 / WGS 84), m^3/s^2.
EARTH_MU = 3.986004418e14
#: Magnitude of the Earth's dipole moment, A m^2 (``B0 = 1e-7 m / R^3 = 3.07e-5 T`` at
#: the equator for R = 6371.2 km; Wertz's 3.12e-5 T corresponds to 8.1e22 A m^2).
EARTH_DIPOLE_MOMENT = 7.94e22
#: Angle between the dipole axis and the rotation axis (IGRF-13, epoch 2020: 9.4 deg), rad.
EARTH_DIPOLE_TILT = np.radians(9.4)
#: East longitude of the northern geomagnetic pole (IGRF-13, 2020: 72.7 deg W), rad.
EARTH_DIPOLE_POLE_LONGITUDE = np.radians(-72.7)
#: Sidereal rotation rate of the Earth (IERS), rad/s.
EARTH_ROTATION_RATE = 7.292115e-5
#: Standard acceleration of gravity, m/s^2.
STANDARD_GRAVITY = 9.80665
_MU0_OVER_4PI = 1e-7  # T m / A



# --- small numpy kernels (integrators call models once per stage: keep overhead low) ----




def _dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    if a.ndim == 1 and b.ndim == 1:
        return np.dot(a, b)
    return np.sum(a * b, axis=-1)


def _unit_quaternion(quaternion) -> np.ndarray:
    if isinstance(quaternion, Rotation):
        return quaternion.as_quat()
    q = np.asarray(quaternion, dtype=float)
    if q.shape[-1:] != (4,):
        raise ValueError(f"quaternion: expected shape (..., 4) scalar-last, got {q.shape}")
    if q.ndim == 1:
        return q / np.sqrt(np.dot(q, q))
    return q / np.sqrt(np.sum(q * q, axis=-1, keepdims=True))


def _inertia_of(body) -> np.ndarray:
    """Inertia ``(3, 3)`` of a body, or ``(n, 3, 3)`` of a sequence of bodies."""
    if isinstance(body, RigidBody):
        return body.inertia
    if isinstance(body, np.ndarray):
        if body.shape[-2:] != (3, 3):
            raise ValueError(f"body: expected an inertia array (..., 3, 3), got {body.shape}")
        return body
    if hasattr(body, "inertia"):
        return np.asarray(body.inertia, dtype=float)
    if isinstance(body, Sequence) and len(body) > 0:
        return np.stack([_inertia_of(b) for b in body])
    raise TypeError(f"body: expected a RigidBody, a sequence of them or an inertia array, "
                    f"got {type(body).__name__}")


def _moments_of(body) -> np.ndarray:
    """Sorted principal moments, ``(3,)`` or ``(n, 3)``."""
    if isinstance(body, RigidBody):
        return body.principal_moments
    if isinstance(body, np.ndarray) or hasattr(body, "inertia"):
        return np.linalg.eigvalsh(_inertia_of(body))
    return np.stack([_moments_of(b) for b in body])


def _mass_of(body) -> np.ndarray | float | None:
    if isinstance(body, RigidBody) or hasattr(body, "mass"):
        return body.mass
    if isinstance(body, Sequence) and not isinstance(body, np.ndarray):
        masses = [_mass_of(b) for b in body]
        return None if any(m is None for m in masses) else np.asarray(masses, dtype=float)
    return None


def _matvec(inertia: np.ndarray, v: np.ndarray) -> np.ndarray:
    if inertia.ndim == 2:
        return v @ inertia.T
    return np.einsum("...ij,...j->...i", inertia, v)


def _orbit_rate(path) -> float:
    """Largest angular rate of the body's position about the primary, rad/s (at
    periapsis for a Keplerian orbit, at ``t = 0`` for a path with a velocity, else 0)."""
    if isinstance(path, KeplerOrbit):
        e = path.e
        return path.mean_motion * (1.0 + e) ** 2 / (1.0 - e * e) ** 1.5
    velocity = getattr(path, "velocity", None)
    if callable(velocity):
        try:
            r = np.asarray(path.position(0.0), dtype=float)
            v = np.asarray(velocity(0.0), dtype=float)
            return float(np.linalg.norm(np.cross(r, v)) / np.dot(r, r))
        except Exception:  # noqa: BLE001 - a path without a usable velocity
            return 0.0
    return 0.0


def _min_radius(path) -> float:
    """Periapsis distance of a Keplerian orbit, else ``|r(0)|``, m."""
    if isinstance(path, KeplerOrbit):
        return path.periapsis
    return float(np.linalg.norm(np.asarray(path.position(0.0), dtype=float)))


def _advance(orbit: KeplerOrbit, dt: float) -> KeplerOrbit:
    """The same Keplerian orbit with its time origin moved ``dt`` seconds later."""
    M = math.fmod(orbit.mean_anomaly + orbit.mean_motion * dt, 2.0 * math.pi)
    return dataclasses.replace(orbit, mean_anomaly=M)


# --- conversions of constructor arguments -------------------------------------------------


def _quantity(value, unit: str, key: str, *, shape: tuple | None = ()):
    """A number (SI), a string parsed by astropy, a Quantity, or ``{value, unit}``
    (:func:`attitude.foundations.quantities.to_si`, raising :class:`TorqueConfigError`)."""
    return to_si(value, unit, key=key, shape=shape, error=TorqueConfigError)


def _positive(value, unit: str, key: str) -> float:
    return to_si(value, unit, key=key, shape=(), positive=True, error=TorqueConfigError)


def _check_keys(table: Mapping, allowed: Sequence[str], where: str) -> None:
    for key in table:
        if key not in allowed:
            path = f"{where}.{key}" if where else str(key)
            hint = SYNONYMS.get(str(key).lower())
            if hint not in allowed:
                near = difflib.get_close_matches(str(key), list(allowed), n=1)
                hint = near[0] if near else None
            did = f"did you mean {hint!r}? " if hint else ""
            raise TorqueConfigError(f"unknown key; {did}allowed keys: "
                                    f"{', '.join(allowed)}", key=path)




# --- the protocol --------------------------------------------------------------------


class TorqueModel:
    """Base class of torque models: call protocol, broadcasting, ``+`` and the hooks the
    integrators use (time scale, time shift, internal or external).

    Subclasses implement :meth:`evaluate`, which receives numpy arrays (``t`` as an
    array, a unit quaternion, ``omega_body``) and returns body-frame torques that
    broadcast over the leading axes; :meth:`__call__` does the conversions.  The
    integrators and the Lyapunov test use nothing but this protocol: a user's own
    subclass gets the same treatment as the built-in models (override
    :meth:`characteristic_rate` and :meth:`shifted` when the defaults are too generic).

    Attributes
    ----------
    velocity_dependent : bool
        Whether the torque depends on ``omega_body`` (dissipative models do; gravity
        gradient, constant and pivot torques do not).
    internal : bool
        Whether the torque is exerted by one part of the body on another (a damper, an
        inelastic body): it can only turn ``L`` in the body frame and must keep the
        inertial angular momentum.  Integrators then move the attitude with the body
        frame, ``dq/dt = q (omega + (M x L)/L^2) / 2``, so that ``R L_body`` stays fixed
        (:class:`EnergyDissipation`, docs/torques.md).  The torque must be normal to
        ``L``.

    Examples
    --------
    A user model: only :meth:`evaluate` is required; the defaults of
    :meth:`characteristic_rate` and :meth:`shifted` work from it.

    >>> import numpy as np
    >>> from attitude import RigidBody
    >>> from attitude.model.torques import TorqueModel
    >>> class Wobble(TorqueModel):
    ...     velocity_dependent = False
    ...     def evaluate(self, t, quaternion, omega_body, body):
    ...         return np.stack(np.broadcast_arrays(1e-3 * np.cos(t), 0.0, 0.0), axis=-1)
    >>> body = RigidBody.from_principal_moments([1.0, 2.0, 3.0])
    >>> model = Wobble()
    >>> model.shifted(np.pi)(0.0, [0, 0, 0, 1], [0.0, 0.0, 0.0], body)
    array([-0.001,  0.   ,  0.   ])
    >>> round(float(model.characteristic_rate(0.0, [0, 0, 0, 1], [0.0, 0.0, 0.0], body)), 4)
    0.0316
    """

    velocity_dependent: bool = True
    internal: bool = False

    def __call__(self, t, quaternion, omega_body, body) -> np.ndarray:
        """Body-frame torque, N m, shape ``broadcast(t, quaternion[..., 0],
        omega_body[..., 0]) + (3,)``."""
        t = np.asarray(t, dtype=float)
        q = _unit_quaternion(quaternion)
        w = np.asarray(omega_body, dtype=float)
        out = np.asarray(self.evaluate(t, q, w, body), dtype=float)
        if out.shape == (3,) and t.ndim == 0 and q.ndim == 1 and w.ndim == 1:
            return out
        lead = np.broadcast_shapes(t.shape, q.shape[:-1], w.shape[:-1], out.shape[:-1])
        return out if out.shape[:-1] == lead else np.broadcast_to(out, lead + (3,)).copy()

    def evaluate(self, t: np.ndarray, quaternion: np.ndarray, omega_body: np.ndarray,
                 body) -> np.ndarray:
        """The torque on numpy arrays: ``t`` (float array), ``quaternion`` (unit,
        scalar-last, body -> inertial), ``omega_body`` (rad/s); body-frame N m, broadcast
        over the leading axes.  Subclasses implement this."""
        raise NotImplementedError(f"{type(self).__name__} must implement evaluate()")

    def characteristic_rate(self, t, quaternion, omega_body, body) -> np.ndarray | float:
        """The torque's own time scale: the fastest rate (rad/s) at which it changes the
        motion, per body (leading axes of the state), or one float.

        The default is measured from the torque at the given state:
        ``min(|M| / |L|, sqrt(|I^-1 M|))``: the rate at which it turns ``L`` (a fast
        spinner), or, when that is faster, the rate at which it turns a body from rest
        (a slow or resting body, whose small ``L`` the torque builds up rather than
        turns).  Built-in models return rates
        from their parameters (orbital motion, damping time, pendulum frequency...),
        which do not vanish at an equilibrium; a user model with a time dependence of
        its own (a forcing period) should override this and include it.  The splitting
        integrator adds how fast the torque varies along the free motion itself
        (:func:`attitude.propagation.splitting.choose_step`).

        Examples
        --------
        >>> from attitude import RigidBody
        >>> from attitude.model.torques import ConstantTorque
        >>> body = RigidBody.from_principal_moments([2.0, 3.0, 4.0])
        >>> float(ConstantTorque([0.0, 0.0, 0.04]).characteristic_rate(
        ...     0.0, [0, 0, 0, 1], [0.0, 0.0, 0.0], body))          # sqrt(0.04 / 4)
        0.1
        """
        q = _unit_quaternion(quaternion)
        w = np.asarray(omega_body, dtype=float)
        m = np.asarray(self(t, q, w, body), dtype=float)
        inertia = _inertia_of(body)
        L = _matvec(inertia, w)
        m_norm = np.sqrt(_dot(m, m))
        L_norm = np.sqrt(_dot(L, L))
        accel = np.linalg.solve(inertia, m[..., None])[..., 0] if inertia.ndim > 2 else \
            m @ np.linalg.inv(inertia).T
        from_rest = np.sqrt(np.sqrt(_dot(accel, accel)))
        with np.errstate(divide="ignore", invalid="ignore"):
            turn = np.where(L_norm > 0, m_norm / np.where(L_norm > 0, L_norm, 1.0), np.inf)
        rate = np.minimum(turn, from_rest)
        return float(rate) if np.ndim(rate) == 0 else rate

    def shifted(self, dt: float) -> TorqueModel:
        """The same model with its time origin moved by ``dt`` seconds: the result at
        ``t`` is this model's at ``t + dt`` (what a propagation restarted ``dt`` after
        the epoch needs).  The default wraps the model; built-in models return a model
        of their own class (a Keplerian orbit with its mean anomaly advanced...), or
        themselves when they do not depend on time.

        Examples
        --------
        >>> from attitude.model.torques import ConstantTorque
        >>> m = ConstantTorque([0.0, 0.0, 1e-3])
        >>> m.shifted(60.0) is m                  # no time dependence
        True
        """
        dt = float(dt)
        if dt == 0.0:
            return self
        return _ShiftedTorque(self, dt)

    def compiled_parameters(self, body, t_span=None) -> list[tuple[str, dict]] | None:
        """The model as numbers for a compiled torque kernel, or None when it has no
        compiled form (the default: a user's model runs in Python).

        A list of ``(kind, values)`` terms, one per elementary model, whose sum is this
        model's torque on ``body`` (one body): ``kind`` names the formula, ``values``
        holds its SI parameters and the paths or fields it reads (objects with their own
        ``compiled_parameters``), and optionally ``time_shift`` (s: the term is read at
        ``t + time_shift``, what :meth:`shifted` wraps).
        :func:`attitude.propagation.compiled_torques.compile_torques` lays them out in
        flat arrays; ``t_span = (t0, t1)`` (s) is the time the run covers, which a
        tabulated path needs.

        Examples
        --------
        >>> from attitude import RigidBody
        >>> from attitude.model.torques import ConstantTorque, FunctionTorque
        >>> body = RigidBody.from_principal_moments([1.0, 2.0, 3.0])
        >>> ConstantTorque([0.0, 0.0, 1e-3]).compiled_parameters(body)
        [('constant_body', {'torque': array([0.   , 0.   , 0.001])})]
        >>> FunctionTorque(lambda t, q, w, b: w).compiled_parameters(body) is None
        True
        """
        return None

    def __add__(self, other):
        try:
            other = as_torque_model(other)
        except TypeError:
            return NotImplemented
        return SumTorque(self, other)

    def __radd__(self, other):
        if isinstance(other, (int, float)) and other == 0:  # sum([gg, damping])
            return self
        try:
            other = as_torque_model(other)
        except TypeError:
            return NotImplemented
        return SumTorque(other, self)


class SumTorque(TorqueModel):
    """The sum of several torque models (what ``a + b`` returns).

    Parameters
    ----------
    *terms : torque models or plain functions
        Nested sums are flattened.

    Examples
    --------
    >>> from attitude import RigidBody
    >>> from attitude.model.torques import ConstantTorque
    >>> body = RigidBody.from_principal_moments([1.0, 2.0, 3.0])
    >>> both = ConstantTorque([1e-3, 0, 0]) + ConstantTorque([0, 2e-3, 0])
    >>> type(both).__name__, both(0.0, [0, 0, 0, 1], [0.0, 0.0, 0.1], body)
    ('SumTorque', array([0.001, 0.002, 0.   ]))
    """

    def __init__(self, *terms):
        flat = []
        for term in terms:
            term = as_torque_model(term)
            flat.extend(term.terms if isinstance(term, SumTorque) else [term])
        self.terms = tuple(flat)
        self.velocity_dependent = any(t.velocity_dependent for t in self.terms)
        # a sum is internal only if every term is (integrators take sums apart anyway)
        self.internal = bool(self.terms) and all(t.internal for t in self.terms)

    def characteristic_rate(self, t, quaternion, omega_body, body):
        """The fastest of the terms' rates."""
        rate = 0.0
        for term in self.terms:
            rate = np.maximum(rate, term.characteristic_rate(t, quaternion, omega_body, body))
        return float(rate) if np.ndim(rate) == 0 else rate

    def shifted(self, dt: float) -> SumTorque:
        """The sum of the shifted terms (itself for ``dt = 0``)."""
        if float(dt) == 0.0:
            return self
        return SumTorque(*[term.shifted(dt) for term in self.terms])

    def compiled_parameters(self, body, t_span=None) -> list[tuple[str, dict]] | None:
        """The terms' compiled forms, concatenated; None if any term has none.

        Examples
        --------
        >>> from attitude import RigidBody
        >>> from attitude.model.torques import ConstantTorque
        >>> body = RigidBody.from_principal_moments([1.0, 2.0, 3.0])
        >>> both = ConstantTorque([1e-3, 0, 0]) + ConstantTorque([0, 1e-3, 0], frame="inertial")
        >>> [kind for kind, _ in both.compiled_parameters(body)]
        ['constant_body', 'constant_inertial']
        """
        out = []
        for term in self.terms:
            part = term.compiled_parameters(body, t_span)
            if part is None:
                return None
            out.extend(part)
        return out

    def __call__(self, t, quaternion, omega_body, body) -> np.ndarray:
        total = None
        for term in self.terms:
            out = np.asarray(term(t, quaternion, omega_body, body), dtype=float)
            total = out if total is None else total + out
        if total is None:
            lead = np.broadcast_shapes(np.shape(t), np.shape(omega_body)[:-1])
            return np.zeros(lead + (3,))
        return total

    def __len__(self) -> int:
        return len(self.terms)

    def __iter__(self):
        return iter(self.terms)

    def __repr__(self) -> str:
        return " + ".join(repr(t) for t in self.terms) if self.terms else "SumTorque()"


class FunctionTorque(TorqueModel):
    """A plain function ``f(t, quaternion, omega_body, body) -> torque`` as a model.

    The function receives the arguments exactly as the caller passes them (no
    conversion), so it must itself handle the shapes it is called with.

    Parameters
    ----------
    function : callable
    velocity_dependent : bool
        Declare ``False`` if the torque does not depend on ``omega_body`` (it lets a
        splitting integrator treat it as a conservative kick).
    internal : bool
        Declare ``True`` for a torque between parts of the body (normal to ``L``): the
        integrators then keep the inertial angular momentum (:attr:`TorqueModel.internal`).

    Examples
    --------
    >>> import numpy as np
    >>> from attitude import RigidBody
    >>> from attitude.model.torques import FunctionTorque
    >>> body = RigidBody.from_principal_moments([1.0, 2.0, 3.0])
    >>> drag = FunctionTorque(lambda t, q, w, b: -1e-3 * np.asarray(w))   # rate damping
    >>> drag(0.0, [0, 0, 0, 1], [0.0, 0.0, 2.0], body)
    array([-0.   , -0.   , -0.002])
    """

    def __init__(self, function: Callable, *, velocity_dependent: bool = True,
                 internal: bool = False):
        if not callable(function):
            raise TypeError(f"expected a callable torque(t, quaternion, omega_body, body), "
                            f"got {type(function).__name__}")
        self.function = function
        self.velocity_dependent = bool(velocity_dependent)
        self.internal = bool(internal)

    def __call__(self, t, quaternion, omega_body, body) -> np.ndarray:
        return np.asarray(self.function(t, quaternion, omega_body, body), dtype=float)

    def __repr__(self) -> str:
        return f"FunctionTorque({getattr(self.function, '__name__', repr(self.function))})"


class _ShiftedTorque(TorqueModel):
    """A model evaluated at ``t + dt`` (the default of :meth:`TorqueModel.shifted`)."""

    def __init__(self, inner: TorqueModel, dt: float):
        self.inner, self.dt = inner, float(dt)
        self.velocity_dependent = inner.velocity_dependent
        self.internal = inner.internal

    def __call__(self, t, quaternion, omega_body, body) -> np.ndarray:
        return self.inner(np.asarray(t, dtype=float) + self.dt, quaternion, omega_body, body)

    def characteristic_rate(self, t, quaternion, omega_body, body):
        return self.inner.characteristic_rate(np.asarray(t, dtype=float) + self.dt,
                                              quaternion, omega_body, body)

    def shifted(self, dt: float) -> TorqueModel:
        dt = float(dt)
        return self if dt == 0.0 else _ShiftedTorque(self.inner, self.dt + dt)

    def compiled_parameters(self, body, t_span=None) -> list[tuple[str, dict]] | None:
        """The inner model's terms, each read at ``t + dt`` (``time_shift``), its paths
        over the shifted span; None if the inner model has no compiled form.

        Examples
        --------
        >>> from attitude.model.orbit import TabulatedPath
        >>> t = np.linspace(0.0, 100.0, 11)
        >>> gg = GravityGradient(3.986e14, TabulatedPath(t, np.stack([7e6 + t, 0 * t, 0 * t],
        ...                                                          axis=-1)))
        >>> body = RigidBody.from_principal_moments([1.0, 2.0, 3.0])
        >>> gg.shifted(5.0).compiled_parameters(body, (0.0, 90.0))[0][1]["time_shift"]
        5.0
        """
        span = None if t_span is None else (t_span[0] + self.dt, t_span[1] + self.dt)
        parts = self.inner.compiled_parameters(body, span)
        if parts is None:
            return None
        return [(kind, {**values, "time_shift": values.get("time_shift", 0.0) + self.dt})
                for kind, values in parts]

    def __repr__(self) -> str:
        return f"{self.inner!r} at t + {self.dt:.9g} s"


def as_torque_model(obj, *, velocity_dependent: bool | None = None,
                    internal: bool | None = None) -> TorqueModel:
    """Return ``obj`` if it is a :class:`TorqueModel`, else wrap a callable in a
    :class:`FunctionTorque` (so that ``+`` works on it, and the integrators can ask it
    for its time scale and shift its time origin).

    ``velocity_dependent`` and ``internal`` default to the callable's attributes of
    those names if it has them, else ``True`` and ``False``.

    Raises
    ------
    TypeError
        If ``obj`` is not callable.

    Examples
    --------
    >>> import numpy as np
    >>> from attitude.model.torques import ConstantTorque, as_torque_model
    >>> def spin_up(t, quaternion, omega_body, body):
    ...     return np.broadcast_to([0.0, 0.0, 1e-3], np.shape(omega_body))
    >>> model = as_torque_model(spin_up) + ConstantTorque([1e-3, 0.0, 0.0])
    >>> model(0.0, [0, 0, 0, 1], [0.0, 0.0, 0.1], None)
    array([0.001, 0.   , 0.001])
    """
    if isinstance(obj, TorqueModel):
        return obj
    if velocity_dependent is None:
        velocity_dependent = getattr(obj, "velocity_dependent", True) is not False
    if internal is None:
        internal = getattr(obj, "internal", False) is True
    return FunctionTorque(obj, velocity_dependent=velocity_dependent, internal=internal)


# --- gravity gradient ------------------------------------------------------------------


class GravityGradient(TorqueModel):
    """Gravity-gradient torque of a point-mass primary.

    .. math::

        M = \\frac{3\\mu}{r^3}\\,\\hat r \\times (I \\hat r)
          = \\frac{3\\mu}{r^5}\\, r \\times (I r)

    with ``r`` the position of the body relative to the primary (the torque is even in
    ``r``, so the sign convention does not matter) expressed in body axes through the
    attitude, ``r_b = q^{-1} r q``, and ``I`` the body-frame inertia tensor about the
    centre of mass.  The lowest order of the expansion of the primary's potential over
    the body (Hughes 1986, Ch. 8): valid while the body is small compared with ``r``.
    Conservative: it derives from the potential ``V = mu/(2 r^3) (3 r_hat . I r_hat -
    tr I)`` (MacCullagh's formula), see :meth:`potential`.

    Parameters
    ----------
    mu : float, Quantity or str, optional
        Gravitational parameter of the primary, m^3/s^2.  Default: ``orbit.mu`` when the
        orbit is a :class:`~attitude.model.orbit.KeplerOrbit`.
    orbit : KeplerOrbit, path, callable or (3,) array
        Where the body is: anything with ``position(t)`` (inertial, m; e.g.
        :class:`~attitude.model.orbit.TabulatedPath` for a real ephemeris), a callable
        ``t -> position`` or a fixed position vector.

    Notes
    -----
    A body pitched by ``theta`` about an axis ``k`` normal to ``r`` with the two other
    principal moments ``I_i, I_j`` (``r`` in their plane) feels
    ``3 mu / (2 r^3) (I_j - I_i) sin 2 theta`` about ``k``; the torque vanishes when a
    principal axis points at the primary.  In a circular orbit of mean motion ``n`` the
    small pitch libration of an Earth-pointing body has frequency
    ``n sqrt(3 (I_along - I_radial) / I_normal)``.

    References
    ----------
    .. [1] Hughes, P. C. (1986). *Spacecraft Attitude Dynamics*. Wiley. Ch. 8.
    .. [2] Touma, J. & Wisdom, J. (1994). Lie-Poisson integrators for rigid body
       dynamics in the solar system. *Astron. J.* 107, 1189.

    Examples
    --------
    >>> import numpy as np
    >>> from attitude import RigidBody
    >>> from attitude.model.torques import GravityGradient
    >>> body = RigidBody.from_principal_moments([100.0, 200.0, 250.0])
    >>> gg = GravityGradient(3.986004418e14, [7.0e6, 0.0, 0.0])   # primary along -x
    >>> theta = np.radians(10.0)                                   # pitch about z
    >>> q = [0.0, 0.0, np.sin(theta / 2), np.cos(theta / 2)]
    >>> torque = gg(0.0, q, [0.0, 0.0, 0.0], body)
    >>> expected = 1.5 * 3.986004418e14 / 7.0e6**3 * (200.0 - 100.0) * np.sin(2 * theta)
    >>> bool(np.isclose(torque[2], -expected, rtol=1e-14))
    True
    """

    velocity_dependent = False

    def __init__(self, mu=None, orbit=None):
        if orbit is None:
            raise TorqueConfigError("a gravity-gradient torque needs the body's "
                                    "position: give a KeplerOrbit, a path, a "
                                    "callable or a position vector", key="orbit")
        self.orbit = as_path(orbit)
        if mu is None:
            if not isinstance(self.orbit, KeplerOrbit):
                raise TorqueConfigError("give the gravitational parameter of the "
                                        "primary (only a KeplerOrbit carries one)", key="mu")
            mu = self.orbit.mu
        self.mu = _positive(mu, "m3/s2", "mu")

    def evaluate(self, t, quaternion, omega_body, body):
        r = self.orbit.position(t)
        r_b = quat.rotate(quaternion, r, inverse=True)
        r2 = _dot(r_b, r_b)[..., None]
        Ir = _matvec(_inertia_of(body), r_b)
        return 3.0 * self.mu / (r2 * r2 * np.sqrt(r2)) * quat.cross(r_b, Ir)

    def characteristic_rate(self, t, quaternion, omega_body, body) -> float:
        """``max(sqrt(3 mu / r_p^3), orbital rate at periapsis)``, rad/s: the libration
        rate of a body with ``(C - A)/B = 1`` (``r_p`` the periapsis distance, or
        ``|r(0)|``), or the rate at which the direction to the primary turns."""
        r = _min_radius(self.orbit)
        return max(math.sqrt(3.0 * self.mu / r**3), _orbit_rate(self.orbit))

    def shifted(self, dt: float) -> TorqueModel:
        """On a Keplerian orbit: the same model with the mean anomaly advanced by
        ``n dt``; other paths: the default wrapper."""
        dt = float(dt)
        if dt == 0.0:
            return self
        if isinstance(self.orbit, KeplerOrbit):
            return GravityGradient(self.mu, _advance(self.orbit, dt))
        return super().shifted(dt)

    def compiled_parameters(self, body, t_span=None) -> list[tuple[str, dict]]:
        """``[("gravity_gradient", {mu, inertia, orbit})]``
        (:meth:`TorqueModel.compiled_parameters`).

        Examples
        --------
        >>> from attitude import RigidBody
        >>> from attitude.model.torques import GravityGradient
        >>> body = RigidBody.from_principal_moments([1.0, 2.0, 3.0])
        >>> [(kind, sorted(v)) for kind, v in GravityGradient(
        ...     3.986e14, [7e6, 0, 0]).compiled_parameters(body)]
        [('gravity_gradient', ['inertia', 'mu', 'orbit'])]
        """
        return [("gravity_gradient", {"mu": self.mu, "inertia": _inertia_of(body),
                                      "orbit": self.orbit})]

    def potential(self, t, quaternion, body) -> np.ndarray:
        """Gravity-gradient potential energy ``V = mu/(2 r^3)(3 r_hat.I r_hat - tr I)``, J.

        The second-order term of MacCullagh's formula for the potential energy of an
        extended body, ``U = -mu m / r - mu/(2 r^3)(tr I - 3 r_hat.I r_hat)``: the part that
        depends on the attitude (lowest when the axis of least inertia points at the
        primary).  ``E_kin + V`` is conserved when the primary is fixed.
        """
        t = np.asarray(t, dtype=float)
        q = _unit_quaternion(quaternion)
        r_b = quat.rotate(q, self.orbit.position(t), inverse=True)
        r2 = _dot(r_b, r_b)
        inertia = _inertia_of(body)
        trace = np.trace(inertia, axis1=-2, axis2=-1)
        return self.mu / (2.0 * r2 * np.sqrt(r2)) * (3.0 * _dot(r_b, _matvec(
            inertia, r_b)) / r2 - trace)

    def __repr__(self) -> str:
        return f"GravityGradient(mu={self.mu:.10g}, orbit={self.orbit!r})"


# --- constant torque -------------------------------------------------------------------


class ConstantTorque(TorqueModel):
    """A torque fixed in body axes (a thruster misalignment, a stuck wheel) or in
    inertial axes (rotated into the body frame by the attitude: ``M_b = q^{-1} M q``).

    Parameters
    ----------
    torque : (3,) array-like, Quantity or ``{value, unit}``
        N m.
    frame : {"body", "inertial"}

    Examples
    --------
    >>> import numpy as np
    >>> from attitude import RigidBody
    >>> from attitude.model.torques import ConstantTorque
    >>> body = RigidBody.from_principal_moments([1.0, 2.0, 3.0])
    >>> half_turn_z = [0, 0, 1.0, 0]                     # body x along inertial -x
    >>> ConstantTorque([1e-3, 0, 0], frame="inertial")(0.0, half_turn_z, [0, 0, 0], body)
    array([-0.001,  0.   ,  0.   ])
    """

    velocity_dependent = False
    FRAMES = ("body", "inertial")

    def __init__(self, torque, frame: str = "body"):
        self.torque = _quantity(torque, "N m", "torque", shape=(3,))
        if frame not in self.FRAMES:
            near = difflib.get_close_matches(str(frame), self.FRAMES, n=1)
            did = f"did you mean {near[0]!r}? " if near else ""
            raise TorqueConfigError(f"unknown frame {frame!r}; {did}choose 'body' "
                                    "or 'inertial'", key="frame")
        self.frame = frame

    def evaluate(self, t, quaternion, omega_body, body):
        if self.frame == "body":
            return self.torque.copy()
        return quat.rotate(quaternion, self.torque, inverse=True)

    def compiled_parameters(self, body, t_span=None) -> list[tuple[str, dict]]:
        """``[("constant_body" or "constant_inertial", {torque})]``
        (:meth:`TorqueModel.compiled_parameters`).

        Examples
        --------
        >>> from attitude.model.torques import ConstantTorque
        >>> ConstantTorque([1.0, 0, 0], frame="inertial").compiled_parameters(None)[0][0]
        'constant_inertial'
        """
        return [(f"constant_{self.frame}", {"torque": self.torque.copy()})]

    def shifted(self, dt: float) -> ConstantTorque:
        """Itself (no time dependence)."""
        return self

    def __repr__(self) -> str:
        return f"ConstantTorque({self.torque.tolist()} N m, frame={self.frame!r})"


# --- internal energy dissipation ----------------------------------------------------------


class EnergyDissipation(TorqueModel):
    r"""Internal energy dissipation with the inertial angular momentum fixed: the
    quasi-rigid relaxation of a tumbling asteroid, or of a spacecraft with a nutation
    damper, fuel slosh or flexible antennas (Explorer 1).

    A body that dissipates energy inside itself keeps its total angular momentum: in
    inertial space ``L`` does not move, while in the body frame it drifts toward the
    axis of the largest moment, where the kinetic energy ``E = L.I^-1 L / 2`` is least
    for the given ``|L|`` (the quasi-rigid picture of Sharma, Burns & Hui 2005 and
    Breiter, Rozek & Vokrouhlicky 2012: the body is rigid to first order, the small
    anelastic strains only drain energy).  With ``omega = I^-1 L`` the rigid-body rate,
    the body-frame angular momentum obeys

    .. math::

        \frac{dL}{dt} = L\times\omega + M, \qquad
        M = \frac{k}{L^2}\, L\times(L\times\omega) = -k\,\omega_\perp ,

    ``omega_perp = omega - (omega.L) L / L^2`` the part of ``omega`` normal to ``L``.
    ``M`` is the internal torque this class returns: ``L.M = 0`` (``|L|`` kept) and

    .. math::

        \frac{dE}{dt} = \omega\cdot M = -k\,|\omega_\perp|^2 \le 0 ,

    zero only for a principal-axis spin; among the torques that keep ``|L|`` it is the
    one that removes energy fastest for its size (the "double bracket" dissipation of
    Bloch et al. 1996).  Stable end state: spin about the major axis, ``E = L^2/2C``.

    **The attitude.**  ``L_inertial = R L`` is fixed, so the body frame cannot turn at
    ``omega`` alone: with ``dR/dt = R [Omega x]``, ``d(R L)/dt = R (Omega x L + L x
    omega + M) = 0`` holds for

    .. math::

        \Omega = \omega + \frac{M\times L}{L^2}

    (``(M x L) x L = -L^2 M`` since ``L.M = 0``).  The extra rate is normal to ``L``; a
    rate along ``L`` would only re-label the rotation phase about ``L``, which the free
    motion carries, and is taken zero.  The model is therefore *internal*
    (:attr:`TorqueModel.internal`): the integrators apply ``M`` to ``L`` in the body
    frame and ``Omega`` to the attitude, the splitting integrator in a kick that ends
    by re-imposing the inertial ``L`` exactly (:mod:`attitude.propagation.splitting`),
    the DOP853 reference in its right-hand side.  The body-frame motion of ``L`` (and
    so ``E``, the regime, the nutation angles) is the same as with an external torque
    ``M``; only the attitude differs: an external ``M`` would turn the inertial ``L``
    (by per cents over a long-axis to flat-spin relaxation), a drift of the pole that no
    internal mechanism can cause.

    **The time constant.**  ``k`` is set from ``time_constant`` ``tau`` so that near
    the final state the excess energy ``E - L^2/(2C)`` decays as ``exp(-t / tau)`` (and
    the nutation angle between ``L`` and the major axis, ``~ sqrt(E - L^2/2C)``, as
    ``exp(-t / 2 tau)``).  Near spin about ``C``, ``omega_perp ~= ((C-A) w1, (C-B) w2,
    0) / C``, so ``dE/dt = -k ((C-A)^2 w1^2 + (C-B)^2 w2^2) / C^2``, while the free
    nutation keeps ``A (C-A) w1^2 + B (C-B) w2^2 = 2 C (E - L^2/2C)`` and shares it
    equally between the two terms on average; hence

    .. math::

        \frac{1}{\tau} = \frac{k}{C}\left(\frac{C-A}{A} + \frac{C-B}{B}\right),
        \qquad k = \frac{C}{\tau\,[(C-A)/A + (C-B)/B]} .

    For a prolate body (``B = C``) only the ``w1`` term is excited and
    ``k = A C / (2 tau (C - A))`` gives the same e-folding exactly.  (For a nearly
    prolate triaxial body the nutation period near the final state,
    ``2 pi / (omega sqrt((C-A)(C-B)/(AB)))``, becomes long and the averaged rate
    applies only once it is short compared with ``tau``.)  A spherical body has
    ``omega_perp = 0``: no torque.  For an asteroid, ``tau`` follows from its size,
    density, spin and ``mu Q`` (:func:`damping_timescale`).

    Parameters
    ----------
    time_constant : float (s), Quantity or str (``"30 min"``)
        e-folding time of the excess kinetic energy near the final (major-axis) spin.

    Notes
    -----
    The rate of a real body depends on its rheology and on the nutation angle (the
    dissipation happens at the nutation frequency and its harmonics; Efroimsky &
    Lazarian 2000, Breiter et al. 2012, Frouard & Efroimsky 2018); this model fixes the
    e-folding time near the end state and keeps the qualitative path (LAM ->
    separatrix -> SAM -> principal-axis spin).

    References
    ----------
    .. [1] Sharma, I., Burns, J. A. & Hui, C.-Y. (2005). Nutational damping times in
       solids of revolution. *MNRAS* 359, 79-92.
    .. [2] Breiter, S., Rozek, A. & Vokrouhlicky, D. (2012). Stress field and spin axis
       relaxation for inelastic triaxial ellipsoids. *MNRAS* 427, 755.
    .. [3] Bloch, A. M., Krishnaprasad, P. S., Marsden, J. E. & Ratiu, T. S. (1996).
       The Euler-Poincare equations and double bracket dissipation. *Commun. Math.
       Phys.* 175, 1-42.
    .. [4] Hughes, P. C. (1986). *Spacecraft Attitude Dynamics*. Wiley. Ch. 5 (energy
       sink, major-axis rule).
    .. [5] Bracewell, R. N. & Garriott, O. K. (1958). Rotation of artificial Earth
       satellites. *Nature* 182, 760-762 (Explorer 1).

    Examples
    --------
    >>> import numpy as np
    >>> from attitude import RigidBody
    >>> from attitude.model.torques import EnergyDissipation
    >>> body = RigidBody.from_principal_moments([1.0, 1.5, 2.0])
    >>> damper = EnergyDissipation("10 min")
    >>> damper.internal
    True
    >>> w = np.array([0.3, 0.1, 0.2])
    >>> M = damper(0.0, [0, 0, 0, 1], w, body)
    >>> L = body.inertia @ w
    >>> float(abs(L @ M)) < 1e-16, bool(w @ M < 0)
    (True, True)
    """

    velocity_dependent = True
    internal = True

    def __init__(self, time_constant):
        self.time_constant = _positive(time_constant, "s", "time_constant")
        self._cache = None

    def coefficient(self, body) -> np.ndarray | float:
        """Damping coefficient ``k`` (kg m^2/s) for ``body`` (see the class notes).

        Examples
        --------
        >>> from attitude import RigidBody
        >>> from attitude.model.torques import EnergyDissipation
        >>> body = RigidBody.from_principal_moments([2.0, 4.0, 4.0])   # prolate
        >>> EnergyDissipation(10.0).coefficient(body)     # A C / (2 tau (C - A))
        0.2
        """
        cached = self._cache
        if cached is not None and cached[0] is body:   # bodies are immutable values
            return cached[1]
        k = self._coefficient(_moments_of(body))
        if isinstance(body, RigidBody):
            self._cache = (body, k)
        return k

    def _coefficient(self, m: np.ndarray) -> np.ndarray | float:
        A, B, C = m[..., 0], m[..., 1], m[..., 2]
        tol = SYMMETRY_RTOL * C
        prolate = (C - B) <= tol
        sigma = np.where(prolate, 2.0 * (C - A) / A, (C - A) / A + (C - B) / B)
        spherical = (C - A) <= tol
        k = np.where(spherical, 0.0, C / (self.time_constant * np.where(spherical, 1.0,
                                                                             sigma)))
        return float(k) if np.ndim(k) == 0 else k

    def evaluate(self, t, quaternion, omega_body, body):
        k = self.coefficient(body)
        L = _matvec(_inertia_of(body), omega_body)
        if L.ndim == 1:                                 # one epoch
            L2 = float(np.dot(L, L))
            if L2 == 0.0:
                return np.zeros(3)
            w_perp = omega_body - (np.dot(omega_body, L) / L2) * L
            w_perp = w_perp - (np.dot(w_perp, L) / L2) * L    # re-project (round-off)
            return -k * w_perp
        k = np.asarray(k)[..., None]
        L2 = _dot(L, L)[..., None]
        safe = np.where(L2 > 0, L2, 1.0)
        w_perp = omega_body - _dot(omega_body, L)[..., None] / safe * L
        # re-project once: removes the rounding error of the projection along L, so that
        # L . M vanishes to the last bit
        w_perp = w_perp - _dot(w_perp, L)[..., None] / safe * L
        return -k * w_perp

    def characteristic_rate(self, t, quaternion, omega_body, body) -> float:
        """``1 / time_constant``, rad/s."""
        return 1.0 / self.time_constant

    def compiled_parameters(self, body, t_span=None) -> list[tuple[str, dict]]:
        """``[("dissipation", {k, inertia})]``, ``k`` the :meth:`coefficient` for
        ``body`` (:meth:`TorqueModel.compiled_parameters`).

        Examples
        --------
        >>> from attitude import RigidBody
        >>> from attitude.model.torques import EnergyDissipation
        >>> body = RigidBody.from_principal_moments([2.0, 4.0, 4.0])
        >>> EnergyDissipation(10.0).compiled_parameters(body)[0][1]["k"]
        0.2
        """
        return [("dissipation", {"k": float(self.coefficient(body)),
                                 "inertia": _inertia_of(body)})]

    def shifted(self, dt: float) -> EnergyDissipation:
        """Itself (no time dependence)."""
        return self

    def __repr__(self) -> str:
        return f"EnergyDissipation(time_constant={self.time_constant:.6g} s)"


def internal_rate(torque, omega_body, body) -> np.ndarray:
    r"""Extra body-frame rate of the attitude under an internal torque, rad/s.

    ``(M x L) / L^2`` with ``L = I omega``: added to ``omega`` in the attitude
    kinematics it keeps the inertial ``L`` fixed while ``M`` turns ``L`` in the body
    frame (:class:`EnergyDissipation`).  Zero where ``L = 0``.

    Parameters
    ----------
    torque : (..., 3) array
        Internal torque (normal to ``L``), body frame, N m.
    omega_body : (..., 3) array
        rad/s.
    body : RigidBody, sequence of them, or inertia array (..., 3, 3)

    Examples
    --------
    >>> import numpy as np
    >>> from attitude import RigidBody
    >>> from attitude.model.torques import EnergyDissipation, internal_rate
    >>> body = RigidBody.from_principal_moments([1.0, 1.5, 2.0])
    >>> w = np.array([0.3, 0.1, 0.2])
    >>> M = EnergyDissipation(60.0)(0.0, [0, 0, 0, 1], w, body)
    >>> L = body.inertia @ w
    >>> bool(np.allclose(np.cross(internal_rate(M, w, body), L), -M, atol=1e-17))
    True
    """
    M = np.asarray(torque, dtype=float)
    L = _matvec(_inertia_of(body), np.asarray(omega_body, dtype=float))
    L2 = _dot(L, L)
    safe = np.where(L2 > 0, L2, 1.0)
    out = quat.cross(M, L) / np.asarray(safe)[..., None]
    return np.where(np.asarray(L2)[..., None] > 0, out, 0.0)


def damping_timescale(diameter, density, *, period=None, spin_rate=None,
                      rigidity_q="5e11 Pa", k3_squared: float = 0.1) -> u.Quantity:
    r"""Damping time scale of a tumbling asteroid (Burns & Safronov 1973; Harris 1994).

    .. math::

        \tau \simeq \frac{\mu Q}{\rho\, K_3^2\, R^2\, \omega^3}

    with ``mu`` the rigidity, ``Q`` the quality factor (they enter only as the product
    ``mu Q``), ``rho`` the bulk density, ``R = D/2`` the mean radius, ``omega`` the spin
    rate and ``K_3^2`` a shape factor (about 0.1 for a nearly spherical body, smaller
    for elongated ones).  An order-of-magnitude estimate: published coefficients of
    this form differ by factors of ~10 between authors (Sharma, Burns & Hui 2005 derive
    ``T_d = D(h) mu Q / (rho a^2 Omega^3)`` with ``D(h)`` a few hundred, shape
    dependent).  Use it as the ``time_constant`` of :class:`EnergyDissipation` (order
    of magnitude; docs/torques.md has a worked Apophis example).

    Parameters
    ----------
    diameter : float (m), Quantity or str
        Mean (volume-equivalent) diameter.
    density : float (kg/m^3), Quantity or str
    period : float (s), Quantity or str, optional
        Spin period (give this or ``spin_rate``).
    spin_rate : float (rad/s), Quantity or str, optional
    rigidity_q : float (Pa), Quantity or str
        ``mu Q``; default 5e11 Pa (Harris 1994's value for rock-like asteroids, as used
        by Pravec et al. 2005, 2014).
    k3_squared : float
        Shape factor ``K_3^2`` (default 0.1).

    Returns
    -------
    Quantity
        The time scale, in years.

    Raises
    ------
    TorqueConfigError
        A non-positive or non-finite input, a unit of the wrong dimension, or both (or
        neither) of ``period`` and ``spin_rate``.

    References
    ----------
    .. [1] Burns, J. A. & Safronov, V. S. (1973). Asteroid nutation angles. *MNRAS* 165,
       403-411.
    .. [2] Harris, A. W. (1994). Tumbling asteroids. *Icarus* 107, 209-211.
    .. [3] Pravec, P. et al. (2005). Tumbling asteroids. *Icarus* 173, 108-131.
    .. [4] Pravec, P. et al. (2014). The tumbling spin state of (99942) Apophis.
       *Icarus* 233, 48-60.
    .. [5] Sharma, I., Burns, J. A. & Hui, C.-Y. (2005). *MNRAS* 359, 79-92.

    Examples
    --------
    Apophis (D = 0.34 km, 2.5 g/cm^3, P = 30.56 h, mu Q = 5e11 Pa):

    >>> from attitude.model.torques import damping_timescale
    >>> tau = damping_timescale("0.34 km", "2.5 g/cm3", period="30.56 h")
    >>> print(f"{tau.to_value('Gyr'):.1f} Gyr")
    11.8 Gyr
    """
    D = _positive(diameter, "m", "diameter")
    rho = _positive(density, "kg/m3", "density")
    muq = _positive(rigidity_q, "Pa", "rigidity_q")
    k3 = _positive(k3_squared, "", "k3_squared")
    if (period is None) == (spin_rate is None):
        raise TorqueConfigError("give exactly one of 'period' and 'spin_rate'", key="period")
    omega = (2.0 * math.pi / _positive(period, "s", "period") if spin_rate is None
             else _positive(spin_rate, "rad/s", "spin_rate"))
    R = 0.5 * D
    tau = muq / (rho * k3 * R * R * omega**3)
    return (tau * u.s).to(u.yr)


# --- magnetic fields and eddy currents --------------------------------------------------


class UniformField:
    """A magnetic field constant in inertial space, T (callable ``t -> (..., 3)``).

    Examples
    --------
    >>> from attitude.model.torques import UniformField
    >>> UniformField([0.0, 0.0, 3e-5])([0.0, 60.0])
    array([[0.e+00, 0.e+00, 3.e-05],
           [0.e+00, 0.e+00, 3.e-05]])
    """

    def __init__(self, field):
        self.vector = _quantity(field, "T", "field", shape=(3,))

    def __call__(self, t) -> np.ndarray:
        return np.broadcast_to(self.vector, np.shape(t) + (3,)).copy()

    def compiled_parameters(self, t_span=None) -> tuple[str, dict]:
        """``("uniform", {vector})``: the field as numbers for a compiled kernel
        (:meth:`TorqueModel.compiled_parameters`).

        Examples
        --------
        >>> from attitude.model.torques import UniformField
        >>> UniformField([0.0, 0.0, 3e-5]).compiled_parameters()
        ('uniform', {'vector': array([0.e+00, 0.e+00, 3.e-05])})
        """
        return ("uniform", {"vector": self.vector.copy()})

    def __repr__(self) -> str:
        return f"UniformField({self.vector.tolist()} T)"


class TiltedDipoleField:
    """The Earth's field as a tilted dipole rotating with the Earth, along an orbit.

    .. math::

        B(r) = \\frac{\\mu_0}{4\\pi}\\,\\frac{m}{r^3}\\left(3 (\\hat m\\cdot\\hat r)\\hat r
               - \\hat m\\right)

    with ``hat m`` pointing from the northern geomagnetic pole to the southern one (the
    Earth's moment points roughly south).  In Earth-fixed axes the northern geomagnetic
    pole is at colatitude ``tilt`` and east longitude ``pole_longitude``; Earth-fixed
    axes turn about the inertial ``z`` axis by ``theta(t) = rotation_angle + rate t``
    (the Earth rotation angle).  The inertial frame is taken as equatorial (GCRF,
    EME2000; precession and nutation ignored) and ``r`` comes from the path.

    Parameters
    ----------
    orbit : KeplerOrbit, path, callable or (3,) array
        Position of the body relative to the Earth's centre, inertial, m.
    moment : float (A m^2), Quantity or str
        Dipole moment; default :data:`EARTH_DIPOLE_MOMENT` (7.94e22 A m^2: 3.07e-5 T at
        the magnetic equator on a 6371.2 km sphere).
    tilt, pole_longitude : float (rad), Quantity or str
        Colatitude and east longitude of the northern geomagnetic pole; defaults 9.4 deg
        and -72.7 deg (IGRF-13, 2020).
    rotation_angle : float (rad), Quantity or str
        Earth rotation angle (Greenwich sidereal angle) at ``t = 0``.
    rotation_rate : float (rad/s)
        Default :data:`EARTH_ROTATION_RATE`.

    References
    ----------
    .. [1] Wertz, J. R. (ed.) (1978). *Spacecraft Attitude Determination and Control*.
       Reidel. Sec. 5.1 and App. H (dipole model of the geomagnetic field).
    .. [2] Alken, P. et al. (2021). International Geomagnetic Reference Field: the
       thirteenth generation. *Earth Planets Space* 73, 49.

    Examples
    --------
    >>> import numpy as np
    >>> from attitude.model.orbit import KeplerOrbit
    >>> from attitude.model.torques import TiltedDipoleField
    >>> leo = KeplerOrbit.from_elements(mu=3.986004418e14, a="6871 km", i="51.6 deg")
    >>> b = TiltedDipoleField(leo)(np.linspace(0.0, leo.period, 7))
    >>> bool(np.all((np.linalg.norm(b, axis=-1) > 1.5e-5) & (np.linalg.norm(b, axis=-1) < 6e-5)))
    True
    """

    def __init__(self, orbit, *, moment=EARTH_DIPOLE_MOMENT, tilt=EARTH_DIPOLE_TILT,
                 pole_longitude=EARTH_DIPOLE_POLE_LONGITUDE, rotation_angle=0.0,
                 rotation_rate=EARTH_ROTATION_RATE):
        self.orbit = as_path(orbit)
        self.moment = _positive(moment, "A m2", "moment")
        self.tilt = _quantity(tilt, "rad", "tilt")
        self.pole_longitude = _quantity(pole_longitude, "rad", "pole_longitude")
        self.rotation_angle = _quantity(rotation_angle, "rad", "rotation_angle")
        self.rotation_rate = _quantity(rotation_rate, "rad/s", "rotation_rate")

    def dipole_direction(self, t) -> np.ndarray:
        """Unit vector of the dipole moment (pointing south), inertial, ``S + (3,)``."""
        theta = self.rotation_angle + self.rotation_rate * np.asarray(t, dtype=float)
        lam = theta + self.pole_longitude
        st = np.sin(self.tilt)
        return -np.stack([st * np.cos(lam), st * np.sin(lam),
                          np.broadcast_to(np.cos(self.tilt), np.shape(lam))], axis=-1)

    def __call__(self, t) -> np.ndarray:
        """Field at the body, inertial components, T, shape ``S + (3,)``."""
        r = self.orbit.position(t)
        m_hat = self.dipole_direction(t)
        r2 = _dot(r, r)[..., None]
        rn = np.sqrt(r2)
        r_hat = r / rn
        return _MU0_OVER_4PI * self.moment / (r2 * rn) * (
            3.0 * _dot(m_hat, r_hat)[..., None] * r_hat - m_hat)

    def compiled_parameters(self, t_span=None) -> tuple[str, dict]:
        """``("tilted_dipole", {...})``: the field as numbers for a compiled kernel, the
        same terms as :meth:`__call__` (``coefficient = mu0 / 4 pi * moment``, the sine
        and cosine of the tilt, the rotation angle, rate and pole longitude, the orbit).

        Examples
        --------
        >>> from attitude.model.torques import TiltedDipoleField
        >>> kind, values = TiltedDipoleField([7e6, 0.0, 0.0]).compiled_parameters()
        >>> kind, float(values["coefficient"])
        ('tilted_dipole', 7940000000000000.0)
        """
        return ("tilted_dipole", {
            "coefficient": _MU0_OVER_4PI * self.moment,
            "sin_tilt": float(np.sin(self.tilt)), "cos_tilt": float(np.cos(self.tilt)),
            "rotation_angle": float(self.rotation_angle),
            "rotation_rate": float(self.rotation_rate),
            "pole_longitude": float(self.pole_longitude), "orbit": self.orbit})

    def __repr__(self) -> str:
        return (f"TiltedDipoleField(moment={self.moment:.4g} A m2, tilt="
                f"{np.degrees(self.tilt):.4g} deg, orbit={self.orbit!r})")


class EddyCurrentDamping(TorqueModel):
    """Eddy-current torque on a spinning conducting body in a slowly varying field.

    .. math::

        M = \\big(\\mathbf{M}\\,(\\omega \\times B)\\big) \\times B

    with ``B`` the field in body axes (the inertial field rotated by the attitude) and
    ``bold M`` the symmetric positive semi-definite *magnetic tensor* of the body (body
    frame, S m^4), which depends only on its shape and conductivity (Ortiz Gomez &
    Walker 2015).  It is always dissipative:
    ``ω . M = -(ω x B) . bold M (ω x B) <= 0``.  For an isotropic tensor ``m 1``,
    ``M = -m B^2 ω_perp`` (``ω_perp`` the component of ``ω`` normal to ``B``); a sphere
    of moment ``I`` in a uniform field keeps ``ω_parallel`` and loses ``ω_perp`` as
    ``exp(-m B^2 t / I)``.

    Valid at low spin rates, when the induced field is negligible (skin depth much
    larger than the wall thickness; Praly et al. 2012).

    Parameters
    ----------
    magnetic_tensor : float or (3, 3) array-like, Quantity or str
        S m^4, body frame.  A thin spherical shell (radius ``R``, thickness ``h``,
        conductivity ``sigma``) has ``(2 pi / 3) sigma R^4 h`` times the identity, a solid
        sphere ``(2 pi / 15) sigma R^5``: see :meth:`spherical_shell`,
        :meth:`solid_sphere`.
    field : callable ``t -> (..., 3)`` T, or (3,) array
        Inertial magnetic field at the body: :class:`TiltedDipoleField` along an orbit,
        :class:`UniformField`, any function, or a constant vector.

    Notes
    -----
    Derivation for a sphere: in body axes the field changes as ``dB/dt = -ω x B``; the
    induced electric field ``E = -(1/2) dB/dt x r`` is tangential and divergence-free,
    so ``J = sigma E`` needs no surface charge; its moment ``m = (1/2) ∫ r x J dV =
    -(sigma/4) ∫ r^2 (1 - r_hat r_hat) dV dB/dt`` gives ``(2 pi/3) sigma R^4 h`` for a
    thin shell, and ``M = m x B``.

    References
    ----------
    .. [1] Ortiz Gomez, N. & Walker, S. J. I. (2015). Eddy currents applied to
       de-tumbling of space debris: analysis and validation of approximate proposed
       methods. *Acta Astronautica* 114, 34-53.
    .. [2] Praly, N., Hillion, M., Bonnal, C., Laurent-Varin, J. & Petit, N. (2012).
       Study on the eddy current damping of the spin dynamics of space debris from the
       Ariane upper stage. *Acta Astronautica* 76, 145-153.

    Examples
    --------
    >>> import numpy as np
    >>> from attitude import RigidBody
    >>> from attitude.model.torques import EddyCurrentDamping, UniformField
    >>> body = RigidBody.from_principal_moments([10.0, 10.0, 10.0])
    >>> damper = EddyCurrentDamping.solid_sphere("0.5 m", "3.5e7 S/m", UniformField([0, 0, 3e-5]))
    >>> m = damper(0.0, [0, 0, 0, 1], [0.1, 0.0, 0.1], body)
    >>> bool(m[0] < 0 and abs(m[2]) < 1e-20)      # brakes the spin across B, not along it
    True
    """

    velocity_dependent = True

    def __init__(self, magnetic_tensor, field):
        tensor = np.asarray(_quantity(magnetic_tensor, "S m4", "magnetic_tensor",
                                      shape=None), dtype=float)
        if tensor.shape == ():
            if tensor < 0:
                raise TorqueConfigError(f"must be >= 0, got {tensor}", key="magnetic_tensor")
            self.isotropic = True
        elif tensor.shape == (3, 3):
            scale = np.max(np.abs(tensor))
            if np.any(np.abs(tensor - tensor.T) > 1e-10 * scale):
                raise TorqueConfigError("must be symmetric", key="magnetic_tensor")
            tensor = 0.5 * (tensor + tensor.T)
            if np.linalg.eigvalsh(tensor)[0] < -1e-12 * scale:
                raise TorqueConfigError("must be positive semi-definite "
                                        "(a negative eigenvalue would pump energy in)",
                                        key="magnetic_tensor")
            self.isotropic = False
        else:
            raise TorqueConfigError(f"expected a scalar or a 3x3 tensor, "
                                    f"got shape {tensor.shape}", key="magnetic_tensor")
        self.magnetic_tensor = tensor
        if callable(field):
            self.field = field
        else:
            self.field = UniformField(field)

    @classmethod
    def spherical_shell(cls, radius, thickness, conductivity, field) -> EddyCurrentDamping:
        """Thin spherical shell: ``bold M = (2 pi / 3) sigma R^4 h`` (isotropic)."""
        R = _positive(radius, "m", "radius")
        h = _positive(thickness, "m", "thickness")
        sigma = _positive(conductivity, "S/m", "conductivity")
        return cls(2.0 * np.pi / 3.0 * sigma * R**4 * h, field)

    @classmethod
    def solid_sphere(cls, radius, conductivity, field) -> EddyCurrentDamping:
        """Solid sphere: ``bold M = (2 pi / 15) sigma R^5`` (isotropic)."""
        R = _positive(radius, "m", "radius")
        sigma = _positive(conductivity, "S/m", "conductivity")
        return cls(2.0 * np.pi / 15.0 * sigma * R**5, field)

    def characteristic_rate(self, t, quaternion, omega_body, body):
        """``lambda_max(bold M) |B(t)|^2 / A``, rad/s: the fastest damping rate of the
        spin (``A`` the least moment), or the orbital rate of a field along an orbit if
        larger."""
        tensor = np.atleast_2d(self.magnetic_tensor)
        strength = (float(abs(self.magnetic_tensor)) if self.isotropic
                    else float(np.max(np.abs(np.linalg.eigvalsh(tensor)))))
        field = np.asarray(self.field(np.asarray(t, dtype=float)), dtype=float)
        rate = strength * _dot(field, field) / _moments_of(body)[..., 0]
        orbit = getattr(self.field, "orbit", None)
        if orbit is not None:
            rate = np.maximum(rate, _orbit_rate(orbit))
        return float(rate) if np.ndim(rate) == 0 else rate

    def shifted(self, dt: float) -> TorqueModel:
        """Itself in a uniform field; in a tilted dipole on a Keplerian orbit, the same
        model with the orbit and the Earth rotation angle advanced by ``dt``; else the
        default wrapper."""
        dt = float(dt)
        if dt == 0.0 or isinstance(self.field, UniformField):
            return self
        f = self.field
        if isinstance(f, TiltedDipoleField) and isinstance(f.orbit, KeplerOrbit):
            field = TiltedDipoleField(_advance(f.orbit, dt), moment=f.moment, tilt=f.tilt,
                                      pole_longitude=f.pole_longitude,
                                      rotation_angle=f.rotation_angle
                                      + f.rotation_rate * dt,
                                      rotation_rate=f.rotation_rate)
            return EddyCurrentDamping(self.magnetic_tensor, field)
        return super().shifted(dt)

    def compiled_parameters(self, body, t_span=None) -> list[tuple[str, dict]] | None:
        """``[("eddy_current", {isotropic, scalar, tensor, field})]`` (``tensor`` 3 x 3,
        the isotropic ``scalar`` times the identity when ``isotropic``), or None when the
        field has no compiled form (a user's function)
        (:meth:`TorqueModel.compiled_parameters`).

        Examples
        --------
        >>> from attitude.model.torques import EddyCurrentDamping, UniformField
        >>> damper = EddyCurrentDamping(2.0, UniformField([0, 0, 3e-5]))
        >>> damper.compiled_parameters(None)[0][1]["isotropic"]
        True
        """
        if not callable(getattr(self.field, "compiled_parameters", None)):
            return None
        tensor = (float(self.magnetic_tensor) * np.eye(3) if self.isotropic
                  else np.array(self.magnetic_tensor, dtype=float))
        return [("eddy_current", {"tensor": tensor, "isotropic": self.isotropic,
                                  "scalar": float(self.magnetic_tensor[()]) if
                                  self.isotropic else 0.0, "field": self.field})]

    def evaluate(self, t, quaternion, omega_body, body):
        B = quat.rotate(quaternion, np.asarray(self.field(t), dtype=float), inverse=True)
        x = quat.cross(omega_body, B)
        Mx = self.magnetic_tensor * x if self.isotropic else x @ self.magnetic_tensor.T
        return quat.cross(Mx, B)

    def __repr__(self) -> str:
        m = (f"{float(self.magnetic_tensor):.6g}" if self.isotropic
             else str(self.magnetic_tensor.tolist()))
        return f"EddyCurrentDamping(magnetic_tensor={m} S m4, field={self.field!r})"


# --- residual magnetic dipole -------------------------------------------------------------


def _shifted_field(field, dt: float):
    """``field`` with its time origin moved ``dt`` s later, as a field of its own class
    (uniform: itself; tilted dipole on a Keplerian orbit: the orbit and the Earth
    rotation angle advanced), or None when it has no such form."""
    if isinstance(field, UniformField):
        return field
    if isinstance(field, TiltedDipoleField) and isinstance(field.orbit, KeplerOrbit):
        return TiltedDipoleField(_advance(field.orbit, dt), moment=field.moment,
                                 tilt=field.tilt, pole_longitude=field.pole_longitude,
                                 rotation_angle=field.rotation_angle
                                 + field.rotation_rate * dt,
                                 rotation_rate=field.rotation_rate)
    return None


class MagneticDipole(TorqueModel):
    """Torque of a residual magnetic dipole fixed in the body: ``M = m x B``.

    .. math::

        M = m \\times B_b, \\qquad V = -\\,m \\cdot B_b

    with ``m`` the body's magnetic moment (A m^2, body frame: the net moment of its
    current loops and magnetised parts, magnetorquers off) and ``B_b`` the field at the
    body in body axes (the inertial field rotated by the attitude,
    ``B_b = q^{-1} B q``).  The torque depends on the attitude and the time only
    (``velocity_dependent = False``: an exact kick in the splitting integrator) and
    turns ``m`` toward ``B`` like a compass needle: in a uniform field it derives from
    the potential ``V`` (:meth:`potential`), and a small swing of ``m`` about ``B``
    about a principal axis of moment ``I`` normal to both oscillates at
    ``sqrt(|m| |B| / I)``.  Satellites carry residual dipoles of order 0.1-1 A m^2
    (an assumption unless measured: Inamori et al. 2011 estimate one in flight), which
    in a LEO field of 2e-5-5.5e-5 T gives torques up to ``|m| |B|`` ~ 2e-6-5e-5 N m.

    Parameters
    ----------
    moment : (3,) array-like, Quantity or ``{value, unit}``
        Magnetic moment, A m^2, body frame.
    field : callable ``t -> (..., 3)`` T, or (3,) array
        Inertial magnetic field at the body: :class:`UniformField`,
        :class:`TiltedDipoleField` along an orbit, :class:`attitude.environment.IGRF`,
        any function, or a constant vector.

    References
    ----------
    .. [1] Wertz, J. R. (ed.) (1978). *Spacecraft Attitude Determination and Control*.
       Reidel (environmental torques: the magnetic disturbance torque).
    .. [2] Inamori, T., Sako, N. & Nakasuka, S. (2011). Magnetic dipole moment
       estimation and compensation for an accurate attitude control in nano-satellite
       missions. *Acta Astronautica* 68, 2038-2046.

    Examples
    --------
    >>> import numpy as np
    >>> from attitude import RigidBody
    >>> from attitude.model.torques import MagneticDipole, UniformField
    >>> body = RigidBody.from_principal_moments([0.02, 0.03, 0.04])
    >>> needle = MagneticDipole({"value": [0.5, 0.0, 0.0], "unit": "A m2"},
    ...                         UniformField([0.0, 3e-5, 0.0]))
    >>> needle(0.0, [0, 0, 0, 1], [0.0, 0.0, 0.0], body)      # m x B, about +z
    array([0.0e+00, 0.0e+00, 1.5e-05])
    >>> float(needle.potential(0.0, [0, 0, 0, 1], body))      # m normal to B
    0.0
    """

    velocity_dependent = False

    def __init__(self, moment, field):
        self.moment = _quantity(moment, "A m2", "moment", shape=(3,))
        if field is None:
            raise TorqueConfigError("a magnetic dipole needs the field: give a "
                                    "UniformField, a TiltedDipoleField, an IGRF, a "
                                    "callable t -> B (T) or a vector", key="field")
        self.field = field if callable(field) else UniformField(field)

    def evaluate(self, t, quaternion, omega_body, body):
        B = quat.rotate(quaternion, np.asarray(self.field(t), dtype=float), inverse=True)
        return quat.cross(self.moment, B)

    def potential(self, t, quaternion, body=None) -> np.ndarray:
        """Magnetic potential energy ``V = -m . B_b``, J: lowest with ``m`` along ``B``.
        ``E_kin + V`` is conserved when the field is fixed in inertial space.

        Examples
        --------
        >>> from attitude.model.torques import MagneticDipole
        >>> float(MagneticDipole([1.0, 0.0, 0.0], [2e-5, 0.0, 0.0]).potential(
        ...     0.0, [0, 0, 0, 1]))
        -2e-05
        """
        t = np.asarray(t, dtype=float)
        q = _unit_quaternion(quaternion)
        B = quat.rotate(q, np.asarray(self.field(t), dtype=float), inverse=True)
        return -_dot(np.broadcast_to(self.moment, B.shape), B)

    def characteristic_rate(self, t, quaternion, omega_body, body):
        """``sqrt(|m| |B(t)| / A)``, rad/s: the compass libration rate (``A`` the least
        moment), or the orbital rate of a field along an orbit if faster (the rate at
        which the field turns).

        Examples
        --------
        >>> from attitude import RigidBody
        >>> from attitude.model.torques import MagneticDipole
        >>> body = RigidBody.from_principal_moments([1.0, 1.5, 2.0])
        >>> float(MagneticDipole([0.0, 0.0, 2.0], [0.0, 0.0, 4e-5]).characteristic_rate(
        ...     0.0, [0, 0, 0, 1], [0.0, 0.0, 0.0], body))           # sqrt(2 * 4e-5 / 1.0)
        0.008944271909999159
        """
        field = np.asarray(self.field(np.asarray(t, dtype=float)), dtype=float)
        strength = float(np.linalg.norm(self.moment)) * np.sqrt(_dot(field, field))
        rate = np.sqrt(strength / _moments_of(body)[..., 0])
        orbit = getattr(self.field, "orbit", None)
        if orbit is not None:
            rate = np.maximum(rate, _orbit_rate(orbit))
        return float(rate) if np.ndim(rate) == 0 else rate

    def shifted(self, dt: float) -> TorqueModel:
        """Itself in a uniform field; in a tilted dipole on a Keplerian orbit, the same
        model with the orbit and the Earth rotation angle advanced by ``dt``; else (IGRF,
        a function) the default wrapper.

        Examples
        --------
        >>> from attitude.model.torques import MagneticDipole, UniformField
        >>> m = MagneticDipole([1.0, 0.0, 0.0], UniformField([0.0, 0.0, 3e-5]))
        >>> m.shifted(60.0) is m
        True
        """
        dt = float(dt)
        if dt == 0.0:
            return self
        field = _shifted_field(self.field, dt)
        if field is self.field:
            return self
        if field is not None:
            return MagneticDipole(self.moment, field)
        return super().shifted(dt)

    def compiled_parameters(self, body, t_span=None) -> list[tuple[str, dict]] | None:
        """``[("magnetic_dipole", {moment, field})]``, or None when the field has no
        compiled form (a user's function) (:meth:`TorqueModel.compiled_parameters`).

        Examples
        --------
        >>> from attitude.model.torques import MagneticDipole, UniformField
        >>> model = MagneticDipole([0.3, 0.0, 0.0], UniformField([0, 0, 3e-5]))
        >>> [(kind, sorted(v)) for kind, v in model.compiled_parameters(None)]
        [('magnetic_dipole', ['field', 'moment'])]
        """
        if not callable(getattr(self.field, "compiled_parameters", None)):
            return None
        return [("magnetic_dipole", {"moment": self.moment.copy(), "field": self.field})]

    def __repr__(self) -> str:
        return f"MagneticDipole(moment={self.moment.tolist()} A m2, field={self.field!r})"


# --- heavy top -------------------------------------------------------------------------


class HeavyTopPivot(TorqueModel):
    """Uniform gravity acting on a body that turns about a fixed pivot (the heavy top).

    .. math::

        M = l \\times (-m g\\, \\hat u_b) = m g\\, \\hat u_b \\times l

    with ``l`` the body-frame vector from the pivot to the centre of mass and ``hat u_b``
    the inertial "up" direction in body axes.  **The body's inertia must be the inertia
    about the pivot** (``I_pivot = I_cm + m (|l|^2 1 - l l^T)``, e.g.
    ``MassProperties.inertia_about(pivot)``), since Euler's equations are then written
    about the fixed point.

    For a symmetric top (``I1`` about the pivot, ``I3`` about the axis ``l``), steady
    precession at rate ``Omega`` with the axis at angle ``theta`` from up and spin
    component ``ω3`` requires ``m g l = Omega (I3 ω3 - I1 Omega cos theta)``; for a fast
    top ``Omega ~= m g l / (I3 ω3)`` (Goldstein, Poole & Safko 2002, Sec. 5.7).

    Parameters
    ----------
    mass : float (kg), Quantity or str, optional
        Default: ``body.mass``.
    pivot_to_com : (3,) array-like, Quantity or ``{value, unit}``
        Pivot -> centre of mass, body frame, m.
    g : float (m/s^2)
        Default :data:`STANDARD_GRAVITY`.
    up : (3,) array-like
        Inertial direction opposite to gravity (normalised).

    References
    ----------
    .. [1] Goldstein, H., Poole, C. & Safko, J. (2002). *Classical Mechanics*, 3rd ed.
       Addison-Wesley. Sec. 5.7 (heavy symmetrical top).

    Examples
    --------
    >>> import numpy as np
    >>> from attitude import RigidBody
    >>> from attitude.model.torques import HeavyTopPivot
    >>> top = HeavyTopPivot(mass=1.0, pivot_to_com=[0.0, 0.0, 0.1])   # 10 cm up the axis
    >>> body = RigidBody.from_principal_moments([0.02, 0.02, 0.01])
    >>> tilted = [np.sin(0.25), 0.0, 0.0, np.cos(0.25)]               # axis 0.5 rad from up
    >>> round(float(np.linalg.norm(top(0.0, tilted, [0, 0, 50.0], body))), 6)   # m g l sin
    0.47016
    """

    velocity_dependent = False

    def __init__(self, mass=None, pivot_to_com=None, g=STANDARD_GRAVITY, up=(0.0, 0.0, 1.0)):
        self.mass = None if mass is None else _positive(mass, "kg", "mass")
        if pivot_to_com is None:
            raise TorqueConfigError("give the vector from the pivot to the "
                                    "centre of mass (body frame, m)", key="pivot_to_com")
        self.pivot_to_com = _quantity(pivot_to_com, "m", "pivot_to_com", shape=(3,))
        self.g = _positive(g, "m/s2", "g")
        up = _quantity(up, "", "up", shape=(3,))
        norm = float(np.linalg.norm(up))
        if norm == 0:
            raise TorqueConfigError("must be a non-zero vector", key="up")
        self.up = up / norm

    def evaluate(self, t, quaternion, omega_body, body):
        mass = self.mass if self.mass is not None else _mass_of(body)
        if mass is None:
            raise TorqueConfigError("the body has no mass: give HeavyTopPivot a "
                                    "mass, or build the body with one", key="mass")
        up_b = quat.rotate(quaternion, self.up, inverse=True)
        return np.asarray(mass)[..., None] * self.g * quat.cross(up_b, self.pivot_to_com)

    def characteristic_rate(self, t, quaternion, omega_body, body):
        """``sqrt(m g |l| / I_swing)``, rad/s: the small-swing pendulum frequency
        (``I_swing`` the least moment about an axis normal to ``l``: the torque is always
        normal to ``l``), the time scale of a slow top; a fast top precesses more slowly,
        at about ``m g l / |L|``, and the splitting step adds how fast the torque changes
        along its nutation.

        Examples
        --------
        >>> import numpy as np
        >>> from attitude import RigidBody
        >>> from attitude.model.torques import HeavyTopPivot
        >>> top = RigidBody(np.diag([9.5e-4, 9.5e-4, 2.0e-4]), mass=0.5)
        >>> pivot = HeavyTopPivot(pivot_to_com=[0.0, 0.0, 0.04])
        >>> round(pivot.characteristic_rate(0.0, [0, 0, 0, 1], [0, 0, 0.0], top), 3)
        14.369
        """
        mass = self.mass if self.mass is not None else _mass_of(body)
        if mass is None:
            raise TorqueConfigError("the body has no mass: give HeavyTopPivot a "
                                    "mass, or build the body with one", key="mass")
        length = float(np.linalg.norm(self.pivot_to_com))
        mgl = np.asarray(mass, dtype=float) * self.g * length
        inertia = _inertia_of(body)
        axis = self.pivot_to_com / length
        normal = np.eye(3) - np.outer(axis, axis)            # directions of the torque
        A = 1.0 / np.linalg.norm(np.linalg.inv(inertia) @ normal, ord=2, axis=(-2, -1))
        rate = np.sqrt(mgl / A)
        return float(rate) if np.ndim(rate) == 0 else rate

    def compiled_parameters(self, body, t_span=None) -> list[tuple[str, dict]]:
        """``[("heavy_top", {mass_g, up, pivot_to_com})]`` (``mass_g = m g``, the mass
        from the body when not given) (:meth:`TorqueModel.compiled_parameters`).

        Raises
        ------
        TorqueConfigError
            If neither the model nor the body has a mass.

        Examples
        --------
        >>> from attitude.model.torques import HeavyTopPivot
        >>> top = HeavyTopPivot(mass=2.0, pivot_to_com=[0.0, 0.0, 0.1], g=10.0)
        >>> top.compiled_parameters(None)[0][1]["mass_g"]
        20.0
        """
        mass = self.mass if self.mass is not None else _mass_of(body)
        if mass is None or np.ndim(mass) != 0:
            raise TorqueConfigError("the body has no mass: give HeavyTopPivot a "
                                    "mass, or build the body with one", key="mass")
        return [("heavy_top", {"mass_g": float(mass) * self.g,
                               "up": self.up.copy(),
                               "pivot_to_com": self.pivot_to_com.copy()})]

    def shifted(self, dt: float) -> HeavyTopPivot:
        """Itself (no time dependence)."""
        return self

    def __repr__(self) -> str:
        mass = "body.mass" if self.mass is None else f"{self.mass:.6g} kg"
        return (f"HeavyTopPivot(mass={mass}, pivot_to_com={self.pivot_to_com.tolist()} m, "
                f"g={self.g:.6g})")


# --- scenario tables -------------------------------------------------------------------

#: An inline orbit table ``orbit = { a = "7000 km", e = 0.0, ... }``.
ORBIT_TABLE = Table("orbit", (
    Key("a", "quantity", unit="m", positive=True, doc="semi-major axis"),
    Key("e", "quantity", unit="", bounds=(0.0, None), default=0,
        doc="eccentricity, 0 <= e < 1"),
    Key("i", "quantity", unit="rad", default=0, doc="inclination"),
    Key("raan", "quantity", unit="rad", default=0,
        doc="right ascension of the ascending node"),
    Key("argp", "quantity", unit="rad", default=0, doc="argument of periapsis"),
    Key("mean_anomaly", "quantity", unit="rad", default=0, doc="mean anomaly at `epoch`"),
    Key("epoch", "time", doc="when `mean_anomaly` holds; default the scenario epoch"),
    Key("tle", "any", schema={"type": "array", "items": {"type": "string"}, "minItems": 2,
                              "maxItems": 2},
        doc="a two-line element set instead of the elements: SGP4 in GCRF (in the [state] "
            "frame for solar_radiation and drag; attitude.environment.TLEOrbit; t = 0 at "
            "the scenario epoch)"),
), exactly_one=(("a", "tle"),),
    excludes=(("tle", ("e", "i", "raan", "argp", "mean_anomaly", "epoch")),),
    doc="The body's orbit about the primary, inertial frame: Keplerian elements, or a "
        "two-line element set")

#: Builders of the orbit and field sources that live in a wing
#: (:mod:`attitude.environment` registers ``"tle"`` and ``"igrf"`` when imported):
#: ``ORBIT_SOURCES["tle"](lines, base_epoch)`` and
#: ``FIELD_SOURCES["igrf"](orbit, base_epoch, max_degree)``.
ORBIT_SOURCES: dict[str, Callable] = {}
FIELD_SOURCES: dict[str, Callable] = {}

_FIELD_TABLE = Table("field", (
    Key("model", "string", choices=("dipole", "uniform", "igrf"), default="dipole",
        doc="the Earth's tilted dipole along `orbit`, a uniform field, or IGRF-14 along "
            "`orbit` (attitude.environment.IGRF; `field = \"igrf\"` for short)"),
    Key("max_degree", "integer", bounds=(1, 13), default=13, doc="IGRF: highest degree"),
    Key("moment", "quantity", unit="A m2", positive=True, doc="dipole moment"),
    Key("tilt", "quantity", unit="rad", doc="dipole tilt from the inertial z axis"),
    Key("pole_longitude", "quantity", unit="rad", doc="longitude of the dipole pole"),
    Key("rotation_angle", "quantity", unit="rad",
        doc="Earth rotation angle at t = 0; default from the scenario epoch"),
    Key("rotation_rate", "quantity", unit="rad/s", doc="Earth rotation rate"),
    Key("vector", "quantity", unit="T", shape=(3,), doc="uniform field, inertial frame"),
), excludes=(("vector", ("moment", "tilt", "pole_longitude", "rotation_angle",
                          "rotation_rate", "max_degree")),))

#: The keys of each ``[[torques]]`` type (``type`` selects the table).
TORQUE_TABLES: dict[str, Table] = {t.name: t for t in (
    Table("gravity_gradient", (
        Key("mu", "quantity", unit="m3/s2", required=True, positive=True,
            doc="gravitational parameter of the primary"),
        Key("orbit", "table", required=True, table=ORBIT_TABLE, doc=ORBIT_TABLE.doc),
    ), doc="Point-mass primary: `3 mu / r^5 (r x I r)`."),
    Table("constant", (
        Key("torque", "quantity", unit="N m", shape=(3,), required=True, doc="the torque"),
        Key("frame", "string", choices=("body", "inertial"), default="body",
            doc="axes of `torque`"),
    ), doc="A fixed torque in body or inertial axes."),
    Table("dissipation", (
        Key("time_constant", "quantity", unit="s", required=True, positive=True,
            doc="e-folding time of the excess energy"),
    ), doc="Internal energy dissipation (damper, fuel slosh); the inertial L is kept."),
    Table("eddy_current", (
        Key("magnetic_tensor", "quantity", unit="S m4", shape=((), (3, 3)),
            doc="magnetic tensor, body frame (scalar: isotropic)"),
        Key("shell", "table", table=Table("shell", (
            Key("radius", "quantity", unit="m", required=True, positive=True),
            Key("thickness", "quantity", unit="m", required=True, positive=True),
            Key("conductivity", "quantity", unit="S/m", required=True, positive=True))),
            doc="thin conducting spherical shell"),
        Key("sphere", "table", table=Table("sphere", (
            Key("radius", "quantity", unit="m", required=True, positive=True),
            Key("conductivity", "quantity", unit="S/m", required=True, positive=True))),
            doc="solid conducting sphere"),
        Key("field", "any",
            schema={"oneOf": [{"type": "string", "enum": ["dipole", "igrf", "uniform"]},
                              json_schema(_FIELD_TABLE, root=False)]},
            doc="the magnetic field: a table, or the model name (\"igrf\"); default the "
                "Earth's tilted dipole"),
        Key("mu", "quantity", unit="m3/s2", positive=True,
            doc="gravitational parameter of the primary (dipole field); default the Earth's"),
        Key("orbit", "table", table=ORBIT_TABLE, doc=ORBIT_TABLE.doc + " (dipole field)"),
    ), exactly_one=(("magnetic_tensor", "shell", "sphere"),),
        doc="Eddy currents induced by a magnetic field: `(M (w x B)) x B`."),
    Table("heavy_top", (
        Key("pivot_to_com", "quantity", unit="m", shape=(3,), required=True,
            doc="pivot -> centre of mass, body frame"),
        Key("mass", "quantity", unit="kg", positive=True, doc="default the body's mass"),
        Key("g", "quantity", unit="m/s2", positive=True, doc="gravity; default 9.80665"),
        Key("up", "quantity", unit="", shape=(3,), doc="inertial unit vector, up"),
    ), doc="Uniform gravity about a fixed pivot."),
)}
# a residual magnetic dipole: the field keys are eddy_current's (one field reader)
TORQUE_TABLES["magnetic_dipole"] = Table("magnetic_dipole", (
    Key("moment", "quantity", unit="A m2", shape=(3,), required=True,
        doc="magnetic moment, body frame"),
    *(TORQUE_TABLES["eddy_current"][name] for name in ("field", "mu", "orbit")),
), doc="A body-fixed (residual) magnetic dipole in a magnetic field: `m x B`.")

def _orbit_from_table(table, mu: float, key: str, base_epoch) -> KeplerOrbit:
    """A validated :data:`ORBIT_TABLE` (SI values; ``epoch`` an astropy Time) -> orbit."""
    if "tle" in table:
        if "tle" not in ORBIT_SOURCES:
            raise TorqueConfigError("a TLE orbit needs attitude.environment (import "
                                    "attitude)", key=f"{key}.tle")
        try:
            return ORBIT_SOURCES["tle"](table["tle"], base_epoch)
        except OrbitError as err:
            raise TorqueConfigError(err.reason, key=f"{key}.{err.key}") from None
    elements = {k: table[k] for k in ORBIT_TABLE.names() if k in table and k != "epoch"}
    try:
        orbit = KeplerOrbit(mu=mu, **elements)
    except OrbitError as err:
        raise TorqueConfigError(err.reason, key=f"{key}.{err.key}") from None
    if "epoch" in table:
        if base_epoch is None:
            raise TorqueConfigError("an orbit epoch needs the scenario epoch "
                                    "(from_config(..., base_epoch=...))", key=f"{key}.epoch")
        dt = float((base_epoch - table["epoch"]).to_value(u.s))
        orbit = KeplerOrbit(orbit.mu, orbit.a, orbit.e, orbit.i, orbit.raan, orbit.argp,
                            orbit.mean_anomaly + orbit.mean_motion * dt)
    return orbit


def _earth_rotation_angle(epoch) -> float:
    """Earth rotation angle (IAU 2000) at ``epoch``, with UT1 ~ UTC (|UT1 - UTC| < 0.9 s,
    4e-4 deg; beyond the leap-second table the last TAI - UTC is used, without the
    "dubious year" warning)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", erfa.ErfaWarning)
        utc = epoch.utc
    return float(erfa.era00(utc.jd1, utc.jd2))


def _gravity_gradient(table, base_epoch):
    mu = table["mu"]
    return GravityGradient(mu, _orbit_from_table(table["orbit"], mu, "orbit", base_epoch))


def _constant(table, base_epoch):
    return ConstantTorque(table["torque"], frame=table.get("frame", "body"))


def _dissipation(table, base_epoch):
    _check_keys(table, ("type", "time_constant"), "")
    if "time_constant" not in table:
        raise TorqueConfigError("missing: give the e-folding time of the "
                                "excess energy, e.g. \"30 min\"", key="time_constant")
    return EnergyDissipation(table["time_constant"])


_FIELD_KEYS = {"dipole": ("model", "moment", "tilt", "pole_longitude", "rotation_angle",
                          "rotation_rate"),
               "uniform": ("model", "vector"),
               "igrf": ("model", "max_degree")}


def _prefixed(prefix: str, build: Callable, *args, **kwargs):
    """Call ``build``; re-raise its :class:`TorqueConfigError` under ``prefix.key``."""
    try:
        return build(*args, **kwargs)
    except TorqueConfigError as err:
        raise TorqueConfigError(err.reason, key=f"{prefix}.{err.key}") from None


def _field_from_table(table, base_epoch):
    field_table = table.get("field", {"model": "dipole"})
    if isinstance(field_table, str):                 # field = "igrf": the model by name
        field_table = {"model": field_table}
    field_table = validate(field_table, _FIELD_TABLE, where="field", error=TorqueConfigError)
    model = field_table.get("model", "dipole")
    _check_keys(field_table, _FIELD_KEYS[model], "field")
    if model == "uniform":
        for key in ("orbit", "mu"):
            if key in table:
                raise TorqueConfigError("not used by a uniform field; remove it", key=key)
        if "vector" not in field_table:
            raise TorqueConfigError("missing: give { value = [x, y, z], "
                                    "unit = \"nT\" }", key="field.vector")
        return UniformField(field_table["vector"])
    if "orbit" not in table:
        raise TorqueConfigError("missing: the dipole field is evaluated along the "
                                "body's orbit (or use field.model = \"uniform\")", key="orbit")
    mu = table.get("mu", EARTH_MU)
    orbit = _orbit_from_table(table["orbit"], mu, "orbit", base_epoch)
    if model == "igrf":
        if base_epoch is None:
            raise TorqueConfigError("the IGRF field needs the scenario epoch", key="field")
        try:
            return FIELD_SOURCES["igrf"](orbit, base_epoch, field_table.get("max_degree", 13))
        except OrbitError as err:
            raise TorqueConfigError(err.reason, key=f"field.{err.key}") from None
    kwargs = {k: field_table[k] for k in _FIELD_KEYS["dipole"][1:] if k in field_table}
    if "rotation_angle" not in kwargs and base_epoch is not None:
        kwargs["rotation_angle"] = _earth_rotation_angle(base_epoch)
    return _prefixed("field", TiltedDipoleField, orbit, **kwargs)


def _eddy_current(table, base_epoch):
    field = _field_from_table(table, base_epoch)
    if "magnetic_tensor" in table:
        return EddyCurrentDamping(table["magnetic_tensor"], field)
    if "shell" in table:
        spec = table["shell"]
        return _prefixed("shell", EddyCurrentDamping.spherical_shell, spec["radius"],
                         spec["thickness"], spec["conductivity"], field)
    spec = table["sphere"]
    return _prefixed("sphere", EddyCurrentDamping.solid_sphere, spec["radius"],
                     spec["conductivity"], field)


def _magnetic_dipole(table, base_epoch):
    return MagneticDipole(table["moment"], _field_from_table(table, base_epoch))


def _heavy_top(table, base_epoch):
    kwargs = {k: table[k] for k in ("mass", "g", "up") if k in table}
    return HeavyTopPivot(pivot_to_com=table["pivot_to_com"], **kwargs)


#: ``type`` values of scenario ``[[torques]]`` tables and their builders
#: ``build(values, base_epoch)``.
TORQUE_TYPES: dict[str, Callable] = {
    "gravity_gradient": _gravity_gradient,
    "constant": _constant,
    "dissipation": _dissipation,
    "eddy_current": _eddy_current,
    "heavy_top": _heavy_top,
    "magnetic_dipole": _magnetic_dipole,
}


@dataclasses.dataclass(frozen=True, eq=False)
class BuildContext:
    """What a ``[[torques]]`` builder may need beyond its own table.

    A scenario builds one context and passes it to every torque table it reads
    (:func:`from_config`); builders registered with :func:`register_torque_type` receive
    it whole, the built-in ones its ``epoch``.

    Parameters
    ----------
    epoch : astropy Time, optional
        The scenario epoch, ``t = 0``.
    frame : str
        Inertial frame of the states (the ``[state]`` frame).
    folder : path-like, optional
        Folder of the scenario file: file names in torque tables are relative to it.
    body : RigidBody, optional
        The scenario's body (its centre of mass: torques are taken about it).
    shape : str, optional
        The ``[body] shape`` file name (relative to ``folder``), when the body was given
        by a shape model.
    length_unit : str
        Unit of the vertex coordinates of ``shape``.

    Examples
    --------
    >>> from astropy.time import Time
    >>> ctx = BuildContext(epoch=Time("2024-03-01T00:00:00", scale="utc"), frame="GCRF")
    >>> orbit_table = {"a": 7.0e6, "e": 0.001}
    >>> ctx.orbit(orbit_table) is ctx.orbit(dict(orbit_table))   # built once, shared
    True
    """

    epoch: Any = None
    frame: str = "ICRF"
    folder: Path | None = None
    body: RigidBody | None = None
    shape: str | None = None
    length_unit: str = "m"
    _shared: dict = dataclasses.field(default_factory=dict, init=False, repr=False)

    def shared(self, key, build: Callable):
        """``build()`` the first time ``key`` is asked for, the same object after: the
        torques of one scenario share their orbit tables and the Sun's path, so each is
        tabulated once and interpolated once per integrator stage."""
        if key not in self._shared:
            self._shared[key] = build()
        return self._shared[key]

    def orbit(self, table: Mapping, *, mu: float = EARTH_MU, key: str = "orbit"):
        """The orbit of a validated ``orbit`` table (:data:`ORBIT_TABLE`): Keplerian
        elements about ``mu``, or an element set through SGP4 in :attr:`frame` (needs
        :mod:`attitude.environment`); equal tables give the same object."""
        def build():
            if "tle" in table and "tle" in ORBIT_SOURCES:
                try:
                    return ORBIT_SOURCES["tle"](table["tle"], self.epoch, self.frame)
                except OrbitError as err:
                    raise TorqueConfigError(err.reason, key=f"{key}.{err.key}") from None
            return _orbit_from_table(table, mu, key, self.epoch)
        memo = ("orbit", float(mu), tuple(sorted((k, repr(v)) for k, v in table.items())))
        return self.shared(memo, build)


#: Builders ``build(values, context)`` of the torque types a wing registers
#: (:func:`register_torque_type`); they get the whole :class:`BuildContext`.
_CONTEXT_BUILDERS: dict[str, Callable] = {}


def register_torque_type(table: Table, build: Callable) -> None:
    """Add a ``[[torques]]`` type declared outside this module (the environment wing's
    ``"solar_radiation"`` and ``"drag"``): ``table`` (its keys, named ``table.name``) is
    checked by :func:`from_config`, and ``build(values, context)`` gets the validated
    values (SI) and the :class:`BuildContext`.

    Examples
    --------
    >>> "solar_radiation" in TORQUE_TABLES       # registered by attitude.environment
    True
    """
    TORQUE_TABLES[table.name] = table
    _CONTEXT_BUILDERS[table.name] = build


def from_config(table: Mapping, *, base_epoch=None,
                context: BuildContext | None = None) -> TorqueModel:
    """Build a torque model from a scenario ``[[torques]]`` table.

    Quantities are numbers (SI), strings parsed by astropy (``"7000 km"``) or
    ``{ value = ..., unit = "..." }`` tables.

    ==================  ====================================================================
    ``type``            keys
    ==================  ====================================================================
    gravity_gradient    ``mu`` (m3/s2); ``orbit = { a, e = 0, i = 0, raan = 0, argp = 0,
                        mean_anomaly = 0, epoch }`` (``epoch``: when ``mean_anomaly``
                        holds; default the scenario epoch)
    constant            ``torque`` (N m, 3-vector); ``frame = "body" | "inertial"``
    dissipation         ``time_constant`` (s)
    eddy_current        one of ``magnetic_tensor`` (S m4, scalar or 3x3, body frame),
                        ``shell = { radius, thickness, conductivity }``,
                        ``sphere = { radius, conductivity }``; ``field = { model =
                        "dipole", moment, tilt, pole_longitude, rotation_angle,
                        rotation_rate }`` (default: the Earth's tilted dipole, with the
                        rotation angle from ``base_epoch``) with ``orbit`` and ``mu``
                        (default the Earth's), or ``field = { model = "uniform",
                        vector = {value, unit} }``
    magnetic_dipole     ``moment`` (A m2, 3-vector, body frame); ``field``, ``orbit``,
                        ``mu`` as ``eddy_current`` (``field = "igrf"`` for IGRF-14)
    heavy_top           ``pivot_to_com`` (m, body frame); ``mass`` (kg, default the
                        body's); ``g`` (m/s2); ``up`` (inertial unit vector)
    solar_radiation,    ``orbit``; ``facets`` (boxes, plates, facets) or the ``[body]``
    drag                shape, named ``materials``; registered by
                        :mod:`attitude.environment.config` (docs/environment.md)
    ==================  ====================================================================

    Parameters
    ----------
    table : mapping
        One ``[[torques]]`` table (``type`` plus the keys above).
    base_epoch : astropy Time, optional
        The scenario epoch (``t = 0``): used for ``orbit.epoch`` and the Earth rotation
        angle of the dipole field.
    context : BuildContext, optional
        What the scenario knows beyond the table (epoch, frame, folder, body); its
        ``epoch`` is used when ``base_epoch`` is not given.  The environment's types
        (``solar_radiation``, ``drag``; docs/environment.md) need it.

    Returns
    -------
    TorqueModel

    Raises
    ------
    TorqueConfigError
        (a ``ValueError``) whose message starts with the key path inside the table, e.g.
        ``"orbit.e: must be in [0, 1), got 1.2"``; unknown keys and types come with a
        did-you-mean suggestion.

    Examples
    --------
    >>> from attitude.model.torques import from_config
    >>> gg = from_config({"type": "gravity_gradient", "mu": "3.986004418e14 m3/s2",
    ...                   "orbit": {"a": "7000 km", "e": 0.0, "i": "0 deg"}})
    >>> gg
    GravityGradient(mu=3.986004418e+14, orbit=KeplerOrbit(mu=398600441800000.0, a=7000000.0, ...))
    >>> from_config({"type": "gravity_gradient", "mu": 3.986e14, "orbit": {"a": 7e6, "e": 1.2}})
    Traceback (most recent call last):
    ...
    attitude.errors.TorqueConfigError: orbit.e: must be in [0, 1), got 1.2; ...
    >>> from_config({"type": "disipation", "time_constant": "30 min"})
    Traceback (most recent call last):
    ...
    attitude.errors.TorqueConfigError: type: unknown torque type 'disipation'; did you mean ...
    """
    if not isinstance(table, Mapping):
        raise TorqueConfigError(f"expected a table with a 'type' key, got "
                                f"{type(table).__name__}", key="type")
    kinds = [*TORQUE_TYPES, *_CONTEXT_BUILDERS]
    if "type" not in table:
        raise TorqueConfigError(f"missing; choose one of {', '.join(kinds)}", key="type")
    kind = table["type"]
    if not isinstance(kind, str) or kind not in kinds:
        near = difflib.get_close_matches(kind, kinds, n=1) if isinstance(kind, str) else []
        did = f"did you mean {near[0]!r}? " if near else ""
        raise TorqueConfigError(f"unknown torque type {kind!r}; {did}choose one of "
                                f"{', '.join(kinds)}", key="type")
    if context is None:
        context = BuildContext(epoch=base_epoch)
    elif base_epoch is None:
        base_epoch = context.epoch
    orbit = table.get("orbit")
    if base_epoch is not None and isinstance(orbit, Mapping) and isinstance(
            orbit.get("epoch"), str):     # an orbit epoch is read in the scenario's scale
        table = {**table, "orbit": {**orbit, "epoch": {"value": orbit["epoch"],
                                                       "scale": base_epoch.scale}}}
    values = validate(table, TORQUE_TABLES[kind].with_keys(Key("type", "string")),
                      error=TorqueConfigError)
    if kind in _CONTEXT_BUILDERS:
        return _CONTEXT_BUILDERS[kind](values, context)
    return TORQUE_TYPES[kind](values, base_epoch)

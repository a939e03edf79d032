"""What the environment's torque models share: a time origin that can be moved, the
characteristic rate from a bound on the torque, the orbit's own rate.

:class:`EnvironmentTorque` is a :class:`attitude.model.torques.TorqueModel` whose paths
(orbit, Sun) are read at ``t + time_offset``; :meth:`EnvironmentTorque.shifted` returns a
copy with the offset moved, and :meth:`EnvironmentTorque.characteristic_rate` the
fastest rate the torque can drive: ``sqrt(|M|_max / I_min)`` (the libration rate of the
body under the largest torque the model can give) or the orbital rate, whichever is
larger.
"""

from __future__ import annotations

import copy

import numpy as np

from ..foundations.errors import TorqueConfigError
from ..model.body import RigidBody
from ..model.torques import TorqueModel

__all__ = ["EnvironmentTorque", "smallest_moment", "orbital_rate", "check_vector"]


def smallest_moment(body) -> float:
    """Smallest principal moment of inertia of a body (or of a sequence of bodies, or of
    an inertia array), kg m^2.

    Examples
    --------
    >>> smallest_moment(RigidBody.from_principal_moments([3.0, 1.0, 2.0]))
    1.0
    """
    if isinstance(body, RigidBody):
        return float(body.principal_moments[0])
    if hasattr(body, "inertia"):
        return float(np.linalg.eigvalsh(np.asarray(body.inertia, dtype=float))[0])
    if isinstance(body, np.ndarray):
        return float(np.min(np.linalg.eigvalsh(body)))
    return min(smallest_moment(b) for b in body)




def check_vector(value, key: str) -> np.ndarray:
    """A finite 3-vector, or a :class:`~attitude.foundations.errors.TorqueConfigError` naming
    ``key``.

    Examples
    --------
    >>> check_vector([0, 0, 1], "center_of_mass")
    array([0., 0., 1.])
    """
    try:
        v = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        v = np.full(2, np.nan)
    if v.shape != (3,) or not np.all(np.isfinite(v)):
        raise TorqueConfigError(f"expected a finite 3-vector (m), got {value!r}", key=key)
    return v


def orbital_rate(orbit, t) -> float:
    """Largest ``|r x v| / r^2`` (rad/s) of an orbit at times ``t``; 0 for a path without
    ``velocity``.

    Examples
    --------
    >>> from attitude.model.orbit import KeplerOrbit
    >>> orbit = KeplerOrbit.from_elements(mu=3.986004418e14, a=7.0e6, e=0.0)
    >>> bool(np.isclose(orbital_rate(orbit, 0.0), 2 * np.pi / orbit.period))
    True
    """
    if not callable(getattr(orbit, "velocity", None)):
        return 0.0
    t = np.atleast_1d(np.asarray(t, dtype=float))
    r, v = orbit.position(t), orbit.velocity(t)
    h = np.linalg.norm(np.cross(r, v), axis=-1)
    return float(np.max(h / np.sum(r * r, axis=-1)))


class EnvironmentTorque(TorqueModel):
    """Base of the environment's torque models: a movable time origin and the rate hooks.

    Subclasses read their paths at ``self.time(t)`` and implement :meth:`unit_torque`
    and :meth:`pressure_at` (the torque is their product for the attitude at hand).

    Examples
    --------
    >>> class Zero(EnvironmentTorque):
    ...     velocity_dependent = False
    ...     def evaluate(self, t, quaternion, omega_body, body):
    ...         return np.zeros(np.shape(t) + (3,))
    ...     def unit_torque(self, directions):
    ...         return np.zeros_like(directions)
    ...     def pressure_at(self, t):
    ...         return 0.0
    >>> later = Zero().shifted(60.0)
    >>> float(later.time(0.0))
    60.0
    """

    velocity_dependent = False
    time_offset: float = 0.0
    orbit = None

    def time(self, t):
        """``t`` in the time of the paths (``t + time_offset``)."""
        return t + self.time_offset if self.time_offset else t

    def shifted(self, dt: float):
        """A copy whose time origin is moved by ``dt`` s: it gives at ``t`` what this
        model gives at ``t + dt``."""
        other = copy.copy(self)
        other.time_offset = self.time_offset + float(dt)
        return other

    def unit_torque(self, directions: np.ndarray) -> np.ndarray:
        """Torque per unit pressure (m^3) when the light or the flow comes from
        ``directions`` (unit, body frame, ``(m, 3)``); subclasses implement this."""
        raise NotImplementedError

    def pressure_at(self, t) -> np.ndarray:
        """The pressure that multiplies :meth:`unit_torque` at ``t`` (N/m^2)."""
        raise NotImplementedError

    def largest_torque(self, t) -> float:
        """The largest torque over all attitudes at ``t``, N m: the pressure times the
        largest :meth:`unit_torque` over 4000 directions evenly spread on the sphere
        (a Fibonacci lattice, 3.2 deg apart; computed once)."""
        if self._largest_unit is None:
            k = np.arange(4000) + 0.5
            z = 1.0 - 2.0 * k / 4000
            phi = np.pi * (3.0 - np.sqrt(5.0)) * k
            rho = np.sqrt(1.0 - z * z)
            dirs = np.stack([rho * np.cos(phi), rho * np.sin(phi), z], axis=-1)
            self._largest_unit = float(np.max(np.linalg.norm(self.unit_torque(dirs),
                                                             axis=-1)))
        return float(np.max(self.pressure_at(t))) * self._largest_unit

    _largest_unit = None

    def characteristic_rate(self, t, quaternion, omega_body, body) -> float:
        """Fastest rate the torque drives, rad/s: ``max(sqrt(|M|_max / I_min), n)`` with
        ``|M|_max`` the :meth:`largest_torque` over attitudes and ``n`` the orbital rate
        at ``t``."""
        rate = np.sqrt(self.largest_torque(t) / smallest_moment(body))
        if self.orbit is not None:
            rate = max(rate, orbital_rate(self.orbit, self.time(t)))
        return float(rate)

"""A binary system and its state: two rigid bodies, their mutual orbit and both attitudes.

:class:`BinarySystem` holds the two bodies (each with a mass, and beyond order 2 its mass
distribution: a primitive or a shape model), the order of the mutual potential and the
inertia integrals of both.  :class:`BinaryState` holds one epoch's relative position and
velocity (the secondary's centre of mass relative to the primary's, inertial frame) and
each body's attitude (body -> inertial) and body-frame angular velocity.
:class:`Impulse` is a sudden change: a velocity change and an angular impulse on one body
(the DART impact on Dimorphos).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from astropy.time import Time
from scipy.spatial.transform import Rotation

from attitude.binary.integrals import InertiaIntegrals, inertia_integrals
from attitude.binary.mutual import MutualGravity
from attitude.foundations.constants import G as GRAVITATIONAL_CONSTANT
from attitude.foundations.errors import BinarySystemError
from attitude.foundations.quantities import DEFAULT_TIME_SCALE, to_si, to_time
from attitude.model.body import RigidBody
from attitude.model.state import as_epoch, as_omega, check_frame

__all__ = ["BinarySystem", "BinaryState", "Impulse", "BODIES", "impact_delta_v"]

#: The names of the two bodies, in the order of the ephemeris's ``body`` dimension.
BODIES = ("primary", "secondary")


@dataclass(frozen=True, eq=False)
class BinarySystem:
    """Two rigid bodies that torque each other through their mutual gravity.

    Parameters
    ----------
    primary, secondary : RigidBody
        Each with a mass.  Beyond ``order = 2`` each needs its mass distribution
        (``RigidBody.from_obj``, or ``RigidBody.from_mass_properties`` of
        ``MassProperties.solid_ellipsoid`` / ``solid_sphere``).
    order : int
        Highest total degree of the mutual potential (default 2; GUBAS's examples use 4).
    G : float
        Gravitational constant, m^3 kg^-1 s^-2 (CODATA 2018 by default).

    Raises
    ------
    BinarySystemError
        A body without a mass, or without a distribution beyond order 2.

    Examples
    --------
    >>> import attitude as att
    >>> ellipsoid = att.MassProperties.solid_ellipsoid
    >>> system = att.BinarySystem(
    ...     att.RigidBody.from_mass_properties(ellipsoid(5.2e11, [425.0, 410.0, 390.0])),
    ...     att.RigidBody.from_mass_properties(ellipsoid(4.3e9, [103.16, 79.35, 66.13])),
    ...     order=4)
    >>> system.order, f"{system.reduced_mass:.4g}"
    (4, '4.265e+09')
    """

    primary: RigidBody
    secondary: RigidBody
    order: int = 2
    G: float = GRAVITATIONAL_CONSTANT
    integrals: tuple[InertiaIntegrals, InertiaIntegrals] = field(init=False, repr=False)

    #: ``att.propagate(system, ...)`` runs this wing's propagator
    #: (:data:`attitude.foundations.lazy.WING_METHODS`).
    wing_propagator = "propagate.BinarySystem"

    def __post_init__(self):
        for name in BODIES:
            if not isinstance(getattr(self, name), RigidBody):
                raise BinarySystemError(f"{name}: expected a RigidBody, got "
                                        f"{type(getattr(self, name)).__name__}")
        G = to_si(self.G, "m3 / (kg s2)", name="G", shape=(), positive=True,
                  error=BinarySystemError)
        object.__setattr__(self, "G", float(G))
        integrals = tuple(inertia_integrals(getattr(self, name), self.order, name=name)
                          for name in BODIES)
        object.__setattr__(self, "integrals", integrals)

    @property
    def gravity(self) -> MutualGravity:
        return MutualGravity(self.order, self.G)

    @property
    def masses(self) -> np.ndarray:
        """kg, primary then secondary."""
        return np.array([self.primary.mass, self.secondary.mass])

    @property
    def reduced_mass(self) -> float:
        m1, m2 = self.masses
        return m1 * m2 / (m1 + m2)

    @property
    def mu(self) -> float:
        """``G (m1 + m2)``, m^3/s^2: the Keplerian parameter of the mutual orbit."""
        return self.G * float(self.masses.sum())


@dataclass(frozen=True, eq=False)
class BinaryState:
    """The state of a binary system at one epoch.

    Parameters
    ----------
    epoch : astropy Time or str (ISO 8601, TDB)
    position, velocity : (3,) array-like or Quantity
        The secondary's centre of mass relative to the primary's, inertial frame,
        m and m/s.
    primary_attitude, secondary_attitude : scipy Rotation
        Body -> inertial.
    primary_omega, secondary_omega : (3,) array-like or Quantity
        Angular velocities in each body's frame, rad/s.
    frame : str
        The inertial frame's label (default ``"ICRF"``).

    Examples
    --------
    >>> import numpy as np, astropy.units as u, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> state = att.BinaryState("2022-09-26T23:14:00", position=[1.19, 0, 0] * u.km,
    ...                         velocity=[0, 0.17, 0] * u.m / u.s,
    ...                         primary_attitude=Rotation.identity(),
    ...                         primary_omega=[0, 0, 2 * np.pi / 8136.0],
    ...                         secondary_attitude=Rotation.identity(),
    ...                         secondary_omega=[0, 0, 2 * np.pi / 42912.0])
    >>> state.position, state.epoch.scale
    (array([1190.,    0.,    0.]), 'tdb')
    """

    epoch: Time
    position: np.ndarray
    velocity: np.ndarray
    primary_attitude: Rotation
    primary_omega: np.ndarray
    secondary_attitude: Rotation
    secondary_omega: np.ndarray
    frame: str = "ICRF"

    def __post_init__(self):
        object.__setattr__(self, "epoch", as_epoch(self.epoch, error=BinarySystemError))
        for key, unit in (("position", "m"), ("velocity", "m/s")):
            v = np.array(to_si(getattr(self, key), unit, name=key, error=BinarySystemError),
                         dtype=float)
            if v.shape != (3,):
                raise BinarySystemError(f"{key}: expected 3 components, got shape {v.shape}")
            object.__setattr__(self, key, v)
        if not np.any(self.position):
            raise BinarySystemError("position: the two centres of mass coincide; give the "
                                    "secondary's position relative to the primary")
        for name in BODIES:
            rot = getattr(self, f"{name}_attitude")
            if not isinstance(rot, Rotation) or not rot.single:
                raise BinarySystemError(
                    f"{name}_attitude: expected a single scipy Rotation (body -> inertial), "
                    f"got {type(rot).__name__}")
            object.__setattr__(self, f"{name}_omega",
                               as_omega(getattr(self, f"{name}_omega"),
                                        name=f"{name}_omega", error=BinarySystemError))
        object.__setattr__(self, "frame", check_frame(self.frame, error=BinarySystemError))

    @property
    def quaternions(self) -> np.ndarray:
        """(2, 4): both attitudes, body -> inertial, scalar-last."""
        return np.array([self.primary_attitude.as_quat(), self.secondary_attitude.as_quat()])

    @property
    def omegas(self) -> np.ndarray:
        """(2, 3): both body-frame angular velocities, rad/s."""
        return np.array([self.primary_omega, self.secondary_omega])


@dataclass(frozen=True, eq=False)
class Impulse:
    """A sudden change of one body's motion at ``time``: a velocity change of its centre
    of mass and an angular impulse about it (both inertial frame).

    Parameters
    ----------
    time : float (s since the state's epoch), Quantity, or astropy Time / ISO string
    body : {"primary", "secondary"}
    delta_v : (3,) array-like or Quantity, optional
        m/s, the body's velocity change (the other body's is unchanged, so the relative
        velocity changes by ``delta_v`` for the secondary, ``-delta_v`` for the primary).
    angular_impulse : (3,) array-like or Quantity, optional
        N m s (kg m^2/s), added to the body's angular momentum.

    Examples
    --------
    The DART impact: 580 kg at 6.1 km/s with a momentum enhancement beta = 3.6 on a
    4.3e9 kg Dimorphos, along -x:

    >>> import attitude as att
    >>> dv = 3.6 * 580.0 * 6145.0 / 4.3e9
    >>> kick = att.Impulse("2022-09-26T23:14:24", body="secondary", delta_v=[-dv, 0, 0])
    >>> f"{kick.delta_v[0] * 1e3:.2f} mm/s"
    '-2.98 mm/s'
    """

    time: object
    body: str = "secondary"
    delta_v: np.ndarray = field(default_factory=lambda: np.zeros(3))
    angular_impulse: np.ndarray = field(default_factory=lambda: np.zeros(3))

    def __post_init__(self):
        if not isinstance(self.body, str) or self.body not in BODIES:
            raise BinarySystemError(f"body: expected 'primary' or 'secondary', got "
                                    f"{self.body!r}")
        object.__setattr__(self, "time", _impulse_time(self.time))
        for key, unit in (("delta_v", "m/s"), ("angular_impulse", "kg m2 / s")):
            v = np.array(to_si(getattr(self, key), unit, name=key, error=BinarySystemError),
                         dtype=float)
            if v.shape != (3,):
                raise BinarySystemError(f"{key}: expected 3 components, got shape {v.shape}")
            object.__setattr__(self, key, v)

    def seconds_after(self, epoch: Time) -> float:
        """The impulse's time in seconds after ``epoch`` (TDB)."""
        if isinstance(self.time, Time):
            return float((self.time.tdb - epoch.tdb).to_value("s"))
        return self.time


def _impulse_time(value) -> float | Time:
    """An impulse's time, checked when it is made: a scalar Time (a string is read as
    ISO 8601, TDB) or a finite number of seconds (a float, or a Quantity of time)."""
    if isinstance(value, (Time, str)):
        if isinstance(value, str):
            value = to_time(value, scale=DEFAULT_TIME_SCALE, key="time",
                            error=BinarySystemError, precision=None)
        if not value.isscalar:
            raise BinarySystemError(f"time: expected a single time, got an array of shape "
                                    f"{value.shape}")
        return value
    return float(to_si(value, "s", name="time", shape=(), error=BinarySystemError))


def impact_delta_v(impactor_mass: float, impactor_velocity, beta: float, body_mass: float,
                   ejecta_direction=None) -> np.ndarray:
    """A kinetic impact's velocity change of the body, m/s (Cheng et al. 2023, eq. 1):
    ``M dv = m U + m (beta - 1) (E . U) E``, with ``E`` the ejecta's direction (default:
    the impactor's, so ``dv = beta m U / M``).

    Examples
    --------
    >>> impact_delta_v(580.0, [0.0, -6145.0, 0.0], 3.61, 4.3e9).round(7).tolist()
    [0.0, -0.0029923, 0.0]
    """
    U = np.asarray(impactor_velocity, dtype=float)
    E = U if ejecta_direction is None else np.asarray(ejecta_direction, dtype=float)
    norm = np.linalg.norm(E)
    if not norm > 0:
        return impactor_mass * U / body_mass
    E = E / norm
    return impactor_mass * (U + (beta - 1) * (E @ U) * E) / body_mass

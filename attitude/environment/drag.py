"""Aerodynamic drag in free-molecular flow on the facets of a spacecraft, and its torque.

Above ~150 km the mean free path exceeds the size of a satellite and each facet feels
the molecules it intercepts independently (flat-plate, free-molecular model; Wertz 1978,
Sec. 17.2; Vallado 2013, Sec. 8.6.2): a facet of area ``A`` whose outward normal ``n``
makes ``cos(theta) = n . v_hat > 0`` with the velocity relative to the air receives

.. math::

    F = -\\tfrac12 \\rho v^2 C_D A \\cos\\theta\\, \\hat v

and facets facing away receive nothing (no shadowing of one facet by another: exact
for a convex body).  The air co-rotates with the Earth: ``v = v_orbit - omega_E x r``
(inertial frame with ``z`` along the Earth's axis).  The torque about the centre of mass
is ``M = -1/2 rho v^2 C_D (sum_k A_k c_k r_k) x v_hat``.

:class:`ExponentialAtmosphere` is Vallado's piecewise-exponential density model (2013,
Table 8-4, after CIRA-72 / the US Standard Atmosphere 1976): a base altitude, nominal
density and scale height per layer, ``rho = rho_0 exp(-(h - h_0) / H)``.  Any callable
``altitude (m) -> density (kg/m^3)`` can replace it.  A model that depends on the time
and the place as well gives the density along the orbit through an ``along(orbit,
epoch=, frame=)`` method returning a function of ``t``: NRLMSIS,
:class:`~attitude.environment.msis.MSISAtmosphere` (``pymsis``, the ``msis`` extra).

References
----------
.. [1] D. A. Vallado, *Fundamentals of Astrodynamics and Applications*, 4th ed.,
   Microcosm (2013), Sec. 8.6.2, Table 8-4.
.. [2] J. R. Wertz (ed.), *Spacecraft Attitude Determination and Control*, Reidel
   (1978), Sec. 17.2 and App. L.
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass, field

import numpy as np

from ..foundations import quaternion as quat
from ..foundations.constants import EARTH_ROTATION_RATE
from ..foundations.errors import TorqueConfigError
from ..foundations.quantities import to_si
from ..model.orbit import as_path
from ..model.torques.common import parts, stacked
from ..model.torques.surface_forces import (
    corotating_air,
    drag_pressure,
    drag_torque,
    exponential_density,
    facing,
)
from .facets import Facets, as_facets
from .sun import EARTH_RADIUS
from .torquebase import EnvironmentTorque, check_vector

__all__ = ["AerodynamicDrag", "ExponentialAtmosphere", "VALLADO_EXPONENTIAL_TABLE"]

#: Vallado (2013), Table 8-4: base altitude (km), nominal density (kg/m^3), scale height
#: (km).  Values cross-checked against two independent transcriptions (Vallado &
#: McClain 3rd ed. p. 564 as used in UT Austin course code, and SatelliteToolbox.jl).
VALLADO_EXPONENTIAL_TABLE = (
    (0, 1.225, 7.249), (25, 3.899e-2, 6.349), (30, 1.774e-2, 6.682),
    (40, 3.972e-3, 7.554), (50, 1.057e-3, 8.382), (60, 3.206e-4, 7.714),
    (70, 8.770e-5, 6.549), (80, 1.905e-5, 5.799), (90, 3.396e-6, 5.382),
    (100, 5.297e-7, 5.877), (110, 9.661e-8, 7.263), (120, 2.438e-8, 9.473),
    (130, 8.484e-9, 12.636), (140, 3.845e-9, 16.149), (150, 2.070e-9, 22.523),
    (180, 5.464e-10, 29.740), (200, 2.789e-10, 37.105), (250, 7.248e-11, 45.546),
    (300, 2.418e-11, 53.628), (350, 9.518e-12, 53.298), (400, 3.725e-12, 58.515),
    (450, 1.585e-12, 60.828), (500, 6.967e-13, 63.822), (600, 1.454e-13, 71.835),
    (700, 3.614e-14, 88.667), (800, 1.170e-14, 124.64), (900, 5.245e-15, 181.05),
    (1000, 3.019e-15, 268.00),
)


@dataclass(frozen=True)
class ExponentialAtmosphere:
    """Piecewise-exponential density of the atmosphere against altitude.

    Parameters
    ----------
    table : sequence of (base altitude km, density kg/m^3, scale height km)
        Increasing base altitudes; default :data:`VALLADO_EXPONENTIAL_TABLE`.  Below the
        first base the first layer applies, above the last the last one.

    Examples
    --------
    >>> atm = ExponentialAtmosphere()
    >>> float(atm.density(400e3))                       # the base of a layer
    3.725e-12
    >>> bool(np.isclose(atm(420e3), 3.725e-12 * np.exp(-20 / 58.515)))
    True
    """

    table: tuple = VALLADO_EXPONENTIAL_TABLE
    _base: np.ndarray = field(init=False, repr=False)
    _rho: np.ndarray = field(init=False, repr=False)
    _scale: np.ndarray = field(init=False, repr=False)
    _bases: tuple = field(init=False, repr=False)

    def __post_init__(self):
        try:
            rows = np.asarray(self.table, dtype=float)
        except (TypeError, ValueError):
            raise TorqueConfigError("expected rows of (base altitude km, density kg/m3, "
                                    "scale height km)", key="table") from None
        if rows.ndim != 2 or rows.shape[1] != 3 or len(rows) == 0 \
                or not np.all(np.isfinite(rows)):
            raise TorqueConfigError("expected rows of (base altitude km, density kg/m3, "
                                    "scale height km)", key="table")
        if np.any(np.diff(rows[:, 0]) <= 0):
            raise TorqueConfigError("base altitudes must increase", key="table")
        if np.any(rows[:, 1] <= 0) or np.any(rows[:, 2] <= 0):
            raise TorqueConfigError("densities and scale heights must be positive",
                                    key="table")
        object.__setattr__(self, "table", tuple(map(tuple, rows.tolist())))
        object.__setattr__(self, "_base", rows[:, 0] * 1e3)
        object.__setattr__(self, "_rho", rows[:, 1])
        object.__setattr__(self, "_scale", rows[:, 2] * 1e3)
        object.__setattr__(self, "_bases", tuple(self._base.tolist()))

    def density(self, altitude) -> np.ndarray:
        """Density at ``altitude`` (m above the reference sphere), kg/m^3."""
        h = np.asarray(altitude, dtype=float)
        if h.ndim == 0:                                  # one epoch: plain floats
            x = float(h)
            k = min(max(bisect.bisect_right(self._bases, x) - 1, 0), len(self._bases) - 1)
            return np.float64(exponential_density(x, self._bases[k], float(self._rho[k]),
                                                  float(self._scale[k])))
        k = np.clip(np.searchsorted(self._base, h, side="right") - 1, 0, len(self._base) - 1)
        return exponential_density(h, self._base[k], self._rho[k], self._scale[k])

    def __call__(self, altitude) -> np.ndarray:
        return self.density(altitude)


class AerodynamicDrag(EnvironmentTorque):
    """Torque of the upper atmosphere on the facets of a body (see the module docstring).

    Parameters
    ----------
    shape : Polyhedron, Surface or Facets
        The outer surface, body frame (the optical properties are not used).
    orbit : TLEOrbit, KeplerOrbit or anything with ``position(t)`` and ``velocity(t)``
        Inertial, geocentric, m and m/s; the frame's ``z`` axis along the Earth's axis
        (GCRF, EME2000, TEME: the tilt of the pole by precession is neglected).
    density : ExponentialAtmosphere, MSISAtmosphere or callable
        ``density(altitude) -> kg/m^3``, altitude in m above a sphere of the Earth's
        equatorial radius; or a model with ``along(orbit, epoch=, frame=)`` (the density
        along the orbit as a function of ``t``, e.g. NRLMSIS).
    cd : float
        Drag coefficient (2.2, the customary free-molecular value for a flat plate).
    center_of_mass : 3-vector, m
        In the coordinates of the facets.
    corotation : bool
        Subtract the velocity of the co-rotating air (default True).
    epoch : astropy Time, optional
        Time ``t = 0`` for a density model that depends on the time (default
        ``orbit.epoch``).
    frame : str, optional
        Inertial frame of the orbit, for such a model (default ``orbit.frame``, else
        ``"GCRF"``).

    Raises
    ------
    TorqueConfigError
        Naming the key: a bad facet, a negative drag coefficient, an orbit without
        velocity, a density model giving a negative or non-finite density.

    Examples
    --------
    A plate of 1 m^2 facing the flow at 7.5 km/s, 1 m off the centre of mass along +y,
    at 400 km (a path given as functions; no Earth rotation):

    >>> from types import SimpleNamespace
    >>> from attitude.environment import AerodynamicDrag, Facets
    >>> r = np.array([6778137.0, 0.0, 0.0])
    >>> orbit = SimpleNamespace(position=lambda t: np.broadcast_to(r, np.shape(t) + (3,)),
    ...                         velocity=lambda t: np.broadcast_to([7500.0, 0, 0],
    ...                                                            np.shape(t) + (3,)))
    >>> plate = Facets.plate(1.0, [1.0, 0.0, 0.0], centroid=[0.0, 1.0, 0.0])
    >>> drag = AerodynamicDrag(plate, orbit, corotation=False)
    >>> m = drag(0.0, [0, 0, 0, 1], [0, 0, 0], np.eye(3))
    >>> bool(np.isclose(m[2], 0.5 * 3.725e-12 * 7500.0**2 * 2.2, rtol=1e-12))
    True
    """

    velocity_dependent = False

    def __init__(self, shape, orbit, *, density=None, cd=2.2,
                 center_of_mass=(0.0, 0.0, 0.0), corotation: bool = True, epoch=None,
                 frame: str | None = None):
        self.facets: Facets = as_facets(shape)
        if orbit is None or not callable(getattr(orbit, "velocity", None)):
            raise TorqueConfigError("drag needs the orbit's velocity: give a TLEOrbit, "
                                    "a KeplerOrbit or a path with velocity(t)", key="orbit")
        self.orbit = as_path(orbit)
        self.density = ExponentialAtmosphere() if density is None else density
        if not callable(self.density):
            raise TorqueConfigError("expected an ExponentialAtmosphere or a callable "
                                    "altitude (m) -> density (kg/m^3)", key="density")
        self.cd = to_si(cd, "", key="cd", shape=(), error=TorqueConfigError)
        if not (np.isfinite(self.cd) and self.cd >= 0):
            raise TorqueConfigError(f"must be >= 0, got {self.cd!r}", key="cd")
        self.center_of_mass = check_vector(center_of_mass, "center_of_mass")
        self.corotation = bool(corotation)
        self._density_path = None
        if callable(getattr(self.density, "along", None)):   # time and place: NRLMSIS
            epoch = getattr(orbit, "epoch", None) if epoch is None else epoch
            if epoch is None:
                raise TorqueConfigError("the density model depends on the time: pass "
                                        "epoch= or an orbit with an epoch", key="epoch")
            frame = getattr(orbit, "frame", "GCRF") if frame is None else frame
            self._density_path = self.density.along(self.orbit, epoch=epoch, frame=frame)
        else:
            self._check_density(np.array([200e3, 400e3, 800e3]))
        f = self.facets
        self._r = f.centroids - self.center_of_mass
        self._ar = f.areas[:, None] * self._r                     # (n, 3): A_k r_k
        self._normals = np.ascontiguousarray(f.normals)
        self._normal_parts = tuple(np.ascontiguousarray(f.normals[:, k]) for k in range(3))

    def _check_density(self, altitude) -> np.ndarray:
        rho = np.asarray(self.density(altitude), dtype=float)
        if rho.shape != np.shape(altitude):
            rho = np.broadcast_to(rho, np.shape(altitude))
        if rho.ndim == 0 and 0.0 <= float(rho) < np.inf:   # one epoch, valid: fast exit
            return rho
        if not np.all(np.isfinite(rho) & (rho >= 0)):
            bad = rho[~(np.isfinite(rho) & (rho >= 0))].flat[0]
            raise TorqueConfigError(f"the density model gives {float(bad):.6g} kg/m^3: densities "
                                    "must be finite and >= 0", key="density")
        return rho

    def airflow(self, t):
        """``(v_rel, q)``: velocity relative to the air (inertial, m/s) and the dynamic
        pressure times the drag coefficient, ``1/2 rho v^2 C_D`` (N/m^2)."""
        t = self.time(np.asarray(t, dtype=float))
        r = np.asarray(self.orbit.position(t), dtype=float)
        v = np.asarray(self.orbit.velocity(t), dtype=float)
        if self.corotation:
            v = stacked(corotating_air(EARTH_ROTATION_RATE, parts(r), parts(v)))
        if self._density_path is not None:
            rho = self._density_path(t)
        else:
            rho = self._check_density(np.sqrt(np.sum(r * r, axis=-1)) - EARTH_RADIUS)
        return v, drag_pressure(rho, np.sum(v * v, axis=-1), self.cd)

    def _facing(self, v_hat: np.ndarray) -> np.ndarray:
        """The facets' cosines ``(..., n)`` for flow directions ``v_hat (..., 3)``."""
        return facing(self._normal_parts, tuple(x[..., None] for x in parts(v_hat))
                      if v_hat.ndim > 1 else parts(v_hat))

    def _weights(self, t, quaternion):
        v_in, q = self.airflow(t)
        v = quat.rotate(quaternion, v_in, inverse=True)
        speed = np.sqrt(np.sum(v * v, axis=-1, keepdims=True))
        v_hat = np.divide(v, speed, out=np.zeros_like(v), where=speed > 0)
        return v_hat, np.asarray(q)[..., None], self._facing(v_hat)

    def evaluate(self, t, quaternion, omega_body, body):
        if t.ndim == 0 and quaternion.ndim == 1:
            return self._one_epoch(float(t), quaternion)
        v_hat, q, c = self._weights(t, quaternion)
        return stacked(drag_torque(q[..., 0], parts(c @ self._ar), parts(v_hat)))

    def _one_epoch(self, t: float, quaternion: np.ndarray) -> np.ndarray:
        """:meth:`evaluate` at one epoch and attitude, in floats where numpy is slow."""
        t = self.time(t)
        r = np.asarray(self.orbit.position(t), dtype=float).tolist()
        v = np.asarray(self.orbit.velocity(t), dtype=float).tolist()
        if self.corotation:
            v = corotating_air(EARTH_ROTATION_RATE, r, v)
        x, y, z = r
        if self._density_path is not None:
            rho = float(self._density_path(t))
        else:
            rho = float(self._check_density(np.float64(math.sqrt(x * x + y * y + z * z)
                                                       - EARTH_RADIUS)))
        vx, vy, vz = v
        v2 = vx * vx + vy * vy + vz * vz
        if v2 == 0.0 or rho == 0.0:
            return np.zeros(3)
        speed = math.sqrt(v2)
        v_hat = quat.rotate_parts(quaternion.tolist(), (vx / speed, vy / speed, vz / speed),
                                  inverse=True)
        c = self._facing(np.array(v_hat))
        return stacked(drag_torque(drag_pressure(rho, v2, self.cd),
                                   tuple((c @ self._ar).tolist()), v_hat))

    def compiled_parameters(self, body, t_span=None) -> list[tuple[str, dict]] | None:
        """``[("drag", {...})]``: the terms of the one-epoch evaluation (facet sums, drag
        coefficient, co-rotation, the layers of an :class:`ExponentialAtmosphere`, the
        orbit, the time offset) for a compiled kernel, or None with another density
        model (:meth:`attitude.model.torques.TorqueModel.compiled_parameters`).

        Examples
        --------
        >>> from attitude.environment import AerodynamicDrag, Facets
        >>> from attitude.model.orbit import KeplerOrbit
        >>> leo = KeplerOrbit(mu=3.986004418e14, a=6.8e6)
        >>> drag = AerodynamicDrag(Facets.box([1.0, 1.0, 2.0]), leo)
        >>> drag.compiled_parameters(None)[0][1]["bases"][:2]
        array([    0., 25000.])
        >>> AerodynamicDrag(Facets.box([1.0, 1.0, 2.0]), leo, density=lambda h: 1e-12
        ...                 ).compiled_parameters(None) is None
        True
        """
        atmosphere = self.density
        if not isinstance(atmosphere, ExponentialAtmosphere):
            return None
        return [("drag", {
            "time_offset": float(self.time_offset), "cd": float(self.cd),
            "corotation": self.corotation, "rotation_rate": EARTH_ROTATION_RATE,
            "earth_radius": EARTH_RADIUS, "bases": atmosphere._base.copy(),
            "densities": atmosphere._rho.copy(), "scale_heights": atmosphere._scale.copy(),
            "normals": self._normals.copy(), "ar": self._ar.copy(), "orbit": self.orbit})]

    def force(self, t, quaternion) -> np.ndarray:
        """Total drag force, body frame, N, shape ``broadcast + (3,)``."""
        qn = np.asarray(quaternion, dtype=float)
        qn = qn / np.linalg.norm(qn, axis=-1, keepdims=True)
        v_hat, q, c = self._weights(np.asarray(t, dtype=float), qn)
        return -q * (c @ self.facets.areas)[..., None] * v_hat

    def unit_torque(self, directions) -> np.ndarray:
        """Torque per unit dynamic pressure ``1/2 rho v^2 C_D``, m^3, for the velocity
        relative to the air along ``directions`` (body frame)."""
        v_hat = np.asarray(directions, dtype=float)
        return stacked(drag_torque(1.0, parts(self._facing(v_hat) @ self._ar), parts(v_hat)))

    def pressure_at(self, t) -> np.ndarray:
        """``1/2 rho v^2 C_D`` at ``t``, N/m^2."""
        return self.airflow(t)[1]

    def torque_bound(self, t) -> float:
        """``1/2 rho v^2 C_D sum_k A_k |r_k|``, N m: no attitude exceeds it."""
        _, q = self.airflow(t)
        return float(np.max(q)) * float(np.sum(self.facets.areas
                                               * np.linalg.norm(self._r, axis=1)))

    def __repr__(self) -> str:
        return (f"AerodynamicDrag({len(self.facets)} facets, cd={self.cd:g}, "
                f"density={self.density!r}, orbit={self.orbit!r})")

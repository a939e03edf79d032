"""Solar radiation pressure on the facets of a spacecraft, and its torque.

A flat facet of area ``A`` and outward normal ``n`` lit by the Sun from the direction
``s`` (unit, body frame, toward the Sun), ``cos(theta) = n . s > 0``, absorbs the
fraction ``1 - rho_s - rho_d`` of the light, reflects ``rho_s`` specularly and
``rho_d`` diffusely (Lambert); the force of the light on it is

.. math::

    F = -P A \\cos\\theta \\left[(1 - \\rho_s)\\, s
        + 2 \\left(\\rho_s \\cos\\theta + \\frac{\\rho_d}{3}\\right) n\\right]

(Montenbruck & Gill 2000, Sec. 3.4, eq. 3.73; Wertz 1978, Sec. 17.2), with ``P`` the
radiation pressure, ``4.56e-6 N/m^2`` at 1 au, scaled by ``(1 au / d)^2`` with ``d`` the
distance to the Sun.  Facets facing away (``cos(theta) <= 0``) feel nothing; the light
they would block is not followed (no self-shadowing: exact for a convex body).  The
torque is ``sum_k (r_k - r_cm) x F_k`` and is multiplied by the visible fraction of the
solar disk (:func:`~attitude.environment.sun.illumination`): zero in the umbra,
continuous through the penumbra with the conical shadow.

The sums over facets reduce to two weighted sums per epoch,

.. math::

    M = -P \\Big[\\big(\\textstyle\\sum_k w_k r_k\\big) \\times s
        + 2 \\sum_k u_k\\, (r_k \\times n_k)\\Big],\\quad
    w_k = A_k c_k (1 - \\rho_{s,k}),\\ u_k = A_k c_k (\\rho_{s,k} c_k + \\rho_{d,k}/3)

so one evaluation is two matrix products of ``(epochs, facets)`` weights.

References
----------
.. [1] O. Montenbruck, E. Gill, *Satellite Orbits*, Springer (2000), Sec. 3.4.
.. [2] J. R. Wertz (ed.), *Spacecraft Attitude Determination and Control*, Reidel
   (1978), Sec. 17.2.
"""

from __future__ import annotations

import math

import numpy as np

from .. import quaternion as quat
from ..errors import TorqueConfigError
from ..orbit import as_path
from ..quantities import to_si
from ..quaternion import cross
from .facets import Facets, as_facets
from .sun import EARTH_RADIUS, SHADOW_MODELS, SUN_RADIUS, illumination
from .torquebase import EnvironmentTorque, check_vector

__all__ = ["SolarRadiationPressure", "SOLAR_PRESSURE_1AU", "ASTRONOMICAL_UNIT"]

#: Solar radiation pressure at 1 au on an absorbing surface, N/m^2 (1367 W/m^2 / c;
#: Montenbruck & Gill 2000, Sec. 3.4.1).
SOLAR_PRESSURE_1AU = 4.56e-6
#: The astronomical unit (IAU 2012), m.
ASTRONOMICAL_UNIT = 1.495978707e11


class SolarRadiationPressure(EnvironmentTorque):
    """Torque of sunlight on the facets of a body (see the module docstring).

    Parameters
    ----------
    shape : Polyhedron, Surface or Facets
        The outer surface, body frame (a mesh's faces, or explicit facets such as
        :meth:`Facets.plate` for surfaces a closed mesh cannot describe).
    surface : Surface or OpticalProperties, optional
        The materials of a Polyhedron's faces (the description photometry uses);
        default black (all light absorbed).
    sun : SunPath, path, callable or 3-vector
        Geocentric position of the Sun, inertial, m.
    orbit : TLEOrbit, KeplerOrbit, path, callable or 3-vector
        Geocentric position of the body, same frame, m.
    shadow : {"conical", "cylindrical"} or None
        Earth-shadow model (:func:`~attitude.environment.sun.illumination`); None: always
        lit.
    center_of_mass : 3-vector, m
        In the coordinates of the facets (torques are taken about it).
    pressure : float, Quantity or str
        Radiation pressure at 1 au, N/m^2 (default :data:`SOLAR_PRESSURE_1AU`).

    Raises
    ------
    TorqueConfigError
        Naming the key, on a bad facet, material, vector, shadow model or pressure.

    Examples
    --------
    A black plate of 1 m^2, its centre 1 m along +y from the centre of mass, facing a
    Sun along +x (1 au away): the force ``P`` along -x gives a torque ``P`` about +z.

    >>> from attitude.environment import Facets, SolarRadiationPressure
    >>> plate = Facets.plate(1.0, [1.0, 0.0, 0.0], centroid=[0.0, 1.0, 0.0])
    >>> srp = SolarRadiationPressure(plate, sun=[1.495978707e11, 0, 0], orbit=[0, 0, 0],
    ...                              shadow=None)
    >>> srp(0.0, [0, 0, 0, 1], [0, 0, 0], np.eye(3))
    array([0.00e+00, 0.00e+00, 4.56e-06])
    """

    velocity_dependent = False

    def __init__(self, shape, surface=None, sun=None, orbit=None, *, shadow="conical",
                 center_of_mass=(0.0, 0.0, 0.0), pressure=SOLAR_PRESSURE_1AU):
        if sun is None:
            raise TorqueConfigError("radiation pressure needs the Sun's position: a "
                                    "SunPath, a path or a vector", key="sun")
        if orbit is None:
            raise TorqueConfigError("radiation pressure needs the body's position: an "
                                    "orbit, a path or a vector", key="orbit")
        if shadow is not None and shadow not in SHADOW_MODELS:
            raise TorqueConfigError(f"unknown shadow model {shadow!r}; use one of "
                                    f"{', '.join(SHADOW_MODELS)} or None", key="shadow")
        self.facets: Facets = as_facets(shape, surface)
        self.center_of_mass = check_vector(center_of_mass, "center_of_mass")
        self.pressure = to_si(pressure, "N/m2", key="pressure", shape=(),
                              error=TorqueConfigError)
        if not (np.isfinite(self.pressure) and self.pressure >= 0):
            raise TorqueConfigError(f"must be >= 0, got {self.pressure!r}", key="pressure")
        self.sun = as_path(sun)
        self.orbit = as_path(orbit)
        self.shadow = shadow
        f = self.facets
        self._r = f.centroids - self.center_of_mass                # (n, 3)
        self._normals = np.ascontiguousarray(f.normals)
        self._rxn = np.cross(self._r, f.normals)                    # (n, 3)
        self._one_minus_s = f.areas * (1.0 - f.specular)            # A (1 - rho_s)
        self._spec = f.areas * f.specular                           # A rho_s
        self._diff = f.areas * f.diffuse / 3.0                      # A rho_d / 3

    def sunlight(self, t):
        """``(s_inertial, p)``: unit vector from the body to the Sun (inertial) and the
        pressure there times the visible fraction of the solar disk, N/m^2."""
        t = self.time(np.asarray(t, dtype=float))
        r_sun = np.asarray(self.sun.position(t), dtype=float)
        r_sat = np.asarray(self.orbit.position(t), dtype=float)
        d = r_sun - r_sat
        dist = np.sqrt(np.sum(d * d, axis=-1))
        p = self.pressure * (ASTRONOMICAL_UNIT / dist) ** 2
        if self.shadow is not None:
            p = p * illumination(r_sat, r_sun, self.shadow)
        return d / dist[..., None], p

    def _weights(self, t, quaternion):
        s_in, p = self.sunlight(t)
        s = quat.rotate(quaternion, s_in, inverse=True)              # (..., 3) body
        c = np.maximum(s @ self.facets.normals.T, 0.0)               # (..., n)
        w = c * self._one_minus_s
        u = c * (c * self._spec + self._diff)
        return s, np.asarray(p)[..., None], w, u

    def evaluate(self, t, quaternion, omega_body, body):
        if t.ndim == 0 and quaternion.ndim == 1:
            return self._one_epoch(float(t), quaternion)
        s, p, w, u = self._weights(t, quaternion)
        return -p * (cross(w @ self._r, s) + 2.0 * (u @ self._rxn))

    def _one_epoch(self, t: float, quaternion: np.ndarray) -> np.ndarray:
        """:meth:`evaluate` at one epoch and attitude, in floats where numpy is slow."""
        t = self.time(t)
        r_sun = np.asarray(self.sun.position(t), dtype=float)
        r_sat = np.asarray(self.orbit.position(t), dtype=float)
        dx, dy, dz = (r_sun - r_sat).tolist()
        dist = math.sqrt(dx * dx + dy * dy + dz * dz)
        p = self.pressure * (ASTRONOMICAL_UNIT / dist) ** 2
        if self.shadow is not None:
            p *= float(illumination(r_sat, r_sun, self.shadow))
        if p == 0.0:
            return np.zeros(3)
        s = np.array(quat.rotate_parts(quaternion.tolist(),
                                       (dx / dist, dy / dist, dz / dist), inverse=True))
        c = self._normals @ s
        np.maximum(c, 0.0, out=c)
        w = c * self._one_minus_s
        u = c * (c * self._spec + self._diff)
        return -p * (cross(w @ self._r, s) + 2.0 * (u @ self._rxn))

    def compiled_parameters(self, body, t_span=None) -> list[tuple[str, dict]]:
        """``[("radiation_pressure", {...})]``: the terms of the one-epoch evaluation
        (facet sums, pressure, shadow model, the Sun's and the body's paths, the time
        offset) for a compiled kernel (:meth:`attitude.torques.TorqueModel.compiled_parameters`).

        Examples
        --------
        >>> from attitude.environment import Facets
        >>> srp = SolarRadiationPressure(Facets.plate(1.0, [1.0, 0, 0]), sun=[1.5e11, 0, 0],
        ...                              orbit=[7e6, 0, 0])
        >>> kind, values = srp.compiled_parameters(None)[0]
        >>> kind, values["shadow"], values["normals"].shape
        ('radiation_pressure', 'conical', (2, 3))
        """
        return [("radiation_pressure", {
            "time_offset": float(self.time_offset), "pressure": float(self.pressure),
            "astronomical_unit": ASTRONOMICAL_UNIT, "shadow": self.shadow,
            "earth_radius": EARTH_RADIUS, "sun_radius": SUN_RADIUS,
            "normals": self._normals.copy(), "r": self._r.copy(), "rxn": self._rxn.copy(),
            "one_minus_s": self._one_minus_s.copy(), "spec": self._spec.copy(),
            "diff": self._diff.copy(), "sun": self.sun, "orbit": self.orbit})]

    def force(self, t, quaternion) -> np.ndarray:
        """Total radiation force, body frame, N, shape ``broadcast + (3,)``.

        Examples
        --------
        >>> from attitude.environment import Facets
        >>> plate = Facets.plate(1.0, [0.0, 0.0, 1.0], specular=1.0)   # a mirror
        >>> srp = SolarRadiationPressure(plate, sun=[0, 0, 1.495978707e11],
        ...                              orbit=[0, 0, 0], shadow=None)
        >>> srp.force(0.0, [0, 0, 0, 1])[2] / 4.56e-6               # twice the push
        np.float64(-2.0)
        """
        q = np.asarray(quaternion, dtype=float)
        q = q / np.linalg.norm(q, axis=-1, keepdims=True)
        s, p, w, u = self._weights(np.asarray(t, dtype=float), q)
        return -p * (w.sum(axis=-1)[..., None] * s + 2.0 * (u @ self.facets.normals))

    def unit_torque(self, directions) -> np.ndarray:
        """Torque per unit pressure, m^3, for the Sun in ``directions`` (body frame)."""
        s = np.asarray(directions, dtype=float)
        c = np.maximum(s @ self._normals.T, 0.0)
        w = c * self._one_minus_s
        u = c * (c * self._spec + self._diff)
        return -(cross(w @ self._r, s) + 2.0 * (u @ self._rxn))

    def pressure_at(self, t) -> np.ndarray:
        """Radiation pressure at the body times the visible fraction of the Sun, N/m^2."""
        return self.sunlight(t)[1]

    def torque_bound(self, t) -> float:
        """``P(t) sum_k A_k |r_k| (1 + rho_s + 2 rho_d / 3)``, N m: no attitude exceeds it."""
        _, p = self.sunlight(t)
        f = self.facets
        lever = np.linalg.norm(self._r, axis=1)
        return float(np.max(p)) * float(np.sum(f.areas * lever * (
            1.0 + f.specular + 2.0 * f.diffuse / 3.0)))

    def __repr__(self) -> str:
        return (f"SolarRadiationPressure({len(self.facets)} facets, shadow="
                f"{self.shadow!r}, sun={self.sun!r}, orbit={self.orbit!r})")

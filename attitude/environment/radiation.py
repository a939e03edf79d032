"""Solar radiation pressure on the facets of a spacecraft, and its torque.

A flat facet of area ``A`` and outward normal ``n`` lit by the Sun from the direction
``s`` (unit, body frame, toward the Sun), ``cos(theta) = n . s > 0``, absorbs the
fraction ``1 - rho_s - rho_d`` of the light, reflects ``rho_s`` specularly and
``rho_d`` diffusely (Lambert); the force of the light on it is

.. math::

    F = -P A \\cos\\theta \\left[(1 - \\rho_s)\\, s
        + 2 \\left(\\rho_s \\cos\\theta + \\frac{\\rho_d}{3}\\right) n\\right]

(Montenbruck & Gill 2000, Sec. 3.4, eq. 3.73; Wertz 1978, Sec. 17.2), with ``P`` the
radiation pressure, ``1367 W/m^2 / c = 4.5598e-6 N/m^2`` at 1 au
(:data:`~attitude.foundations.constants.SOLAR_PRESSURE_1AU`), scaled by ``(1 au / d)^2``
with ``d`` the distance to the Sun.  Facets facing away (``cos(theta) <= 0``) feel nothing.  By
default the light one facet blocks from another is not followed (exact for a convex
body); with ``self_shadowing=True`` a facet feels only its part that sees the Sun past
the rest of the body (see below).  The
torque is ``sum_k (r_k - r_cm) x F_k`` and is multiplied by the visible fraction of the
solar disk (:func:`~attitude.environment.sun.illumination`): zero in the umbra,
continuous through the penumbra with the conical shadow.

The sums over facets reduce to two weighted sums per epoch,

.. math::

    M = -P \\Big[\\big(\\textstyle\\sum_k w_k r_k\\big) \\times s
        + 2 \\sum_k u_k\\, (r_k \\times n_k)\\Big],\\quad
    w_k = A_k c_k (1 - \\rho_{s,k}),\\ u_k = A_k c_k (\\rho_{s,k} c_k + \\rho_{d,k}/3)

so one evaluation is two matrix products of ``(epochs, facets)`` weights.

Self-shadowing
--------------
With ``self_shadowing=True``, each triangle of a facet's outline
(:attr:`Facets.triangles <attitude.environment.Facets.triangles>`) is cut into ``k^2``
equal triangles, each edge in ``k``: ``k = shadow_subdivision``, or by default per
triangle the smallest ``k`` that makes the sub-triangles' edges at most
:data:`AUTO_SPACING` (1/24) of the body's extent, up to :data:`AUTO_MAX_SUBDIVISION`
(16).  One ray leaves the centroid of each sub-triangle toward the Sun, a little above
the surface (:data:`attitude.model.raycast.OFFSET_RTOL` of the body's extent); embree
(:class:`attitude.model.raycast.Occluder`) tells which rays meet another part of the body.
The lit area ``A_k^lit = sum_j a_j`` and its first moment ``m_k = sum_j a_j (r_j -
r_cm)`` over the unblocked samples replace ``A_k`` and ``A_k r_k`` in the sums above,
so the force of a partly lit facet acts at the centroid of its lit part.  This is the
midpoint rule on the sub-triangles: it is exact when no shadow edge crosses a
sub-triangle, and a straight shadow edge crossing a triangle cuts at most ``3k - 2`` of
its ``k^2`` sub-triangles, so the lit area is in error by at most ``(3k - 2) / k^2`` of
that triangle (0.625 at ``k = 4``, 0.18 at ``k = 16``); the errors of the cut
sub-triangles have both signs, and the error in the tests is a few per cent at ``k =
4``, 0.1 % at ``k = 16`` (docs/environment.md).  Only facets that some part of the body
rises above (a corner strictly in front of the facet's plane) can be shadowed; the
others, all of them on a convex body, cast no rays and keep the sums above.  The Sun's
direction in the body frame changes at every call, so the rays are cast at every call:
``k^2`` per lit triangle that can be shadowed.

References
----------
.. [1] O. Montenbruck, E. Gill, *Satellite Orbits*, Springer (2000), Sec. 3.4.
.. [2] J. R. Wertz (ed.), *Spacecraft Attitude Determination and Control*, Reidel
   (1978), Sec. 17.2.
"""

from __future__ import annotations

import numpy as np

from ..foundations import quaternion as quat
from ..foundations.constants import AU as ASTRONOMICAL_UNIT
from ..foundations.constants import SOLAR_PRESSURE_1AU
from ..foundations.errors import TorqueConfigError
from ..foundations.quantities import to_si
from ..model.orbit import as_path
from ..model.raycast import OFFSET_RTOL, Occluder, load_embree
from ..model.torques.common import parts, stacked
from ..model.torques.surface_forces import facing, radiation_torque, radiation_weights, sunlight
from .facets import Facets, as_facets, triangle_areas
from .sun import EARTH_RADIUS, SHADOW_MODELS, SUN_RADIUS, illumination
from .torquebase import EnvironmentTorque, check_vector

__all__ = ["SolarRadiationPressure", "SOLAR_PRESSURE_1AU", "ASTRONOMICAL_UNIT",
           "AUTO_SPACING", "AUTO_MAX_SUBDIVISION"]


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
    self_shadowing : bool
        Follow the light the body blocks from its own facets (ray casting with embree,
        the ``shadows`` extra; see the module docstring).  Default False: every facet
        facing the Sun is lit whole.
    shadow_subdivision : int, optional
        With ``self_shadowing``: each triangle of a facet cut into ``k^2`` sub-triangles,
        one ray each; default (None) ``k`` per triangle, from its size (sub-triangles
        at most :data:`AUTO_SPACING` of the body's extent, ``k <= 16``).

    Raises
    ------
    TorqueConfigError
        Naming the key, on a bad facet, material, vector, shadow model, pressure or
        subdivision.
    MissingDependencyError
        ``self_shadowing=True`` without embreex (the message names the ``shadows`` extra).

    Examples
    --------
    A black plate of 1 m^2, its centre 1 m along +y from the centre of mass, facing a
    Sun along +x (1 au away): the force ``P`` along -x gives a torque ``P`` about +z.

    >>> from attitude.environment import Facets, SolarRadiationPressure
    >>> plate = Facets.plate(1.0, [1.0, 0.0, 0.0], centroid=[0.0, 1.0, 0.0])
    >>> srp = SolarRadiationPressure(plate, sun=[1.495978707e11, 0, 0], orbit=[0, 0, 0],
    ...                              shadow=None)
    >>> srp(0.0, [0, 0, 0, 1], [0, 0, 0], np.eye(3))
    array([0.0000e+00, 0.0000e+00, 4.5598e-06])
    """

    velocity_dependent = False

    def __init__(self, shape, surface=None, sun=None, orbit=None, *, shadow="conical",
                 center_of_mass=(0.0, 0.0, 0.0), pressure=SOLAR_PRESSURE_1AU,
                 self_shadowing: bool = False, shadow_subdivision: int | None = None):
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
        self._normal_parts = tuple(np.ascontiguousarray(f.normals[:, k]) for k in range(3))
        self._rxn = np.cross(self._r, f.normals)                    # (n, 3)
        self._one_minus_s = f.areas * (1.0 - f.specular)            # A (1 - rho_s)
        self._spec = f.areas * f.specular                           # A rho_s
        self._diff = f.areas * f.diffuse / 3.0                      # A rho_d / 3
        self.self_shadowing = bool(self_shadowing)
        if shadow_subdivision is not None and not (
                isinstance(shadow_subdivision, (int, np.integer))
                and not isinstance(shadow_subdivision, bool) and shadow_subdivision >= 1):
            raise TorqueConfigError(f"expected a whole number >= 1 or None, got "
                                    f"{shadow_subdivision!r}", key="shadow_subdivision")
        self.shadow_subdivision = (None if shadow_subdivision is None
                                   else int(shadow_subdivision))
        self._shaded = None
        if self.self_shadowing:
            self._shaded = _ShadedFacets(f, self.center_of_mass, self.shadow_subdivision)
            # the facets that can be shadowed leave the plain sums for _ShadedFacets's
            keep = np.ones(len(f))
            keep[self._shaded.index] = 0.0
            self._one_minus_s = self._one_minus_s * keep
            self._spec = self._spec * keep
            self._diff = self._diff * keep

    @property
    def shadeable(self) -> np.ndarray:
        """Indices of the facets the rest of the body can shade (some corner of the body
        in front of their plane): those whose rays are cast; empty without
        ``self_shadowing`` and for a convex body.

        Examples
        --------
        >>> from attitude.environment import Facets
        >>> pair = Facets.join([Facets.plate(1.0, [1, 0, 0], [1.0, 0, 0]),
        ...                     Facets.plate(1.0, [1, 0, 0], [0.0, 0, 0])])
        >>> SolarRadiationPressure(pair, sun=[1.5e11, 0, 0], orbit=[0, 0, 0],
        ...                        self_shadowing=True).shadeable   # facing each other
        array([1, 2])
        """
        if self._shaded is None:
            return np.zeros(0, dtype=int)
        return self._shaded.index.copy()

    def sunlight(self, t):
        """``(s_inertial, p)``: unit vector from the body to the Sun (inertial) and the
        pressure there times the visible fraction of the solar disk, N/m^2."""
        t = self.time(np.asarray(t, dtype=float))
        r_sun = np.asarray(self.sun.position(t), dtype=float)
        r_sat = np.asarray(self.orbit.position(t), dtype=float)
        p, s = sunlight(self.pressure, ASTRONOMICAL_UNIT, parts(r_sun), parts(r_sat))
        if self.shadow is not None:
            p = p * illumination(r_sat, r_sun, self.shadow)
        return stacked(s), p

    def _weights(self, t, quaternion):
        s_in, p = self.sunlight(t)
        s = quat.rotate(quaternion, s_in, inverse=True)              # (..., 3) body
        w, u = self._facet_weights(s)
        return s, np.asarray(p)[..., None], w, u

    def _facet_weights(self, s: np.ndarray) -> tuple:
        """``(w, u)`` of the facets, ``(..., n)``, for Sun directions ``s (..., 3)``."""
        c = facing(self._normal_parts, tuple(x[..., None] for x in parts(s))
                   if s.ndim > 1 else parts(s))
        return radiation_weights(c, self._one_minus_s, self._spec, self._diff)

    def _torque(self, p, s: np.ndarray, w: np.ndarray, u: np.ndarray) -> np.ndarray:
        """The torque from the facets' weights (their sums, then the formula)."""
        W, U = w @ self._r, u @ self._rxn
        if self._shaded is not None:
            Ws, Us = self._shaded.sums(s)
            W, U = W + Ws, U + Us
        return stacked(radiation_torque(p, parts(W), parts(U), parts(s)))

    def evaluate(self, t, quaternion, omega_body, body):
        if t.ndim == 0 and quaternion.ndim == 1:
            return self._one_epoch(float(t), quaternion)
        s, p, w, u = self._weights(t, quaternion)
        return self._torque(p[..., 0], s, w, u)

    def _one_epoch(self, t: float, quaternion: np.ndarray) -> np.ndarray:
        """:meth:`evaluate` at one epoch and attitude, in floats where numpy is slow."""
        t = self.time(t)
        r_sun = np.asarray(self.sun.position(t), dtype=float)
        r_sat = np.asarray(self.orbit.position(t), dtype=float)
        p, s = sunlight(self.pressure, ASTRONOMICAL_UNIT, r_sun.tolist(), r_sat.tolist())
        p = float(p)
        if self.shadow is not None:
            p *= float(illumination(r_sat, r_sun, self.shadow))
        if p == 0.0:
            return np.zeros(3)
        s = np.array(quat.rotate_parts(quaternion.tolist(), s, inverse=True))
        w, u = self._facet_weights(s)
        return self._torque(p, s, w, u)

    def compiled_parameters(self, body, t_span=None) -> list[tuple[str, dict]] | None:
        """``[("radiation_pressure", {...})]``: the terms of the one-epoch evaluation
        (facet sums, pressure, shadow model, the Sun's and the body's paths, the time
        offset) for a compiled kernel
        (:meth:`attitude.model.torques.TorqueModel.compiled_parameters`);
        None with ``self_shadowing`` (the rays are cast in Python: the integrators call
        the model).

        Examples
        --------
        >>> from attitude.environment import Facets
        >>> srp = SolarRadiationPressure(Facets.plate(1.0, [1.0, 0, 0]), sun=[1.5e11, 0, 0],
        ...                              orbit=[7e6, 0, 0])
        >>> kind, values = srp.compiled_parameters(None)[0]
        >>> kind, values["shadow"], values["normals"].shape
        ('radiation_pressure', 'conical', (2, 3))
        """
        if self._shaded is not None:
            return None
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
        >>> from attitude.foundations.constants import SOLAR_PRESSURE_1AU
        >>> srp.force(0.0, [0, 0, 0, 1])[2] / SOLAR_PRESSURE_1AU    # twice the push
        np.float64(-2.0)
        """
        q = np.asarray(quaternion, dtype=float)
        q = q / np.linalg.norm(q, axis=-1, keepdims=True)
        s, p, w, u = self._weights(np.asarray(t, dtype=float), q)
        force = w.sum(axis=-1)[..., None] * s + 2.0 * (u @ self.facets.normals)
        if self._shaded is not None:
            force = force + self._shaded.force(s)
        return -p * force

    def unit_torque(self, directions) -> np.ndarray:
        """Torque per unit pressure, m^3, for the Sun in ``directions`` (body frame)."""
        s = np.asarray(directions, dtype=float)
        w, u = self._facet_weights(s)
        return self._torque(1.0, s, w, u)

    def pressure_at(self, t) -> np.ndarray:
        """Radiation pressure at the body times the visible fraction of the Sun, N/m^2."""
        return self.sunlight(t)[1]

    def torque_bound(self, t) -> float:
        """``P(t) sum_k A_k |r_k| (1 + rho_s + 2 rho_d / 3)``, N m: no attitude exceeds it."""
        _, p = self.sunlight(t)
        f = self.facets
        lever = np.linalg.norm(self._r, axis=1)
        if self._shaded is not None:                 # the lit part's centroid moves
            lever[self._shaded.index] = self._shaded.lever
        return float(np.max(p)) * float(np.sum(f.areas * lever * (
            1.0 + f.specular + 2.0 * f.diffuse / 3.0)))

    def __repr__(self) -> str:
        shading = ", self_shadowing=True" if self.self_shadowing else ""
        return (f"SolarRadiationPressure({len(self.facets)} facets, shadow="
                f"{self.shadow!r}{shading}, sun={self.sun!r}, orbit={self.orbit!r})")


#: With ``shadow_subdivision=None``: the longest edge of a sub-triangle is at most this
#: fraction of the body's extent ...
AUTO_SPACING = 1.0 / 24.0
#: ... but no triangle is cut in more than this many pieces per edge (256 rays).
AUTO_MAX_SUBDIVISION = 16

# Sample points times epochs handled at once by _ShadedFacets.lit (memory ~ 50 B each).
_RAYS_PER_CHUNK = 1 << 20


def _subdivisions(triangles: np.ndarray, extent: float, k: int | None) -> np.ndarray:
    """``k`` for each triangle: the one given, or the smallest that cuts its longest
    edge into pieces of at most :data:`AUTO_SPACING` times the body's extent (at most
    :data:`AUTO_MAX_SUBDIVISION`)."""
    if k is not None:
        return np.full(len(triangles), k, dtype=int)
    edges = triangles - np.roll(triangles, 1, axis=1)
    longest = np.linalg.norm(edges, axis=-1).max(axis=-1) if len(triangles) else \
        np.zeros(0)
    k_auto = np.ceil(longest / (AUTO_SPACING * extent) - 1e-9)
    return np.clip(k_auto, 1, AUTO_MAX_SUBDIVISION).astype(int)


def _sub_centroids(k: int) -> np.ndarray:
    """Barycentric weights ``(k^2, 3)`` of the centroids of the ``k^2`` equal triangles
    that cut a triangle with ``k`` pieces per edge."""
    points = [(i + 1 / 3, j + 1 / 3) for i in range(k) for j in range(k - i)]
    points += [(i + 2 / 3, j + 2 / 3) for i in range(k - 1) for j in range(k - 1 - i)]
    b = np.array(points) / k
    return np.column_stack([1.0 - b.sum(axis=1), b])


class _ShadedFacets:
    """The facets that the body can shadow, their sample points and the ray caster."""

    def __init__(self, facets: Facets, center_of_mass: np.ndarray, k: int):
        tris, owner = facets.triangles, facets.triangle_facets
        corners = np.unique(tris.reshape(-1, 3), axis=0)
        extent = float(np.ptp(corners, axis=0).max())
        # a facet can be shadowed only if some corner of the body is in front of its
        # plane: a ray toward the Sun (n . s > 0) climbs away from the plane
        height = np.full(len(facets), -np.inf)
        for start in range(0, len(facets), 256):                  # bounded memory
            n = facets.normals[start:start + 256]
            c = facets.centroids[start:start + 256]
            height[start:start + 256] = np.max(corners @ n.T, axis=0) - np.sum(c * n, 1)
        self.index = np.flatnonzero(height > 1e-9 * extent)
        # embree is asked for even when no facet can be shadowed: the setting needs it
        self.occluder = None
        load_embree("self_shadowing", "self_shadowing = false")
        if self.index.size:
            self.occluder = Occluder(tris, key="self_shadowing",
                                     switch="self_shadowing = false")
        shaded = np.zeros(len(facets), dtype=bool)
        shaded[self.index] = True
        mine = np.flatnonzero(shaded[owner])
        self.subdivision = _subdivisions(tris[mine], extent, k)  # k per triangle
        points, area, facet_of = [np.zeros((0, 3))], [np.zeros(0)], [np.zeros(0, int)]
        for kv in np.unique(self.subdivision):
            these = mine[self.subdivision == kv]
            bary = _sub_centroids(int(kv))                        # (k^2, 3)
            points.append(np.einsum("sb,tbx->tsx", bary, tris[these]).reshape(-1, 3))
            area.append(np.repeat(triangle_areas(tris[these]) / kv**2, kv**2))
            facet_of.append(np.repeat(owner[these], kv**2))
        points, area, facet_of = (np.concatenate(x) for x in (points, area, facet_of))
        order = np.argsort(facet_of, kind="stable")               # grouped by facet
        points, area, facet_of = points[order], area[order], facet_of[order]
        local = np.searchsorted(self.index, facet_of)             # 0..len(index)-1
        self.normals = facets.normals[self.index]
        self.one_minus_s = 1.0 - facets.specular[self.index]
        self.spec = facets.specular[self.index]
        self.diff = facets.diffuse[self.index] / 3.0
        self._local = local
        self._area = area
        self._lever = points - center_of_mass                     # r_j - r_cm
        self._origins = points + OFFSET_RTOL * extent * facets.normals[facet_of]
        starts = np.searchsorted(local, np.arange(self.index.size))
        self.lever = (np.maximum.reduceat(np.linalg.norm(self._lever, axis=1), starts)
                      if self.index.size else np.zeros(0))

    def lit(self, s: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(c, A_lit, m)`` for Sun directions ``s (N, 3)``: the cosines ``(N, n)``, lit
        areas ``(N, n)`` and their first moments about the centre of mass ``(N, n, 3)``."""
        c = np.maximum(s @ self.normals.T, 0.0)                   # (N, n)
        N, n = c.shape
        area = np.zeros((N, n))
        moment = np.zeros((N, n, 3))
        if n == 0:
            return c, area, moment
        rows = max(1, _RAYS_PER_CHUNK // self._area.size)        # bounded memory
        for start in range(0, N, rows):
            part = slice(start, start + rows)
            e_idx, j_idx = np.nonzero(c[part, self._local] > 0.0)  # rays worth casting
            if not e_idx.size:
                continue
            clear = ~self.occluder.occluded(self._origins[j_idx], s[part][e_idx])
            e_idx, j_idx = e_idx[clear], j_idx[clear]
            a = self._area[j_idx]
            m = c[part].shape[0]
            flat = e_idx * n + self._local[j_idx]
            area[part] = np.bincount(flat, weights=a, minlength=m * n).reshape(m, n)
            moment[part] = np.stack([np.bincount(flat, weights=a * self._lever[j_idx, i],
                                                 minlength=m * n) for i in range(3)],
                                    axis=-1).reshape(m, n, 3)
        return c, area, moment

    def sums(self, s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The facet sums ``W = sum_k w_k m_k`` and ``U = sum_k u_k (m_k x n_k)`` of the
        torque formula over these facets (``m_k`` the lit part's first moment), each
        ``s.shape``, m^3 (:func:`attitude.model.torques.surface_forces.radiation_torque`)."""
        s = np.asarray(s, dtype=float)
        flat = s.reshape(-1, 3)
        c, _, m = self.lit(flat)
        w, u = radiation_weights(c, self.one_minus_s, self.spec, self.diff)
        W = np.einsum("en,enx->ex", w, m)
        U = np.einsum("en,enx->ex", u, np.cross(m, self.normals))
        return W.reshape(s.shape), U.reshape(s.shape)

    def force(self, s: np.ndarray) -> np.ndarray:
        """The bracket of the force over these facets, ``(..., 3)``, m^2."""
        s = np.asarray(s, dtype=float)
        flat = s.reshape(-1, 3)
        c, area, _ = self.lit(flat)
        w, u = radiation_weights(c, self.one_minus_s, self.spec, self.diff)
        w, u = w * area, u * area
        out = w.sum(axis=-1)[:, None] * flat + 2.0 * (u @ self.normals)
        return out.reshape(s.shape)

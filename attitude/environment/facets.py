"""Flat facets of a spacecraft's outer surface: what radiation pressure and drag act on.

A :class:`Facets` holds, per facet, its area, outward unit normal, centroid (body frame)
and the optical fractions of :class:`attitude.model.surface.OpticalProperties` (specular
``rho_s`` and diffuse ``rho_d``; the rest is absorbed).  It is built from the same
description photometry uses -- a :class:`~attitude.model.surface.Surface` or a
:class:`~attitude.model.shape.Polyhedron` with one material -- or directly, for open
surfaces a closed mesh cannot describe (a thin plate, a solar array: two facets back
to back).  The torque models of the wing precompute their sums over facets from it.

Each facet also has an outline, as triangles (:attr:`Facets.triangles`), which only
self-shadowing reads (:class:`~attitude.environment.SolarRadiationPressure` with
``self_shadowing=True``): a mesh's faces are their own triangles, a box's faces are its
rectangles, and a facet or plate given by its area alone is a square of that area
centred on its centroid, edges along ``edge`` projected into its plane (default the
body axis least aligned with its normal) and ``n x edge``; ``size = (a, b)`` makes it an
``a`` by ``b`` rectangle, ``a`` along ``edge``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..foundations.errors import TorqueConfigError
from ..model.shape import Polyhedron
from ..model.surface import OpticalProperties, Surface

__all__ = ["Facets", "as_facets", "rectangle", "triangle_areas"]


def _frozen(a: np.ndarray) -> np.ndarray:
    a = np.array(a, dtype=float)
    a.setflags(write=False)
    return a


def _frozen_int(a: np.ndarray) -> np.ndarray:
    a = np.array(a, dtype=np.int64)
    a.setflags(write=False)
    return a


def triangle_areas(triangles) -> np.ndarray:
    """Areas of triangles ``(m, 3, 3)``, shape ``(m,)``.

    Examples
    --------
    >>> triangle_areas([[[0, 0, 0], [2, 0, 0], [0, 1, 0]]])
    array([1.])
    """
    t = np.asarray(triangles, dtype=float)
    return 0.5 * np.linalg.norm(np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]), axis=-1)


def _squares(areas: np.ndarray, normals: np.ndarray, centers: np.ndarray) -> np.ndarray:
    """:func:`rectangle` of each facet by its area alone, vectorised: ``(2 n, 3, 3)``."""
    e = np.eye(3)[np.argmin(np.abs(normals), axis=1)]                 # (n, 3)
    u = e - np.sum(e * normals, axis=1, keepdims=True) * normals
    u *= (0.5 * np.sqrt(areas) / np.linalg.norm(u, axis=1))[:, None]
    v = np.cross(normals, u)
    p0, p1, p2, p3 = centers - u - v, centers + u - v, centers + u + v, centers - u + v
    return np.stack([np.stack([p0, p1, p2], axis=1), np.stack([p0, p2, p3], axis=1)],
                    axis=1).reshape(-1, 3, 3)


def rectangle(area, normal, center, size=None, edge=None) -> np.ndarray:
    """Two triangles ``(2, 3, 3)`` outlining a rectangle in the plane through ``center``
    normal to ``normal``: a square of ``area``, or ``size = (a, b)`` with ``a`` along
    ``edge`` projected into the plane (default the body axis least aligned with the
    normal).

    Raises
    ------
    TorqueConfigError
        When ``edge`` is parallel to the normal, or ``size`` does not give ``area``.

    Examples
    --------
    >>> tris = rectangle(4.0, [0, 0, 1], [0, 0, 0])
    >>> tris[0]
    array([[-1., -1.,  0.],
           [ 1., -1.,  0.],
           [ 1.,  1.,  0.]])
    >>> float(triangle_areas(tris).sum())
    4.0
    """
    n = np.asarray(normal, dtype=float)
    n = n / np.linalg.norm(n)
    c = np.asarray(center, dtype=float)
    if size is None:
        a = b = float(np.sqrt(area))
    else:
        a, b = (float(x) for x in size)
        if not (a > 0 and b > 0):
            raise TorqueConfigError(f"expected two positive edges, got {size!r}", key="size")
        if area is not None and not abs(a * b - area) <= 1e-9 * area:
            raise TorqueConfigError(f"size {a} x {b} m does not give the area {area} m^2",
                                    key="size")
    e = np.eye(3)[int(np.argmin(np.abs(n)))] if edge is None else np.asarray(edge, float)
    u = e - (e @ n) * n
    length = np.linalg.norm(u)
    if not length > 1e-12 * max(np.linalg.norm(e), 1e-300):
        raise TorqueConfigError("the edge is parallel to the normal; give a direction in "
                                "the facet's plane", key="edge")
    u = 0.5 * a * u / length
    v = 0.5 * b * np.cross(n, u / np.linalg.norm(u))
    p = [c - u - v, c + u - v, c + u + v, c - u + v]
    return np.array([[p[0], p[1], p[2]], [p[0], p[2], p[3]]])


@dataclass(frozen=True, eq=False)
class Facets:
    """Flat facets with optical properties, body frame.

    Parameters
    ----------
    areas : array_like, shape (n,)
        Facet areas, m^2, each > 0.
    normals : array_like, shape (n, 3)
        Outward normals (normalised here; each must be non-zero).
    centroids : array_like, shape (n, 3)
        Facet centroids, m, body frame.
    specular, diffuse : float or array_like, shape (n,)
        ``rho_s`` and ``rho_d`` per facet, in [0, 1], ``rho_s + rho_d <= 1``.
    triangles : array_like, shape (m, 3, 3), optional
        The outlines of the facets as triangles, m (corners in any order); default a
        square of each facet's area centred on its centroid (:func:`rectangle`).
    triangle_facets : array_like of int, shape (m,), optional
        The facet each triangle belongs to (with ``triangles``); every facet needs at
        least one, and their areas must add up to the facet's area (to 1e-6).

    Raises
    ------
    TorqueConfigError
        Naming the key: a facet with zero, negative or non-finite area, a zero normal,
        a fraction outside [0, 1], arrays of inconsistent shapes, triangles that do
        not cover the facets' areas.

    Examples
    --------
    >>> plate = Facets.plate(2.0, [1.0, 0.0, 0.0], specular=0.3)   # two faces, 2 m^2
    >>> plate.normals
    array([[ 1.,  0.,  0.],
           [-1.,  0.,  0.]])
    >>> float(plate.areas.sum())
    4.0
    """

    areas: np.ndarray
    normals: np.ndarray
    centroids: np.ndarray
    specular: np.ndarray = 0.0
    diffuse: np.ndarray = 0.0
    triangles: np.ndarray | None = None
    triangle_facets: np.ndarray | None = None

    def __post_init__(self):
        areas = np.atleast_1d(np.asarray(self.areas, dtype=float))
        n = areas.shape[0]
        if areas.ndim != 1 or n == 0:
            raise TorqueConfigError(f"expected a 1-D array of facet areas, got shape "
                                    f"{areas.shape}", key="areas")
        bad = np.flatnonzero(~(np.isfinite(areas) & (areas > 0)))
        if bad.size:
            raise TorqueConfigError(f"facet {bad[0]} has area {areas[bad[0]]!r}: every "
                                    "facet needs a positive finite area (drop degenerate "
                                    "facets)", key="areas")
        vectors = {}
        for key in ("normals", "centroids"):
            v = np.asarray(getattr(self, key), dtype=float)
            if v.shape != (n, 3) or not np.all(np.isfinite(v)):
                raise TorqueConfigError(f"expected finite values of shape ({n}, 3), got "
                                        f"shape {v.shape}", key=key)
            vectors[key] = v
        length = np.linalg.norm(vectors["normals"], axis=1)
        bad = np.flatnonzero(~(length > 0))
        if bad.size:
            raise TorqueConfigError(f"facet {bad[0]} has a zero normal", key="normals")
        fractions = {}
        for key in ("specular", "diffuse"):
            try:
                f = np.broadcast_to(np.asarray(getattr(self, key), dtype=float), (n,))
            except ValueError:
                raise TorqueConfigError(f"expected a number or one per facet ({n})",
                                        key=key) from None
            bad = np.flatnonzero(~((f >= 0) & (f <= 1)))
            if bad.size:
                raise TorqueConfigError(f"facet {bad[0]}: must be in [0, 1], got "
                                        f"{f[bad[0]]!r}", key=key)
            fractions[key] = f
        bad = np.flatnonzero(fractions["specular"] + fractions["diffuse"] > 1 + 1e-12)
        if bad.size:
            raise TorqueConfigError(f"facet {bad[0]}: specular + diffuse exceeds 1",
                                    key="diffuse")
        object.__setattr__(self, "areas", _frozen(areas))
        object.__setattr__(self, "normals", _frozen(vectors["normals"] / length[:, None]))
        object.__setattr__(self, "centroids", _frozen(vectors["centroids"]))
        object.__setattr__(self, "specular", _frozen(fractions["specular"]))
        object.__setattr__(self, "diffuse", _frozen(fractions["diffuse"]))
        triangles, owner = self._outlines(areas)
        object.__setattr__(self, "triangles", _frozen(triangles))
        object.__setattr__(self, "triangle_facets", _frozen_int(owner))

    def _outlines(self, areas: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        n = areas.shape[0]
        if self.triangles is None:
            if self.triangle_facets is not None:
                raise TorqueConfigError("give triangles with triangle_facets",
                                        key="triangles")
            return _squares(areas, self.normals, self.centroids), np.repeat(np.arange(n), 2)
        tris = np.asarray(self.triangles, dtype=float)
        if tris.ndim != 3 or tris.shape[1:] != (3, 3) or not np.all(np.isfinite(tris)):
            raise TorqueConfigError(f"expected finite corners of shape (m, 3, 3), got shape "
                                    f"{tris.shape}", key="triangles")
        if self.triangle_facets is None:
            raise TorqueConfigError("give the facet of each triangle, triangle_facets",
                                    key="triangle_facets")
        owner = np.asarray(self.triangle_facets)
        if (owner.shape != tris.shape[:1] or not np.issubdtype(owner.dtype, np.integer)
                or (owner.size and (owner.min() < 0 or owner.max() >= n))):
            raise TorqueConfigError(f"expected {tris.shape[0]} facet indices in [0, {n})",
                                    key="triangle_facets")
        covered = np.bincount(owner, weights=triangle_areas(tris), minlength=n)
        bad = np.flatnonzero(~(np.abs(covered - areas) <= 1e-6 * areas))
        if bad.size:
            raise TorqueConfigError(f"facet {bad[0]}: its triangles cover "
                                    f"{covered[bad[0]]!r} m^2, its area is "
                                    f"{areas[bad[0]]!r} m^2", key="triangles")
        return tris, owner

    def __len__(self) -> int:
        return len(self.areas)

    @classmethod
    def from_surface(cls, surface: Surface) -> Facets:
        """The facets of a :class:`~attitude.model.surface.Surface` (mesh and materials).

        Examples
        --------
        >>> import attitude as att
        >>> from attitude.model.surface import OpticalProperties, Surface
        >>> ball = att.Polyhedron.ellipsoid(1, 1, 1, subdivisions=1)
        >>> f = Facets.from_surface(Surface.uniform(ball, OpticalProperties(0.1, 0.2)))
        >>> len(f), float(f.diffuse[0])
        (80, 0.2)
        """
        shape = surface.shape
        return cls(shape.face_areas, shape.face_normals, shape.face_centroids,
                   surface.specular, surface.diffuse, shape.vertices[shape.faces],
                   np.arange(len(shape.faces)))

    @classmethod
    def from_shape(cls, shape: Polyhedron, properties: OpticalProperties | None = None
                   ) -> Facets:
        """The faces of a closed mesh, all with ``properties`` (default: black).

        Examples
        --------
        >>> import attitude as att
        >>> len(Facets.from_shape(att.Polyhedron.ellipsoid(1, 1, 1, subdivisions=0)))
        20
        """
        properties = OpticalProperties() if properties is None else properties
        return cls.from_surface(Surface.uniform(shape, properties))

    @classmethod
    def plate(cls, area: float | None, normal, centroid=(0.0, 0.0, 0.0), *, specular=0.0,
              diffuse=0.0, back=None, size=None, edge=None) -> Facets:
        """A thin plate: two facets of ``area`` back to back (normals ``+n`` and ``-n``).

        ``back`` is an optional ``(specular, diffuse)`` pair for the rear face (default:
        as the front).  The outline (for self-shadowing only) is a square of ``area``,
        or ``size = (a, b)`` m with ``a`` along ``edge`` (:func:`rectangle`; ``area`` may
        then be None).

        Examples
        --------
        >>> len(Facets.plate(1.0, [0, 0, 1]))
        2
        >>> Facets.plate(None, [0, 0, 1], size=(8.0, 2.0), edge=[0, 1, 0]).areas
        array([16., 16.])
        """
        n = np.asarray(normal, dtype=float)
        c = np.asarray(centroid, dtype=float)
        if not np.linalg.norm(n) > 0:
            raise TorqueConfigError("the normal is zero", key="normal")
        rs, rd = (specular, diffuse) if back is None else back
        tris = rectangle(area, n, c, size, edge)
        if area is None:
            if size is None:
                raise TorqueConfigError("give the area or the size of the plate", key="area")
            area = float(size[0]) * float(size[1])
        return cls([area, area], [n, -n], [c, c], [specular, rs], [diffuse, rd],
                   np.concatenate([tris, tris[:, ::-1]]), [0, 0, 1, 1])

    @classmethod
    def box(cls, size, center=(0.0, 0.0, 0.0), *, specular=0.0, diffuse=0.0) -> Facets:
        """A rectangular box of edges ``size = (a, b, c)`` along the body axes, six facets
        (+x, -x, +y, -y, +z, -z).

        Examples
        --------
        >>> Facets.box([1.0, 2.0, 3.0]).areas
        array([6., 6., 3., 3., 2., 2.])
        """
        size = np.asarray(size, dtype=float)
        if size.shape != (3,) or not np.all(size > 0):
            raise TorqueConfigError(f"expected three positive edge lengths, got {size!r}",
                                    key="size")
        center = np.asarray(center, dtype=float)
        areas, normals, centroids, tris = [], [], [], []
        for i in range(3):
            j, k = (i + 1) % 3, (i + 2) % 3
            for sign in (1.0, -1.0):
                e = np.zeros(3)
                e[i] = sign
                areas.append(size[j] * size[k])
                normals.append(e)
                centroids.append(center + 0.5 * size[i] * e)
                tris.append(rectangle(areas[-1], e, centroids[-1], (size[j], size[k]),
                                      np.eye(3)[j]))
        return cls(areas, normals, centroids, specular, diffuse, np.concatenate(tris),
                   np.repeat(np.arange(6), 2))

    @classmethod
    def join(cls, parts) -> Facets:
        """One :class:`Facets` of several, in order (outlines kept).

        Examples
        --------
        >>> both = Facets.join([Facets.box([1.0, 1.0, 1.0]), Facets.plate(2.0, [0, 0, 1])])
        >>> len(both), both.triangle_facets[-1]
        (8, np.int64(7))
        """
        parts = list(parts)
        if not parts:
            raise TorqueConfigError("expected at least one set of facets", key="facets")
        starts = np.cumsum([0] + [len(f) for f in parts[:-1]])
        return cls(np.concatenate([f.areas for f in parts]),
                   np.concatenate([f.normals for f in parts]),
                   np.concatenate([f.centroids for f in parts]),
                   np.concatenate([f.specular for f in parts]),
                   np.concatenate([f.diffuse for f in parts]),
                   np.concatenate([f.triangles for f in parts]),
                   np.concatenate([f.triangle_facets + s for f, s in zip(parts, starts,
                                                                          strict=True)]))


def as_facets(shape, surface=None) -> Facets:
    """:class:`Facets` from a ``Facets``, a ``Surface``, or a ``Polyhedron`` with optional
    :class:`~attitude.model.surface.OpticalProperties` (or a ``Surface`` as ``surface``).

    Examples
    --------
    >>> import attitude as att
    >>> len(as_facets(att.Polyhedron.ellipsoid(1, 1, 1, subdivisions=0)))
    20
    """
    if isinstance(shape, Facets):
        if surface is not None:
            raise TorqueConfigError("give the optical properties inside Facets, not as "
                                    "surface", key="surface")
        return shape
    if isinstance(shape, Surface):
        return Facets.from_surface(shape)
    if isinstance(shape, Polyhedron):
        if isinstance(surface, Surface):
            if surface.shape is not shape:
                raise TorqueConfigError("the surface belongs to another shape",
                                        key="surface")
            return Facets.from_surface(surface)
        if surface is None or isinstance(surface, OpticalProperties):
            return Facets.from_shape(shape, surface)
        raise TorqueConfigError(f"expected a Surface or OpticalProperties, got "
                                f"{type(surface).__name__}", key="surface")
    raise TorqueConfigError(f"expected Facets, a Surface or a Polyhedron, got "
                            f"{type(shape).__name__}", key="shape")

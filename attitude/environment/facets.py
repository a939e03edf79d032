"""Flat facets of a spacecraft's outer surface: what radiation pressure and drag act on.

A :class:`Facets` holds, per facet, its area, outward unit normal, centroid (body frame)
and the optical fractions of :class:`attitude.surface.OpticalProperties` (specular
``rho_s`` and diffuse ``rho_d``; the rest is absorbed).  It is built from the same
description photometry uses -- a :class:`~attitude.surface.Surface` or a
:class:`~attitude.shape.Polyhedron` with one material -- or directly, for open
surfaces a closed mesh cannot describe (a thin plate, a solar array: two facets back
to back).  The torque models of the wing precompute their sums over facets from it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import TorqueConfigError
from ..shape import Polyhedron
from ..surface import OpticalProperties, Surface

__all__ = ["Facets", "as_facets"]


def _frozen(a: np.ndarray) -> np.ndarray:
    a = np.array(a, dtype=float)
    a.setflags(write=False)
    return a


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

    Raises
    ------
    TorqueConfigError
        Naming the key: a facet with zero, negative or non-finite area, a zero normal,
        a fraction outside [0, 1], arrays of inconsistent shapes.

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

    def __len__(self) -> int:
        return len(self.areas)

    @classmethod
    def from_surface(cls, surface: Surface) -> Facets:
        """The facets of a :class:`~attitude.surface.Surface` (mesh and materials).

        Examples
        --------
        >>> import attitude as att
        >>> from attitude.surface import OpticalProperties, Surface
        >>> ball = att.Polyhedron.ellipsoid(1, 1, 1, subdivisions=1)
        >>> f = Facets.from_surface(Surface.uniform(ball, OpticalProperties(0.1, 0.2)))
        >>> len(f), float(f.diffuse[0])
        (80, 0.2)
        """
        shape = surface.shape
        return cls(shape.face_areas, shape.face_normals, shape.face_centroids,
                   surface.specular, surface.diffuse)

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
    def plate(cls, area: float, normal, centroid=(0.0, 0.0, 0.0), *, specular=0.0,
              diffuse=0.0, back=None) -> Facets:
        """A thin plate: two facets of ``area`` back to back (normals ``+n`` and ``-n``).

        ``back`` is an optional ``(specular, diffuse)`` pair for the rear face (default:
        as the front).

        Examples
        --------
        >>> len(Facets.plate(1.0, [0, 0, 1]))
        2
        """
        n = np.asarray(normal, dtype=float)
        c = np.asarray(centroid, dtype=float)
        rs, rd = (specular, diffuse) if back is None else back
        return cls([area, area], [n, -n], [c, c], [specular, rs], [diffuse, rd])

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
        areas, normals, centroids = [], [], []
        for i in range(3):
            j, k = (i + 1) % 3, (i + 2) % 3
            for sign in (1.0, -1.0):
                e = np.zeros(3)
                e[i] = sign
                areas.append(size[j] * size[k])
                normals.append(e)
                centroids.append(center + 0.5 * size[i] * e)
        return cls(areas, normals, centroids, specular, diffuse)


def as_facets(shape, surface=None) -> Facets:
    """:class:`Facets` from a ``Facets``, a ``Surface``, or a ``Polyhedron`` with optional
    :class:`~attitude.surface.OpticalProperties` (or a ``Surface`` as ``surface``).

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

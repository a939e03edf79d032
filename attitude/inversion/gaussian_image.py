"""The Gaussian image of a convex body: facet areas over fixed outward normals.

A convex body is determined, up to a translation, by the area it presents in each
direction (Minkowski's theorem).  Convex inversion (Kaasalainen & Torppa 2001) fits
those areas, not vertices: the unit sphere is triangulated once, each triangle's
outward normal ``n_j`` is one direction of the Gaussian image, and the area of the body's
facet with that normal is

.. math::

    A_j = w_j \\exp\\Big(\\sum_{l \\le L,\\ |m| \\le l} a_{lm} Y_{lm}(n_j)\\Big),

with ``w_j`` the area of the triangle on the unit sphere and ``Y_lm`` the real, orthonormal
spherical harmonics: positive areas for any coefficients, a smooth shape for a low
degree ``L``.  All ``a_lm = 0`` is the triangulated unit sphere itself.

:func:`sphere_triangulation` gives ``8 n^2`` triangles for ``n`` rows per octant (the
subdivided octahedron, projected on the sphere), :func:`real_harmonics` the basis.

References
----------
.. [1] Kaasalainen, M. & Torppa, J. (2001). Optimization methods for asteroid lightcurve
   inversion I. Shape determination. *Icarus* 153, 24-36.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import ConvexHull
from scipy.special import sph_harm_y

from attitude.foundations.errors import PhotometryError

__all__ = ["GaussianImage", "sphere_triangulation", "real_harmonics"]


def sphere_triangulation(rows: int) -> tuple[np.ndarray, np.ndarray]:
    """The unit sphere as ``8 rows^2`` triangles: the octahedron's faces cut in ``rows``
    rows, the vertices pushed out to the sphere.

    Returns
    -------
    vertices : (v, 3) array
        On the unit sphere.
    faces : (8 rows^2, 3) int array
        Counter-clockwise seen from outside.

    Examples
    --------
    >>> v, f = sphere_triangulation(3)
    >>> f.shape, v.shape, bool(np.allclose(np.linalg.norm(v, axis=1), 1.0))
    ((72, 3), (38, 3), True)
    """
    if int(rows) != rows or rows < 1:
        raise PhotometryError(f"must be a positive integer, got {rows!r}", key="rows")
    n = int(rows)
    i, j = np.meshgrid(np.arange(n + 1), np.arange(n + 1), indexing="ij")
    keep = i + j <= n
    octant = np.stack([i[keep], j[keep], n - i[keep] - j[keep]], axis=1) / n
    signs = np.array([[sx, sy, sz] for sx in (1, -1) for sy in (1, -1) for sz in (1, -1)])
    points = (signs[:, None, :] * octant[None, :, :]).reshape(-1, 3)
    points = np.unique(np.round(points, 12) + 0.0, axis=0)
    points /= np.linalg.norm(points, axis=1)[:, None]
    hull = ConvexHull(points)
    faces = hull.simplices.copy()
    # outward: the normal agrees with the centroid's direction
    a, b, c = points[faces[:, 0]], points[faces[:, 1]], points[faces[:, 2]]
    flip = np.einsum("ij,ij->i", np.cross(b - a, c - a), a + b + c) < 0.0
    faces[flip] = faces[flip][:, ::-1]
    return points, faces


def real_harmonics(degree: int, directions) -> np.ndarray:
    """Real orthonormal spherical harmonics ``Y_lm`` up to ``degree`` at unit vectors.

    Ordered ``(0, 0), (1, -1), (1, 0), (1, 1), (2, -2), ...``: column ``l^2 + l + m``;
    ``Y_lm = sqrt(2) (-1)^m Re Y_l^m`` for ``m > 0``, ``sqrt(2) (-1)^m Im Y_l^|m|`` for
    ``m < 0``, with the complex ``Y_l^m`` of :func:`scipy.special.sph_harm_y`.

    Returns
    -------
    (n, (degree + 1)^2) array

    Examples
    --------
    >>> y = real_harmonics(2, [[0.0, 0.0, 1.0]])
    >>> round(float(y[0, 0] * np.sqrt(4 * np.pi)), 12), round(float(y[0, 2]), 12)
    (1.0, 0.488602511903)
    """
    d = np.asarray(directions, dtype=float).reshape(-1, 3)
    theta = np.arccos(np.clip(d[:, 2] / np.linalg.norm(d, axis=1), -1.0, 1.0))
    phi = np.arctan2(d[:, 1], d[:, 0])
    out = np.empty((d.shape[0], (degree + 1) ** 2))
    for ell in range(degree + 1):
        for m in range(ell + 1):
            y = sph_harm_y(ell, m, theta, phi)
            if m == 0:
                out[:, ell * ell + ell] = y.real
            else:
                sign = np.sqrt(2.0) * (-1.0) ** m
                out[:, ell * ell + ell + m] = sign * y.real
                out[:, ell * ell + ell - m] = sign * y.imag
    return out


@dataclass(frozen=True, eq=False)
class GaussianImage:
    """The fixed directions of a Gaussian image and its harmonic basis.

    Parameters
    ----------
    rows : int
        Triangulation rows per octant: ``8 rows^2`` directions (``convexinv``: 8-10).
    degree : int
        Degree ``L`` of the spherical-harmonic series of the log areas
        (``(L + 1)^2`` coefficients; ``convexinv``: 6).

    Attributes
    ----------
    normals : (F, 3) array
        Outward unit normals of the directions.
    weights : (F,) array
        Areas ``w_j`` of the triangles of the unit-sphere polyhedron.
    basis : (F, (L + 1)^2) array
        ``Y_lm(n_j)``.

    Examples
    --------
    >>> g = GaussianImage(rows=4, degree=3)
    >>> g.normals.shape, g.basis.shape
    ((128, 3), (128, 16))
    >>> areas = g.areas(np.zeros(16))       # the sphere's own triangles: they close
    >>> bool(np.allclose(areas @ g.normals, 0.0, atol=1e-15))
    True
    """

    rows: int = 8
    degree: int = 6

    def __post_init__(self):
        if int(self.degree) != self.degree or self.degree < 0:
            raise PhotometryError(f"must be a non-negative integer, got {self.degree!r}",
                                  key="degree")
        vertices, faces = sphere_triangulation(self.rows)
        a, b, c = vertices[faces[:, 0]], vertices[faces[:, 1]], vertices[faces[:, 2]]
        cross = np.cross(b - a, c - a)
        double_area = np.linalg.norm(cross, axis=1)
        normals = cross / double_area[:, None]
        for name, value in (("normals", normals), ("weights", 0.5 * double_area),
                            ("basis", real_harmonics(int(self.degree), normals))):
            value.setflags(write=False)
            object.__setattr__(self, name, value)

    @property
    def n_coefficients(self) -> int:
        """``(L + 1)^2``."""
        return (int(self.degree) + 1) ** 2

    def areas(self, coefficients) -> np.ndarray:
        """Facet areas ``w_j exp(sum a_lm Y_lm(n_j))``, ``(F,)``."""
        return self.weights * np.exp(self.basis @ np.asarray(coefficients, dtype=float))

    def dark_facet(self, areas) -> float:
        """Area of the facet that would close the set, relative to the total: ``|sum
        A_j n_j| / sum A_j`` (0 for the Gaussian image of a convex body; convex
        inversion keeps it below about 1 %, more means albedo variegation or a
        non-convex body)."""
        areas = np.asarray(areas, dtype=float)
        return float(np.linalg.norm(areas @ self.normals) / areas.sum())

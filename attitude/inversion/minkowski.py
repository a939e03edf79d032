"""From a Gaussian image to a convex polyhedron: Minkowski's problem.

Given outward unit normals ``n_j`` and areas ``A_j`` with ``sum A_j n_j = 0``, there is a
convex polyhedron, unique up to translation, whose facet with normal ``n_j`` has area
``A_j`` (Minkowski 1897).  It is ``P(h) = {x : n_j . x <= h_j}`` for the support distances
``h`` that maximise the volume ``V(h)`` at fixed ``sum A_j h_j`` (Little 1983; Lamberg 1993):
the derivative of the volume by ``h_j`` is the area ``F_j(h)`` of facet ``j``, so at the
optimum ``F_j = A_j`` up to one common factor.  ``V^(1/3)`` is concave (Brunn-Minkowski),
so ``w . h - log V(h) / 3`` (``w = A / sum A``) is convex and its minimum, where
``F_j / (3 V) = w_j``, is the solution scaled; it is found with scipy's L-BFGS-B (cost
linear in the number of facets per step), the volume and facet areas of ``P(h)``
computed exactly from scipy's half-space intersection (Qhull).

References
----------
.. [1] Little, J. J. (1983). An iterative method for reconstructing convex polyhedra from
   extended Gaussian images. *Proc. AAAI-83*, 247-250.
.. [2] Lamberg, L. (1993). On the Minkowski problem and the lightcurve operator. *Ann.
   Acad. Sci. Fenn. Math. Diss.* 87.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import minimize
from scipy.spatial import ConvexHull, HalfspaceIntersection, QhullError

from attitude.foundations.errors import ShapeModelError
from attitude.model.shape import Polyhedron

__all__ = ["support_polyhedron", "facet_mesh", "polyhedron_from_areas"]


def support_polyhedron(normals, support) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The polyhedron ``{x : n_j . x <= h_j}`` (the origin inside: every ``h_j > 0``).

    Returns
    -------
    vertices : (v, 3) array
    faces : (t, 3) int array
        Triangles, counter-clockwise seen from outside.
    facet_of : (t,) int array
        The half-space ``j`` each triangle lies on.

    Examples
    --------
    >>> n = np.vstack([np.eye(3), -np.eye(3)])
    >>> v, f, j = support_polyhedron(n, np.ones(6))       # the cube of side 2
    >>> v.shape, f.shape, np.bincount(j).tolist()
    ((8, 3), (12, 3), [2, 2, 2, 2, 2, 2])
    """
    normals = np.asarray(normals, dtype=float)
    h = np.asarray(support, dtype=float)
    halfspaces = np.hstack([normals, -h[:, None]])
    points = HalfspaceIntersection(halfspaces, np.zeros(3)).intersections
    # where more than three planes meet, Qhull returns the corner several times, a
    # round-off apart: one vertex each
    size = np.abs(points).max()
    _, first = np.unique(np.round(points / (1e-9 * size)), axis=0, return_index=True)
    hull = ConvexHull(points[np.sort(first)])
    vertices = hull.points[hull.vertices]
    index = np.full(hull.points.shape[0], -1)
    index[hull.vertices] = np.arange(hull.vertices.size)
    faces = index[hull.simplices]
    a, b, c = vertices[faces[:, 0]], vertices[faces[:, 1]], vertices[faces[:, 2]]
    cross = np.cross(b - a, c - a)
    flip = np.einsum("ij,ij->i", cross, a + b + c) < 0.0       # the origin is inside
    faces[flip] = faces[flip][:, ::-1]
    cross[flip] = -cross[flip]
    facet_of = np.argmax(cross @ normals.T, axis=1)
    return vertices, faces, facet_of


def facet_mesh(normals, support, *, merge: float = 1e-9) -> tuple[np.ndarray, np.ndarray]:
    """The polyhedron ``{x : n_j . x <= h_j}`` as a closed mesh with no sliver: each facet a
    fan of triangles around its centroid.  Which corners bound which facet comes from
    Qhull's half-space intersection (the planes through each corner), not from a distance
    test, so neighbouring facets agree on their common edges; corners closer than
    ``merge`` times the size are one; where a fan triangle would still be too thin for a
    shape model, the two corners of its short edge become one, or a sliver of a facet
    shrinks to a point (its neighbours then meet there).

    Returns
    -------
    vertices : (v, 3) array
    faces : (t, 3) int array
        Counter-clockwise seen from outside.

    Examples
    --------
    >>> n = np.vstack([np.eye(3), -np.eye(3)])
    >>> v, f = facet_mesh(n, np.ones(6))          # the cube: 8 corners + 6 centres
    >>> v.shape, f.shape
    ((14, 3), (24, 3))
    """
    normals = np.asarray(normals, dtype=float)
    h = np.asarray(support, dtype=float)
    hs = HalfspaceIntersection(np.hstack([normals, -h[:, None]]), np.zeros(3))
    points = hs.intersections
    size = np.abs(points).max()
    key = np.round(points / (merge * size))
    _, label = np.unique(key, axis=0, return_inverse=True)
    parent = np.arange(label.max() + 1)

    def root(i):
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    planes = [set() for _ in range(parent.size)]
    for p, duals in enumerate(hs.dual_facets):
        planes[label[p]].update(int(j) for j in duals)
    corner = np.zeros((parent.size, 3))
    np.add.at(corner, label, points)
    corner /= np.bincount(label)[:, None]

    def rings():
        members = {}
        for v in range(parent.size):
            r = root(v)
            for j in planes[v]:
                members.setdefault(j, set()).add(r)
        return members

    def fans():
        """Each facet's corners (roots) in counter-clockwise order, with the positions."""
        members = rings()
        roots = sorted({root(v) for v in range(parent.size)})
        index = {r: k for k, r in enumerate(roots)}
        position = np.zeros((len(roots), 3))
        counts = np.zeros(len(roots))
        for v in range(parent.size):
            position[index[root(v)]] += corner[v]
            counts[index[root(v)]] += 1
        position /= counts[:, None]
        out = []
        for j in sorted(members):
            ring = np.array([index[r] for r in members[j]])
            if ring.size < 3:
                continue
            centre = position[ring].mean(axis=0)
            d = position[ring] - centre
            u = d[np.argmax(np.linalg.norm(d, axis=1))]
            u = u / np.linalg.norm(u)
            w = np.cross(normals[j], u)
            out.append((centre, ring[np.argsort(np.arctan2(d @ w, d @ u))]))
        return roots, position, out

    # a fan triangle too thin for a shape model (twice its area within 100 times the
    # Polyhedron's degenerate bound, 1e-12 size^2): its short edge's corners become one,
    # or, on a sliver of a facet, the whole facet shrinks to a point; until none is left
    for _ in range(50):
        roots, position, facets = fans()
        thin = None
        for centre, ring in facets:
            nxt = np.roll(ring, -1)
            twice = np.linalg.norm(np.cross(position[ring] - centre,
                                            position[nxt] - centre), axis=1)
            k = int(np.argmin(twice))
            if twice[k] <= 1e-10 * size * size:
                edge = np.linalg.norm(position[ring[k]] - position[nxt[k]])
                thin = [ring[k], nxt[k]] if edge <= 1e-5 * size else list(ring)
                break
        if thin is None:
            break
        for k in thin[1:]:
            parent[root(roots[k])] = root(roots[thin[0]])
    vertices, faces = [position], []
    count = len(roots)
    for centre, ring in facets:
        vertices.append(centre[None, :])
        faces.append(np.stack([np.full(ring.size, count), ring, np.roll(ring, -1)], axis=1))
        count += 1
    return np.vstack(vertices), np.vstack(faces)


def _volume_and_areas(normals, h):
    """``V(h)`` and the facet areas ``F_j(h)`` (zero for a facet that has vanished), from
    one convex hull: that of the dual points ``n_j / h_j``.  A dual triangle is a corner
    ``p`` of ``P(h)`` (its plane is ``p . x = 1``), a dual edge ``a -> b`` between
    triangles ``t, t'`` an edge ``p_t p_t'`` of facet ``a``; so
    ``F_a = |n_a . sum (p_t x p_t')| / 2`` over the edges leaving ``a``, and
    ``V = sum_a h_a F_a / 3``."""
    hull = ConvexHull(normals / h[:, None])
    simplices = hull.simplices.copy()
    corner = -hull.equations[:, :3] / hull.equations[:, 3:]
    pts = hull.points
    a, b, c = pts[simplices[:, 0]], pts[simplices[:, 1]], pts[simplices[:, 2]]
    flip = np.einsum("ij,ij->i", np.cross(b - a, c - a), corner) < 0.0
    simplices[flip] = simplices[flip][:, ::-1]
    neighbours = hull.neighbors.copy()
    neighbours[flip] = neighbours[flip][:, ::-1]
    area = np.zeros((normals.shape[0], 3))
    for k in range(3):
        # edge from vertex k+1 to k+2, shared with the triangle opposite vertex k
        start = simplices[:, (k + 1) % 3]
        other = neighbours[:, k]
        np.add.at(area, start, np.cross(corner, corner[other]))
    areas = 0.5 * np.abs(np.einsum("ij,ij->i", area, normals))
    return float(h @ areas) / 3.0, areas


def polyhedron_from_areas(normals, areas, *, volume: float = 1.0, tolerance: float = 1e-10,
                          max_iterations: int = 2000) -> tuple[Polyhedron, float]:
    """The convex polyhedron of a Gaussian image, scaled to ``volume``.

    Parameters
    ----------
    normals : (F, 3) array
        Outward unit normals.
    areas : (F,) array
        Non-negative areas.  If ``sum A_j n_j`` is not zero, the facet that closes the
        set (the *dark facet* of convex inversion) is added.
    volume : float
        Volume of the result (the shape of a Gaussian image does not depend on scale).
    tolerance : float
        Convergence of the optimiser: the largest component of the gradient
        ``w - F / (3 V)``, i.e. of the facet-area shares.
    max_iterations : int

    Returns
    -------
    polyhedron : Polyhedron
        Triangulated, outward normals, centred where the optimiser put it (use its
        ``centroid``).
    mismatch : float
        ``max_j |F_j / sum F - A_j / sum A|`` over the facets (how well the areas are met).

    Raises
    ------
    ShapeModelError
        When the areas are not a Gaussian image (negative, all zero) or the optimiser
        fails.

    Examples
    --------
    The areas of a box of sides 1, 2, 3 give the box back:

    >>> n = np.vstack([np.eye(3), -np.eye(3)])
    >>> A = np.array([6.0, 3.0, 2.0, 6.0, 3.0, 2.0])
    >>> box, mismatch = polyhedron_from_areas(n, A, volume=6.0)
    >>> np.round(np.ptp(box.vertices, axis=0), 6).tolist(), mismatch < 1e-8
    ([1.0, 2.0, 3.0], True)
    """
    normals = np.asarray(normals, dtype=float)
    areas = np.asarray(areas, dtype=float)
    if areas.ndim != 1 or normals.shape != (areas.size, 3):
        raise ShapeModelError(f"need (F, 3) normals and (F,) areas, got {normals.shape} and "
                              f"{areas.shape}", key="areas")
    if not np.isfinite(areas).all() or np.any(areas < 0.0) or areas.sum() <= 0.0:
        raise ShapeModelError("facet areas must be finite, non-negative and not all zero",
                              key="areas")
    closing = areas @ normals
    gap = np.linalg.norm(closing)
    if gap > 1e-12 * areas.sum():
        normals = np.vstack([normals, -closing / gap])
        areas = np.append(areas, gap)
    weights = areas / areas.sum()

    def objective(h):
        # convex: w.h - log V(h) / 3 has its minimum where F_j(h) / (3 V) = w_j
        try:
            v, f = _volume_and_areas(normals, h)
        except QhullError:
            return np.inf, np.zeros_like(h)
        if v <= 0.0:
            return np.inf, np.zeros_like(h)
        return weights @ h - np.log(v) / 3.0, weights - f / (3.0 * v)

    start = np.full(weights.size, 1.0)
    result = minimize(objective, start, jac=True, method="L-BFGS-B",
                      options={"ftol": tolerance * tolerance, "gtol": tolerance,
                               "maxiter": max_iterations, "maxcor": 30})
    if not np.isfinite(result.fun):
        raise ShapeModelError(f"the Minkowski iteration failed: {result.message}",
                              key="areas")
    h = result.x
    v, f = _volume_and_areas(normals, h)
    scale = np.cbrt(volume / v)
    vertices, faces = facet_mesh(normals, h * scale)
    mismatch = float(np.max(np.abs(f / f.sum() - weights)))
    return Polyhedron(vertices, faces), mismatch

"""Inertia integrals of a body to order N: what the mutual potential of two bodies needs.

The inertia integral of multi-index ``(a, b, c)`` is ``T_abc = integral(x^a y^b z^c dm)``
over the body, about its centre of mass, in the body frame (Hou, Scheeres & Xin 2017,
CMDA 127, 369; Ashenberg 2007, CMDA 99, 149).  Degree 0 is the mass, degree 1 vanishes
about the centre of mass, and degree 2 is the inertia tensor in another guise:
``T_ij = tr(I)/2 delta_ij - I_ij``.

Each degree ``k`` is stored as a vector over the ``(k+1)(k+2)/2`` multi-indices of
:func:`multi_indices` (``a`` descending, then ``b``).  The integrals are exact:

- an ellipsoid or a sphere in closed form (the moments of the unit ball, scaled);
- a polyhedron of uniform density from its tetrahedra (each face with the centre of mass),
  by a collapsed Gauss-Jacobi product rule exact for polynomials of the degree asked
  (Stroud 1971, "Approximate calculation of multiple integrals", sect. 2.4): the
  integrals are exact to round-off, not approximated;
- a body known only by its moments: to degree 2, and no further.

Rotating a body rotates its integrals (:func:`rotated`): degree ``k`` as a symmetric
tensor of rank ``k``, each index turned by the attitude matrix.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from functools import cache

import numpy as np
from scipy.special import gammaln, roots_jacobi

from attitude.foundations.errors import BinarySystemError
from attitude.model.body import RigidBody

__all__ = ["InertiaIntegrals", "inertia_integrals", "multi_indices", "rotated"]


@cache
def multi_indices(k: int) -> np.ndarray:
    """The multi-indices ``(a, b, c)`` with ``a + b + c = k``, in storage order.

    Examples
    --------
    >>> multi_indices(2).tolist()
    [[2, 0, 0], [1, 1, 0], [1, 0, 1], [0, 2, 0], [0, 1, 1], [0, 0, 2]]
    """
    rows = [(a, b, k - a - b) for a in range(k, -1, -1) for b in range(k - a, -1, -1)]
    out = np.array(rows, dtype=np.int64).reshape(-1, 3)
    out.flags.writeable = False
    return out


@cache
def position(k: int) -> dict:
    """Multi-index tuple -> its position in degree ``k``'s vector."""
    return {tuple(m): i for i, m in enumerate(multi_indices(k).tolist())}


@cache
def tensor_maps(k: int) -> tuple[np.ndarray, np.ndarray]:
    """For degree ``k``: the multi-index position of each of the ``3^k`` tensor entries,
    and the flat tensor entry that represents each multi-index."""
    pos = position(k)
    full = np.array([pos[tuple(np.bincount(idx, minlength=3))] for idx in
                     itertools.product(range(3), repeat=k)], dtype=np.int64)
    first = np.array([list(full).index(i) for i in range(len(pos))], dtype=np.int64)
    return full, first


@dataclass(frozen=True, eq=False)
class InertiaIntegrals:
    """A body's inertia integrals to degree ``order``, about its centre of mass.

    Attributes
    ----------
    degrees : tuple of ndarray
        ``degrees[k]`` has shape ``(..., (k+1)(k+2)/2)``: kg m^k, the multi-indices of
        :func:`multi_indices` (leading dims for a batch of bodies or of attitudes).

    Examples
    --------
    >>> import attitude as att
    >>> ball = att.RigidBody.from_mass_properties(
    ...     att.MassProperties.solid_sphere(mass=5.0, radius=2.0))
    >>> T = inertia_integrals(ball, 2)
    >>> T.mass, T.degrees[2].round(12).tolist()      # integral x^2 dm = m r^2 / 5
    (5.0, [4.0, 0.0, 0.0, 4.0, 0.0, 4.0])
    """

    degrees: tuple

    @property
    def order(self) -> int:
        return len(self.degrees) - 1

    @property
    def mass(self):
        """kg (an array for a batch)."""
        m = self.degrees[0][..., 0]
        return float(m) if m.ndim == 0 else m


def inertia_integrals(body: RigidBody, order: int, *, name: str = "body") -> InertiaIntegrals:
    """The inertia integrals of ``body`` to degree ``order``, in its body frame.

    Parameters
    ----------
    body : RigidBody
        With a mass.  Beyond degree 2 it needs its mass distribution (a body made by
        ``MassProperties.solid_ellipsoid`` / ``solid_sphere`` or ``RigidBody.from_obj``).
    order : int
        Highest degree, >= 0.
    name : str
        The body's role in messages (``"primary"``).

    Raises
    ------
    BinarySystemError
        No mass, or a degree above 2 for a body known only by its moments.

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> body = att.RigidBody.from_principal_moments([2.0, 3.0, 4.0], mass=1.0)
    >>> T = inertia_integrals(body, 2)
    >>> T.degrees[2][[0, 3, 5]]            # tr(I)/2 - I_ii
    array([2.5, 1.5, 0.5])
    """
    if body.mass is None:
        raise BinarySystemError(f"{name}: the body has no mass; give mass= (a binary's "
                                "mutual gravity needs both masses)")
    if isinstance(order, bool) or not isinstance(order, (int, np.integer)) or order < 0:
        raise BinarySystemError(f"order: expected an integer >= 0, got {order!r}")
    dist = body.distribution
    if dist is None:
        if order > 2:
            raise BinarySystemError(
                f"{name}: a body known only by its moments has no mutual potential beyond "
                f"order 2 (order = {order} asked); make it from its shape "
                "(RigidBody.from_obj) or its primitive (MassProperties.solid_ellipsoid, "
                "solid_sphere), or set order = 2")
        return InertiaIntegrals(_from_inertia(body.mass, body.inertia, order))
    if dist.kind == "polyhedron":
        return InertiaIntegrals(_polyhedron(dist.shape.vertices, dist.shape.faces,
                                            dist.mass, order))
    return InertiaIntegrals(tuple(_ellipsoid(dist.mass, dist.semi_axes, k)
                                  for k in range(order + 1)))


def _from_inertia(mass: float, inertia: np.ndarray, order: int) -> tuple:
    out = [np.array([mass]), np.zeros(3)][:order + 1]
    if order >= 2:
        second = 0.5 * np.trace(inertia) * np.eye(3) - inertia
        out.append(second[_pairs()])
    return tuple(out)


@cache
def _pairs() -> tuple[np.ndarray, np.ndarray]:
    """Row and column of the 3x3 entry of each degree-2 multi-index."""
    rows, cols = [], []
    for a, b, c in multi_indices(2).tolist():
        axes = [0] * a + [1] * b + [2] * c
        rows.append(axes[0])
        cols.append(axes[1])
    return np.array(rows), np.array(cols)


def _ellipsoid(mass: float, semi_axes: np.ndarray, k: int) -> np.ndarray:
    """``m <x^a y^b z^c>`` over a homogeneous ellipsoid: the unit ball's moments scaled
    by ``a1^a a2^b a3^c``; the ball's, ``2 G(a') G(b') G(c') / (G(a'+b'+c') (k+3))``
    with ``a' = (a+1)/2`` (zero when an exponent is odd), over its volume ``4 pi/3``."""
    idx = multi_indices(k)
    even = np.all(idx % 2 == 0, axis=1)
    h = (idx + 1) / 2.0
    log_ball = (math.log(2.0) + gammaln(h).sum(axis=1) - gammaln(h.sum(axis=1))
                - math.log(k + 3))
    mean = np.where(even, np.exp(log_ball) / (4.0 * math.pi / 3.0), 0.0)
    return mass * mean * np.prod(np.asarray(semi_axes, float) ** idx, axis=1)


@cache
def _simplex_rule(order: int) -> tuple[np.ndarray, np.ndarray]:
    """Barycentric points (3 of the 4 coordinates) and weights of a rule on the unit
    tetrahedron exact to degree ``order``: Gauss-Jacobi in collapsed coordinates,
    ``u = s1, v = s2 (1 - s1), w = s3 (1 - s1)(1 - s2)`` with Jacobian
    ``(1 - s1)^2 (1 - s2)``; the weights sum to 1/6, the volume."""
    m = order // 2 + 1                      # 2m - 1 >= order
    rules = []
    for alpha in (2, 1, 0):
        x, w = roots_jacobi(m, alpha, 0)    # weight (1 - x)^alpha on [-1, 1]
        rules.append(((1.0 + x) / 2.0, w / 2.0 ** (alpha + 1)))
    (s1, w1), (s2, w2), (s3, w3) = rules
    S1, S2, S3 = np.meshgrid(s1, s2, s3, indexing="ij")
    W = (w1[:, None, None] * w2[None, :, None] * w3[None, None, :]).ravel()
    u = S1.ravel()
    v = (S2 * (1.0 - S1)).ravel()
    w = (S3 * (1.0 - S1) * (1.0 - S2)).ravel()
    return np.stack([u, v, w], axis=1), W


def _polyhedron(vertices: np.ndarray, faces: np.ndarray, mass: float, order: int) -> tuple:
    """Exact integrals of a uniform polyhedron from the signed tetrahedra (centroid, face)."""
    tri = vertices[faces]
    centroid = _signed_centroid(tri)
    edges = tri - centroid                                   # (f, 3, 3): corners - G
    volume6 = np.einsum("fi,fi->f", edges[:, 0], np.cross(edges[:, 1], edges[:, 2]))
    points, weights = _simplex_rule(max(order, 1))
    r = np.einsum("qj,fjk->fqk", points, edges).reshape(-1, 3)   # (f q, 3) from the centroid
    w = (volume6[:, None] * weights[None, :]).ravel()            # (f q,): 6 V * weight
    density = mass / (volume6.sum() / 6.0)
    moments = _power_moments(r, w, order)
    out = []
    for k in range(order + 1):
        a, b, c = multi_indices(k).T
        out.append(density * moments[a, b, c])
    out[0] = np.array([mass])
    if order >= 1:
        out[1] = np.zeros(3)            # about the centre of mass (round-off dropped)
    return tuple(out)


def _power_moments(r: np.ndarray, w: np.ndarray, order: int, chunk: int = 1 << 15
                   ) -> np.ndarray:
    """``M[a, b, c] = sum_n w_n x_n^a y_n^b z_n^c`` for ``a, b, c <= order`` (``a + b``
    at most ``order``): the powers of each coordinate by repeated products, the sums
    over a chunk of points (a few MB at a time) by ``einsum`` (numpy's own loops: a
    BLAS product here spins threads on a loaded machine for no gain)."""
    p = order + 1
    out = np.zeros((p, p, p))
    for start in range(0, len(r), chunk):
        x, y, z = r[start:start + chunk].T
        px, py, pz = (np.empty((p, len(x))) for _ in range(3))
        px[0], py[0], pz[0] = w[start:start + chunk], 1.0, 1.0
        for e in range(1, p):
            np.multiply(px[e - 1], x, out=px[e])
            np.multiply(py[e - 1], y, out=py[e])
            np.multiply(pz[e - 1], z, out=pz[e])
        for a in range(p):
            out[a, :p - a] += np.einsum("bn,cn->bc", px[a] * py[:p - a], pz)
    return out


def _signed_centroid(tri: np.ndarray) -> np.ndarray:
    origin = tri.reshape(-1, 3).mean(axis=0)
    e = tri - origin
    v6 = np.einsum("fi,fi->f", e[:, 0], np.cross(e[:, 1], e[:, 2]))
    return origin + (v6[:, None] * e.sum(axis=1)).sum(axis=0) / (4.0 * v6.sum())


def rotated(integrals: InertiaIntegrals, matrix: np.ndarray) -> InertiaIntegrals:
    """The integrals of the body turned by ``matrix`` (body -> inertial, ``(..., 3, 3)``):
    each degree as a symmetric tensor, every index turned.

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> rod = att.RigidBody.from_mass_properties(
    ...     att.MassProperties.solid_ellipsoid(mass=1.0, semi_axes=[5.0, 1.0, 1.0]))
    >>> T = inertia_integrals(rod, 3)
    >>> turned = rotated(T, Rotation.from_euler("z", 90, degrees=True).as_matrix())
    >>> turned.degrees[2][[0, 3]].round(12)   # the long axis now along y
    array([0.2, 5. ])
    """
    matrix = np.asarray(matrix, float)
    batch = np.broadcast_shapes(matrix.shape[:-2], *(t.shape[:-1] for t in integrals.degrees))
    out = []
    for k, t in enumerate(integrals.degrees):
        if k < 2:
            out.append(np.broadcast_to(t, batch + t.shape[-1:]).copy())
            continue
        full, first = tensor_maps(k)
        tensor = t[..., full]                                   # (..., 3^k), C order
        for _ in range(k):   # turn the first index and move it last: k passes, all turned
            tensor = np.einsum("...ij,...jr->...ri", matrix,
                               tensor.reshape(tensor.shape[:-1] + (3, 3 ** (k - 1))))
            tensor = tensor.reshape(tensor.shape[:-2] + (3**k,))
        out.append(np.broadcast_to(tensor, batch + (3**k,))[..., first].copy())
    return InertiaIntegrals(tuple(out))

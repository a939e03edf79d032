"""The mutual potential of two rigid bodies, its force and both torques, to order N.

With ``R`` the secondary's centre of mass relative to the primary's and ``r1``, ``r2``
points of each body about its centre of mass (inertial frame), the Taylor series of
``1 / |R + r2 - r1|`` about ``R``, integrated over both bodies, gives

    U = -G sum_{alpha, beta} (-1)^|beta| / (alpha! beta!) D_{alpha+beta}(R) T2_alpha T1_beta

over multi-indices with ``|alpha| + |beta| <= N`` (Ashenberg 2007, CMDA 99, 149; the
same series as the recursive form of Hou, Scheeres & Xin 2017, CMDA 127, 369), where
``D_gamma = d^gamma (1/R)`` and ``T`` are the inertia integrals of each body in the
inertial frame (:mod:`attitude.binary.integrals`).  The derivatives of ``1/R`` come from
the recurrence of its Taylor coefficients ``a_gamma = D_gamma / gamma!``,

    n R^2 a_gamma = -(2n - 1) sum_i x_i a_{gamma - e_i} - (n - 1) sum_i a_{gamma - 2 e_i},

with ``n = |gamma|``.  The force on the secondary is ``-dU/dR`` (each ``D`` one degree
higher); the torque on a body is minus the derivative of ``U`` along a small rotation of
that body, through the generators of rotation acting on its integrals.  Each degree pair
of the series is invariant under a rotation of the whole system, so the truncated
series keeps ``tau1 + tau2 + R x F = 0`` to round-off: the total angular momentum is
conserved at any order.

Everything broadcasts over leading dimensions (a batch of systems or of epochs).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cache
from typing import NamedTuple

import numpy as np

from attitude.binary.integrals import InertiaIntegrals, multi_indices, position
from attitude.foundations.constants import G as GRAVITATIONAL_CONSTANT
from attitude.foundations.errors import BinarySystemError

__all__ = ["MutualGravity", "MutualForces"]


class MutualForces(NamedTuple):
    """Potential (J), force on the secondary (N) and the torques on the primary and on
    the secondary about their centres of mass (N m), inertial frame.

    Examples
    --------
    >>> f = MutualForces(-1.0, [1.0, 0, 0], [0, 0, 0], [0, 0, 0])
    >>> f.potential
    -1.0
    """

    potential: np.ndarray
    force: np.ndarray
    torque_primary: np.ndarray
    torque_secondary: np.ndarray


@dataclass(frozen=True)
class _Pair:
    k: int           # degree in the secondary
    l: int           # degree in the primary  # noqa: E741 - the series' own letter
    index: np.ndarray     # (n_k, n_l): position of alpha + beta in degree k + l
    coef: np.ndarray      # (n_k, n_l): (-1)^l / (alpha! beta!)
    force_index: np.ndarray   # (3, n_k, n_l): position of alpha + beta + e_i


@cache
def _factorials(n: int) -> np.ndarray:
    return np.array([math.prod(math.factorial(int(v)) for v in row)
                     for row in multi_indices(n)], dtype=float)


@cache
def _recurrence(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Positions of ``gamma - e_i`` in degree n-1 and of ``gamma - 2 e_i`` in degree n-2
    for each ``gamma`` of degree n (a missing one points at the zero slot at the end)."""
    one = np.full((3, len(multi_indices(n))), len(multi_indices(n - 1)), dtype=np.int64)
    two = np.full_like(one, len(multi_indices(n - 2)) if n >= 2 else 0)
    for j, gamma in enumerate(multi_indices(n).tolist()):
        for i in range(3):
            g = list(gamma)
            g[i] -= 1
            if g[i] >= 0:
                one[i, j] = position(n - 1)[tuple(g)]
            g[i] -= 1
            if g[i] >= 0 and n >= 2:
                two[i, j] = position(n - 2)[tuple(g)]
    return one, two


@cache
def _pairs(order: int) -> tuple[_Pair, ...]:
    pairs = []
    for k in range(order + 1):
        for l in range(order + 1 - k):  # noqa: E741
            if k == 1 or l == 1:        # degree 1 vanishes about the centres of mass
                continue
            A, B = multi_indices(k), multi_indices(l)
            fa, fb = _factorials(k), _factorials(l)
            index = np.empty((len(A), len(B)), dtype=np.int64)
            force = np.empty((3, len(A), len(B)), dtype=np.int64)
            for i, a in enumerate(A.tolist()):
                for j, b in enumerate(B.tolist()):
                    g = tuple(x + y for x, y in zip(a, b))
                    index[i, j] = position(k + l)[g]
                    for axis in range(3):
                        h = list(g)
                        h[axis] += 1
                        force[axis, i, j] = position(k + l + 1)[tuple(h)]
            coef = (-1.0) ** l / np.outer(fa, fb)
            pairs.append(_Pair(k, l, index, coef, force))
    return tuple(pairs)


@cache
def generators(k: int) -> np.ndarray:
    """``(3, n_k, n_k)``: the derivative of degree ``k``'s integrals along a small
    rotation ``dtheta`` of the body (``dr = dtheta x r``), about x, y and z."""
    idx = multi_indices(k)
    pos = position(k)
    out = np.zeros((3, len(idx), len(idx)))
    # d(x^a y^b z^c)/dtheta for dr = dtheta x r: (axis, exponent lost, exponent gained,
    # sign); the term carries -sign times the lost exponent
    moves = ((0, 1, 2, +1), (0, 2, 1, -1),    # theta_x: y -> z carries -b, z -> y carries +c
             (1, 2, 0, +1), (1, 0, 2, -1),    # theta_y: z -> x carries -c, x -> z carries +a
             (2, 0, 1, +1), (2, 1, 0, -1))    # theta_z: x -> y carries -a, y -> x carries +b
    for j, m in enumerate(idx.tolist()):
        for axis, lose, gain, sign in moves:
            if m[lose] == 0:
                continue
            src = list(m)
            src[lose] -= 1
            src[gain] += 1
            out[axis, j, pos[tuple(src)]] += -sign * m[lose]
    return out


@dataclass(frozen=True)
class MutualGravity:
    """The mutual potential of two bodies truncated at total degree ``order``.

    Parameters
    ----------
    order : int
        Highest total degree of the series (2: point masses plus each body's second
        moments; 4: what GUBAS's examples use).
    G : float
        Gravitational constant, m^3 kg^-1 s^-2.

    Raises
    ------
    BinarySystemError
        An order that is not an integer >= 0, a G that is not finite and positive, or
        (by :meth:`forces` and :meth:`terms`) integrals of a lower order than asked.

    Examples
    --------
    Two spheres attract as point masses at every order:

    >>> import numpy as np, attitude as att
    >>> from attitude.binary.integrals import inertia_integrals
    >>> ball = lambda m, r: att.RigidBody.from_mass_properties(
    ...     att.MassProperties.solid_sphere(mass=m, radius=r))
    >>> T1, T2 = inertia_integrals(ball(5e11, 400.0), 4), inertia_integrals(ball(4e9, 80.0), 4)
    >>> f = MutualGravity(4).forces(np.array([1200.0, 0.0, 0.0]), T1, T2)
    >>> bool(np.isclose(f.potential, -att.binary.G * 5e11 * 4e9 / 1200.0, rtol=1e-14))
    True
    """

    order: int
    G: float = GRAVITATIONAL_CONSTANT

    def __post_init__(self):
        if isinstance(self.order, bool) or not isinstance(self.order, (int, np.integer)) \
                or self.order < 0:
            raise BinarySystemError(f"order: expected an integer >= 0, got {self.order!r}")
        if isinstance(self.G, bool) or not isinstance(self.G, (int, float, np.floating,
                                                                np.integer)) \
                or not (math.isfinite(self.G) and self.G > 0):
            raise BinarySystemError(f"G: expected a finite positive number (m^3 kg^-1 "
                                    f"s^-2), got {self.G!r}")

    def _check(self, primary: InertiaIntegrals, secondary: InertiaIntegrals) -> None:
        for name, T in (("primary", primary), ("secondary", secondary)):
            if not isinstance(T, InertiaIntegrals) or T.order < self.order:
                have = T.order if isinstance(T, InertiaIntegrals) else type(T).__name__
                raise BinarySystemError(
                    f"{name}: the mutual potential to order {self.order} needs the body's "
                    f"inertia integrals to order {self.order} (inertia_integrals(body, "
                    f"{self.order})), got {have}")

    def _inverse_distance(self, R: np.ndarray) -> list:
        """``D_gamma(R)`` for every degree 0..order+1, each ``(..., n_degree)``."""
        x, y, z = R[..., 0:1], R[..., 1:2], R[..., 2:3]
        r2 = x * x + y * y + z * z
        zero = np.zeros_like(x)
        coeffs = [np.concatenate([1.0 / np.sqrt(r2), zero], axis=-1)]
        for n in range(1, self.order + 2):
            one, two = _recurrence(n)
            prev = coeffs[n - 1]
            acc = -(2 * n - 1) * (x * prev[..., one[0]] + y * prev[..., one[1]]
                                  + z * prev[..., one[2]])
            if n >= 2:
                pp = coeffs[n - 2]
                acc -= (n - 1) * (pp[..., two[0]] + pp[..., two[1]] + pp[..., two[2]])
            coeffs.append(np.concatenate([acc / (n * r2), zero], axis=-1))
        return [c[..., :-1] * _factorials(n) for n, c in enumerate(coeffs)]

    def forces(self, R, primary: InertiaIntegrals, secondary: InertiaIntegrals
               ) -> MutualForces:
        """Potential, force on the secondary and both torques, inertial frame.

        Parameters
        ----------
        R : (..., 3) array
            Secondary's centre of mass relative to the primary's, m.
        primary, secondary : InertiaIntegrals
            Each body's integrals **in the inertial frame**
            (:func:`attitude.binary.integrals.rotated`), to at least ``order``.
        """
        self._check(primary, secondary)
        R = np.asarray(R, float)
        D = self._inverse_distance(R)
        T1, T2 = primary.degrees, secondary.degrees
        U = 0.0
        F = 0.0
        g1 = {}
        g2 = {}
        for p in _pairs(self.order):
            M = D[p.k + p.l][..., p.index] * p.coef                 # (..., n_k, n_l)
            MT1 = np.einsum("...kl,...l->...k", M, T1[p.l])
            U = U + np.einsum("...k,...k->...", T2[p.k], MT1)
            g2[p.k] = g2.get(p.k, 0.0) + MT1
            g1[p.l] = g1.get(p.l, 0.0) + np.einsum("...k,...kl->...l", T2[p.k], M)
            FM = D[p.k + p.l + 1][..., p.force_index] * p.coef       # (..., 3, n_k, n_l)
            F = F + np.einsum("...ikl,...k,...l->...i", FM, T2[p.k], T1[p.l])
        G = self.G
        torque1 = G * sum(_rotation_work(g1[k], T1[k], k) for k in g1 if k >= 2)
        torque2 = G * sum(_rotation_work(g2[k], T2[k], k) for k in g2 if k >= 2)
        zeros = np.zeros(R.shape)
        return MutualForces(-G * U, G * F + zeros, torque1 + zeros, torque2 + zeros)

    def terms(self, R, primary: InertiaIntegrals, secondary: InertiaIntegrals
              ) -> np.ndarray:
        """The potential's contribution of each total degree ``0..order``, J
        (``(order + 1, ...)``): the last one is the change from order N-1 to N.

        Examples
        --------
        >>> import numpy as np, attitude as att
        >>> from attitude.binary.integrals import inertia_integrals
        >>> egg = att.RigidBody.from_mass_properties(
        ...     att.MassProperties.solid_ellipsoid(mass=1e9, semi_axes=[100.0, 80.0, 60.0]))
        >>> T = inertia_integrals(egg, 4)
        >>> t = MutualGravity(4).terms([1000.0, 0, 0], T, T)
        >>> bool(abs(t[4] / t.sum()) < abs(t[2] / t.sum()) < 1e-2)   # converging
        True
        """
        self._check(primary, secondary)
        R = np.asarray(R, float)
        D = self._inverse_distance(R)
        out = np.zeros((self.order + 1,) + R.shape[:-1])
        for p in _pairs(self.order):
            M = D[p.k + p.l][..., p.index] * p.coef
            out[p.k + p.l] += np.einsum("...k,...kl,...l->...", secondary.degrees[p.k], M,
                                        primary.degrees[p.l])
        return -self.G * out


def _rotation_work(field: np.ndarray, integrals: np.ndarray, k: int) -> np.ndarray:
    """``sum_alpha dU/dT_alpha dT_alpha/dtheta`` without ``-G``: the torque is minus the
    potential's derivative along the body's small rotation; ``U = -G sum(field T)``."""
    turned = np.einsum("iab,...b->...ia", generators(k), integrals)
    return np.einsum("...a,...ia->...i", field, turned)


@cache
def series_tables(order: int) -> dict:
    """The series' tables flattened for compiled code (:mod:`attitude.binary.compiled`
    consumes them rather than re-deriving the series): with ``n_k = (k+1)(k+2)/2`` and
    ``offset[k]`` the start of degree ``k`` in a vector of all degrees 0..order+1,

    - ``one``, ``two`` ``(3, offset[order + 2])``: the recurrence's positions of
      ``gamma - e_i`` (in degree n-1) and ``gamma - 2 e_i`` (in degree n-2) at ``gamma``'s
      slot (a missing one is ``n_{n-1}``, resp. ``n_{n-2}``);
    - ``factorials``: ``gamma!`` at ``gamma``'s slot;
    - per pair ``(k, l)`` of the series (``pair_k``, ``pair_l``, ``pair_start``): its
      ``index`` and ``coef`` (``n_k x n_l`` from ``pair_start``) and ``force_index``
      (``3 x n_k x n_l`` from ``3 pair_start``);
    - ``generators`` of degree ``k >= 2``, ``3 x n_k x n_k`` from ``generator_start[k]``.
    """
    degrees = order + 2
    sizes = [(k + 1) * (k + 2) // 2 for k in range(degrees + 1)]
    offset = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
    one = np.zeros((3, offset[degrees]), dtype=np.int64)
    two = np.zeros_like(one)
    factorials = np.empty(offset[degrees])
    for n in range(degrees):
        factorials[offset[n]:offset[n + 1]] = _factorials(n)
        if n >= 1:
            one[:, offset[n]:offset[n + 1]], two[:, offset[n]:offset[n + 1]] = _recurrence(n)
    pairs = _pairs(order)
    starts = np.concatenate([[0], np.cumsum([p.index.size for p in pairs])]).astype(np.int64)
    gen_sizes = [3 * sizes[k] ** 2 if k >= 2 else 0 for k in range(order + 1)]
    return {
        "offset": offset, "one": one, "two": two, "factorials": factorials,
        "pair_k": np.array([p.k for p in pairs], dtype=np.int64),
        "pair_l": np.array([p.l for p in pairs], dtype=np.int64),
        "pair_start": starts,
        "index": np.concatenate([p.index.ravel() for p in pairs]).astype(np.int64),
        "coef": np.concatenate([p.coef.ravel() for p in pairs]),
        "force_index": np.concatenate([p.force_index.ravel() for p in pairs]).astype(np.int64),
        "generator_start": np.concatenate([[0], np.cumsum(gen_sizes)]).astype(np.int64),
        "generators": np.concatenate([np.zeros(0)] + [generators(k).ravel()
                                                      for k in range(2, order + 1)]),
    }

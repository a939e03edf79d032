"""The Lie-group variational integrator (LGVI) of the full two-body problem.

Lee, Leok & McClamroch (2007, Comput. Methods Appl. Mech. Engrg. 196, 2907), the form
GUBAS uses (Fahnestock & Scheeres 2006; Davis & Scheeres 2020), in the inertial frame.
With ``h`` the step, ``mu`` the reduced mass, ``p = mu V``, ``Pi_i = I_i w_i`` each
body's angular momentum in its own frame, ``M_i = A_i^T tau_i`` its torque in its frame,
``F`` the force on the secondary (``-dU/dR``) and ``J_i = tr(I_i)/2 E - I_i`` the
nonstandard inertia, one step is

    h S(Pi_i + h/2 M_i) = F_i J_i - J_i F_i^T             (solved for F_i in SO(3))
    R'    = R + h/mu p + h^2/(2 mu) F
    A_i'  = A_i F_i
    p'    = p + h/2 (F + F')
    Pi_i' = F_i^T (Pi_i + h/2 M_i) + h/2 M_i'

(``S(x)`` the cross-product matrix, primes the next step).  The first line is solved by
Newton's method on the Cayley parameters ``f`` of ``F = (E + S(f))(E - S(f))^-1``: with
``g = Pi + h/2 M`` it reads ``h g (1 + f.f) = 2 (I f + f x I f)``, so ``F`` is a rotation
to round-off whatever the iterate.  The map is symplectic and keeps the total angular
momentum ``R x p + sum A_i Pi_i`` exactly (the step adds ``h/2 (R x F + tau_1 + tau_2)``
twice, zero for the mutual potential at any order); the energy error is ``O(h^2)`` and
oscillates without drift.  Impulses change ``p`` and ``Pi`` between two steps.
"""

from __future__ import annotations

import itertools
import math
from functools import cache

import numpy as np
from scipy.spatial.transform import Rotation

from attitude.binary.dynamics import unpack
from attitude.binary.integrals import InertiaIntegrals, multi_indices
from attitude.binary.system import BinarySystem
from attitude.foundations import quaternion as quat
from attitude.foundations.errors import PropagationError
from attitude.propagation.splitting import step_count

__all__ = ["integrate_lgvi", "default_step", "step_grid", "cayley_step"]

#: Newton on the Cayley parameters stops when the correction is below this fraction of
#: ``|f|`` (about 4.5 ulps).
NEWTON_RTOL = 1e-15
#: ... or after this many iterations (a step too long for the spin has no solution).
NEWTON_MAX = 20
#: The default step is this fraction of the shortest of the orbit and spin periods.
STEP_FRACTION = 1.0 / 200.0


def _cayley(f) -> np.ndarray:
    """``(E + S(f))(E - S(f))^-1 = E + 2 (S + S^2) / (1 + f.f)`` of one ``f``."""
    x, y, z = f
    c = 2.0 / (1.0 + x * x + y * y + z * z)
    return np.array([[1.0 - c * (y * y + z * z), c * (x * y - z), c * (x * z + y)],
                     [c * (x * y + z), 1.0 - c * (x * x + z * z), c * (y * z - x)],
                     [c * (x * z - y), c * (y * z + x), 1.0 - c * (x * x + y * y)]])


def _solve3(m, r):
    """``m^-1 r`` for a 3x3 ``m`` (nested lists) by Cramer's rule."""
    (a, b, c), (d, e, f), (g, h, i) = m
    A, B, C = e * i - f * h, f * g - d * i, d * h - e * g
    det = a * A + b * B + c * C
    x = (r[0] * A + r[1] * (c * h - b * i) + r[2] * (b * f - c * e)) / det
    y = (r[0] * B + r[1] * (a * i - c * g) + r[2] * (c * d - a * f)) / det
    z = (r[0] * C + r[1] * (b * g - a * h) + r[2] * (a * e - b * d)) / det
    return x, y, z


def cayley_step(g, inertia, h: float) -> np.ndarray:
    """The rotation ``F`` (3x3) with ``h S(g) = F J - J F^T``, ``J = tr(I)/2 E - I``, for
    a body-frame momentum ``g`` (3,) and inertia tensor ``inertia`` (3x3): Newton's
    method on the Cayley parameters ``f``, ``h g (1 + f.f) = 2 (I f + f x I f)``, from
    ``f = h I^-1 g / 2`` (3-vectors as Python floats: faster than numpy at this size).

    Raises
    ------
    PropagationError
        Newton does not converge in :data:`NEWTON_MAX` iterations (``h |g|`` beyond
        what one rotation can carry: the step is too long for the spin).

    Examples
    --------
    A free body spinning about a principal axis turns by ``asin(h w)`` in one step
    (``h w`` to second order):

    >>> import numpy as np
    >>> I = np.diag([1.0, 2.0, 3.0])
    >>> F = cayley_step([0.0, 0.0, 3.0 * 0.1], I, 2.0)   # w = 0.1 rad/s
    >>> bool(np.isclose(np.arctan2(F[1, 0], F[0, 0]), np.arcsin(0.2), rtol=1e-14))
    True
    """
    I = np.asarray(inertia, float).tolist()  # noqa: E741 - the inertia tensor
    u0, u1, u2 = (h * float(v) for v in g)
    f0, f1, f2 = _solve3(I, (0.5 * u0, 0.5 * u1, 0.5 * u2))
    previous = math.inf
    eps = np.finfo(float).eps
    for _ in range(NEWTON_MAX):
        i0 = I[0][0] * f0 + I[0][1] * f1 + I[0][2] * f2
        i1 = I[1][0] * f0 + I[1][1] * f1 + I[1][2] * f2
        i2 = I[2][0] * f0 + I[2][1] * f1 + I[2][2] * f2
        s = 1.0 + f0 * f0 + f1 * f1 + f2 * f2
        residual = (u0 * s - 2.0 * (i0 + f1 * i2 - f2 * i1),
                    u1 * s - 2.0 * (i1 + f2 * i0 - f0 * i2),
                    u2 * s - 2.0 * (i2 + f0 * i1 - f1 * i0))
        # d/df of the residual: 2 u f^T - 2 (I + S(f) I - S(I f))
        SI = [[f1 * I[2][j] - f2 * I[1][j] for j in range(3)],
              [f2 * I[0][j] - f0 * I[2][j] for j in range(3)],
              [f0 * I[1][j] - f1 * I[0][j] for j in range(3)]]
        SIf = ((0.0, -i2, i1), (i2, 0.0, -i0), (-i1, i0, 0.0))
        u, f = (u0, u1, u2), (f0, f1, f2)
        jac = [[2.0 * u[r] * f[c] - 2.0 * (I[r][c] + SI[r][c] - SIf[r][c]) for c in range(3)]
               for r in range(3)]
        d0, d1, d2 = _solve3(jac, residual)
        f0, f1, f2 = f0 - d0, f1 - d1, f2 - d2
        correction = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
        size = math.sqrt(f0 * f0 + f1 * f1 + f2 * f2)
        # converged, or at the round-off floor (the correction stopped shrinking at a
        # few ulps of |f|)
        if correction <= NEWTON_RTOL * size or (correction <= 64 * eps * size
                                                 and correction >= 0.5 * previous):
            return _cayley((f0, f1, f2))
        if not math.isfinite(size):
            break
        previous = correction
    raise PropagationError(
        f"step: the LGVI's implicit rotation did not converge in {NEWTON_MAX} Newton "
        f"iterations (h |I^-1 g| = {math.hypot(*_solve3(I, (u0, u1, u2))):.3g} rad in one "
        "step); give a shorter step")


@cache
def _tensor_index(k: int) -> tuple[np.ndarray, np.ndarray]:
    """Degree ``k``: the multi-index position of each of the ``3^k`` tensor entries, and
    one tensor entry for each multi-index."""
    pos = {tuple(m): i for i, m in enumerate(multi_indices(k).tolist())}
    full = np.array([pos[tuple(np.bincount(idx, minlength=3))] for idx in
                     itertools.product(range(3), repeat=k)], dtype=np.int64)
    first = np.array([int(np.flatnonzero(full == i)[0]) for i in range(len(pos))])
    return full, first


class _Turner:
    """One body's inertia integrals as full tensors, turned by an attitude matrix with
    ``k`` small matrix products per degree (the lean form of
    :func:`attitude.binary.integrals.rotated` for one attitude)."""

    def __init__(self, integrals: InertiaIntegrals):
        self.low = [np.asarray(t, float) for t in integrals.degrees[:2]]
        self.tensors = [(k, np.asarray(t, float)[_tensor_index(k)[0]].reshape(3, -1),
                         _tensor_index(k)[1]) for k, t in enumerate(integrals.degrees)
                        if k >= 2]

    def __call__(self, A: np.ndarray) -> InertiaIntegrals:
        out = list(self.low)
        for k, X, first in self.tensors:
            for _ in range(k):     # turn the first index, then move it to the back
                X = (A @ X).T.reshape(3, -1)
            out.append(X.reshape(-1)[first])
        return InertiaIntegrals(tuple(out))


def default_step(system: BinarySystem, y0: np.ndarray) -> float:
    """The default LGVI step, s: :data:`STEP_FRACTION` (1/200) of the shortest of the
    osculating orbit period (Kepler, from the relative position and velocity; for an
    unbound orbit the circular period at the current separation) and both spin periods
    ``2 pi / |w_i|``.

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from attitude.binary.dynamics import pack
    >>> ball = att.RigidBody.from_mass_properties(att.MassProperties.solid_sphere(1e9, 50.0))
    >>> system = att.BinarySystem(ball, ball)
    >>> y0 = pack([500.0, 0, 0], [0, np.sqrt(system.mu / 500.0), 0], [0, 0, 0, 1.0],
    ...           [0, 0, 2 * np.pi / 3600.0], [0, 0, 0, 1.0], [0, 0, 0])
    >>> default_step(system, y0)          # the primary's 1 h spin is the fastest
    18.0
    """
    R, V, _, w1, _, w2 = unpack(np.asarray(y0, float))
    r, v2 = float(np.linalg.norm(R)), float(V @ V)
    inverse_a = 2.0 / r - v2 / system.mu
    a = 1.0 / inverse_a if inverse_a > 0 else r
    periods = [2.0 * math.pi * math.sqrt(a**3 / system.mu)]
    periods += [2.0 * math.pi / float(np.linalg.norm(w)) for w in (w1, w2) if np.any(w)]
    return STEP_FRACTION * min(periods)


def step_grid(knots: np.ndarray, h: float) -> np.ndarray:
    """0, the knots (output and impulse times) and equal steps no longer than ``h``
    between consecutive knots (as the splitting's grid): a knot inside a uniform step
    shortens the steps of its interval, never lands inside one.

    Examples
    --------
    >>> step_grid(np.array([60.0, 100.0]), 30.0).tolist()
    [0.0, 30.0, 60.0, 80.0, 100.0]
    """
    knots = np.unique(np.concatenate([[0.0], np.asarray(knots, float)]))
    parts = [knots[:1]]
    for a, b in zip(knots[:-1], knots[1:]):
        parts.append(np.linspace(a, b, step_count(b - a, h) + 1)[1:])
    return np.concatenate(parts)


def _loads(system: BinarySystem, turners, R: np.ndarray, A: np.ndarray):
    """Force on the secondary (inertial) and both body-frame torques ``(2, 3)``."""
    f = system.gravity.forces(R, turners[0](A[0]), turners[1](A[1]))
    M = np.stack([A[0].T @ f.torque_primary, A[1].T @ f.torque_secondary])
    return f.force, M


def integrate_lgvi(system: BinarySystem, y0: np.ndarray, t: np.ndarray, step: float,
                   impulses=()) -> np.ndarray:
    """Integrate one system from ``y0`` (time 0) to the sorted times ``t >= 0`` with the
    LGVI at steps no longer than ``step`` (s); returns ``(len(t), 20)`` state vectors
    (:mod:`attitude.binary.dynamics`) with canonical unit quaternions.

    ``impulses`` are ``(time, Impulse)`` pairs: the steps end at each impulse's time,
    where it changes the momenta (a sample at that time holds the state after it).

    Examples
    --------
    Two spheres on a circular orbit: after one period the secondary is back within the
    method's error, ``r (n h)^2 (n t / 3 + 1)`` (it lags by ``r (n h)^2 n t / 3``):

    >>> import numpy as np, attitude as att
    >>> from attitude.binary.dynamics import pack
    >>> ball = att.RigidBody.from_mass_properties(att.MassProperties.solid_sphere(1e9, 50.0))
    >>> system = att.BinarySystem(ball, ball)
    >>> v = np.sqrt(system.mu / 500.0)
    >>> y0 = pack([500.0, 0, 0], [0, v, 0], [0, 0, 0, 1.0], [0, 0, 0], [0, 0, 0, 1.0],
    ...           [0, 0, 0])
    >>> period = 2 * np.pi * 500.0 / v
    >>> y = integrate_lgvi(system, y0, [0.0, period], period / 400)
    >>> lag = np.linalg.norm(y[-1, :3] - [500.0, 0, 0])
    >>> bool(lag < 500.0 * (2 * np.pi / 400)**2 * (2 * np.pi / 3 + 1))
    True
    """
    t = np.asarray(t, float)
    y0 = np.asarray(y0, float)
    out = np.empty((t.size, 20))
    if t.size == 0:
        return out
    mu = system.reduced_mass
    inertia = np.stack([system.primary.inertia, system.secondary.inertia])
    kicks = sorted((e for e in impulses if e[0] <= t[-1]), key=lambda e: e[0])  # later: no effect
    grid = step_grid(np.concatenate([t, [s for s, _ in kicks]]), step)
    sample = np.searchsorted(grid, t)                 # grid node of each output time
    kick_at = np.searchsorted(grid, [s for s, _ in kicks]).tolist()

    R, V, q1, w1, q2, w2 = unpack(y0)
    R = R.copy()
    p = mu * V
    A = Rotation.from_quat(np.stack([q1, q2])).as_matrix()
    Pi = np.einsum("bij,bj->bi", inertia, np.stack([w1, w2]))
    turners = [_Turner(T) for T in system.integrals]
    F, M = _loads(system, turners, R, A)

    nodes = np.unique(sample)
    Rs, ps = np.empty((nodes.size, 3)), np.empty((nodes.size, 3))
    As, Pis = np.empty((nodes.size, 2, 3, 3)), np.empty((nodes.size, 2, 3))
    j = 0
    for k in range(grid.size):
        if k > 0:
            h = grid[k] - grid[k - 1]
            g = Pi + 0.5 * h * M
            Fk = np.stack([cayley_step(g[0], inertia[0], h), cayley_step(g[1], inertia[1], h)])
            R = R + (h / mu) * p + (0.5 * h * h / mu) * F
            A = A @ Fk
            F1, M1 = _loads(system, turners, R, A)
            p = p + 0.5 * h * (F + F1)
            Pi = np.einsum("bji,bj->bi", Fk, g) + 0.5 * h * M1
            F, M = F1, M1
        while kick_at and kick_at[0] == k:
            kick_at.pop(0)
            p, Pi = _kick(p, Pi, A, mu, kicks.pop(0)[1])
        if j < nodes.size and nodes[j] == k:
            Rs[j], ps[j], As[j], Pis[j] = R, p, A, Pi
            j += 1
    rows = np.searchsorted(nodes, sample)
    omega = np.linalg.solve(inertia, Pis[..., None])[..., 0]               # (n, 2, 3)
    q = quat.canonical(Rotation.from_matrix(As.reshape(-1, 3, 3)).as_quat()
                       ).reshape(nodes.size, 2, 4)
    out[:, 0:3] = Rs[rows]
    out[:, 3:6] = ps[rows] / mu
    out[:, 6:10], out[:, 10:13] = q[rows, 0], omega[rows, 0]
    out[:, 13:17], out[:, 17:20] = q[rows, 1], omega[rows, 1]
    return out


def _kick(p, Pi, A, mu, impulse):
    """Momenta after an impulse: ``p`` by ``mu dv`` (``-mu dv`` on the primary), the
    body's ``Pi`` by its angular impulse in its frame."""
    b = 1 if impulse.body == "secondary" else 0
    p = p + (1.0 if b else -1.0) * mu * impulse.delta_v
    Pi = Pi.copy()
    Pi[b] += A[b].T @ impulse.angular_impulse
    return p, Pi

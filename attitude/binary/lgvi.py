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

:func:`integrate_lgvi_batch` runs many systems of one family at once: every operation is
per member, vectorised over the members (the implicit rotations too: the same Newton
iteration on floats for a few bodies, on arrays over the bodies for many).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.spatial.transform import Rotation

from attitude.binary import compiled as compiled_lgvi
from attitude.binary.dynamics import unpack
from attitude.binary.integrals import InertiaIntegrals, rotated
from attitude.binary.system import BinarySystem
from attitude.foundations import quaternion as quat
from attitude.foundations.errors import BinarySystemError, PropagationError
from attitude.propagation.jit import NUMBA
from attitude.propagation.splitting import step_count

__all__ = ["integrate_lgvi", "integrate_lgvi_batch", "default_step", "step_grid",
           "cayley_step", "cayley_steps", "cayley_rotation", "cayley_difference",
           "impulse_change"]

#: Newton on the Cayley parameters stops when the correction is below this fraction of
#: ``|f|`` (about 4.5 ulps).
NEWTON_RTOL = 1e-15
#: ... or after this many iterations (a step too long for the spin has no solution).
NEWTON_MAX = 20
#: Up to this many bodies, the implicit rotations are solved one by one in Python floats
#: (faster than numpy's per-call overhead); more, as arrays over the bodies.
FLOAT_MEMBERS = 4
#: The default step is this fraction of the shortest of the orbit and spin periods.
STEP_FRACTION = 1.0 / 200.0


def _solve3(m, r) -> tuple:
    """``m^-1 r`` by Cramer's rule, ``m`` 3x3 nested and ``r`` 3 components, each entry
    a float or an array over members (numpy's batched solve costs far more at 3x3)."""
    (a, b, c), (d, e, f), (g, h, i) = m
    A, B, C = e * i - f * h, f * g - d * i, d * h - e * g
    det = a * A + b * B + c * C
    x = (r[0] * A + r[1] * (c * h - b * i) + r[2] * (b * f - c * e)) / det
    y = (r[0] * B + r[1] * (a * i - c * g) + r[2] * (c * d - a * f)) / det
    z = (r[0] * C + r[1] * (b * g - a * h) + r[2] * (a * e - b * d)) / det
    return x, y, z


def _keep(done, old, new):
    """``old`` where ``done``, else ``new`` (a bool and floats, or arrays)."""
    if isinstance(done, (bool, np.bool_)):
        return old if done else new
    return np.where(done, old, new)


def _cayley_parameters(u, I) -> tuple:
    """Newton on ``u (1 + f.f) = 2 (I f + f x I f)`` for the Cayley parameters ``f``,
    from ``f = I^-1 u / 2``: ``u`` 3 components and ``I`` 3x3 nested, each entry a float
    (one body: Python floats, fastest at this size) or an array over members (the same
    arithmetic, vectorised); a member stops at its own convergence.  ``None`` if Newton
    does not converge in :data:`NEWTON_MAX` iterations."""
    u0, u1, u2 = u
    f0, f1, f2 = _solve3(I, (0.5 * u0, 0.5 * u1, 0.5 * u2))
    previous = math.inf
    done = False
    eps = float(np.finfo(float).eps)
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
        uu, ff = (u0, u1, u2), (f0, f1, f2)
        jac = [[2.0 * uu[r] * ff[c] - 2.0 * (I[r][c] + SI[r][c] - SIf[r][c])
                for c in range(3)] for r in range(3)]
        d0, d1, d2 = _solve3(jac, residual)
        f0, f1, f2 = (_keep(done, f0, f0 - d0), _keep(done, f1, f1 - d1),
                      _keep(done, f2, f2 - d2))
        correction = (d0 * d0 + d1 * d1 + d2 * d2) ** 0.5
        size = (f0 * f0 + f1 * f1 + f2 * f2) ** 0.5
        # converged, or at the round-off floor (the correction stopped shrinking at a
        # few ulps of |f|); a member once done stays done
        done = done | (correction <= NEWTON_RTOL * size) | (
            (correction <= 64 * eps * size) & (correction >= 0.5 * previous))
        if np.all(done):
            return f0, f1, f2
        if not np.all(np.isfinite(size)):
            return None
        previous = correction
    return None


def _cayley_matrix(f0, f1, f2) -> list:
    """``E + 2 (S + S^2) / (1 + f.f)`` as nested rows (floats or arrays)."""
    c = 2.0 / (1.0 + f0 * f0 + f1 * f1 + f2 * f2)
    return [[1.0 - c * (f1 * f1 + f2 * f2), c * (f0 * f1 - f2), c * (f0 * f2 + f1)],
            [c * (f0 * f1 + f2), 1.0 - c * (f0 * f0 + f2 * f2), c * (f1 * f2 - f0)],
            [c * (f0 * f2 - f1), c * (f1 * f2 + f0), 1.0 - c * (f0 * f0 + f1 * f1)]]


def cayley_difference(f: np.ndarray) -> np.ndarray:
    """``F - E = 2 (S + S^2) / (1 + f.f)`` of Cayley parameters ``(..., 3)``, ``(..., 3,
    3)``: the change a step's rotation makes, formed without the cancellation of
    ``F - E`` (the compensated LGVI adds it to the attitude, ``A' = A + A (F - E)``).

    Examples
    --------
    >>> f = np.array([1e-9, 0.0, 0.0])
    >>> D = cayley_difference(f)
    >>> float(D[2, 1]), float(D[1, 1])        # 2 f and -2 f^2, to round-off
    (2e-09, -2e-18)
    """
    f = np.asarray(f, float)
    f0, f1, f2 = f[..., 0], f[..., 1], f[..., 2]
    c = 2.0 / (1.0 + f0 * f0 + f1 * f1 + f2 * f2)
    rows = [[-c * (f1 * f1 + f2 * f2), c * (f0 * f1 - f2), c * (f0 * f2 + f1)],
            [c * (f0 * f1 + f2), -c * (f0 * f0 + f2 * f2), c * (f1 * f2 - f0)],
            [c * (f0 * f2 - f1), c * (f1 * f2 + f0), -c * (f0 * f0 + f1 * f1)]]
    return np.stack([np.stack(row, axis=-1) for row in rows], axis=-2)


def cayley_rotation(f: np.ndarray) -> np.ndarray:
    """``(E + S(f))(E - S(f))^-1 = E + 2 (S + S^2) / (1 + f.f)`` of Cayley parameters
    ``(..., 3)``: rotation matrices ``(..., 3, 3)``, orthogonal to round-off for any ``f``.

    Examples
    --------
    >>> F = cayley_rotation(np.array([0.0, 0.0, np.tan(0.25)]))     # 0.5 rad about z
    >>> bool(np.isclose(np.arctan2(F[1, 0], F[0, 0]), 0.5, rtol=1e-15))
    True
    """
    f = np.asarray(f, float)
    rows = _cayley_matrix(f[..., 0], f[..., 1], f[..., 2])
    return np.stack([np.stack(row, axis=-1) for row in rows], axis=-2)


def cayley_steps(g, inertia, h) -> np.ndarray:
    """The rotations ``F`` ``(n, 3, 3)`` with ``h S(g) = F J - J F^T``,
    ``J = tr(I)/2 E - I``, for body-frame momenta ``g`` ``(n, 3)``, inertia tensors
    ``(n, 3, 3)`` and steps ``h`` (a float or ``(n,)``): Newton's method on the Cayley
    parameters ``f``, ``h g (1 + f.f) = 2 (I f + f x I f)``, from ``f = h I^-1 g / 2``,
    every member at once (each stops at its own convergence).

    Raises
    ------
    PropagationError
        Newton does not converge in :data:`NEWTON_MAX` iterations (``h |g|`` beyond
        what one rotation can carry: the step is too long for the spin).

    Examples
    --------
    >>> I = np.diag([1.0, 2.0, 3.0])[None]
    >>> F = cayley_steps(np.array([[0.0, 0.0, 0.3]]), I, 2.0)        # w = 0.1 rad/s
    >>> bool(np.isclose(np.arctan2(F[0, 1, 0], F[0, 0, 0]), np.arcsin(0.2), rtol=1e-14))
    True
    """
    return cayley_rotation(_cayley_solution(g, inertia, h))


def _cayley_solution(g, inertia, h) -> np.ndarray:
    """The Cayley parameters ``(n, 3)`` of :func:`cayley_steps` (which see)."""
    I = np.asarray(inertia, float)  # noqa: E741 - the inertia tensor
    u = np.asarray(h, float).reshape(-1, 1) * np.asarray(g, float)
    if len(u) <= FLOAT_MEMBERS:        # a few bodies: one by one in Python floats
        fs = [_cayley_parameters(v.tolist(), m.tolist()) for v, m in zip(u, I)]
        f = np.array(fs, float) if all(f is not None for f in fs) else None
    else:                              # many: arrays over the members
        f = _cayley_parameters(tuple(u.T), [[I[:, r, c] for c in range(3)] for r in range(3)])
        f = None if f is None else np.stack(f, axis=-1)
    if f is not None:
        return f
    worst = max(float(np.linalg.norm(_solve3(m.tolist(), v.tolist())))
                for m, v in zip(I, u))
    raise PropagationError(
        f"step: the LGVI's implicit rotation did not converge in {NEWTON_MAX} Newton "
        f"iterations (h |I^-1 g| = {worst:.3g} rad in one step); give a shorter step")


def cayley_step(g, inertia, h: float) -> np.ndarray:
    """:func:`cayley_steps` of one body: ``F`` (3x3) for ``g`` (3,), ``inertia`` (3x3).

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
    return cayley_steps(np.asarray(g, float)[None], np.asarray(inertia, float)[None], h)[0]


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


def _stacked(systems) -> tuple:
    """The integrals of both bodies of every member, stacked ``(n, n_k)`` per degree."""
    return tuple(InertiaIntegrals(tuple(np.stack([s.integrals[b].degrees[k] for s in systems])
                                        for k in range(len(systems[0].integrals[b].degrees))))
                 for b in range(2))


def _loads(gravity, integrals, R: np.ndarray, A: np.ndarray):
    """Force on the secondary (inertial, ``(n, 3)``) and both body-frame torques
    ``(n, 2, 3)`` of the members at ``R`` ``(n, 3)``, attitudes ``A`` ``(n, 2, 3, 3)``."""
    f = gravity.forces(R, rotated(integrals[0], A[:, 0]), rotated(integrals[1], A[:, 1]))
    M = np.einsum("nbji,nbj->nbi", A, np.stack([f.torque_primary, f.torque_secondary], 1))
    return f.force, M


def integrate_lgvi(system: BinarySystem, y0: np.ndarray, t: np.ndarray, step: float,
                   impulses=()) -> np.ndarray:
    """Integrate one system from ``y0`` (time 0) to the sorted times ``t >= 0`` with the
    LGVI at steps no longer than ``step`` (s); returns ``(len(t), 20)`` state vectors
    (:mod:`attitude.binary.dynamics`) with canonical unit quaternions
    (:func:`integrate_lgvi_batch` of one member).

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
    return integrate_lgvi_batch([system], np.asarray(y0, float)[None], t, step,
                                [list(impulses)])[0]


def integrate_lgvi_batch(systems, y0: np.ndarray, t: np.ndarray, step: float,
                         impulses=None, *, compensated: bool = True,
                         compiled: bool | None = None) -> np.ndarray:
    """Integrate ``n`` systems at once (a family: one mutual-potential order and ``G``)
    from ``y0`` ``(n, 20)`` to the sorted times ``t >= 0`` at a common step no longer than
    ``step``; returns ``(n, len(t), 20)``.  Each member is the same map as
    :func:`integrate_lgvi` alone (every operation is per member), vectorised over the
    members: an ensemble costs far less than its members one by one.

    ``impulses``: for each member a list of ``(time, Impulse)`` pairs (the steps of
    every member end at every member's impulse times).

    Every update of the state is a sum ``x' = x + dx`` (the rotations too:
    ``A' = A + A (F - E)``, ``Pi' = Pi + (F - E)^T g + h/2 (M + M')``), and with
    ``compensated`` (the default) each is a compensated sum (Neumaier 1974): the low part
    each addition loses is carried into the next step's, so the state's round-off grows
    with the increments, not with the state (``benchmarks/binary.py --only --long
    10000``: ``|dH/H|`` 1.1e-14 over 4e5 steps, 5.4e-14 with plain sums).  The orbit's
    increment is ``h/mu (p + h/2 F)``: the rounding of ``h/mu`` scales it along
    ``p + h/2 F``, which keeps ``R x p`` (the step's change of it is ``h/2 (R x F +
    R' x F')`` whatever that factor), where ``h/mu p + h^2/(2 mu) F`` turned it by the
    two factors' different roundings, the same way at every step (a linear drift, to
    2.7e-13).  ``compensated=False`` is the plain sum of the same map.

    ``compiled`` (default: when numba is there and ``ATTITUDE_NO_NUMBA=1`` is not set)
    runs each member's whole step loop in compiled code
    (:mod:`attitude.binary.compiled`), the cost then proportional to the members;
    ``False``, the numpy path, vectorised over the members.  Both are the same map and
    agree to round-off.

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from attitude.binary.dynamics import pack
    >>> ball = att.RigidBody.from_mass_properties(att.MassProperties.solid_sphere(1e9, 50.0))
    >>> egg = att.RigidBody.from_mass_properties(
    ...     att.MassProperties.solid_ellipsoid(2e8, [30.0, 20.0, 15.0]))
    >>> systems = [att.BinarySystem(ball, egg), att.BinarySystem(ball, ball)]
    >>> y0 = np.stack([pack([500.0, 0, 0], [0, np.sqrt(s.mu / 500.0), 0], [0, 0, 0, 1.0],
    ...                     [0, 0, 0], [0, 0, 0, 1.0], [0, 0, 1e-4]) for s in systems])
    >>> y = integrate_lgvi_batch(systems, y0, [0.0, 3600.0], 30.0)
    >>> one = integrate_lgvi(systems[0], y0[0], [0.0, 3600.0], 30.0)
    >>> y.shape, bool(np.allclose(y[0], one, rtol=0, atol=1e-12))
    ((2, 2, 20), True)
    """
    systems = list(systems)
    n = len(systems)
    order, G = systems[0].order, systems[0].G
    if any(s.order != order or s.G != G for s in systems):
        raise BinarySystemError("systems: a batch shares one mutual-potential order and G")
    t = np.asarray(t, float)
    y0 = np.asarray(y0, float).reshape(n, 20)
    out = np.empty((n, t.size, 20))
    if t.size == 0:
        return out
    impulses = [[] for _ in range(n)] if impulses is None else [list(i) for i in impulses]
    mu = np.array([s.reduced_mass for s in systems])[:, None]
    inertia = np.array([[s.primary.inertia, s.secondary.inertia] for s in systems])
    kicks = sorted(((when, m, e) for m, events in enumerate(impulses) for when, e in events
                    if when <= t[-1]), key=lambda k: k[0])      # later ones: no effect
    grid = step_grid(np.concatenate([t, [k[0] for k in kicks]]), step)
    sample = np.searchsorted(grid, t)                 # grid node of each output time
    kick_at = np.searchsorted(grid, [k[0] for k in kicks]).tolist()

    R, V, q1, w1, q2, w2 = unpack(y0)
    R = R.copy()
    A = Rotation.from_quat(np.stack([q1, q2], 1).reshape(-1, 4)).as_matrix().reshape(n, 2, 3, 3)
    Pi = np.einsum("nbij,nbj->nbi", inertia, np.stack([w1, w2], 1))
    nodes = np.unique(sample)
    events = [(kick_at[i], m, e) for i, (_, m, e) in enumerate(kicks)]
    march = _march_compiled if (NUMBA if compiled is None else compiled) else _march
    Rs, ps, As, Pis = march(systems, grid, nodes, R, mu * V, A, Pi, inertia, events,
                            compensated)
    rows = np.searchsorted(nodes, sample)
    omega = np.linalg.solve(inertia[None], Pis[..., None])[..., 0]         # (T, n, 2, 3)
    q = quat.canonical(Rotation.from_matrix(As.reshape(-1, 3, 3)).as_quat()
                       ).reshape(nodes.size, n, 2, 4)
    out[:, :, 0:3] = np.swapaxes(Rs[rows], 0, 1)
    out[:, :, 3:6] = np.swapaxes(ps[rows], 0, 1) / mu[:, None]
    out[:, :, 6:10] = np.swapaxes(q[rows, :, 0], 0, 1)
    out[:, :, 10:13] = np.swapaxes(omega[rows, :, 0], 0, 1)
    out[:, :, 13:17] = np.swapaxes(q[rows, :, 1], 0, 1)
    out[:, :, 17:20] = np.swapaxes(omega[rows, :, 1], 0, 1)
    return out


def _march(systems, grid, nodes, R, p, A, Pi, inertia, events, compensated) -> tuple:
    """The numpy path of :func:`integrate_lgvi_batch`: every member at once, step by
    step; the state ``(R, p, A, Pi)`` at the grid ``nodes``, each ``(nodes, n, ...)``.
    ``events``: ``(step, member, Impulse)`` sorted by step."""
    n = len(systems)
    mu = np.array([s.reduced_mass for s in systems])[:, None]
    events = list(events)
    integrals, gravity = _stacked(systems), systems[0].gravity
    flat_inertia = inertia.reshape(-1, 3, 3)
    F, M = _loads(gravity, integrals, R, A)
    Rs, ps = np.empty((nodes.size, n, 3)), np.empty((nodes.size, n, 3))
    As, Pis = np.empty((nodes.size, n, 2, 3, 3)), np.empty((nodes.size, n, 2, 3))
    add = _compensated_sum if compensated else _plain_sum
    carry = [np.zeros_like(x) for x in (R, p, A, Pi)]        # the sums' lost low parts
    j = 0
    for k in range(grid.size):
        if k > 0:
            h = grid[k] - grid[k - 1]
            g = Pi + 0.5 * h * M
            f = _cayley_solution(g.reshape(-1, 3), flat_inertia, h)
            D = cayley_difference(f).reshape(n, 2, 3, 3)                  # F - E
            # h/mu (p + h/2 F): the rounding of h/mu scales R' - R along p + h/2 F, which
            # keeps R x p (as a factor of p and F apart would not: it turns R' - R)
            R, carry[0] = add(R, carry[0], (h / mu) * (p + 0.5 * h * F))
            A, carry[2] = add(A, carry[2], np.einsum("nbij,nbjk->nbik", A, D))
            F1, M1 = _loads(gravity, integrals, R, A)
            p, carry[1] = add(p, carry[1], 0.5 * h * (F + F1))
            # F^T g + h/2 M' = Pi + (F - E)^T g + h/2 (M + M')
            Pi, carry[3] = add(Pi, carry[3], np.einsum("nbji,nbj->nbi", D, g)
                               + 0.5 * h * (M + M1))
            F, M = F1, M1
        while events and events[0][0] == k:
            _, m, impulse = events.pop(0)
            p[m], Pi[m] = _kick(p[m], Pi[m], A[m], mu[m, 0], impulse)
        if j < nodes.size and nodes[j] == k:
            Rs[j], ps[j], As[j], Pis[j] = R, p, A, Pi
            j += 1
    return Rs, ps, As, Pis


def _march_compiled(systems, grid, nodes, R, p, A, Pi, inertia, events,
                    compensated) -> tuple:
    """:func:`_march` by :func:`attitude.binary.compiled.lgvi_members`: each member's
    step loop in compiled code, on the series' tables."""
    n, order = len(systems), systems[0].order
    mu = np.array([s.reduced_mass for s in systems])
    body = [np.ascontiguousarray([np.concatenate(s.integrals[b].degrees[:order + 1])
                                  for s in systems]) for b in range(2)]
    kick_dp, kick_L, kick_body = np.zeros((len(events), 3)), np.zeros((len(events), 3)), []
    for e, (_, m, impulse) in enumerate(events):
        dV, b, kick_L[e] = impulse_change(impulse)
        kick_dp[e] = mu[m] * dV
        kick_body.append(b)
    Rs, ps = np.empty((nodes.size, n, 3)), np.empty((nodes.size, n, 3))
    As, Pis = np.empty((nodes.size, n, 2, 3, 3)), np.empty((nodes.size, n, 2, 3))
    failed = compiled_lgvi.lgvi_members(
        np.ascontiguousarray(R), np.ascontiguousarray(p), np.ascontiguousarray(A),
        np.ascontiguousarray(Pi), np.ascontiguousarray(inertia), mu, body[0], body[1],
        float(systems[0].G), compiled_lgvi.kernel_tables(order), np.asarray(grid, float),
        np.asarray(nodes, np.int64), np.array([e[0] for e in events], np.int64),
        np.array([e[1] for e in events], np.int64), np.array(kick_body, np.int64),
        kick_dp, kick_L, bool(compensated), NEWTON_RTOL, NEWTON_MAX, Rs, ps, As, Pis)
    if failed >= 0:
        raise PropagationError(
            f"step: the LGVI's implicit rotation of member {failed} did not converge in "
            f"{NEWTON_MAX} Newton iterations (the step is too long for the spin); give a "
            f"shorter step")
    return Rs, ps, As, Pis


def _plain_sum(x, carry, dx):
    """``x + dx`` (``carry`` stays zero)."""
    return x + dx, carry


def _compensated_sum(x, carry, dx):
    """``x + dx`` compensated (Neumaier 1974): the carried low part joins the increment,
    and what this addition loses becomes the next carry."""
    y = dx + carry
    total = x + y
    lost = np.where(np.abs(x) >= np.abs(y), (x - total) + y, (y - total) + x)
    return total, lost


def impulse_change(impulse) -> tuple:
    """What an :class:`~attitude.binary.system.Impulse` changes: the relative velocity's
    change (the body's ``delta_v``, minus it for the primary), the body (0 the primary,
    1 the secondary) and its angular impulse (inertial frame, N m s).  The LGVI adds
    ``mu dV`` to ``p`` and the angular impulse in the body's frame to its ``Pi``;
    :func:`attitude.binary.propagate.apply_impulse` the same to ``V`` and ``w``.

    Examples
    --------
    >>> import attitude as att
    >>> dV, body, L = impulse_change(att.Impulse(0.0, body="primary", delta_v=[0, 1e-3, 0]))
    >>> dV.tolist(), body, L.tolist()
    ([-0.0, -0.001, -0.0], 0, [0.0, 0.0, 0.0])
    """
    b = 1 if impulse.body == "secondary" else 0
    return ((1.0 if b else -1.0) * np.asarray(impulse.delta_v, float), b,
            np.asarray(impulse.angular_impulse, float))


def _kick(p, Pi, A, mu, impulse):
    """Momenta after an impulse (:func:`impulse_change`): ``p`` by ``mu dV``, the
    body's ``Pi`` by its angular impulse in its frame."""
    dV, b, L = impulse_change(impulse)
    p = p + mu * dV
    Pi = Pi.copy()
    Pi[b] += A[b].T @ L
    return p, Pi

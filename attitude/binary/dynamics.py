"""Equations of motion of the full two-body problem, and the reference integrator.

The state of one system is ``y = (R, V, q1, w1, q2, w2)`` (20 numbers): the secondary's
position and velocity relative to the primary (inertial frame, m and m/s), each body's
attitude quaternion (body -> inertial, scalar-last) and body-frame angular velocity
(rad/s).  With ``mu`` the reduced mass and ``F, tau1, tau2`` the mutual force and torques
(:mod:`attitude.binary.mutual`, inertial frame),

    dR/dt = V,      mu dV/dt = F,
    dq_i/dt = q_i (x) (w_i, 0) / 2,
    I_i dw_i/dt = I_i w_i x w_i + A_i^T tau_i.

:func:`integrate_dop853` integrates them with scipy's DOP853 (the reference method);
:func:`energy_momentum` gives the conserved total energy and angular momentum.
"""

from __future__ import annotations

import numpy as np
from scipy.integrate import solve_ivp

from attitude.binary.integrals import rotated
from attitude.binary.system import BinarySystem
from attitude.foundations import quaternion as quat
from attitude.foundations.errors import PropagationError

__all__ = ["derivatives", "integrate_dop853", "energy_momentum", "matrix", "pack", "unpack",
           "mutual_forces", "system_scales", "tolerance_scale"]


def matrix(q: np.ndarray) -> np.ndarray:
    """``(..., 3, 3)`` rotation matrices of scalar-last unit quaternions ``(..., 4)``.

    Examples
    --------
    >>> import numpy as np
    >>> matrix(np.array([0.0, 0.0, np.sin(np.pi / 4), np.cos(np.pi / 4)])).round(12)
    array([[ 0., -1.,  0.],
           [ 1.,  0.,  0.],
           [ 0.,  0.,  1.]])
    """
    q = np.asarray(q, float)
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    x, y, z, w = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    return np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)], -1),
        np.stack([2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)], -1),
        np.stack([2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)], -1),
    ], -2)


def pack(R, V, q1, w1, q2, w2) -> np.ndarray:
    """The state vector ``(..., 20)`` from its parts.

    Examples
    --------
    >>> y = pack([1.0, 0, 0], [0, 1.0, 0], [0, 0, 0, 1.0], [0, 0, 1e-3], [0, 0, 0, 1.0],
    ...          [0, 0, 2e-3])
    >>> y.shape, unpack(y)[5].tolist()
    ((20,), [0.0, 0.0, 0.002])
    """
    return np.concatenate([np.asarray(a, float) for a in (R, V, q1, w1, q2, w2)], axis=-1)


def unpack(y: np.ndarray) -> tuple:
    """``(R, V, q1, w1, q2, w2)`` of a state vector ``(..., 20)`` (views).

    Examples
    --------
    >>> [a.shape for a in unpack(np.zeros((5, 20)))]
    [(5, 3), (5, 3), (5, 4), (5, 3), (5, 4), (5, 3)]
    """
    return (y[..., 0:3], y[..., 3:6], y[..., 6:10], y[..., 10:13], y[..., 13:17],
            y[..., 17:20])


def mutual_forces(system: BinarySystem, R, A1, A2):
    """The mutual potential, force on the secondary and both torques (inertial frame) for
    attitude matrices ``A1``, ``A2`` (body -> inertial).

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> ball = att.RigidBody.from_mass_properties(att.MassProperties.solid_sphere(1e9, 50.0))
    >>> f = mutual_forces(att.BinarySystem(ball, ball), [500.0, 0, 0], np.eye(3), np.eye(3))
    >>> bool(np.isclose(f.force[0], -att.binary.G * 1e18 / 500.0**2, rtol=1e-14))
    True
    """
    T1, T2 = system.integrals
    return system.gravity.forces(R, rotated(T1, A1), rotated(T2, A2))


def derivatives(system: BinarySystem, y: np.ndarray) -> np.ndarray:
    """``dy/dt`` of state vectors ``(..., 20)``.

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> ball = att.RigidBody.from_mass_properties(att.MassProperties.solid_sphere(1e9, 50.0))
    >>> y = pack([500.0, 0, 0], [0, 0.01, 0], [0, 0, 0, 1.0], [0, 0, 1e-4],
    ...          [0, 0, 0, 1.0], [0, 0, 0])
    >>> d = derivatives(att.BinarySystem(ball, ball), y)
    >>> bool(np.isclose(d[3], -att.binary.G * 2e9 / 500.0**2, rtol=1e-14))  # -G M / R^2
    True
    """
    y = np.asarray(y, float)
    R, V, q1, w1, q2, w2 = unpack(y)
    A1, A2 = matrix(q1), matrix(q2)
    f = mutual_forces(system, R, A1, A2)
    out = np.empty(np.shape(y))
    out[..., 0:3] = V
    out[..., 3:6] = f.force / system.reduced_mass
    for (qs, ws, A, tau, body) in ((slice(6, 10), slice(10, 13), A1, f.torque_primary,
                                    system.primary),
                                   (slice(13, 17), slice(17, 20), A2, f.torque_secondary,
                                    system.secondary)):
        q, w = y[..., qs], y[..., ws]
        out[..., qs] = 0.5 * quat.multiply(q, np.concatenate([w, np.zeros(w.shape[:-1] + (1,))],
                                                             axis=-1))
        I = body.inertia
        torque_body = np.einsum("...ji,...j->...i", A, tau)
        Iw = w @ I.T
        out[..., ws] = (np.cross(Iw, w) + torque_body) @ np.linalg.inv(I).T
    return out


def energy_momentum(system: BinarySystem, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Total energy (J: orbital and both spins' kinetic energy plus the mutual potential)
    and total angular momentum about the system's centre of mass (kg m^2/s, inertial) of
    state vectors ``(..., 20)``: both conserved between impulses.

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> ball = att.RigidBody.from_mass_properties(att.MassProperties.solid_sphere(1e9, 50.0))
    >>> system = att.BinarySystem(ball, ball)
    >>> y = pack([500.0, 0, 0], [0, 0.01, 0], [0, 0, 0, 1.0], [0, 0, 0], [0, 0, 0, 1.0],
    ...          [0, 0, 0])
    >>> E, L = energy_momentum(system, y)
    >>> L.tolist() == [0.0, 0.0, system.reduced_mass * 500.0 * 0.01]
    True
    """
    R, V, q1, w1, q2, w2 = unpack(np.asarray(y, float))
    A1, A2 = matrix(q1), matrix(q2)
    f = mutual_forces(system, R, A1, A2)
    mu = system.reduced_mass
    E = 0.5 * mu * np.sum(V * V, axis=-1) + f.potential
    L = mu * np.cross(R, V)
    for A, w, body in ((A1, w1, system.primary), (A2, w2, system.secondary)):
        Iw = w @ body.inertia.T
        E = E + 0.5 * np.sum(w * Iw, axis=-1)
        L = L + np.einsum("...ij,...j->...i", A, Iw)
    return E, L


def system_scales(system: BinarySystem, y0: np.ndarray) -> tuple[float, float, float]:
    """The system's length, speed and rate scales at the state ``y0`` (20,): the
    separation ``r0 = |R|``, the circular orbital speed there ``n r0`` and the mean
    motion ``n = sqrt(mu / r0^3)`` (m, m/s, rad/s).

    The one source of these scales: :func:`tolerance_scale` (DOP853's absolute
    tolerance) and the metric of :mod:`attitude.binary.chaos` are built on them.

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> ball = att.RigidBody.from_mass_properties(att.MassProperties.solid_sphere(1e9, 50.0))
    >>> system = att.BinarySystem(ball, ball)
    >>> y0 = pack([500.0, 0, 0], [0, 0.01, 0], [0, 0, 0, 1.0], [0, 0, 0], [0, 0, 0, 1.0],
    ...           [0, 0, 0])
    >>> r0, v0, n = system_scales(system, y0)
    >>> r0, bool(np.isclose(n, np.sqrt(system.mu / 500.0**3), rtol=1e-15)), v0 == n * r0
    (500.0, True, True)
    """
    r0 = float(np.linalg.norm(np.asarray(y0, float)[:3]))
    n = float(np.sqrt(system.mu / r0**3))
    return r0, n * r0, n


def tolerance_scale(system: BinarySystem, y0: np.ndarray) -> np.ndarray:
    """The scale of each state component (20,) that DOP853's ``atol`` is a fraction of
    (:func:`integrate_dop853`): the separation for ``R``, the orbital speed for ``V``, 1
    for the quaternions, each body's fastest rate for its ``w``, the speed and rates never
    below the system's own (:func:`system_scales`).

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> ball = att.RigidBody.from_mass_properties(att.MassProperties.solid_sphere(1e9, 50.0))
    >>> system = att.BinarySystem(ball, ball)
    >>> y0 = pack([500.0, 0, 0], [0, 0.01, 0], [0, 0, 0, 1.0], [0, 0, 1.0], [0, 0, 0, 1.0],
    ...           [0, 0, 0])
    >>> s = tolerance_scale(system, y0)
    >>> s[:3].tolist(), s[10:13].tolist(), bool(s[17] == system_scales(system, y0)[2])
    ([500.0, 500.0, 500.0], [1.0, 1.0, 1.0], True)
    """
    r, speed, rate = system_scales(system, y0)
    _, V, _, w1, _, w2 = unpack(np.asarray(y0, float))
    return np.concatenate([np.full(3, r), np.full(3, max(np.linalg.norm(V), speed)),
                           np.ones(4), np.full(3, max(np.abs(w1).max(), rate)), np.ones(4),
                           np.full(3, max(np.abs(w2).max(), rate))])


def integrate_dop853(system: BinarySystem, y0: np.ndarray, t: np.ndarray, *,
                     rtol: float = 1e-12, atol_scale: float | None = None) -> np.ndarray:
    """Integrate one system from ``y0`` (at time 0) to the sorted times ``t >= 0`` with
    scipy's DOP853; returns ``(len(t), 20)`` with unit quaternions.

    ``atol`` per component: ``atol_scale`` (default ``rtol``: one tolerance, relative to
    the system's scales) times the component's scale (the separation
    for R, the orbital speed for V, 1 for q, each body's fastest rate for its w), the
    speed and rate never below the system's own, ``sqrt(mu / R)`` and ``sqrt(mu / R^3)``
    (a body that does not spin at first would otherwise get no absolute tolerance at
    all, and DOP853 steps that crawl or fail as its torques set it turning).

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> ball = att.RigidBody.from_mass_properties(att.MassProperties.solid_sphere(1e9, 50.0))
    >>> system = att.BinarySystem(ball, ball)
    >>> v = np.sqrt(system.mu / 500.0)                       # a circular orbit
    >>> y0 = pack([500.0, 0, 0], [0, v, 0], [0, 0, 0, 1.0], [0, 0, 0], [0, 0, 0, 1.0],
    ...           [0, 0, 0])
    >>> period = 2 * np.pi * 500.0 / v
    >>> y = integrate_dop853(system, y0, [0.0, period])
    >>> bool(np.allclose(y[-1, :3], [500.0, 0, 0], atol=1e-6))
    True
    """
    t = np.asarray(t, float)
    y0 = np.asarray(y0, float)
    scale = tolerance_scale(system, y0)
    if t.size == 0:
        return np.empty((0, 20))
    if t[-1] == 0.0:
        return np.repeat(y0[None], t.size, axis=0)
    sol = solve_ivp(lambda _, y: derivatives(system, y), (0.0, float(t[-1])), y0,
                    method="DOP853", t_eval=t, rtol=rtol,
                    atol=(rtol if atol_scale is None else atol_scale) * scale)
    if not sol.success:
        raise PropagationError(f"binary DOP853: {sol.message}")
    y = sol.y.T.copy()
    for s in (slice(6, 10), slice(13, 17)):
        y[:, s] /= np.linalg.norm(y[:, s], axis=-1, keepdims=True)
    return y

"""Equations of motion of the full two-body problem, and the reference integrator.

The state of one system is ``y = (R, V, q1, w1, q2, w2)`` (20 numbers): the secondary's
position and velocity relative to the primary (inertial frame, m and m/s), each body's
attitude quaternion (body -> inertial, scalar-last) and body-frame angular velocity
(rad/s).  With ``mu`` the reduced mass and ``F, tau1, tau2`` the mutual force and torques
(:mod:`attitude.binary.mutual`, inertial frame),

    dR/dt = V,      mu dV/dt = F,
    dq_i/dt = q_i (x) (w_i, 0) / 2,
    I_i dw_i/dt = I_i w_i x w_i + A_i^T tau_i.

:func:`integrate_dop853` integrates them with scipy's DOP853 (the reference method) in
Encke's form, the deviation from an exact Kepler orbit (:func:`kepler_flow`);
:func:`energy_momentum` gives the conserved total energy and angular momentum.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.integrate import solve_ivp

from attitude.binary.integrals import rotated
from attitude.binary.system import BinarySystem
from attitude.foundations import quaternion as quat
from attitude.foundations.errors import PropagationError

__all__ = ["derivatives", "integrate_dop853", "energy_momentum", "matrix", "pack", "unpack",
           "mutual_forces", "system_scales", "tolerance_scale", "kepler_flow", "RECTIFY"]


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


EPS = float(np.finfo(float).eps)

#: Encke's rectification: a new reference orbit when the deviation from the current one
#: passes this fraction of the system's length scale (:func:`integrate_dop853`).
RECTIFY = 1e-2


def _stumpff(z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Stumpff's ``C(z) = (1 - cos sqrt z) / z`` and ``S(z) = (sqrt z - sin sqrt z) /
    z^(3/2)`` (their hyperbolic forms for ``z < 0``), without cancellation: the series
    for ``|z| < 1``, ``C = 2 sin^2(sqrt(z) / 2) / z`` beyond."""
    C, S = np.empty_like(z), np.empty_like(z)
    small = np.abs(z) < 1.0
    zs = z[small]
    c, s = np.zeros_like(zs), np.zeros_like(zs)
    tc, ts = np.full_like(zs, 0.5), np.full_like(zs, 1.0 / 6.0)
    for k in range(1, 13):                  # the last terms < 1 / 26! of the first
        c, s = c + tc, s + ts
        tc = -tc * zs / ((2 * k + 1) * (2 * k + 2))
        ts = -ts * zs / ((2 * k + 2) * (2 * k + 3))
    C[small], S[small] = c, s
    pos, neg = ~small & (z > 0), ~small & (z < 0)
    x, y = np.sqrt(z[pos]), np.sqrt(-z[neg])
    C[pos], S[pos] = 2.0 * np.sin(0.5 * x) ** 2 / z[pos], (x - np.sin(x)) / x**3
    C[neg], S[neg] = 2.0 * np.sinh(0.5 * y) ** 2 / -z[neg], (np.sinh(y) - y) / y**3
    return C, S


def _stumpff_scalar(z: float) -> tuple[float, float]:
    """:func:`_stumpff` of one float (the right-hand side's path)."""
    if abs(z) < 1.0:
        c = s = 0.0
        tc, ts = 0.5, 1.0 / 6.0
        for k in range(1, 13):
            c, s = c + tc, s + ts
            tc = -tc * z / ((2 * k + 1) * (2 * k + 2))
            ts = -ts * z / ((2 * k + 2) * (2 * k + 3))
        return c, s
    if z > 0:
        x = math.sqrt(z)
        return 2.0 * math.sin(0.5 * x) ** 2 / z, (x - math.sin(x)) / x**3
    y = math.sqrt(-z)
    return 2.0 * math.sinh(0.5 * y) ** 2 / -z, (math.sinh(y) - y) / y**3


def _universal(constants, dt, stumpff):
    """``chi``, ``C`` and ``S`` of the universal Kepler equation at ``dt`` (reduced by
    whole periods), by Newton's iteration kept in its bracket (:func:`kepler_flow`);
    ``dt`` a float (``stumpff`` :func:`_stumpff_scalar`, ``np`` the math module) or an
    array (:func:`_stumpff`)."""
    r0, sq, alpha, a1, a2, period, r_max, q = constants
    xp = np if isinstance(dt, np.ndarray) else math
    if period:
        dt = dt - xp.floor(dt / period + 0.5) * period
    ends = sq * dt / r_max, sq * dt / q
    lo, hi = (np.minimum(*ends), np.maximum(*ends)) if xp is np else sorted(ends)
    chi = sq * dt * (alpha if alpha > 0 else 1.0 / r0)
    chi = np.clip(chi, lo, hi) if xp is np else min(max(chi, lo), hi)
    for _ in range(100):
        z = alpha * chi * chi
        C, S = stumpff(z)
        F = a1 * chi * chi * C + a2 * chi**3 * S + r0 * chi - sq * dt
        new = chi - F / (a1 * chi * (1.0 - z * S) + a2 * chi * chi * C + r0)
        if xp is np:
            lo = np.where(F < 0, np.maximum(lo, chi), lo)
            hi = np.where(F > 0, np.minimum(hi, chi), hi)
            new = np.where((new < lo) | (new > hi), 0.5 * (lo + hi), new)
            done = bool(np.all(np.abs(new - chi) <= 4.0 * EPS * np.abs(chi)))
        else:
            lo, hi = (max(lo, chi), hi) if F < 0 else (lo, min(hi, chi)) if F > 0 else (lo, hi)
            new = new if lo <= new <= hi else 0.5 * (lo + hi)
            done = abs(new - chi) <= 4.0 * EPS * abs(chi)
        chi = new
        if done:
            break
    return (chi, dt) + stumpff(alpha * chi * chi)


def _kepler_constants(mu: float, R0: np.ndarray, V0: np.ndarray) -> tuple:
    """``r0, sqrt(mu), alpha, r0 v_r / sqrt(mu), 1 - alpha r0``, the period (0 when not an
    ellipse), the apoapsis (inf) and the periapsis of the orbit through ``(R0, V0)``."""
    r0, sq = float(np.linalg.norm(R0)), math.sqrt(mu)
    alpha = 2.0 / r0 - float(V0 @ V0) / mu
    h = np.cross(R0, V0)
    p = float(h @ h) / mu                                   # semi-latus rectum
    e = float(np.linalg.norm(np.cross(V0, h) / mu - R0 / r0))
    period = 2.0 * math.pi / math.sqrt(mu * alpha**3) if alpha > 0 else 0.0
    r_max = p / (1.0 - e) if e < 1.0 else math.inf
    return r0, sq, alpha, float(R0 @ V0) / sq, 1.0 - alpha * r0, period, r_max, p / (1.0 + e)


def kepler_flow(mu: float, R0, V0, dt) -> tuple[np.ndarray, np.ndarray]:
    """Position and velocity ``dt`` (s, a float or any shape) after ``(R0, V0)`` on the
    Kepler orbit of ``mu`` (m^3/s^2): ellipse, parabola or hyperbola alike (the universal
    variable).

    The universal Kepler equation ``sqrt(mu) dt = r0 v_r/sqrt(mu) chi^2 C(z) + (1 - alpha
    r0) chi^3 S(z) + r0 chi`` (``z = alpha chi^2``, ``alpha = 2/r0 - v0^2/mu``, Stumpff's
    ``C`` and ``S``) has the derivative ``r > 0`` in ``chi``, so its root lies between
    ``sqrt(mu) dt / r_max`` and ``sqrt(mu) dt / r_min`` (apoapsis and periapsis): Newton's
    iteration kept in that bracket (bisecting when a step leaves it) to a few ulps, then
    Lagrange's ``f, g`` (Vallado 2013, Algorithm 8; Battin 1999, Sec. 4.5).  On an ellipse
    ``dt`` is first reduced by whole periods.  Accurate to a few ulps of the phase (over
    100 orbits: ~1e-13 of the semi-major axis).

    Examples
    --------
    >>> import numpy as np
    >>> from attitude.model.orbit import KeplerOrbit
    >>> orbit = KeplerOrbit(mu=1.0, a=1.0, e=0.5, i=0.3, argp=1.0)
    >>> R, V = kepler_flow(1.0, *orbit.state(0.0), [0.3, 10 * orbit.period + 2.0])
    >>> bool(np.allclose(R, orbit.position([0.3, 10 * orbit.period + 2.0]), atol=1e-13))
    True
    """
    R0, V0 = np.asarray(R0, float), np.asarray(V0, float)
    return _flow(_kepler_constants(mu, R0, V0), R0, V0, dt)


def _flow(constants, R0, V0, dt):
    """:func:`kepler_flow` with the orbit's :func:`_kepler_constants` given."""
    r0, sq, alpha = constants[:3]
    if np.ndim(dt) == 0:
        chi, dt, C, S = _universal(constants, float(dt), _stumpff_scalar)
        f, g = 1.0 - chi * chi / r0 * C, dt - chi**3 * S / sq
        R = f * R0 + g * V0
        r = math.sqrt(float(R @ R))
        return R, sq / (r * r0) * (alpha * chi * chi * S - 1.0) * chi * R0 \
            + (1.0 - chi * chi * C / r) * V0
    dt = np.asarray(dt, float)
    chi, dtr, C, S = _universal(constants, dt.reshape(-1), _stumpff)
    f, g = 1.0 - chi * chi / r0 * C, dtr - chi**3 * S / sq
    R = f[:, None] * R0 + g[:, None] * V0
    r = np.linalg.norm(R, axis=-1)
    fdot = sq / (r * r0) * (alpha * chi * chi * S - 1.0) * chi
    V = fdot[:, None] * R0 + (1.0 - chi * chi * C / r)[:, None] * V0
    return R.reshape(dt.shape + (3,)), V.reshape(dt.shape + (3,))


def _encke_segment(system, y, start, t, rtol, atol, limit):
    """One of Encke's segments from the state ``y`` at ``start``: DOP853 on the deviation
    from the Kepler orbit through ``y``'s ``R, V`` (the attitudes and spins as they are),
    to the end of ``t`` or until the deviation passes ``limit`` (m).  Returns the states at
    the times of ``t`` reached, and the time and state of the stop (None at the end)."""
    mu = system.mu
    R_s, V_s = y[:3].copy(), y[3:6].copy()
    constants = _kepler_constants(mu, R_s, V_s)

    def full(s, z):
        Rk, Vk = _flow(constants, R_s, V_s, s - start)
        out = z.copy()
        out[..., 0:3] += Rk
        out[..., 3:6] += Vk
        return out, Rk

    def rhs(s, z):
        yy, Rk = full(s, z)
        d = derivatives(system, yy)
        d[0:3] = z[3:6]
        d[3:6] += mu / math.sqrt(float(Rk @ Rk)) ** 3 * Rk
        return d

    def drift(_, z):
        return float(np.linalg.norm(z[:3])) - limit

    drift.terminal, drift.direction = True, 1.0
    z0 = y.copy()
    z0[:6] = 0.0
    sol = solve_ivp(rhs, (start, float(t[-1])), z0, method="DOP853", t_eval=t, rtol=rtol,
                    atol=atol, events=drift)
    if not sol.success:
        raise PropagationError(f"binary DOP853: {sol.message}")
    reached = np.asarray(sol.t, float)      # a list when no time of t falls in the segment
    ys = full(reached, np.asarray(sol.y).T)[0] if reached.size else np.empty((0, 20))
    if sol.status == 1:
        stop = float(sol.t_events[0][0])
        return ys, stop, full(np.array(stop), sol.y_events[0][0])[0]
    return ys, None, None


def integrate_dop853(system: BinarySystem, y0: np.ndarray, t: np.ndarray, *,
                     rtol: float = 1e-12, atol_scale: float | None = None) -> np.ndarray:
    """Integrate one system from ``y0`` (at time 0) to the sorted times ``t >= 0`` with
    scipy's DOP853 in Encke's form; returns ``(len(t), 20)`` with unit quaternions.

    Encke's method (Battin 1999, Sec. 10.2): DOP853 integrates the deviation of ``R, V``
    from a Kepler orbit of ``mu`` (:func:`kepler_flow`, exact), the attitudes and spins
    as they are; a new reference orbit (the osculating one) when the deviation passes
    :data:`RECTIFY` of the separation, whose absolute tolerance is :data:`RECTIFY` of
    ``R``'s and ``V``'s.  The Keplerian part of the motion then carries no truncation
    error.  In Cartesian form DOP853's error at its smallest tolerance (scipy's ``rtol``
    floor, 2.2e-14) builds up into the orbit's energy and drifts its phase quadratically
    in time, the more so the more eccentric the orbit: 8.2e-9 of the semi-major axis
    after 100 orbits of e = 0.3 for two spheres (``benchmarks/binary.py --only
    --kepler`` before this form; now 3.5e-11 at e = 0.5).

    ``atol`` per component: ``atol_scale`` (default ``rtol``: one tolerance, relative to
    the system's scales) times the component's scale (:func:`tolerance_scale`: the
    separation for R, the orbital speed for V, 1 for q, each body's fastest rate for its
    w), the speed and rate never below the system's own, ``sqrt(mu / R)`` and ``sqrt(mu /
    R^3)`` (a body that does not spin at first would otherwise get no absolute tolerance
    at all, and DOP853 steps that crawl or fail as its torques set it turning).

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
    >>> bool(np.allclose(y[-1, :3], [500.0, 0, 0], atol=1e-9))
    True
    """
    t = np.asarray(t, float)
    y0 = np.asarray(y0, float)
    scale = tolerance_scale(system, y0)
    if t.size == 0:
        return np.empty((0, 20))
    if t[-1] == 0.0:
        return np.repeat(y0[None], t.size, axis=0)
    atol = (rtol if atol_scale is None else atol_scale) * scale
    atol[:6] *= RECTIFY                 # the deviation's own scale: RECTIFY of R's and V's
    out = np.empty((t.size, 20))
    done, start, y = 0, 0.0, y0
    while True:
        ys, start, y = _encke_segment(system, y, start, t[done:], rtol, atol,
                                      RECTIFY * scale[0])
        out[done:done + len(ys)] = ys
        done += len(ys)
        if start is None:
            break
    for s in (slice(6, 10), slice(13, 17)):
        out[:, s] /= np.linalg.norm(out[:, s], axis=-1, keepdims=True)
    return out

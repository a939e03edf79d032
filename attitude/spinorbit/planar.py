r"""The planar spin-orbit problem, vectorised over many initial conditions.

With time in units of ``1/n`` (so the mean anomaly is ``M = t``) and ``theta`` the angle
of the long axis (moment ``A``) from the periapsis direction, the spin axis (moment
``C``) along the orbit normal,

.. math::

    \ddot\theta = -\frac{\omega_0^2}{2}\left(\frac{a}{r}\right)^3 \sin 2(\theta - f),
    \qquad \omega_0^2 = 3\,\frac{B - A}{C}

(Goldreich & Peale 1966; Wisdom, Peale & Mignard 1984, eq. 1; Murray & Dermott 1999,
eq. 5.16).  This is the gravity-gradient torque of :class:`attitude.model.torques.GravityGradient`
about the ``C`` axis, ``3 mu / (2 r^3) (B - A) sin 2 (f - theta)``, divided by ``C n^2``.

The tangent (variational) equation

.. math::

    \delta\ddot\theta = -\omega_0^2 \left(\frac{a}{r}\right)^3 \cos 2(\theta - f)\,
    \delta\theta

is integrated alongside, for the finite-time Lyapunov exponents of the surface of
section (Benettin et al. 1980, renormalised at each periapsis) and the monodromy matrix
of periodic orbits.  All trajectories share the orbit, so each right-hand side solves
Kepler's equation once, and the whole batch is one DOP853 system (``scipy``), advanced
one orbit at a time.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.integrate import solve_ivp

from ..foundations.errors import SpinOrbitError
from ..foundations.progress import track
from ..model.orbit import solve_kepler
from .resonances import cayley_coefficient

__all__ = ["planar_rhs", "advance", "stroboscopic_map", "periodic_orbit", "TWO_PI"]

TWO_PI = 2.0 * math.pi


def _orbit_terms(M: float, e: float) -> tuple[float, float]:
    """``(a/r)^3`` and the true anomaly ``f`` at the mean anomaly ``M`` (scalar)."""
    if e == 0.0:
        return 1.0, M
    E = _kepler(M, e)
    a_over_r = 1.0 / (1.0 - e * math.cos(E))
    f = 2.0 * math.atan2(math.sqrt(1.0 + e) * math.sin(E / 2),
                         math.sqrt(1.0 - e) * math.cos(E / 2))
    return a_over_r**3, f


def _kepler(M: float, e: float) -> float:
    """Eccentric anomaly for one mean anomaly: Newton from Danby's start (scalar, pure
    Python: the right-hand side calls it once per stage); :func:`solve_kepler` as a
    fallback if it has not converged to a few ulps in 8 steps."""
    turns = math.floor(M / TWO_PI + 0.5)
    x = M - TWO_PI * turns                       # in [-pi, pi)
    E = x + 0.85 * e * (1.0 if x >= 0 else -1.0)
    for _ in range(8):
        d = (E - e * math.sin(E) - x) / (1.0 - e * math.cos(E))
        E -= d
        if abs(d) <= 4e-16 * (1.0 + abs(E)):
            return E + TWO_PI * turns
    return float(solve_kepler(M, e))


def planar_rhs(M, theta, rate, omega0: float, e: float):
    """``d theta / dM`` and ``d rate / dM`` of the planar problem (vectorised in theta).

    Parameters
    ----------
    M : float
        Mean anomaly (time in units of ``1/n``), rad.
    theta, rate : array-like
        Angle of the long axis from periapsis (rad), spin rate / mean motion.
    omega0 : float
        ``sqrt(3 (B - A) / C)``.
    e : float
        Eccentricity.

    Examples
    --------
    >>> planar_rhs(0.0, 0.3, 1.0, 1.0, 0.0)[1].round(6)     # -(1/2) sin 0.6
    np.float64(-0.282321)
    """
    ar3, f = _orbit_terms(float(M), float(e))
    theta = np.asarray(theta, dtype=float)
    return np.asarray(rate, dtype=float), -0.5 * omega0**2 * ar3 * np.sin(2.0 * (theta - f))


class _System:
    """The batch: ``N`` trajectories (some with ``e = 0``: the regular control) and ``K``
    tangent vectors each; the state vector is ``[theta (N), w (N), dth (N K), dw (N K)]``."""

    def __init__(self, omega0: float, e: float, control: np.ndarray, k: int):
        self.w02 = float(omega0) ** 2
        self.e = float(e)
        self.control = np.asarray(control, dtype=bool)
        self.any_control = bool(self.control.any())
        # the control rows are a contiguous block at the end (stroboscopic_map's layout)
        self.first_control = int(np.argmax(self.control)) if self.any_control else None
        if self.any_control and not self.control[self.first_control:].all():
            raise SpinOrbitError("internal: control rows must be the last block")
        self.n = self.control.size
        self.k = int(k)

    def split(self, y):
        n, k = self.n, self.k
        return (y[:n], y[n:2 * n], y[2 * n:2 * n + n * k].reshape(n, k),
                y[2 * n + n * k:].reshape(n, k))

    def __call__(self, M, y):
        th, w, dth, dw = self.split(y)
        ar3, f = _orbit_terms(M, self.e)
        if self.any_control:
            c = self.first_control
            ar3 = np.concatenate([np.full(c, ar3), np.ones(self.n - c)])
            f = np.concatenate([np.full(c, f), np.full(self.n - c, M)])
        x = 2.0 * (th - f)
        acc = -0.5 * self.w02 * ar3 * np.sin(x)
        if self.k:
            stiff = (-self.w02 * ar3 * np.cos(x))[:, None]
            return np.concatenate([w, acc, dw.ravel(), (stiff * dth).ravel()])
        return np.concatenate([w, acc])


def _advance(system: _System, y, M0: float, M1: float, rtol: float, atol: float,
             first_step: float | None):
    sol = solve_ivp(system, (M0, M1), y, method="DOP853", rtol=rtol, atol=atol,
                    first_step=first_step)
    if not sol.success:
        raise SpinOrbitError(f"the planar spin-orbit integration failed between M = "
                             f"{M0:.6g} and {M1:.6g} rad: {sol.message}")
    steps = sol.t.size - 1
    return sol.y[:, -1], (M1 - M0) / max(steps, 1)


def advance(omega0: float, e: float, angle: float, rate: float, M0: float, M1: float, *,
            rtol: float = 1e-12) -> tuple[float, float]:
    """Advance one planar state from mean anomaly ``M0`` to ``M1`` (rad).

    Examples
    --------
    >>> th, w = advance(0.5, 0.0, 0.0, 1.0, 0.0, 10.0)      # locked on a circular orbit
    >>> round(th - 10.0, 9), round(w, 9)
    (0.0, 1.0)
    """
    system = _System(omega0, e, np.zeros(1, bool), 0)
    y, _h = _advance(system, np.array([float(angle), float(rate)]), float(M0), float(M1),
                     rtol, rtol * 1e-2, None)
    return float(y[0]), float(y[1])


def stroboscopic_map(omega0: float, e: float, angles, rates, n_orbits: int, *,
                     lyapunov: bool = True, control: bool = True, rtol: float = 1e-10,
                     seed: int = 0) -> dict:
    """Iterate the periapsis-to-periapsis map of the planar problem for many points.

    Parameters
    ----------
    omega0, e : float
        ``sqrt(3 (B - A) / C)`` and the eccentricity.
    angles, rates : array-like, shape ``(N,)``
        Initial angle of the long axis from the direction of periapsis (rad) and spin
        rate / mean motion, at a periapsis passage.
    n_orbits : int
        Number of orbits (map iterations).
    lyapunov : bool
        Also integrate one tangent vector per trajectory (random direction, seeded),
        renormalised at every periapsis.
    control : bool
        Also run every initial condition on a circular orbit (``e = 0``: an integrable
        pendulum in the rotating frame), the regular control of the Lyapunov test.
    rtol : float
        Relative tolerance of DOP853 (absolute: ``rtol / 100``).

    Returns
    -------
    dict
        ``angle`` (N, n_orbits + 1), reduced to ``[-pi/2, pi/2)`` (the problem is
        ``pi``-periodic in theta); ``rate`` (N, n_orbits + 1); with ``lyapunov``:
        ``log_growth`` (N, n_orbits), ``ln(d_k / d_{k-1})`` over each orbit, and with
        ``control`` the same for the control, ``control_log_growth``.

    Examples
    --------
    >>> out = stroboscopic_map(0.5, 0.0, [0.0], [1.0], 3, lyapunov=False, control=False)
    >>> out["angle"].round(9).tolist(), out["rate"].round(9).tolist()   # locked, e = 0
    ([[0.0, 0.0, 0.0, 0.0]], [[1.0, 1.0, 1.0, 1.0]])
    """
    th0 = np.atleast_1d(np.asarray(angles, dtype=float)).ravel()
    w0 = np.atleast_1d(np.asarray(rates, dtype=float)).ravel()
    if th0.shape != w0.shape:
        raise SpinOrbitError(f"angles and rates must have the same length, got "
                             f"{th0.size} and {w0.size}", key="rates")
    if not (np.all(np.isfinite(th0)) and np.all(np.isfinite(w0))):
        raise SpinOrbitError("initial angles and rates must be finite", key="angles")
    n_orbits = int(n_orbits)
    if n_orbits < 1:
        raise SpinOrbitError(f"must be >= 1, got {n_orbits}", key="n_orbits")
    N = th0.size
    use_control = bool(control and lyapunov)
    ctrl = np.concatenate([np.zeros(N, bool), np.ones(N, bool)]) if use_control \
        else np.zeros(N, bool)
    rows = ctrl.size
    k = 1 if lyapunov else 0
    system = _System(omega0, e, ctrl, k)
    th = np.tile(th0, rows // N)
    w = np.tile(w0, rows // N)
    if k:
        rng = np.random.default_rng(seed)
        phi = rng.uniform(0.0, TWO_PI, size=N)
        phi = np.tile(phi, rows // N)
        dth, dw = np.cos(phi)[:, None], np.sin(phi)[:, None]
    else:
        dth = dw = np.zeros((rows, 0))
    angle = np.empty((rows, n_orbits + 1))
    rate = np.empty((rows, n_orbits + 1))
    growth = np.empty((rows, n_orbits)) if k else None

    def reduce(x):
        return x - math.pi * np.floor(x / math.pi + 0.5)

    th = reduce(th)
    angle[:, 0], rate[:, 0] = th, w
    h = None
    atol = rtol * 1e-2
    # reported on stderr when the caller shows progress (the attitude command does)
    for j in track(range(n_orbits), n_orbits, "surface of section", unit="orbits"):
        y = np.concatenate([th, w, dth.ravel(), dw.ravel()])
        y, h = _advance(system, y, 0.0, TWO_PI, rtol, atol, h)
        th, w, dth, dw = system.split(y)
        th = reduce(th)
        angle[:, j + 1], rate[:, j + 1] = th, w
        if k:
            d = np.sqrt(dth[:, 0] ** 2 + dw[:, 0] ** 2)
            growth[:, j] = np.log(d)
            dth, dw = dth / d[:, None], dw / d[:, None]
    out = {"angle": angle[:N], "rate": rate[:N]}
    if k:
        out["log_growth"] = growth[:N]
        if use_control:
            out["control_log_growth"] = growth[N:]
    return out


def periodic_orbit(omega0: float, e: float, p: int, q: int, *, angle: float | None = None,
                   rate: float | None = None, rtol: float = 1e-12, tol: float = 1e-11,
                   max_iter: int = 30) -> tuple[float, float, np.ndarray]:
    """The periodic orbit of the p:q state: after ``q`` orbits the body has turned ``p``
    times (``theta -> theta + 2 pi p``) and the spin rate is back.

    Newton's method on the map over ``q`` orbits, with the Jacobian from the tangent
    equations (the monodromy matrix).  The default guess is the centre of the resonance
    (``theta = 0`` at periapsis, or ``pi/2`` when ``H(p/q, e) < 0``) at the spin rate
    ``p/q`` plus the linear forced libration for the 1:1 state.

    Returns
    -------
    angle, rate : float
        The periodic orbit at periapsis (rad; units of n).
    monodromy : ndarray, shape (2, 2)
        ``d(theta, rate)_q / d(theta, rate)_0``: in-plane Floquet multipliers are its
        eigenvalues (stable when ``|trace| < 2``).

    Raises
    ------
    SpinOrbitError
        When Newton's method does not converge (no periodic orbit near the guess, e.g.
        a resonance that does not exist at this ``omega0`` or lies in a chaotic zone).

    Examples
    --------
    >>> th, w, mono = periodic_orbit(0.6, 0.01, 1, 1)
    >>> round(th, 12), round(w - 1, 4)   # linear theory: rate - 1 = 2e w0^2/(w0^2-1) = -0.0113
    (0.0, -0.0114)
    """
    p, q = int(p), int(q)
    if q < 1 or p < 0:
        raise SpinOrbitError(f"expected p >= 0, q >= 1, got {p}:{q}", key="resonance")
    if angle is None:
        half_integer = (2 * p) % q == 0
        angle = 0.0 if not half_integer or cayley_coefficient(p / q, e) >= 0 \
            else math.pi / 2
    if rate is None:
        rate = p / q
        if p == q and abs(omega0**2 - 1.0) > 1e-6:
            rate += 2.0 * e * omega0**2 / (omega0**2 - 1.0)
    x = np.array([float(angle), float(rate)])
    system = _System(omega0, e, np.zeros(1, bool), 2)
    span = TWO_PI * q
    for _ in range(int(max_iter)):
        y = np.concatenate([x, [1.0, 0.0], [0.0, 1.0]])
        y, _h = _advance(system, y, 0.0, span, rtol, rtol * 1e-2, None)
        th, w, dth, dw = system.split(y)
        mono = np.array([[dth[0, 0], dth[0, 1]], [dw[0, 0], dw[0, 1]]])
        res = np.array([th[0] - x[0] - TWO_PI * p, w[0] - x[1]])
        if np.max(np.abs(res)) < tol:
            return float(x[0]), float(x[1]), mono
        try:
            dx = np.linalg.solve(mono - np.eye(2), -res)
        except np.linalg.LinAlgError:
            break
        step = float(np.max(np.abs(dx)))
        if step > 0.5:
            dx *= 0.5 / step
        x = x + dx
    raise SpinOrbitError(f"no periodic orbit of the {p}:{q} state found near angle = "
                         f"{angle:.4g} rad, rate = {rate:.4g} n (omega0 = {omega0:.4g}, "
                         f"e = {e:.4g}); give another guess or check that the "
                         f"resonance exists", key="resonance")

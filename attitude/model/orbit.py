"""The minimal orbit a torque model needs: where the primary is, seen from the body.

Torque models that depend on the body's position (gravity gradient, the geomagnetic field
of eddy-current damping) take a *path*: any object with a method ``position(t)`` that
returns the position of the body relative to the primary, in the inertial frame, in
metres, for ``t`` in seconds since the scenario epoch (vectorised: ``t`` of shape ``S``
gives ``S + (3,)``).  Three are provided:

:class:`KeplerOrbit`
    a two-body (Keplerian) ellipse of any eccentricity ``0 <= e < 1``, from classical
    elements at the epoch; Kepler's equation is solved vectorised to machine precision.
:class:`TabulatedPath`
    positions sampled by the user (a real ephemeris), interpolated by a cubic spline.
:class:`CallablePath`
    a user function ``t -> position``.

Conventions: SI (m, s, rad, m^3/s^2); angles of the classical elements are measured in
the inertial frame the attitude is expressed in (for the Earth, an equatorial frame such
as GCRF / EME2000, so that ``i`` is the inclination to the equator).  The sign of the
position does not matter to the gravity-gradient torque or to a dipole field (both are
even in ``r``), but the convention here is *body relative to primary*.

Hyperbolic and parabolic orbits (``e >= 1``, a fly-by) are not Keplerian ellipses:
:class:`KeplerOrbit` rejects them with :class:`OrbitError`; give such a trajectory as a
:class:`TabulatedPath` or a :class:`CallablePath`.

References
----------
.. [1] Vallado, D. A. (2013). *Fundamentals of Astrodynamics and Applications*, 4th ed.,
   Microcosm Press. Sec. 2.2 (Kepler's equation, Algorithm 2), Sec. 2.6 (COE2RV).
.. [2] Danby, J. M. A. (1987). The solution of Kepler's equation, III. *Celestial
   Mechanics* 40, 303-312 (the starting value ``E0 = M + 0.85 e``).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.interpolate import CubicSpline

from ..foundations.errors import OrbitError
from ..foundations.quantities import to_si

__all__ = [
    "KeplerOrbit",
    "TabulatedPath",
    "CallablePath",
    "ConstantPosition",
    "as_path",
    "solve_kepler",
    "solve_kepler_scalar",
    "mean_from_eccentric",
    "kepler_position",
    "kepler_velocity",
]

_EPS = np.finfo(float).eps
_TWO_PI = 2.0 * np.pi



# --- Kepler's equation --------------------------------------------------------------------


def mean_from_eccentric(E, e):
    """Mean anomaly ``M = E - e sin E`` (Kepler's equation), vectorised.

    Parameters
    ----------
    E : array-like
        Eccentric anomaly, rad.
    e : float or array-like
        Eccentricity, ``0 <= e < 1``; broadcasts against ``E``.

    Returns
    -------
    M : ndarray or float
        Mean anomaly, rad (same branch as ``E``: no reduction modulo 2 pi).

    Examples
    --------
    >>> from attitude.model.orbit import mean_from_eccentric, solve_kepler
    >>> round(float(solve_kepler(mean_from_eccentric(1.2, 0.3), 0.3)), 12)
    1.2
    """
    E = np.asarray(E, dtype=float)
    return E - np.asarray(e, dtype=float) * np.sin(E)


def solve_kepler(M, e, *, max_iter: int = 50):
    """Eccentric anomaly ``E`` with ``E - e sin E = M``, vectorised, for ``0 <= e < 1``.

    ``M`` is reduced to ``x = |M mod 2 pi| <= pi`` (``E`` is odd and 2 pi-periodic in
    ``M`` up to the added turns), where the root is bracketed by ``x <= E <= min(x + e,
    pi)`` because ``E - x = e sin E`` lies in ``[0, e]``.  Starting value: Danby's
    ``E0 = x + 0.85 e`` [2]_, or, near periapsis (where it is poor for ``e -> 1``), the
    root of the cubic ``(1 - e) E + e E^3 / 6 = x`` (``sin E ~ E - E^3/6``) when that root
    is below 1 rad.  Then Halley's iteration (cubic convergence), each iterate clipped to
    the bracket, until the step is below a few ulps or the residual is at the rounding
    level of ``E - e sin E`` (near periapsis with ``e -> 1`` the step cannot get below
    ``eps E / (1 - e cos E)``).  Typically 2 to 4 iterations for any ``e < 1``; the result
    has a backward error of a few ulps, i.e. a forward error of a few ulps times
    ``dE/dM = 1 / (1 - e cos E)``.

    Parameters
    ----------
    M : array-like
        Mean anomaly, rad, any real value.
    e : float or array-like
        Eccentricity in ``[0, 1)``; broadcasts against ``M``.
    max_iter : int
        Safety cap on the iterations.

    Returns
    -------
    E : ndarray or float
        Eccentric anomaly, rad, on the same turn as ``M`` (``E = M`` when ``M`` is a
        multiple of pi).

    Raises
    ------
    OrbitError
        If an eccentricity is outside ``[0, 1)``.

    References
    ----------
    .. [1] Vallado (2013), Sec. 2.2, Algorithm 2 and Example 2-1.
    .. [2] Danby (1987), Celest. Mech. 40, 303.

    Examples
    --------
    Vallado (2013) Example 2-1: ``M = 235.4 deg``, ``e = 0.4`` gives
    ``E = 220.512 074 767 522 deg``:

    >>> import numpy as np
    >>> from attitude.model.orbit import solve_kepler
    >>> float(np.degrees(solve_kepler(np.radians(235.4), 0.4)))
    220.512074767522...
    """
    M = np.asarray(M, dtype=float)
    e = np.asarray(e, dtype=float)
    if np.any(~np.isfinite(e)) or np.any(e < 0) or np.any(e >= 1):
        bad = e[(~np.isfinite(e)) | (e < 0) | (e >= 1)].ravel()[0] if e.ndim else float(e)
        raise OrbitError(f"must be in [0, 1), got {bad:g} (Kepler's equation for "
                         "elliptic orbits)", key="e")
    if e.ndim == 0 and e == 0.0:
        return M.copy() if M.ndim else float(M)
    if M.ndim == 0 and e.ndim == 0:
        return solve_kepler_scalar(float(M), float(e), max_iter)
    shape = np.broadcast_shapes(M.shape, e.shape)
    M = np.broadcast_to(M, shape).ravel()
    e = np.broadcast_to(e, shape).ravel()
    turns = np.round(M / _TWO_PI)
    Mr = M - turns * _TWO_PI                  # in [-pi, pi]
    sign = np.where(Mr < 0, -1.0, 1.0)
    x = np.abs(Mr)
    lo = x
    hi = np.minimum(x + e, np.pi)
    E = np.clip(_starting_value(x, e), lo, hi)
    active = e > 0
    E[~active] = x[~active]
    for _ in range(max_iter):
        if not active.any():
            break
        idx = np.flatnonzero(active)
        Ea, ea, xa = E[idx], e[idx], x[idx]
        se, ce = np.sin(Ea), np.cos(Ea)
        f = Ea - ea * se - xa                 # Kepler's equation residual
        f1 = 1.0 - ea * ce                    # f'  >= 1 - e > 0
        newton = -f / f1
        step = -f / (f1 + 0.5 * newton * ea * se)   # Halley (f'' = e sin E)
        En = np.clip(Ea + step, lo[idx], hi[idx])
        done = ((np.abs(En - Ea) <= 4.0 * _EPS * np.maximum(En, 1.0))
                | (np.abs(f) <= 2.0 * _EPS * Ea))
        E[idx] = En
        active[idx[done]] = False
    out = (sign * E + turns * _TWO_PI).reshape(shape)
    return out if out.ndim else float(out)


def _starting_value(x, e):
    """Danby's ``x + 0.85 e``, or the root of ``(1 - e) E + e E^3/6 = x`` where it is
    below 1 rad (trigonometric form of Cardano's formula, no cancellation)."""
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        p = 6.0 * (1.0 - e) / e               # E^3 + p E - 6 x / e = 0
        q = 6.0 * x / e
        cubic = 2.0 * np.sqrt(p / 3.0) * np.sinh(np.arcsinh(1.5 * q / p * np.sqrt(3.0 / p))
                                                 / 3.0)
    return np.where(np.isfinite(cubic) & (cubic < 1.0), cubic, x + 0.85 * e)


def solve_kepler_scalar(M: float, e: float, max_iter: int = 50) -> float:
    """:func:`solve_kepler` for one mean anomaly, in plain floats.

    The same reduction, starting value, Halley iteration and stopping rule without numpy
    overhead (integrators call torque models one epoch at a time); also the compiled
    torques' solver (:mod:`attitude.propagation.compiled_torques` compiles this function
    with numba, so the two agree bit for bit).

    Parameters
    ----------
    M : float
        Mean anomaly, rad (any value).
    e : float
        Eccentricity, ``0 <= e < 1`` (not checked here: :func:`solve_kepler` checks).
    max_iter : int
        Most Halley iterations.

    Returns
    -------
    float
        Eccentric anomaly, rad, in the same turn as ``M``.

    Examples
    --------
    >>> import math
    >>> from attitude.model.orbit import solve_kepler_scalar
    >>> E = solve_kepler_scalar(1.0, 0.3)
    >>> abs(E - 0.3 * math.sin(E) - 1.0) < 1e-15
    True
    """
    turns = round(M / _TWO_PI)
    Mr = M - turns * _TWO_PI
    sign = -1.0 if Mr < 0 else 1.0
    x = abs(Mr)
    lo, hi = x, min(x + e, math.pi)
    E = x + 0.85 * e
    if e <= 0.0:
        return M
    # the cubic (1 - e) E + e E^3 / 6 = x increases with E, so its root is below 1 only
    # for x < 1 - 5 e / 6: skip its sinh and asinh beyond (a margin, 0.8 e, for rounding)
    if x < 1.0 - 0.8 * e:
        p = 6.0 * (1.0 - e) / e
        cubic = 2.0 * math.sqrt(p / 3.0) * math.sinh(
            math.asinh(1.5 * (6.0 * x / e) / p * math.sqrt(3.0 / p)) / 3.0)
        if cubic < 1.0:
            E = cubic
    E = min(max(E, lo), hi)
    for _ in range(max_iter):
        se, ce = math.sin(E), math.cos(E)
        f = E - e * se - x
        f1 = 1.0 - e * ce
        newton = -f / f1
        En = min(max(E - f / (f1 + 0.5 * newton * e * se), lo), hi)
        if abs(En - E) <= 4.0 * _EPS * max(En, 1.0) or abs(f) <= 2.0 * _EPS * E:
            E = En
            break
        E = En
    return sign * E + turns * _TWO_PI


# --- Keplerian orbit -------------------------------------------------------------------


def _si(value, unit: str, key: str):
    """``to_si`` raising :class:`OrbitError` whose key is ``key``."""
    return to_si(value, unit, key=key, error=OrbitError)


def _check_angle(value, key: str) -> float:
    x = float(value)
    if not np.isfinite(x):
        raise OrbitError(f"must be a finite angle, got {value!r}", key=key)
    return x


def kepler_position(a, e, root, toward_periapsis, ahead, cos_e, sin_e):
    """Position on a Kepler orbit from the eccentric anomaly: ``r = a ((cos E - e) P +
    b sin E Q)`` (``root = b = sqrt(1 - e^2)``; ``toward_periapsis = P`` and ``ahead = Q``
    the unit vectors toward periapsis and 90 deg ahead in the plane, 3-tuples).  The one
    source of the formula: ``cos_e``, ``sin_e`` floats (the compiled kernels) or arrays
    (:meth:`KeplerOrbit.state`); returns the components as a tuple.

    Examples
    --------
    >>> kepler_position(2.0, 0.5, 0.75 ** 0.5, (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), 1.0, 0.0)
    (1.0, 0.0, 0.0)
    """
    p, q = toward_periapsis, ahead
    ce = cos_e - e
    bs = root * sin_e
    return (a * (ce * p[0] + bs * q[0]), a * (ce * p[1] + bs * q[1]),
            a * (ce * p[2] + bs * q[2]))


def kepler_velocity(mu, a, e, root, toward_periapsis, ahead, cos_e, sin_e):
    """Velocity on a Kepler orbit from the eccentric anomaly: ``v = sqrt(mu a) / r
    (-sin E P + b cos E Q)`` with ``r = a (1 - e cos E)``; arguments as
    :func:`kepler_position`.

    Examples
    --------
    >>> v = kepler_velocity(1.0, 1.0, 0.0, 1.0, (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), 1.0, 0.0)
    >>> [float(x) for x in v]                   # circular: speed sqrt(mu / a), along Q
    [0.0, 1.0, 0.0]
    """
    p, q = toward_periapsis, ahead
    f = np.sqrt(mu * a) / (a * (1.0 - e * cos_e))
    bc = root * cos_e
    return (f * (-sin_e * p[0] + bc * q[0]), f * (-sin_e * p[1] + bc * q[1]),
            f * (-sin_e * p[2] + bc * q[2]))


@dataclass(frozen=True)
class KeplerOrbit:
    """A two-body elliptic orbit of the body about a point-mass primary.

    Parameters
    ----------
    mu : float
        Gravitational parameter ``G (M + m)`` of the primary, m^3/s^2.
    a : float
        Semi-major axis, m.
    e : float
        Eccentricity, ``0 <= e < 1``.
    i, raan, argp : float
        Inclination, right ascension of the ascending node, argument of periapsis, rad,
        in the inertial frame.
    mean_anomaly : float
        Mean anomaly at the epoch (``t = 0``), rad.

    Raises
    ------
    OrbitError
        On a non-positive ``mu`` or ``a``, ``e`` outside ``[0, 1)`` (hyperbolic or
        parabolic orbits are not supported: use :class:`TabulatedPath` or
        :class:`CallablePath`), or a non-finite angle.  The message starts with the name
        of the element.

    Notes
    -----
    Position and velocity from the eccentric anomaly ``E`` (perifocal frame, then the
    3-1-3 rotation ``R3(-raan) R1(-i) R3(-argp)``; Vallado 2013, Sec. 2.6):

    .. math::

        r = a (\\cos E - e)\\,\\hat P + a\\sqrt{1-e^2}\\sin E\\,\\hat Q, \\qquad
        v = \\frac{\\sqrt{\\mu a}}{|r|}\\left(-\\sin E\\,\\hat P
            + \\sqrt{1-e^2}\\cos E\\,\\hat Q\\right)

    with ``M(t) = mean_anomaly + n t``, ``n = sqrt(mu / a^3)``.

    Examples
    --------
    >>> from attitude.model.orbit import KeplerOrbit
    >>> leo = KeplerOrbit.from_elements(mu="3.986004418e14 m3/s2", a="7000 km", e=0.0)
    >>> round(leo.period / 60, 3)          # minutes
    97.142
    >>> leo.position(0.0)                  # at periapsis, along the line of nodes
    array([7000000.,       0.,       0.])
    """

    mu: float
    a: float
    e: float = 0.0
    i: float = 0.0
    raan: float = 0.0
    argp: float = 0.0
    mean_anomaly: float = 0.0

    def __post_init__(self):
        mu, a, e = float(self.mu), float(self.a), float(self.e)
        if not (np.isfinite(mu) and mu > 0):
            raise OrbitError(f"must be a finite, positive gravitational parameter "
                             f"(m^3/s^2), got {self.mu!r}", key="mu")
        if not (np.isfinite(a) and a > 0):
            raise OrbitError(f"must be a finite, positive semi-major axis (m), got "
                             f"{self.a!r}", key="a")
        if not (np.isfinite(e) and 0.0 <= e < 1.0):
            raise OrbitError(f"must be in [0, 1), got {self.e!r}"
                             + ("; hyperbolic and parabolic orbits are not Keplerian "
                             "ellipses: give the trajectory as a TabulatedPath or a "
                             "CallablePath" if np.isfinite(e) and e >= 1 else ""), key="e")
        object.__setattr__(self, "mu", mu)
        object.__setattr__(self, "a", a)
        object.__setattr__(self, "e", e)
        for key in ("i", "raan", "argp", "mean_anomaly"):
            object.__setattr__(self, key, _check_angle(getattr(self, key), key))
        object.__setattr__(self, "_pqw", self._compute_frame())

    @classmethod
    def from_elements(cls, *, mu, a, e=0.0, i=0.0, raan=0.0, argp=0.0,
                      mean_anomaly=0.0) -> KeplerOrbit:
        """Build from classical elements given as floats (SI), Quantities or strings.

        Parameters
        ----------
        mu : float (m^3/s^2), Quantity or str (``"3.986004418e14 m3/s2"``)
        a : float (m), Quantity or str (``"7000 km"``)
        e : float
            Eccentricity (dimensionless).
        i, raan, argp, mean_anomaly : float (rad), Quantity or str (``"98 deg"``)

        Raises
        ------
        OrbitError
            On an unparseable quantity, a wrong unit or a non-physical element; the
            message starts with the element's name.
        """
        conv = _si
        return cls(mu=conv(mu, "m3/s2", "mu"), a=conv(a, "m", "a"),
                   e=conv(e, "", "e"), i=conv(i, "rad", "i"), raan=conv(raan, "rad", "raan"),
                   argp=conv(argp, "rad", "argp"),
                   mean_anomaly=conv(mean_anomaly, "rad", "mean_anomaly"))

    # --- scalar properties ---------------------------------------------------------
    @property
    def mean_motion(self) -> float:
        """``n = sqrt(mu / a^3)``, rad/s."""
        return float(np.sqrt(self.mu / self.a**3))

    @property
    def period(self) -> float:
        """Orbital period ``2 pi sqrt(a^3 / mu)`` (Kepler's third law), s."""
        return _TWO_PI / self.mean_motion

    @property
    def periapsis(self) -> float:
        """Periapsis distance ``a (1 - e)``, m."""
        return self.a * (1.0 - self.e)

    @property
    def apoapsis(self) -> float:
        """Apoapsis distance ``a (1 + e)``, m."""
        return self.a * (1.0 + self.e)

    @property
    def specific_energy(self) -> float:
        """``-mu / (2 a)``, J/kg."""
        return -self.mu / (2.0 * self.a)

    @property
    def specific_angular_momentum(self) -> np.ndarray:
        """``r x v = sqrt(mu a (1 - e^2)) W`` (W the orbit normal), m^2/s, inertial."""
        return np.sqrt(self.mu * self.a * (1.0 - self.e**2)) * self._frame()[2]

    def _frame(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Unit vectors P (periapsis), Q, W (normal) in the inertial frame."""
        return self._pqw

    def _compute_frame(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        cO, sO = np.cos(self.raan), np.sin(self.raan)
        cw, sw = np.cos(self.argp), np.sin(self.argp)
        ci, si = np.cos(self.i), np.sin(self.i)
        P = np.array([cO * cw - sO * sw * ci, sO * cw + cO * sw * ci, sw * si])
        Q = np.array([-cO * sw - sO * cw * ci, -sO * sw + cO * cw * ci, cw * si])
        W = np.array([sO * si, -cO * si, ci])
        return P, Q, W

    def compiled_parameters(self, t_span=None) -> tuple[str, dict]:
        """``("kepler", {...})``: the orbit as numbers for a compiled kernel, the terms of
        :meth:`state` (``a``, ``e``, ``b = sqrt(1 - e^2)``, the mean anomaly at the epoch
        and the mean motion, the unit vectors ``P`` and ``Q`` of the orbit's plane, ``mu``).

        Examples
        --------
        >>> from attitude.model.orbit import KeplerOrbit
        >>> kind, values = KeplerOrbit(mu=3.986004418e14, a=7.0e6).compiled_parameters()
        >>> kind, values["P"]
        ('kepler', array([1., 0., 0.]))
        """
        P, Q, _ = self._frame()
        return ("kepler", {"mu": self.mu, "a": self.a, "e": self.e,
                           "b": float(np.sqrt(1.0 - self.e**2)),
                           "mean_anomaly": self.mean_anomaly,
                           "mean_motion": self.mean_motion, "P": P.copy(), "Q": Q.copy()})

    # --- along the orbit -------------------------------------------------------------
    def mean_anomaly_at(self, t) -> np.ndarray:
        """``M(t) = M0 + n t``, rad (not reduced modulo 2 pi)."""
        return self.mean_anomaly + self.mean_motion * np.asarray(t, dtype=float)

    def eccentric_anomaly(self, t) -> np.ndarray:
        """Eccentric anomaly at ``t`` (s since the epoch), rad."""
        if np.ndim(t) == 0:                   # the integrators' one-epoch-at-a-time path
            M = self.mean_anomaly + self.mean_motion * float(t)
            return np.asarray(M if self.e == 0.0 else solve_kepler_scalar(M, self.e, 50))
        return np.asarray(solve_kepler(self.mean_anomaly_at(t), self.e))

    def true_anomaly(self, t) -> np.ndarray:
        """True anomaly at ``t``, rad, on the same turn as the mean anomaly."""
        E = self.eccentric_anomaly(t)
        half = np.arctan2(np.sqrt(1 + self.e) * np.sin(E / 2),
                          np.sqrt(1 - self.e) * np.cos(E / 2))
        return 2.0 * half

    def radius(self, t) -> np.ndarray:
        """Distance ``a (1 - e cos E)`` from the primary, m."""
        return self.a * (1.0 - self.e * np.cos(self.eccentric_anomaly(t)))

    def position(self, t) -> np.ndarray:
        """Position of the body relative to the primary, inertial frame, m.

        Parameters
        ----------
        t : float or array-like, shape ``S``
            Seconds since the epoch.

        Returns
        -------
        ndarray, shape ``S + (3,)``
        """
        return self.state(t)[0]

    def velocity(self, t) -> np.ndarray:
        """Velocity of the body relative to the primary, inertial frame, m/s, shape
        ``S + (3,)``."""
        return self.state(t)[1]

    def state(self, t) -> tuple[np.ndarray, np.ndarray]:
        """Position (m) and velocity (m/s), each of shape ``S + (3,)``."""
        E = self.eccentric_anomaly(t)
        P, Q, _ = self._frame()
        p, q = tuple(P.tolist()), tuple(Q.tolist())
        b = float(np.sqrt(1.0 - self.e**2))
        cE, sE = np.cos(E), np.sin(E)
        r = kepler_position(self.a, self.e, b, p, q, cE, sE)
        v = kepler_velocity(self.mu, self.a, self.e, b, p, q, cE, sE)
        return np.stack(r, axis=-1), np.stack(v, axis=-1)


# --- user-supplied paths --------------------------------------------------------------


class TabulatedPath:
    """Positions sampled by the user, interpolated by a cubic spline.

    Parameters
    ----------
    times : (N,) array-like
        Strictly increasing sample times, s since the epoch (a Quantity is converted);
        ``N >= 4``.
    positions : (N, 3) array-like
        Inertial position of the body relative to the primary at each time, m (a
        Quantity is converted).
    extrapolate : bool
        Allow evaluation outside ``[times[0], times[-1]]`` (cubic extrapolation is
        rarely what you want); by default such a time raises :class:`OrbitError`.

    Notes
    -----
    ``scipy.interpolate.CubicSpline`` with not-a-knot ends, one spline per component.
    The interpolation error of a smooth trajectory sampled every ``h`` seconds scales as
    ``h^4``: sample an orbit at least ~50 times per revolution for 1e-6 relative
    accuracy.  :meth:`velocity` is the spline's derivative.

    Examples
    --------
    >>> import numpy as np
    >>> from attitude.model.orbit import TabulatedPath
    >>> t = np.linspace(0.0, 100.0, 11)
    >>> path = TabulatedPath(t, np.stack([7e6 + t, 0 * t, 0 * t], axis=-1))
    >>> path.position(55.0)
    array([7000055.,       0.,       0.])
    """

    def __init__(self, times, positions, *, extrapolate: bool = False):
        t = np.asarray(_si(times, "s", "times"), dtype=float)
        r = np.asarray(_si(positions, "m", "positions"), dtype=float)
        if t.ndim != 1 or t.size < 4:
            raise OrbitError(f"expected a 1-D array of at least 4 times, got shape "
                             f"{t.shape}", key="times")
        if r.shape != (t.size, 3):
            raise OrbitError(f"expected shape ({t.size}, 3), got {r.shape}", key="positions")
        if not (np.all(np.isfinite(t)) and np.all(np.isfinite(r))):
            raise OrbitError("times and positions must be finite", key="positions")
        if np.any(np.diff(t) <= 0):
            raise OrbitError("must be strictly increasing", key="times")
        self.times = t
        self.extrapolate = bool(extrapolate)
        self._spline = CubicSpline(t, r, axis=0)
        self._dspline = self._spline.derivative()

    def _check(self, t) -> np.ndarray:
        t = np.asarray(t, dtype=float)
        if not self.extrapolate:
            lo, hi = self.times[0], self.times[-1]
            if np.any((t < lo) | (t > hi)):
                bad = t[(t < lo) | (t > hi)].ravel()[0] if t.ndim else float(t)
                raise OrbitError(f"{bad:.9g} s is outside the tabulated span "
                                 f"[{lo:.9g}, {hi:.9g}] s; extend the table or pass "
                                 "extrapolate=True", key="t")
        return t

    def position(self, t) -> np.ndarray:
        """Interpolated position, m, shape ``S + (3,)``."""
        return self._spline(self._check(t))

    def velocity(self, t) -> np.ndarray:
        """Derivative of the spline, m/s, shape ``S + (3,)``."""
        return self._dspline(self._check(t))

    def compiled_parameters(self, t_span=None) -> tuple[str, dict]:
        """``("piecewise_cubic", {breakpoints, coefficients})``: the spline itself (its
        breakpoints ``(N,)`` and coefficients ``(4, N - 1, 3)``, highest power first, in
        powers of ``t - breakpoint``) for a compiled kernel.

        Raises
        ------
        OrbitError
            If ``t_span`` reaches outside the table and extrapolation is off.

        Examples
        --------
        >>> import numpy as np
        >>> from attitude.model.orbit import TabulatedPath
        >>> t = np.linspace(0.0, 100.0, 11)
        >>> path = TabulatedPath(t, np.stack([7e6 + t, 0 * t, 0 * t], axis=-1))
        >>> kind, values = path.compiled_parameters((0.0, 50.0))
        >>> kind, values["coefficients"].shape
        ('piecewise_cubic', (4, 10, 3))
        """
        if t_span is not None:
            self._check(np.asarray(t_span, dtype=float))
        return ("piecewise_cubic", {"breakpoints": np.array(self._spline.x, dtype=float),
                                    "coefficients": np.array(self._spline.c, dtype=float)})

    def __repr__(self) -> str:
        return (f"TabulatedPath({self.times.size} samples, t in [{self.times[0]:.6g}, "
                f"{self.times[-1]:.6g}] s)")


class CallablePath:
    """A user function ``position(t) -> (..., 3)`` metres, inertial, body relative to
    the primary.

    The function is first called with the whole array of times; if it fails or does not
    return shape ``t.shape + (3,)``, it is called once per time (so a scalar-only function
    works, slowly).

    Examples
    --------
    >>> import numpy as np
    >>> from attitude.model.orbit import CallablePath
    >>> path = CallablePath(lambda t: np.stack([np.cos(t), np.sin(t), 0 * t], -1) * 7e6)
    >>> path.position(0.0)
    array([7000000.,       0.,       0.])
    """

    def __init__(self, function: Callable):
        if not callable(function):
            raise OrbitError(f"expected a callable t -> position, got "
                             f"{type(function).__name__}", key="position")
        self.function = function
        self._vectorised: bool | None = None

    def position(self, t) -> np.ndarray:
        t = np.asarray(t, dtype=float)
        if self._vectorised is not False:
            try:
                r = np.asarray(self.function(t), dtype=float)
                if r.shape == t.shape + (3,):
                    self._vectorised = True
                    return r
            except Exception:  # noqa: BLE001 - fall back to per-element calls
                if self._vectorised:
                    raise
            self._vectorised = False
        flat = t.ravel()
        r = np.array([np.asarray(self.function(float(x)), dtype=float) for x in flat])
        if r.shape != (flat.size, 3):
            raise OrbitError(f"the function must return 3 components per time, "
                             f"got shape {r.shape[1:]}", key="position")
        return r.reshape(t.shape + (3,))

    def __repr__(self) -> str:
        return f"CallablePath({getattr(self.function, '__name__', repr(self.function))})"


class ConstantPosition:
    """A fixed inertial position (m): a body hanging at rest relative to the primary
    (handy for tests and static analyses).

    Examples
    --------
    >>> from attitude.model.orbit import ConstantPosition
    >>> ConstantPosition([7e6, 0, 0]).position([0.0, 1.0]).shape
    (2, 3)
    """

    def __init__(self, position):
        r = np.asarray(_si(position, "m", "position"), dtype=float)
        if r.shape != (3,) or not np.all(np.isfinite(r)):
            raise OrbitError(f"expected 3 finite components, got {r!r}", key="position")
        self.vector = r

    def position(self, t) -> np.ndarray:
        t = np.asarray(t, dtype=float)
        return np.broadcast_to(self.vector, t.shape + (3,)).copy()

    def compiled_parameters(self, t_span=None) -> tuple[str, dict]:
        """``("fixed", {position})`` for a compiled kernel.

        Examples
        --------
        >>> from attitude.model.orbit import ConstantPosition
        >>> ConstantPosition([7e6, 0, 0]).compiled_parameters()
        ('fixed', {'position': array([7000000.,       0.,       0.])})
        """
        return ("fixed", {"position": self.vector.copy()})

    def __repr__(self) -> str:
        return f"ConstantPosition({self.vector.tolist()})"


def as_path(obj):
    """Return an object with ``position(t)``.

    Accepts an object that already has ``position(t)`` (:class:`KeplerOrbit`,
    :class:`TabulatedPath`, ...), a callable ``t -> position`` (wrapped in
    :class:`CallablePath`), or a fixed 3-vector (:class:`ConstantPosition`).

    Examples
    --------
    >>> from attitude.model.orbit import as_path
    >>> as_path([7e6, 0.0, 0.0])
    ConstantPosition([7000000.0, 0.0, 0.0])
    """
    if hasattr(obj, "position") and callable(obj.position):
        return obj
    if callable(obj):
        return CallablePath(obj)
    try:
        return ConstantPosition(obj)
    except (OrbitError, TypeError, ValueError):
        raise OrbitError(f"expected a KeplerOrbit, an object with position(t), a "
                         f"callable t -> position or a 3-vector, got "
                         f"{type(obj).__name__}", key="orbit") from None

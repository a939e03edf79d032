"""What a binary's ephemeris says: the mutual orbit's periods, the secondary's libration and
regime, both spins, and the period change across an impulse (the DART result).

Every measurement is read from the ephemeris of :func:`attitude.propagate` on a
:class:`~attitude.binary.system.BinarySystem` (``relative_position``,
``relative_velocity``, both bodies' quaternions and rates, the ``inertia`` of each body,
the attributes ``gravitational_constant`` and ``masses``):

- **orbit period** (sidereal): the angle of the separation ``R`` in the mutual orbit plane
  (normal: the mean direction of ``R x V``), unwrapped; the times it completes whole
  turns are interpolated (cubic Hermite, with the angle's rate ``(R x V).n / |R_p|^2``
  from the velocity), and the period is the time of the last whole turn over the number
  of turns.  Fewer than one turn: NaN.
- **osculating period**: Kepler's third law for the energy of the first sample,
  ``a = -mu / (2 E)``, ``E = |V|^2 / 2 - mu / |R|``, ``mu = G (m1 + m2)``; NaN if
  unbound.
- **eccentricity**: geometric, ``(r_max - r_min) / (r_max + r_min)`` of the samples
  (the osculating one of a circular orbit about an oblate primary is not small);
- **apsidal rate**: the advance of the periapsis (the minima of ``|R|``, refined on a
  parabola) per unit time, rad/s; NaN for a near-circular orbit (eccentricity below
  :data:`CIRCULAR_ECCENTRICITY`) or fewer than two passages.
- **libration angle** (:func:`libration_angle`): in the orbit plane, the angle from the
  direction to the primary (``-R``) to the secondary's long axis (the principal axis of
  its smallest moment), positive about the orbit normal, wrapped to (-90, 90] deg (the
  axis has two ends).  Unwrapped (modulo 180 deg, each step predicted from the rates) it
  *circulates* when it covers 180 deg or more.
- **libration amplitude**: half the peak-to-peak of the unwrapped angle, if it does not
  circulate; **libration period**: twice the mean spacing of the zero crossings of the
  angle minus its mean, over an even number of half cycles (NaN with fewer than two
  whole cycles).  After an impulse (DART) that period mixes two motions: the libration
  *forced* by the orbit's eccentricity, at the anomalistic orbital frequency, and the
  *free* libration the impulse excited, at the secondary's own frequency.
- **free libration** (:func:`free_libration`): the angle fitted by a constant and two
  sinusoids, the forced one (its frequency started from the strongest line of the
  separation ``|R|``: the anomalistic frequency) and the free one (started from the
  strongest line of the angle away from the forced one), both frequencies refined by
  least squares (the amplitudes solved linearly for each pair: variable projection).
  NaN with fewer than two free cycles, the two lines closer than the run resolves
  (``2 pi / span``), or a fit that leaves more than half the free line's amplitude
  (root mean square): no free line stands out.
- **secondary regime** (:func:`secondary_regime`), one of :data:`REGIMES`:

  * ``tumbling``: the secondary's body-frame angular velocity leaves the principal axis
    it is nearest to on average by more than :data:`TUMBLING_ANGLE` (30 deg): its
    polhode is not near a principal-axis spin;
  * ``circulating``: otherwise, if the libration angle circulates;
  * ``non-principal``: otherwise, if the angular velocity leaves that axis, or the axis
    of largest moment leaves the orbit normal (roll or pitch), by more than
    :data:`PRINCIPAL_ANGLE` (5 deg);
  * ``librating``: a principal-axis spin, locked, its long axis swinging about the
    direction to the primary.

  (Samples where ``|w|`` is below a tenth of its mean, a spin that stops and reverses in
  a large libration, are left out of the angle from the axis.)
- **spin periods**: ``2 pi / mean |w|`` of each body.

Given the times of impulses, :func:`diagnose` reads the orbit and the secondary after the
last one (the motion they left) and the conservation figures within each stretch between
them; :func:`period_change` measures the orbit period before and after a time (an
impulse).  The angles are unwrapped from sample to sample with the step each rate
predicts, so the output step may be long against the orbit, not against the change of the
rates (a tumble's): sample a tumbling secondary finely.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from attitude.binary.chaos import lyapunov_exponent
from attitude.binary.dynamics import matrix
from attitude.binary.propagate import is_binary_dataset
from attitude.binary.system import BinarySystem
from attitude.foundations.errors import BinarySystemError
from attitude.model.body import RigidBody
from attitude.model.ephemeris import Ephemeris

__all__ = ["BinaryDiagnosis", "PeriodChange", "FreeLibration", "diagnose", "free_libration",
           "libration_angle", "orbit_period",
           "osculating_period", "period_change", "secondary_regime", "REGIMES",
           "TUMBLING_ANGLE", "PRINCIPAL_ANGLE", "CIRCULAR_ECCENTRICITY"]

#: The secondary's regimes, from locked to tumbling.
REGIMES = ("librating", "non-principal", "circulating", "tumbling", "chaotic")
#: rad: the angular velocity farther than this from its principal axis is a tumble.
TUMBLING_ANGLE = math.radians(30.0)
#: rad: a locked secondary whose rate or largest-moment axis leaves its axis / the orbit
#: normal by more than this is in a non-principal (roll, pitch) libration.
PRINCIPAL_ANGLE = math.radians(5.0)
#: Eccentricity below which the apsidal rate is not measured.
CIRCULAR_ECCENTRICITY = 1e-3


@dataclass(frozen=True)
class BinaryDiagnosis:
    """The diagnosis of a binary's ephemeris (:func:`diagnose`); SI units.

    Attributes
    ----------
    orbit_period : float
        s, sidereal, measured from the separation vector (NaN: less than one turn).
    osculating_period : float
        s, Kepler's third law at the first sample (NaN: unbound).
    apsidal_rate : float
        rad/s, precession of the eccentricity vector (NaN: near-circular).
    eccentricity : float
        Geometric, from the extremes of the sampled separation.
    libration_amplitude : float
        rad, half the peak-to-peak of the libration angle (NaN: it circulates).
    libration_period : float
        s (NaN: fewer than two cycles).
    secondary_regime : str
        One of :data:`REGIMES`.
    primary_spin_period, secondary_spin_period : float
        s, ``2 pi / mean |w|``.
    max_spin_axis_angle, max_tilt : float
        rad: the secondary's rate from its principal axis, its largest-moment axis from
        the orbit normal (the regime's evidence).
    conservation : dict
        ``energy_rel_drift`` and ``angular_momentum_rel_drift``: the largest relative
        change of the total energy and angular momentum, within each stretch between
        impulses.
    lyapunov_exponent : float
        1/s, the finite-time Lyapunov exponent (``diagnose(..., chaos=True)``; NaN
        otherwise).
    lyapunov : BinaryLyapunov or None
        Its details (:func:`attitude.binary.chaos.lyapunov_exponent`).
    free_libration_period : float
        s, the free libration alone, the forced one fitted apart (:func:`free_libration`;
        NaN: it circulates, or too short a run to separate them).

    Examples
    --------
    >>> nan = float("nan")
    >>> b = BinaryDiagnosis(42917.0, 42950.0, nan, 0.0, 0.05, 48800.0, "librating",
    ...                     8136.0, 42917.0, 0.0, 0.0, {})
    >>> b.periods()["libration"], b.secondary_regime
    (48800.0, 'librating')
    """

    orbit_period: float
    osculating_period: float
    apsidal_rate: float
    eccentricity: float
    libration_amplitude: float
    libration_period: float
    secondary_regime: str
    primary_spin_period: float
    secondary_spin_period: float
    max_spin_axis_angle: float
    max_tilt: float
    conservation: dict
    lyapunov_exponent: float = math.nan
    lyapunov: object = None
    free_libration_period: float = math.nan

    def periods(self) -> dict:
        """The periods of the report: ``orbit``, ``osculating``, ``libration``,
        ``primary_spin``, ``secondary_spin`` (s)."""
        return {"orbit": self.orbit_period, "osculating": self.osculating_period,
                "libration": self.libration_period, "primary_spin": self.primary_spin_period,
                "secondary_spin": self.secondary_spin_period}


@dataclass(frozen=True)
class PeriodChange:
    """The orbit period before and after a time (:func:`period_change`), s.

    ``before``/``after`` are measured from the separation (sidereal),
    ``osculating_before``/``osculating_after`` from Kepler's third law at the last
    sample before and the first at or after the time; ``change = after - before``.

    Examples
    --------
    >>> c = PeriodChange(86400.0, 42917.0, 40937.0, 42950.0, 40970.0)
    >>> c.change / 60, c.osculating_change / 60          # min
    (-33.0, -33.0)
    """

    time: float
    before: float
    after: float
    osculating_before: float
    osculating_after: float

    @property
    def change(self) -> float:
        return self.after - self.before

    @property
    def osculating_change(self) -> float:
        return self.osculating_after - self.osculating_before


# --- reading the ephemeris -----------------------------------------------------------


def _binary_dataset(eph):
    ds = eph.dataset if isinstance(eph, Ephemeris) else eph
    if not is_binary_dataset(ds):
        raise BinarySystemError("ephemeris: not a binary system's ephemeris (it needs "
                                "relative_position and the attribute system = 'binary'; "
                                "propagate a BinarySystem)")
    return ds


def _mu(ds) -> float:
    G = float(ds.attrs["gravitational_constant"])
    return G * float(np.sum(np.asarray(ds.attrs["masses"], dtype=float)))


def _plane_normal(R: np.ndarray, V: np.ndarray) -> np.ndarray:
    h = np.cross(R, V)
    h = h / np.linalg.norm(h, axis=-1, keepdims=True)
    n = h.mean(axis=0)
    norm = np.linalg.norm(n)
    if not norm > 0:
        raise BinarySystemError("ephemeris: no orbit plane (the orbital angular momentum "
                                "averages to zero)")
    return n / norm


def _plane_basis(R: np.ndarray, n: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors spanning the plane normal to ``n``, the first along R[0]'s part."""
    e1 = R[0] - (R[0] @ n) * n
    if not np.linalg.norm(e1) > 1e-12 * np.linalg.norm(R[0]):
        e1 = np.cross(n, [1.0, 0.0, 0.0] if abs(n[0]) < 0.9 else [0.0, 1.0, 0.0])
    e1 = e1 / np.linalg.norm(e1)
    return e1, np.cross(n, e1)


def _in_plane_angle_and_rate(X, Xdot, n, e1, e2):
    """The angle of ``X`` (T, 3) projected on the plane, and its rate from ``Xdot``."""
    Xp = X - (X @ n)[:, None] * n
    Xdp = Xdot - (Xdot @ n)[:, None] * n
    angle = np.arctan2(Xp @ e2, Xp @ e1)
    rate = (np.cross(Xp, Xdp) @ n) / np.sum(Xp * Xp, axis=-1)
    return angle, rate


def _unwrap(angle, rate, t, period: float) -> np.ndarray:
    """Unwrap ``angle`` (modulo ``period``): each step is the one nearest the
    trapezoidal prediction from the rates."""
    if angle.size < 2:
        return angle.copy()
    predicted = 0.5 * (rate[1:] + rate[:-1]) * np.diff(t)
    step = np.diff(angle) - predicted
    step = step - period * np.round(step / period)
    return angle[0] + np.concatenate([[0.0], np.cumsum(step + predicted)])


def _whole_turn_period(theta, rate, t) -> float:
    """Time of the last whole turn over the number of turns (cubic Hermite in time)."""
    turns = math.floor(abs(theta[-1] - theta[0]) / (2 * math.pi))
    if turns < 1:
        return math.nan
    sign = 1.0 if theta[-1] > theta[0] else -1.0
    target = theta[0] + sign * 2 * math.pi * turns
    k = int(np.nonzero(sign * (theta - target) >= 0)[0][0])   # first sample past it
    if k == 0:
        return math.nan
    crossing = _hermite_root(t[k - 1], t[k], theta[k - 1] - target, theta[k] - target,
                             rate[k - 1], rate[k])
    return float((crossing - t[0]) / turns)


def _hermite_root(t0, t1, f0, f1, d0, d1) -> float:
    """The root in [t0, t1] of the cubic Hermite interpolant of f (values f0, f1 and
    derivatives d0, d1); bisection on the bracket (f0, f1 of opposite signs or zero)."""
    h = t1 - t0
    if f1 == 0:
        return t1

    def f(s):
        h00, h10 = 2 * s**3 - 3 * s**2 + 1, s**3 - 2 * s**2 + s
        h01, h11 = -2 * s**3 + 3 * s**2, s**3 - s**2
        return h00 * f0 + h10 * h * d0 + h01 * f1 + h11 * h * d1

    lo, hi = 0.0, 1.0
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if (f(mid) > 0) == (f1 > 0):
            hi = mid
        else:
            lo = mid
    return t0 + h * 0.5 * (lo + hi)


def _orbit_arrays(ds, sel=slice(None)):
    t = np.asarray(ds["time"].values, dtype=float)[sel]
    R = np.asarray(ds["relative_position"].values, dtype=float)[sel]
    V = np.asarray(ds["relative_velocity"].values, dtype=float)[sel]
    return t, R, V


def _sidereal_period(t, R, V) -> float:
    if t.size < 2:
        return math.nan
    n = _plane_normal(R, V)
    e1, e2 = _plane_basis(R, n)
    angle, rate = _in_plane_angle_and_rate(R, V, n, e1, e2)
    return _whole_turn_period(_unwrap(angle, rate, t, 2 * math.pi), rate, t)


def _kepler_period(R, V, mu) -> float:
    energy = 0.5 * float(V @ V) - mu / float(np.linalg.norm(R))
    if not energy < 0:
        return math.nan
    a = -mu / (2 * energy)
    return 2 * math.pi * math.sqrt(a**3 / mu)


# --- the public measurements ---------------------------------------------------------


def orbit_period(eph) -> float:
    """The mutual orbit's sidereal period measured from the separation vector, s (NaN
    with less than one whole turn).

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> ball = att.RigidBody.from_mass_properties(att.MassProperties.solid_sphere(1e9, 50.0))
    >>> system = att.BinarySystem(ball, ball)
    >>> v = np.sqrt(system.mu / 500.0)
    >>> P = 2 * np.pi * 500.0 / v
    >>> state = att.BinaryState("2026-12-01", [500.0, 0, 0], [0, v, 0], Rotation.identity(),
    ...                         [0, 0, 0], Rotation.identity(), [0, 0, 0])
    >>> eph = att.propagate(system, state, np.linspace(0.0, 1.5 * P, 61), rtol=1e-12)
    >>> bool(abs(orbit_period(eph) / P - 1) < 1e-9)
    True
    """
    ds = _binary_dataset(eph)
    return _sidereal_period(*_orbit_arrays(ds))


def osculating_period(eph, index: int = 0) -> float:
    """Kepler's period ``2 pi sqrt(a^3 / mu)`` of the relative state at sample ``index``,
    ``a = -mu / (2 E)``, ``mu = G (m1 + m2)``; s, NaN if unbound.

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> ball = att.RigidBody.from_mass_properties(att.MassProperties.solid_sphere(1e9, 50.0))
    >>> system = att.BinarySystem(ball, ball)
    >>> v = np.sqrt(system.mu / 500.0)
    >>> state = att.BinaryState("2026-12-01", [500.0, 0, 0], [0, v, 0], Rotation.identity(),
    ...                         [0, 0, 0], Rotation.identity(), [0, 0, 0])
    >>> eph = att.propagate(system, state, [0.0])
    >>> bool(np.isclose(osculating_period(eph), 2 * np.pi * 500.0 / v, rtol=1e-14))
    True
    """
    ds = _binary_dataset(eph)
    _, R, V = _orbit_arrays(ds)
    return _kepler_period(R[index], V[index], _mu(ds))


def libration_angle(eph) -> np.ndarray:
    """The secondary's libration angle over time, rad, wrapped to (-pi/2, pi/2].

    In the mutual orbit plane: the angle from the direction to the primary (``-R``) to the
    secondary's long axis (the principal axis of its smallest moment), positive about the
    orbit normal (the mean direction of ``R x V``).  Zero for a secondary locked with its
    long axis on the line of centres.

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> ellipsoid = att.MassProperties.solid_ellipsoid
    >>> system = att.BinarySystem(
    ...     att.RigidBody.from_mass_properties(ellipsoid(5.2e11, [400.0, 400.0, 400.0])),
    ...     att.RigidBody.from_mass_properties(ellipsoid(4.3e9, [103.0, 79.0, 66.0])))
    >>> n = np.sqrt(system.mu / 1190.0**3)
    >>> tilt = Rotation.from_euler("z", 10, degrees=True)   # long axis 10 deg ahead
    >>> state = att.BinaryState("2026-12-01", [1190.0, 0, 0], [0, n * 1190.0, 0],
    ...                         Rotation.identity(), [0, 0, 0], tilt, [0, 0, n])
    >>> eph = att.propagate(system, state, [0.0])
    >>> np.degrees(libration_angle(eph)).round(9).tolist()
    [10.0]
    """
    ds = _binary_dataset(eph)
    angle, _ = _libration(ds)
    return angle


def _secondary_axes(ds) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The secondary's principal axes (columns, body frame; A <= B <= C) and moments."""
    inertia = np.asarray(ds["inertia"].values[1], dtype=float).reshape(3, 3)
    moments, axes = np.linalg.eigh(inertia)
    return axes, moments, inertia


def _libration(ds):
    """The wrapped libration angle and its rate (rad, rad/s)."""
    t, R, V = _orbit_arrays(ds)
    n = _plane_normal(R, V)
    e1, e2 = _plane_basis(R, n)
    q2 = np.asarray(ds["quaternion"].values[1], dtype=float)
    w2 = np.asarray(ds["angular_velocity"].values[1], dtype=float)
    axes, _, _ = _secondary_axes(ds)
    A2 = matrix(q2)
    u = A2 @ axes[:, 0]                                  # long axis, inertial
    w_inertial = np.einsum("tij,tj->ti", A2, w2)
    angle_u, rate_u = _in_plane_angle_and_rate(u, np.cross(w_inertial, u), n, e1, e2)
    angle_r, rate_r = _in_plane_angle_and_rate(-R, -V, n, e1, e2)
    phi = angle_u - angle_r
    phi = math.pi / 2 - np.mod(math.pi / 2 - phi, math.pi)     # (-pi/2, pi/2]
    return phi, rate_u - rate_r


def _zero_crossing_period(t, x) -> float:
    """The period of ``x`` from its zero crossings after its mean is taken off (linear
    interpolation): twice the mean spacing over an even number of half cycles (a mean
    that is slightly off shifts up and down crossings oppositely, and cancels); NaN with
    fewer than two whole cycles."""
    x = x - x.mean()
    k = np.nonzero(((x[:-1] < 0) & (x[1:] >= 0)) | ((x[:-1] >= 0) & (x[1:] < 0)))[0]
    halves = (k.size - 1) // 2 * 2
    if halves < 4:
        return math.nan
    k = k[:halves + 1]
    tc = t[k] - x[k] * (t[k + 1] - t[k]) / (x[k + 1] - x[k])
    return float(2 * (tc[-1] - tc[0]) / halves)


@dataclass(frozen=True)
class FreeLibration:
    """The secondary's libration split into its free and forced parts
    (:func:`free_libration`).

    Attributes
    ----------
    period, amplitude : float
        The free libration's period (s) and amplitude (rad).
    forced_period, forced_amplitude : float
        The forced libration's (the anomalistic orbital period, s; rad).
    mean : float
        rad, the constant of the fit.
    residual : float
        rad, the root mean square of what the fit leaves.

    Examples
    --------
    >>> f = FreeLibration(55000.0, 0.02, 42900.0, 0.01, 0.0, 1e-5)
    >>> round(f.period / 3600, 2)
    15.28
    """

    period: float
    amplitude: float
    forced_period: float
    forced_amplitude: float
    mean: float
    residual: float


_NO_FREE_LIBRATION = FreeLibration(*[math.nan] * 6)


def _strongest_line(t, x, exclude=None, width=0.0) -> float:
    """Angular frequency of the strongest line of ``x(t)`` (uniform samples: the
    Hann-windowed FFT, padded eight times; its peak on a parabola), leaving out the
    frequencies within ``width`` of ``exclude``; NaN if none."""
    h = (t[-1] - t[0]) / (t.size - 1)
    size = 8 * t.size
    power = np.abs(np.fft.rfft((x - x.mean()) * np.hanning(t.size), size))
    omega = 2 * math.pi * np.fft.rfftfreq(size, h)
    power[0] = 0.0
    if exclude is not None:
        power[np.abs(omega - exclude) <= width] = 0.0
    k = int(np.argmax(power))
    if not power[k] > 0 or k == 0 or k == power.size - 1:
        return math.nan
    a, b, c = power[k - 1], power[k], power[k + 1]
    shift = 0.5 * (a - c) / (a - 2 * b + c) if a - 2 * b + c != 0 else 0.0
    return float(omega[k] + shift * (omega[1] - omega[0]))


def _two_lines(t, x, omegas):
    """The least-squares amplitudes of ``c + sum_k a_k cos(w_k t) + b_k sin(w_k t)`` and
    the residual, for the frequencies ``omegas``."""
    columns = [np.ones_like(t)]
    for w in omegas:
        columns += [np.cos(w * t), np.sin(w * t)]
    M = np.stack(columns, axis=1)
    c = np.linalg.lstsq(M, x, rcond=None)[0]
    return c, x - M @ c


def _free_libration(t, R, phi) -> FreeLibration:
    """:func:`free_libration` on arrays: the times, separations and unwrapped angle."""
    span = float(t[-1] - t[0]) if t.size else 0.0
    if t.size < 16 or not span > 0 or np.ptp(phi) >= math.pi:
        return _NO_FREE_LIBRATION
    tc = t - 0.5 * (t[0] + t[-1])
    if not np.allclose(np.diff(t), span / (t.size - 1), rtol=1e-6, atol=0.0):
        grid = np.linspace(t[0], t[-1], t.size)           # the lines' first guesses only
        x, r = np.interp(grid, t, phi), np.interp(grid, t, np.linalg.norm(R, axis=-1))
    else:
        grid, x, r = t, phi, np.linalg.norm(R, axis=-1)
    resolution = 2 * math.pi / span
    forced = _strongest_line(grid, r)
    free = _strongest_line(grid, x, exclude=forced, width=2 * resolution)
    if not (math.isfinite(forced) and math.isfinite(free)):
        return _NO_FREE_LIBRATION
    scale = np.array([forced, free])
    fit = least_squares(lambda u: _two_lines(tc, phi, u * scale)[1], np.ones(2),
                        x_scale=resolution / scale, method="lm")
    forced, free = fit.x * scale
    if free * span < 4 * math.pi or abs(free - forced) < resolution:
        return _NO_FREE_LIBRATION
    c, rest = _two_lines(tc, phi, (forced, free))
    if not np.sqrt(np.mean(rest**2)) < 0.5 * np.hypot(*c[3:5]):
        return _NO_FREE_LIBRATION
    return FreeLibration(period=2 * math.pi / abs(free), amplitude=float(np.hypot(*c[3:5])),
                         forced_period=2 * math.pi / abs(forced),
                         forced_amplitude=float(np.hypot(*c[1:3])), mean=float(c[0]),
                         residual=float(np.sqrt(np.mean(rest**2))))


def free_libration(eph, *, after: float | None = None) -> FreeLibration:
    """The secondary's free libration, its forced libration fitted apart: the period and
    amplitude of each (the rule of this module's documentation), over the samples at or
    after ``after`` (s since the epoch: an impulse, DART), all of them by default.

    The run must hold a few free cycles, and enough of them to tell the free frequency
    from the orbit's: ``span > 2 pi / |w_free - w_orbit|``; otherwise every field is NaN.

    Examples
    --------
    A Dimorphos-like ellipsoid locked to a spherical primary is kicked along its track,
    1 % of its speed: the orbit turns eccentric (a forced libration at its frequency)
    and the secondary swings at its own.

    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> ellipsoid = att.MassProperties.solid_ellipsoid
    >>> system = att.BinarySystem(
    ...     att.RigidBody.from_mass_properties(ellipsoid(5.2e11, [400.0, 400.0, 400.0])),
    ...     att.RigidBody.from_mass_properties(ellipsoid(4.3e9, [103.0, 79.0, 66.0])))
    >>> n = np.sqrt(system.mu / 1190.0**3)
    >>> state = att.BinaryState("2026-12-01", [1190.0, 0, 0], [0, n * 1190.0, 0],
    ...                         Rotation.identity(), [0, 0, 0], Rotation.identity(),
    ...                         [0, 0, n])
    >>> along = [-np.sin(n * 3600.0), np.cos(n * 3600.0), 0.0]     # the track an hour on
    >>> kick = att.Impulse(3600.0, body="secondary",
    ...                    delta_v=-0.01 * n * 1190.0 * np.array(along))
    >>> eph = att.propagate(system, state, np.arange(0.0, 12 * 2 * np.pi / n, 900.0),
    ...                     events=[kick])
    >>> f = free_libration(eph, after=3600.0)
    >>> A, B, C = system.secondary.principal_moments
    >>> float(round(f.period * n * np.sqrt(3 * (B - A) / C) / (2 * np.pi), 2))  # formula's
    1.01
    """
    ds = _binary_dataset(eph)
    if after is not None:
        t = np.asarray(ds["time"].values, dtype=float)
        ds = ds.isel(time=np.nonzero(t >= float(after))[0])
    t, R, V = _orbit_arrays(ds)
    if t.size < 16:
        return _NO_FREE_LIBRATION
    phi, rate = _libration(ds)
    return _free_libration(t, R, _unwrap(phi, rate, t, math.pi))


def _angle_from(v, axis) -> np.ndarray:
    """Angle of each vector ``v`` (T, 3) from the line of ``axis`` (3,), rad."""
    c = np.abs(v @ axis) / np.linalg.norm(v, axis=-1)
    return np.arccos(np.clip(c, 0.0, 1.0))


def secondary_regime(eph) -> str:
    """The secondary's regime (one of :data:`REGIMES`) by the rule of this module's
    documentation: ``tumbling``, ``circulating``, ``non-principal`` or ``librating``.

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> ellipsoid = att.MassProperties.solid_ellipsoid
    >>> system = att.BinarySystem(
    ...     att.RigidBody.from_mass_properties(ellipsoid(5.2e11, [400.0, 400.0, 400.0])),
    ...     att.RigidBody.from_mass_properties(ellipsoid(4.3e9, [103.0, 79.0, 66.0])))
    >>> n = np.sqrt(system.mu / 1190.0**3)
    >>> state = att.BinaryState("2026-12-01", [1190.0, 0, 0], [0, n * 1190.0, 0],
    ...                         Rotation.identity(), [0, 0, 0], Rotation.identity(),
    ...                         [0, 0, 5 * n])              # five times synchronous
    >>> eph = att.propagate(system, state, np.linspace(0.0, 2 * np.pi / n, 200))
    >>> secondary_regime(eph)
    'circulating'
    """
    return _regime(_binary_dataset(eph))[0]


def _regime(ds):
    t, R, V = _orbit_arrays(ds)
    phi, rate = _libration(ds)
    unwrapped = _unwrap(phi, rate, t, math.pi)
    circulates = bool(np.ptp(unwrapped) >= math.pi)
    axes, _, _ = _secondary_axes(ds)
    w2 = np.asarray(ds["angular_velocity"].values[1], dtype=float)
    speed = np.linalg.norm(w2, axis=-1)
    moving = speed > 0.1 * speed.mean() if speed.mean() > 0 else np.zeros(speed.shape, bool)
    if np.any(moving):
        share = np.mean((w2[moving] @ axes) ** 2, axis=0)     # of w^2 along each axis
        axis = axes[:, int(np.argmax(share))]
        spin_angle = float(_angle_from(w2[moving], axis).max())
    else:
        spin_angle = 0.0
    n = _plane_normal(R, V)
    c_axis = matrix(np.asarray(ds["quaternion"].values[1], dtype=float)) @ axes[:, 2]
    tilt = float(np.arccos(np.clip(c_axis @ n, -1.0, 1.0)).max())
    if spin_angle > TUMBLING_ANGLE:
        regime = "tumbling"
    elif circulates:
        regime = "circulating"
    elif spin_angle > PRINCIPAL_ANGLE or tilt > PRINCIPAL_ANGLE:
        regime = "non-principal"
    else:
        regime = "librating"
    return regime, unwrapped, circulates, spin_angle, tilt


def _eccentricity(R) -> float:
    """Geometric eccentricity ``(r_max - r_min) / (r_max + r_min)`` of the sampled
    separation."""
    r = np.linalg.norm(R, axis=-1)
    return float((r.max() - r.min()) / (r.max() + r.min()))


def _apsidal(t, R, V, period) -> float:
    """The apsidal rate, rad/s, from the periapsis passages: the minima of ``|R|`` (each
    the least within half an orbit, refined on a parabola through three samples) and the
    angle of ``R`` there, less a whole turn per passage; NaN for a near-circular orbit or
    fewer than two passages."""
    if _eccentricity(R) < CIRCULAR_ECCENTRICITY or t.size < 5 or not math.isfinite(period):
        return math.nan
    n = _plane_normal(R, V)
    e1, e2 = _plane_basis(R, n)
    angle, rate = _in_plane_angle_and_rate(R, V, n, e1, e2)
    theta = _unwrap(angle, rate, t, 2 * math.pi)
    r = np.linalg.norm(R, axis=-1)
    k = np.nonzero((r[1:-1] <= r[:-2]) & (r[1:-1] < r[2:]))[0] + 1
    k = [i for i in k if r[i] == r[np.abs(t - t[i]) <= period / 2].min()]
    if len(k) < 2:
        return math.nan
    k = np.array(k)
    curvature = r[k - 1] - 2 * r[k] + r[k + 1]
    d = 0.5 * (r[k - 1] - r[k + 1]) / curvature                  # in steps, |d| <= 1/2
    tp = t[k] + d * 0.5 * (t[k + 1] - t[k - 1])
    thp = theta[k] + d * (theta[k + 1] - theta[k - 1]) / 2 + d**2 * (
        theta[k + 1] - 2 * theta[k] + theta[k - 1]) / 2
    turn = 2 * math.pi * np.sign(theta[-1] - theta[0])
    advance = np.diff(thp) - turn
    return float(advance.sum() / (tp[-1] - tp[0]))


def _drifts(ds, breaks) -> dict:
    """Largest relative change of E and |L| within each stretch between ``breaks``."""
    t = np.asarray(ds["time"].values, dtype=float)
    E = np.asarray(ds["total_energy"].values, dtype=float)
    L = np.asarray(ds["total_angular_momentum"].values, dtype=float)
    edges = [-np.inf, *sorted(float(b) for b in breaks), np.inf]
    dE = dL = 0.0
    for lo, hi in zip(edges[:-1], edges[1:]):
        sel = (t >= lo) & (t < hi)
        if not np.any(sel):
            continue
        e, ell = E[sel], L[sel]
        dE = max(dE, float(np.abs(e - e[0]).max() / abs(e[0])))
        dL = max(dL, float(np.linalg.norm(ell - ell[0], axis=-1).max()
                           / np.linalg.norm(ell[0])))
    return {"energy_rel_drift": dE, "angular_momentum_rel_drift": dL}


def _spin_period(w) -> float:
    mean = float(np.linalg.norm(w, axis=-1).mean())
    return 2 * math.pi / mean if mean > 0 else math.inf


def _chaos(ds, system, intervals: int):
    """The Lyapunov exponent of the run in ``ds`` (from its first sample, with its
    method and step; the system rebuilt from the ephemeris at order 2)."""
    if system is None:
        if int(ds.attrs.get("mutual_potential_order", 0)) != 2:
            raise BinarySystemError("chaos: give system= (the ephemeris holds each body's "
                                    "mass and inertia, the whole system only at order 2)")
        masses = np.asarray(ds.attrs["masses"], dtype=float)
        inertia = np.asarray(ds["inertia"].values, dtype=float).reshape(2, 3, 3)
        system = BinarySystem(RigidBody(inertia[0], mass=masses[0]),
                              RigidBody(inertia[1], mass=masses[1]), order=2,
                              G=float(ds.attrs["gravitational_constant"]))
    t = np.asarray(ds["time"].values, dtype=float)
    R, V = ds["relative_position"].values[0], ds["relative_velocity"].values[0]
    q = np.asarray(ds["quaternion"].values[:, 0], dtype=float)
    w = np.asarray(ds["angular_velocity"].values[:, 0], dtype=float)
    y0 = np.concatenate([R, V, q[0], w[0], q[1], w[1]])
    method = str(ds.attrs.get("method", "lgvi"))
    return lyapunov_exponent(system, y0, t - t[0], intervals=intervals, method=method,
                             step=ds.attrs.get("step") if method == "lgvi" else None)


def diagnose(eph, *, impulses=(), chaos: bool = False, system=None,
             intervals: int = 64) -> BinaryDiagnosis:
    """Diagnose a binary's ephemeris: the mutual orbit's periods and apsidal rate, the
    secondary's libration and regime, both spins, the conservation figures.

    Parameters
    ----------
    eph : Ephemeris
        Of :func:`attitude.propagate` on a :class:`~attitude.binary.system.BinarySystem`.
    impulses : sequence of float
        Times (s since the epoch) of impulses in the run: the conservation figures are
        measured within each stretch between them, and the orbit and the secondary after
        the last one (the motion the impulses left; :func:`period_change` compares both
        sides).
    chaos : bool
        Measure the finite-time Lyapunov exponent (:mod:`attitude.binary.chaos`) from
        the first sample (after the last impulse) to the end, renormalised at
        ``intervals`` shares of the samples, with the run's method and step: it costs
        two more propagations of the system and two of its Keplerian control.  A chaotic
        exponent makes the regime ``chaotic``.
    system : BinarySystem, optional
        The run's system; needed by ``chaos`` beyond order 2 (at order 2 the ephemeris's
        masses and inertia are the whole system).
    intervals : int
        Renormalisations of ``chaos``.

    Returns
    -------
    BinaryDiagnosis

    Raises
    ------
    BinarySystemError
        Not a binary's ephemeris; ``chaos`` beyond order 2 without ``system``.

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> ellipsoid = att.MassProperties.solid_ellipsoid
    >>> system = att.BinarySystem(
    ...     att.RigidBody.from_mass_properties(ellipsoid(5.2e11, [400.0, 400.0, 400.0])),
    ...     att.RigidBody.from_mass_properties(ellipsoid(4.3e9, [103.0, 79.0, 66.0])))
    >>> n = np.sqrt(system.mu / 1190.0**3)
    >>> state = att.BinaryState("2026-12-01", [1190.0, 0, 0], [0, n * 1190.0, 0],
    ...                         Rotation.identity(), [0, 0, 2 * np.pi / 8136.0],
    ...                         Rotation.from_euler("z", 5, degrees=True), [0, 0, n])
    >>> b = att.binary.diagnose(att.propagate(system, state,
    ...                                       np.arange(0.0, 4 * 2 * np.pi / n, 600.0)))
    >>> b.secondary_regime, bool(4 < np.degrees(b.libration_amplitude) < 7)  # see below
    ('librating', True)
    >>> round(b.orbit_period / 3600, 2), round(b.primary_spin_period, 6)
    (12.06, 8136.0)

    The amplitude is not the 5 deg offset alone: the speed of a Keplerian circular orbit
    about the centres is not circular in the mutual potential, and the small
    eccentricity forces a libration near the free one.
    """
    ds = _binary_dataset(eph)
    mu = _mu(ds)
    _, R0, V0 = _orbit_arrays(ds, slice(0, 1))
    conservation = _drifts(ds, impulses)
    if len(impulses):                    # the motion the last impulse left
        t = np.asarray(ds["time"].values, dtype=float)
        after = np.nonzero(t >= max(float(s) for s in impulses))[0]
        if after.size >= 2:
            ds = ds.isel(time=after)
    t, R, V = _orbit_arrays(ds)
    regime, unwrapped, circulates, spin_angle, tilt = _regime(ds)
    period = _sidereal_period(t, R, V)
    w = np.asarray(ds["angular_velocity"].values, dtype=float)
    lyapunov = _chaos(ds, system, intervals) if chaos else None
    if lyapunov is not None and lyapunov.chaotic:
        regime = "chaotic"
    return BinaryDiagnosis(
        orbit_period=period,
        osculating_period=_kepler_period(R0[0], V0[0], mu),
        apsidal_rate=_apsidal(t, R, V, period),
        eccentricity=_eccentricity(R),
        libration_amplitude=math.nan if circulates else float(np.ptp(unwrapped) / 2),
        libration_period=math.nan if circulates else _zero_crossing_period(t, unwrapped),
        secondary_regime=regime,
        primary_spin_period=_spin_period(w[0]),
        secondary_spin_period=_spin_period(w[1]),
        max_spin_axis_angle=spin_angle,
        max_tilt=tilt,
        conservation=conservation,
        lyapunov_exponent=math.nan if lyapunov is None else lyapunov.exponent,
        lyapunov=lyapunov,
        free_libration_period=math.nan if circulates else _free_libration(
            t, R, unwrapped).period,
    )


def period_change(eph, time: float) -> PeriodChange:
    """The orbit period before and after ``time`` (s since the epoch: an impulse), each
    measured from the separation over the samples on its side (the sample at ``time``
    belongs to after), and Kepler's osculating periods on either side.

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> ball = att.RigidBody.from_mass_properties(att.MassProperties.solid_sphere(1e9, 50.0))
    >>> system = att.BinarySystem(ball, ball)
    >>> v = np.sqrt(system.mu / 500.0)
    >>> P = 2 * np.pi * 500.0 / v
    >>> state = att.BinaryState("2026-12-01", [500.0, 0, 0], [0, v, 0], Rotation.identity(),
    ...                         [0, 0, 0], Rotation.identity(), [0, 0, 0])
    >>> kick = att.Impulse(1.5 * P, body="secondary", delta_v=[0, 0.01 * v, 0])  # at -x: slower
    >>> eph = att.propagate(system, state, np.linspace(0.0, 3 * P, 241), events=[kick],
    ...                     rtol=1e-12)
    >>> change = period_change(eph, 1.5 * P)
    >>> bool(change.change < 0), bool(abs(change.change / change.osculating_change - 1) < 1e-6)
    (True, True)
    """
    ds = _binary_dataset(eph)
    t, R, V = _orbit_arrays(ds)
    mu = _mu(ds)
    time = float(time)
    before, after = t < time, t >= time
    if not np.any(before) or not np.any(after):
        raise BinarySystemError(f"time: {time:.6g} s is not inside the run "
                                f"({t[0]:.6g} .. {t[-1]:.6g} s)")
    kb, ka = int(np.nonzero(before)[0][-1]), int(np.nonzero(after)[0][0])
    return PeriodChange(time, _sidereal_period(*_orbit_arrays(ds, before)),
                        _sidereal_period(*_orbit_arrays(ds, after)),
                        _kepler_period(R[kb], V[kb], mu), _kepler_period(R[ka], V[ka], mu))

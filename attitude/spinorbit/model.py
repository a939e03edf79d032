r"""``SpinOrbit``: a rigid body on a Keplerian orbit about its primary.

The planar problem (spin axis, moment ``C``, along the orbit normal) is solved by
:mod:`attitude.spinorbit.planar`; the full 3-D problem by :func:`attitude.propagate` with
the gravity-gradient torque of :class:`attitude.model.torques.GravityGradient` on the same
:class:`~attitude.model.orbit.KeplerOrbit`.  The two meet in :meth:`SpinOrbit.initial_state`
(a planar state as a 3-D :class:`~attitude.AttitudeState`) and in
:meth:`SpinOrbit.stability`, which linearises the 3-D motion about the planar periodic
orbit of a p:q state (Wisdom, Peale & Mignard 1984, sec. IV: Hyperion's synchronous state
is attitude-unstable: a small tilt of the spin axis grows).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import xarray as xr
from astropy.time import Time
from scipy.spatial.transform import Rotation

from ..foundations.errors import SpinOrbitError
from ..model.body import RigidBody
from ..model.orbit import KeplerOrbit
from ..model.regimes import Thresholds
from ..model.state import AttitudeState
from ..model.torques import GravityGradient
from ..propagation.propagator import propagate
from .libration import forced_libration_amplitude, orbit_basis
from .planar import TWO_PI, advance, periodic_orbit, stroboscopic_map
from .resonances import Resonance, resonance_list
from .tides import despinning_time

__all__ = ["SpinOrbit", "Stability"]


@dataclass(frozen=True, eq=False)
class Stability:
    """Linear stability of a p:q periodic orbit, planar and in 3-D.

    Attributes
    ----------
    p, q : int
    angle, rate : float
        The planar periodic orbit at periapsis (rad; units of n).
    planar_multipliers : ndarray, shape (2,)
        Floquet multipliers of the in-plane motion (tangent equations).
    multipliers : ndarray, shape (6,)
        Floquet multipliers of the 3-D motion linearised about the planar orbit (finite
        differences of :func:`attitude.propagate` with the gravity gradient over ``q``
        orbits); the in-plane pair is among them.
    planar_stable, stable : bool
        ``max |multiplier| <= 1 + tolerance``.
    tolerance : float

    Examples
    --------
    >>> import attitude as att
    >>> so = SpinOrbit.from_omega0(0.89, att.KeplerOrbit(mu=1.0, a=1.0, e=0.1))
    >>> st = so.stability()                           # synchronous state of Hyperion
    >>> st.p, st.q, st.multipliers.shape
    (1, 1, (6,))
    >>> bool(abs(np.prod(st.planar_multipliers) - 1) < 1e-9)   # area-preserving map
    True
    """

    p: int
    q: int
    angle: float
    rate: float
    planar_multipliers: np.ndarray
    multipliers: np.ndarray
    planar_stable: bool
    stable: bool
    tolerance: float

    @property
    def growth_per_orbit(self) -> float:
        """``max |multiplier|^(1/q)``: the factor by which the fastest-growing
        perturbation grows per orbit."""
        return float(np.max(np.abs(self.multipliers)) ** (1.0 / self.q))


@dataclass(frozen=True, eq=False)
class SpinOrbit:
    """A rigid body on a Keplerian orbit about its primary: the spin-orbit problem.

    Parameters
    ----------
    body : RigidBody
        Principal moments ``A <= B <= C``; in the planar problem ``C`` is along the orbit
        normal and ``theta`` is the angle of the long axis (``A``) from periapsis.
    orbit : KeplerOrbit
        Orbit about the primary (its ``mu`` is the primary's gravitational parameter).

    Examples
    --------
    >>> import attitude as att
    >>> orbit = att.KeplerOrbit.from_elements(mu="4.2828e13 m3/s2", a="9376 km", e=0.0151)
    >>> phobos = att.SpinOrbit(att.RigidBody.from_principal_moments(
    ...     [0.3629, 0.4250, 0.4959]), orbit)
    >>> round(phobos.omega0, 4), round(math.degrees(phobos.forced_libration()), 3)
    (0.6129, 1.041)
    """

    body: RigidBody
    orbit: KeplerOrbit

    def __post_init__(self):
        if not isinstance(self.body, RigidBody):
            raise SpinOrbitError(f"expected a RigidBody, got {type(self.body).__name__}",
                                 key="body")
        orbit_basis(self.orbit)                       # checks it is a KeplerOrbit

    @classmethod
    def from_omega0(cls, omega0: float, orbit: KeplerOrbit, *, C: float = 1.0,
                    name: str = "") -> SpinOrbit:
        """A body with ``3 (B - A) / C = omega0^2`` (``A + B`` halfway between the
        triangle-inequality bound ``C`` and ``2 C - omega0^2 C / 3``).

        Examples
        --------
        >>> import attitude as att
        >>> o = att.KeplerOrbit(mu=3.7931e16, a=1.4811e9, e=0.1)
        >>> round(SpinOrbit.from_omega0(0.89, o).omega0, 12)
        0.89
        """
        w2 = float(omega0) ** 2
        if not 0 < w2 < 3:
            raise SpinOrbitError(f"must be in (0, sqrt(3)), got {omega0!r}", key="omega0")
        d = w2 / 3.0                                  # (B - A) / C
        A = 0.5 * ((1.0 - d) / 2.0 + (1.0 - d))       # between (1-d)/2 and 1-d
        return cls(RigidBody.from_principal_moments([A * C, (A + d) * C, C], name=name),
                   orbit)

    # --- parameters -----------------------------------------------------------------
    @property
    def omega0(self) -> float:
        """``sqrt(3 (B - A) / C)``: the small-libration frequency of the synchronous
        state on a circular orbit, in units of the mean motion."""
        A, B, C = self.body.principal_moments
        return math.sqrt(3.0 * (B - A) / C)

    @property
    def mean_motion(self) -> float:
        """``n``, rad/s."""
        return self.orbit.mean_motion

    @property
    def e(self) -> float:
        """Orbital eccentricity."""
        return self.orbit.e

    def torque(self) -> GravityGradient:
        """The gravity-gradient torque of the primary on this orbit."""
        return GravityGradient(self.orbit.mu, self.orbit)

    # --- resonances and libration ------------------------------------------------------
    def forced_libration(self) -> float:
        """Linear forced libration amplitude in longitude of the synchronous state, rad.

        ``|2 e omega0^2 / (omega0^2 - 1)|`` (:mod:`attitude.spinorbit.libration`); the
        libration is in antiphase with ``sin M`` when ``omega0 < 1``.
        """
        return abs(forced_libration_amplitude(self.omega0, self.e))

    def resonances(self, max_rate: float = 3.0) -> tuple[Resonance, ...]:
        """The p:q states up to ``max_rate`` with spin rate and half-width (units of n).

        Examples
        --------
        >>> import attitude as att
        >>> so = SpinOrbit.from_omega0(0.89, att.KeplerOrbit(mu=1.0, a=1.0, e=0.1))
        >>> [r.name for r in so.resonances()]
        ['1:2', '1:1', '3:2', '2:1', '5:2', '3:1']
        """
        return resonance_list(self.omega0, self.e, max_rate=max_rate)

    def despinning_time(self, *, spin_rate, primary_mass, mass, radius, **kwargs) -> float:
        """Tidal despinning time (s), :func:`attitude.spinorbit.despinning_time` with this
        orbit's semi-major axis and ``moment_factor = C / (m R^2)`` (at most 2/3).

        Examples
        --------
        >>> import attitude as att
        >>> so = SpinOrbit(att.RigidBody.from_principal_moments([4.6e23, 5.4e23, 6.4e23]),
        ...                att.KeplerOrbit(mu=4.282837e13, a=9.376e6, e=0.0151))
        >>> t = so.despinning_time(spin_rate="2 rev/d", primary_mass=6.417e23,
        ...                        mass=1.0659e16, radius=11100.0)
        >>> f"{t / 3.15576e7:.2g} yr"
        '2.3e+04 yr'
        """
        m = float(mass)
        kwargs.setdefault("moment_factor",
                          min(float(self.body.principal_moments[2]) / (m * float(radius)**2),
                              2.0 / 3.0))
        return despinning_time(spin_rate=spin_rate, semi_major_axis=self.orbit.a,
                               primary_mass=primary_mass, mass=m, radius=radius, **kwargs)

    # --- 3-D states -----------------------------------------------------------------
    def initial_state(self, angle: float = 0.0, rate: float = 1.0, *, tilt: float = 0.0,
                      epoch: Time | str = "2000-01-01T12:00:00", frame: str = "ICRF"
                      ) -> AttitudeState:
        """The 3-D state at the orbit's epoch (``t = 0``) for a planar angle and rate.

        Parameters
        ----------
        angle : float
            Angle of the long axis from the periapsis direction, rad.
        rate : float
            Spin rate about ``C`` in units of the mean motion.
        tilt : float
            Rotation of the body about its long axis, rad: tilts ``C`` away from the
            orbit normal (0 for the planar problem).
        epoch : Time or str
            Epoch of ``t = 0`` (TDB when a string).
        frame : str
            Inertial frame label of the orbit's elements.

        Examples
        --------
        >>> import attitude as att
        >>> so = SpinOrbit.from_omega0(0.5, att.KeplerOrbit(mu=1.0, a=1.0))
        >>> s = so.initial_state(0.0, 1.0)
        >>> s.omega_body.round(12).tolist()          # spin n about C (the body z axis)
        [0.0, 0.0, 1.0]
        """
        P, Q, W = orbit_basis(self.orbit)
        to_inertial = Rotation.from_matrix(np.stack([P, Q, W], axis=1))
        principal = to_inertial * Rotation.from_euler("zx", [angle, tilt])
        attitude = principal * self.body.body_to_principal
        w_principal = np.array([0.0, 0.0, float(rate) * self.mean_motion])
        omega = self.body.body_to_principal.inv().apply(w_principal)
        if not isinstance(epoch, Time):
            epoch = Time(epoch, scale="tdb")
        return AttitudeState(epoch, attitude, omega, frame)

    def locked_state(self, p: int = 1, q: int = 1, **kwargs) -> AttitudeState:
        """The periodic orbit of the p:q state (default synchronous, with its forced
        libration) as a 3-D state at the orbit's epoch (``t = 0``).

        Found in the planar problem (:func:`attitude.spinorbit.planar.periodic_orbit`)
        and advanced from periapsis to the epoch's mean anomaly.

        Examples
        --------
        >>> import attitude as att
        >>> so = SpinOrbit.from_omega0(0.6, att.KeplerOrbit(mu=1.0, a=1.0, e=0.01))
        >>> round(float(so.locked_state().omega_body[2]), 4)   # below n at periapsis
        0.9886
        """
        th, w, _ = periodic_orbit(self.omega0, self.e, p, q)
        M0 = math.fmod(self.orbit.mean_anomaly, TWO_PI * q)
        if M0 != 0.0:
            th, w = advance(self.omega0, self.e, th, w, 0.0, M0 % (TWO_PI * q))
        return self.initial_state(th, w, **kwargs)

    def propagate(self, times, state: AttitudeState | None = None, *, rtol: float = 1e-12,
                  **kwargs):
        """Propagate the 3-D motion under the gravity gradient (``att.propagate`` with
        ``method="integrator"``); default state: :meth:`locked_state`.

        Parameters
        ----------
        times : array-like
            Seconds since the orbit's epoch (or astropy Times).
        state : AttitudeState, optional
        rtol : float
            Relative tolerance of DOP853.

        Examples
        --------
        >>> import attitude as att
        >>> so = SpinOrbit.from_omega0(0.6, att.KeplerOrbit(mu=1.0, a=1.0, e=0.0))
        >>> eph = so.propagate([0.0, math.pi])                # half an orbit, locked
        >>> bool(abs(eph.rotation[-1].as_euler("zyx")[0]) > 3.14159)
        True
        """
        state = self.locked_state() if state is None else state
        return propagate(self.body, state, times, torques=[self.torque()],
                         method="integrator", rtol=rtol, **kwargs)

    def stability(self, p: int = 1, q: int = 1, *, delta: float = 1e-6,
                  rtol: float = 1e-12, tolerance: float = 1e-3) -> Stability:
        """Linear stability of the p:q state in the plane and in 3-D.

        The planar periodic orbit (Newton on the map over ``q`` orbits) gives the
        in-plane multipliers; the 3-D monodromy matrix is built by central differences
        (``delta`` in rad and in rate / n) of :func:`attitude.propagate` runs with the
        gravity gradient over ``q`` orbits, in the coordinates (rotation vector of the
        body-frame attitude error, body rates / n).  Unstable when a multiplier exceeds
        ``1 + tolerance`` in modulus (Wisdom, Peale & Mignard 1984 for Hyperion).

        Raises
        ------
        SpinOrbitError
            When the periodic orbit is not found.

        Examples
        --------
        >>> import attitude as att
        >>> so = SpinOrbit.from_omega0(0.89, att.KeplerOrbit(mu=1.0, a=1.0, e=0.1))
        >>> st = so.stability()                         # Hyperion (WPM 1984)
        >>> st.planar_stable, st.stable
        (True, False)
        """
        if self.orbit.mean_anomaly != 0.0:
            orbit = KeplerOrbit(mu=self.orbit.mu, a=self.orbit.a, e=self.orbit.e,
                                i=self.orbit.i, raan=self.orbit.raan, argp=self.orbit.argp)
            return SpinOrbit(self.body, orbit).stability(p, q, delta=delta, rtol=rtol,
                                                         tolerance=tolerance)
        th, w, mono = periodic_orbit(self.omega0, self.e, p, q)
        planar = np.linalg.eigvals(mono)
        ref = self.initial_state(th, w)
        n = self.mean_motion
        R0 = ref.attitude
        w0 = np.asarray(ref.omega_body, dtype=float)
        states = [ref]
        for sign in (1.0, -1.0):
            for j in range(6):
                dx = np.zeros(6)
                dx[j] = sign * delta
                states.append(AttitudeState(ref.epoch, R0 * Rotation.from_rotvec(dx[:3]),
                                            w0 + dx[3:] * n, ref.frame))
        span = TWO_PI * q / n
        eph = propagate([self.body] * len(states), states, [0.0, span],
                        torques=[self.torque()], method="integrator", rtol=rtol)
        Qf = eph.dataset["quaternion"].values[:, -1]
        Wf = eph.dataset["angular_velocity"].values[:, -1]
        Rref = Rotation.from_quat(Qf[0])
        cols = []
        for k in range(len(states) - 1):
            dr = (Rref.inv() * Rotation.from_quat(Qf[k + 1])).as_rotvec()
            cols.append(np.concatenate([dr, (Wf[k + 1] - Wf[0]) / n]))
        cols = np.array(cols)
        jac = (cols[:6] - cols[6:]).T / (2.0 * delta)
        mult = np.linalg.eigvals(jac)
        mult = mult[np.argsort(-np.abs(mult))]
        return Stability(p=p, q=q, angle=th, rate=w, planar_multipliers=planar,
                         multipliers=mult,
                         planar_stable=bool(np.max(np.abs(planar)) <= 1 + tolerance),
                         stable=bool(np.max(np.abs(mult)) <= 1 + tolerance),
                         tolerance=float(tolerance))

    # --- surfaces of section ------------------------------------------------------------
    def surface_of_section(self, angles, rates, n_orbits: int = 200, *,
                           lyapunov: bool = True, rtol: float = 1e-9,
                           thresholds: Thresholds | None = None, seed: int = 0
                           ) -> xr.Dataset:
        """The stroboscopic map at periapsis for many initial conditions in one batch.

        Each initial condition (angle of the long axis from the periapsis direction,
        spin rate / mean motion, at a periapsis passage) is followed for ``n_orbits``
        orbits of the planar problem, and classified regular or chaotic by the test of
        :func:`attitude.analysis.lyapunov.lyapunov_exponent`: the finite-time Lyapunov exponent
        (Benettin et al. 1980, tangent vector renormalised at each periapsis, metric
        ``(delta theta, delta rate / n)``) is compared with that of a regular control,
        the same initial condition on a circular orbit (an integrable pendulum), and the
        trajectory is chaotic when ``(lambda - lambda_control) * duration >=
        thresholds.lyapunov_efolds`` and ``lambda > thresholds.lyapunov_ratio *
        lambda_control``.

        Parameters
        ----------
        angles : array-like, shape (N,)
            rad.
        rates : array-like, shape (N,)
            Spin rate / mean motion.
        n_orbits : int
        lyapunov : bool
            Compute the exponents and the verdicts (twice the work without).
        rtol : float
            Tolerance of the DOP853 integration.
        thresholds : Thresholds, optional
        seed : int
            Seed of the tangent directions.

        Returns
        -------
        xarray.Dataset
            dims ``(initial, orbit)``: ``angle`` (rad, in ``[-pi/2, pi/2)``), ``rate``
            (spin rate / n) at each periapsis (orbit 0 is the initial condition);
            ``chaotic`` (initial,) bool, ``lyapunov_exponent`` and
            ``control_exponent`` (1/s), ``excess_efolds``.

        Examples
        --------
        >>> import attitude as att
        >>> so = SpinOrbit.from_omega0(0.89, att.KeplerOrbit(mu=1.0, a=1.0, e=0.1))
        >>> sec = so.surface_of_section([1.5, 0.0], [1.0, 3.2], n_orbits=60)
        >>> sec["chaotic"].values.tolist()            # chaotic sea, regular rotation
        [True, False]
        """
        th = thresholds or Thresholds()
        out = stroboscopic_map(self.omega0, self.e, angles, rates, n_orbits,
                               lyapunov=lyapunov, control=lyapunov, rtol=rtol, seed=seed)
        n = self.mean_motion
        N = out["angle"].shape[0]
        ds = xr.Dataset(
            {"angle": (("initial", "orbit"), out["angle"],
                       {"units": "rad", "long_name": "angle of the long axis from the "
                        "periapsis direction at periapsis, reduced to [-pi/2, pi/2)"}),
             "rate": (("initial", "orbit"), out["rate"],
                      {"units": "1", "long_name": "spin rate / mean motion at periapsis"})},
            coords={"initial": np.arange(N), "orbit": np.arange(out["angle"].shape[1]),
                    "initial_angle": ("initial", out["angle"][:, 0], {"units": "rad"}),
                    "initial_rate": ("initial", out["rate"][:, 0], {"units": "1"})},
            attrs={"title": "spin-orbit surface of section (stroboscopic map at periapsis)",
                   "omega0": self.omega0, "eccentricity": self.e,
                   "mean_motion_rad_s": n, "n_orbits": int(n_orbits),
                   "convention": "planar problem: C along the orbit normal, angle of the "
                                 "A axis from periapsis (Wisdom, Peale & Mignard 1984)"})
        if lyapunov:
            duration = TWO_PI * int(n_orbits)            # in units of 1/n
            lam = out["log_growth"].sum(axis=1) / duration
            lam_c = out["control_log_growth"].sum(axis=1) / duration
            excess = (lam - lam_c) * duration
            chaotic = (excess >= th.lyapunov_efolds) & (
                lam > th.lyapunov_ratio * np.maximum(lam_c, 0.0))
            ds["chaotic"] = ("initial", chaotic.astype(bool),
                             {"long_name": "chaotic by the finite-time Lyapunov test"})
            ds["lyapunov_exponent"] = ("initial", lam * n, {"units": "1/s"})
            ds["control_exponent"] = ("initial", lam_c * n, {"units": "1/s",
                                      "long_name": "same initial condition, e = 0"})
            ds["excess_efolds"] = ("initial", excess, {"units": "1"})
            ds.attrs["lyapunov_efolds"] = th.lyapunov_efolds
            ds.attrs["lyapunov_ratio"] = th.lyapunov_ratio
        return ds

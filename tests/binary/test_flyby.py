"""A close encounter (docs/binary.md): Apophis past the Earth, against independent physics.

The Earth is a homogeneous sphere (it feels no torque and gives none beyond a point
mass's), Apophis a uniform ellipsoid with Pravec et al.'s (2014) moment ratios on the
2029 hyperbola (perigee 38,000 km, v_inf 5.84 km/s).  The references are computed here
without the package: the hyperbolic Kepler equation ``e sinh H - H = n t``, the
conserved energy ``v_inf^2 / 2`` and angular momentum ``r_p v_p`` of the hyperbola, its
deflection ``2 arcsin(1/e)``, and the closed-form integral of ``1/r^3`` along it (with
``dt = r^2 / h dnu``: ``(nu + e sin nu) / (h p)``), which bounds the tidal torque's
effect.  The Earth does not spin here: its spin angular momentum (7e33 kg m^2/s) would
round the orbit's (1.5e22) and Apophis's (4e10) away in the total.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import simpson
from scipy.optimize import brentq
from scipy.spatial.transform import Rotation

import attitude as att
from attitude.binary.integrals import rotated
from tests.tolerances import EPS

EARTH = att.RigidBody.from_mass_properties(
    att.MassProperties.solid_sphere(mass=5.972e24, radius=6371e3), name="Earth")
#: Apophis: the uniform ellipsoid with A/C = 0.61, B/C = 0.965 (Pravec et al. 2014) at a
#: volume-equivalent radius of 170 m (Brozovic et al. 2018), 2.6 g/cm^3 (assumed).
RADIUS = 170.0
MASS = 2600.0 * 4 / 3 * np.pi * RADIUS**3
_B2 = (1 - (0.965 - 0.61)) / (1 + (0.965 - 0.61))
_SHAPE = np.sqrt([1.0, _B2, 0.965 * (1 + _B2) - 1])
SEMI_AXES = RADIUS * _SHAPE / np.prod(_SHAPE) ** (1 / 3)
APOPHIS = att.RigidBody.from_mass_properties(
    att.MassProperties.solid_ellipsoid(MASS, SEMI_AXES), name="Apophis")
BALL = att.RigidBody.from_mass_properties(
    att.MassProperties.solid_sphere(MASS, RADIUS), name="spherical Apophis")
#: scenarios/apophis.toml's state: P_phi 27.38 h, P_psi 264.6 h (SAM).
ATTITUDE = Rotation.from_euler("ZXZ", [250.0, 165.0, 0.0], degrees=True)
OMEGA = np.radians([3.69358032, 0.0, 11.40856022]) / 3600.0
R_PERIGEE, V_INF = 38_000e3, 5.84e3
SPAN = 6 * 3600.0                     # s either side of perigee
TIMES = np.linspace(0.0, 2 * SPAN, 145)   # every 5 min
RTOL = 1e-10


class Hyperbola:
    """The Kepler hyperbola with perigee on +x and the orbit normal along +z."""

    def __init__(self, gm: float, r_p: float, v_inf: float):
        self.gm = gm
        self.a = -gm / v_inf**2
        self.e = 1 - r_p / self.a
        self.n = np.sqrt(gm / -self.a**3)
        self.h = np.sqrt(gm * self.a * (1 - self.e**2))        # r_p v_p
        self.p = self.h**2 / gm

    def state(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """Position and velocity ``t`` seconds after perigee."""
        a, e, n = self.a, self.e, self.n
        H = brentq(lambda H: e * np.sinh(H) - H - n * t, -60.0, 60.0, xtol=1e-15,
                   rtol=4 * EPS)
        H_dot = n / (e * np.cosh(H) - 1)
        k = -a * np.sqrt(e**2 - 1)
        return (np.array([a * (np.cosh(H) - e), k * np.sinh(H), 0.0]),
                np.array([a * np.sinh(H) * H_dot, k * np.cosh(H) * H_dot, 0.0]))

    def true_anomaly(self, position: np.ndarray) -> np.ndarray:
        return np.arctan2(position[..., 1], position[..., 0])

    def inverse_cube_integral(self, nu1: float, nu2: float) -> float:
        """``integral dt / r^3`` from true anomaly ``nu1`` to ``nu2``, s/m^3."""
        F = lambda nu: (nu + self.e * np.sin(nu)) / (self.h * self.p)   # noqa: E731
        return F(nu2) - F(nu1)


def flyby(secondary: att.RigidBody, *, order: int = 2):
    system = att.BinarySystem(EARTH, secondary, order=order)
    orbit = Hyperbola(system.mu, R_PERIGEE, V_INF)
    position, velocity = orbit.state(-SPAN)
    state = att.BinaryState("2029-04-13T15:46:00", position, velocity,
                            Rotation.identity(), [0.0, 0.0, 0.0], ATTITUDE, OMEGA,
                            frame="ECLIPJ2000")
    eph = att.propagate(system, state, TIMES, method="integrator", rtol=RTOL)
    return system, orbit, eph.dataset


@pytest.fixture(scope="module")
def ball_flyby():
    return flyby(BALL)


@pytest.fixture(scope="module")
def apophis_flyby():
    return flyby(APOPHIS)


def spin_momentum(ds, body: att.RigidBody, index: int = 1) -> np.ndarray:
    """``(time, 3)``: a body's spin angular momentum, inertial frame."""
    w = ds.angular_velocity.values[index]
    return Rotation.from_quat(ds.quaternion.values[index]).apply(w @ body.inertia.T)


def test_a_sphere_feels_no_torque(ball_flyby):
    """Apophis as a sphere: the tide has nothing to grip.  The torque on it is the
    round-off of its rotated isotropic integrals, a few ulp of ``G M T / r^3``: over the
    flyby ``|d omega| <~ eps G M int dt / r^3 ~ eps |omega|``.  Each DOP853 step rounds
    omega at most once more (half an ulp) when that increment is added; the run takes
    about 50 steps (600 evaluations), so 64 ulp of |omega| bound the change."""
    system, orbit, ds = ball_flyby
    w = ds.angular_velocity.values[1]
    assert np.abs(w - OMEGA).max() <= 64 * EPS * np.linalg.norm(OMEGA)
    assert np.abs(ds.angular_velocity.values[0]).max() <= 64 * EPS * np.linalg.norm(OMEGA)
    # and it turns about its fixed rate vector: q(t) = q0 * exp(omega t / 2)
    expected = ATTITUDE * Rotation.from_rotvec(TIMES[:, None] * OMEGA)
    turned = Rotation.from_quat(ds.quaternion.values[1])
    # DOP853 keeps each step's local error below rtol; the rotation over 12 h is 2.6 rad
    # in about 50 steps, so the global error stays below 1e3 rtol
    assert (turned.inv() * expected).magnitude().max() < 1e3 * RTOL


def test_a_sphere_follows_the_kepler_hyperbola(ball_flyby):
    """Two spheres attract as point masses: the relative orbit is the hyperbola, to the
    integrator's error.  DOP853 at rtol 1e-10 keeps the local relative error of R and V
    below rtol per step; the global error of a non-chaotic two-body run grows at most
    linearly with the steps (about 50), so 1e3 rtol relative bounds it."""
    system, orbit, ds = ball_flyby
    R = ds.relative_position.values
    V = ds.relative_velocity.values
    reference = [orbit.state(t - SPAN) for t in TIMES]
    R_ref = np.array([r for r, _ in reference])
    V_ref = np.array([v for _, v in reference])
    assert np.linalg.norm(R - R_ref, axis=1).max() < 1e3 * RTOL * np.linalg.norm(R, axis=1).max()
    assert np.linalg.norm(V - V_ref, axis=1).max() < 1e3 * RTOL * np.linalg.norm(V, axis=1).max()
    # its conserved quantities: energy v_inf^2 / 2 and angular momentum r_p v_p
    energy = 0.5 * np.sum(V * V, axis=1) - system.mu / np.linalg.norm(R, axis=1)
    h = np.cross(R, V)
    assert np.abs(energy / (0.5 * V_INF**2) - 1).max() < 1e3 * RTOL
    assert np.abs(h[:, 2] / orbit.h - 1).max() < 1e3 * RTOL
    assert np.abs(h[:, :2]).max() < 1e3 * RTOL * orbit.h
    # perigee is where and when it should be
    r = np.linalg.norm(R, axis=1)
    assert np.argmin(r) == TIMES.size // 2
    assert abs(r.min() / R_PERIGEE - 1) < 1e3 * RTOL


def test_the_deflection_is_two_arcsin_one_over_e(ball_flyby):
    """The asymptotes of the osculating hyperbola at the first sample (incoming) and at
    the last (outgoing) make the angle ``2 arcsin(1/e)``: from the eccentricity vector
    ``e_vec`` and the normal, the asymptotic velocity directions are
    ``-sin(nu) e_hat + (e + cos nu) q_hat`` at ``nu = -+arccos(-1/e)``, and their angle
    has ``cos(delta) = 1 - 2/e^2``."""
    system, orbit, ds = ball_flyby
    R = ds.relative_position.values
    V = ds.relative_velocity.values

    def asymptote(i, sign):
        r, v = R[i], V[i]
        h = np.cross(r, v)
        e_vec = np.cross(v, h) / system.mu - r / np.linalg.norm(r)
        e = np.linalg.norm(e_vec)
        e_hat, q_hat = e_vec / e, np.cross(h, e_vec) / np.linalg.norm(np.cross(h, e_vec))
        nu = sign * np.arccos(-1 / e)                  # the asymptotic true anomaly
        d = -np.sin(nu) * e_hat + (e + np.cos(nu)) * q_hat
        return d / np.linalg.norm(d), e

    incoming, e_in = asymptote(0, -1)
    outgoing, e_out = asymptote(-1, +1)
    deflection = np.arccos(np.clip(incoming @ outgoing, -1, 1))
    expected = 2 * np.arcsin(1 / orbit.e)
    assert abs(e_in / orbit.e - 1) < 1e3 * RTOL and abs(e_out / orbit.e - 1) < 1e3 * RTOL
    assert abs(deflection - expected) < 1e3 * RTOL
    assert abs(np.degrees(expected) - 27.2) < 0.05     # the 2029 geometry: 27.2 deg


def test_the_spin_takes_what_the_orbit_gives(apophis_flyby):
    """The tide's torque on Apophis is ``-R x F``: what its spin angular momentum gains
    the orbit loses.  The orbit's angular momentum (1.5e22 kg m^2/s) is 3e11 times the
    spin's change, so its difference between two samples is lost in the integrator's
    error; its change is integrated instead, ``int R x F dt`` (Simpson's rule on the
    samples, its error estimated by halving the samples), and it equals minus the
    spin's change taken from the ephemeris."""
    system, orbit, ds = apophis_flyby
    H = spin_momentum(ds, APOPHIS)
    dH = H[-1] - H[0]
    R = ds.relative_position.values
    A1, A2 = (Rotation.from_quat(q).as_matrix() for q in ds.quaternion.values)
    T1, T2 = system.integrals
    f = system.gravity.forces(R, rotated(T1, A1), rotated(T2, A2))
    # the torque identity, pointwise: tau1 + tau2 + R x F = 0 (tau1 = 0 on the sphere)
    RxF = np.cross(R, f.force)
    scale = np.linalg.norm(R, axis=1)[:, None] * np.linalg.norm(f.force, axis=1)[:, None]
    assert np.abs(f.torque_secondary + RxF).max() <= 64 * EPS * scale.max()
    orbit_change = simpson(RxF, x=TIMES, axis=0)
    coarse = simpson(RxF[::2], x=TIMES[::2], axis=0)
    quadrature = np.linalg.norm(orbit_change - coarse)
    # the spin's change from the ephemeris carries the integrator's error: its local
    # relative error per step is below rtol of |H|, over about 50 steps 1e3 rtol |H|
    tolerance = 16 * quadrature + 1e3 * RTOL * np.linalg.norm(H[0])
    assert np.linalg.norm(dH + orbit_change) <= tolerance
    assert tolerance < 1e-3 * np.linalg.norm(dH)       # the test can tell a real change


def test_the_spin_change_is_of_the_order_of_the_tide(apophis_flyby):
    """The gravity-gradient torque of a point mass on a body with moments A <= B <= C is
    at most ``(3/2) G M (C - A) / r^3``, so the spin angular momentum changes by at most
    ``(3/2) G M (C - A) int dt / r^3`` (integrated in closed form along the hyperbola).
    A rigorous upper bound; and the change is of that order (above 1 % of it: a loose,
    order-of-magnitude lower bound; the exact fraction depends on the attitude at
    perigee, 13 % here)."""
    system, orbit, ds = apophis_flyby
    H = spin_momentum(ds, APOPHIS)
    A, B, C = APOPHIS.principal_moments
    R = ds.relative_position.values
    nu = orbit.true_anomaly(R[[0, -1]])
    bound = 1.5 * system.G * EARTH.mass * (C - A) * orbit.inverse_cube_integral(*nu)
    dH = np.linalg.norm(H[-1] - H[0])
    assert 0.01 * bound < dH <= bound
    # the spin rate changes accordingly: | |H| - |H0| | <= |dH|, and it did change
    d_spin = abs(np.linalg.norm(H[-1]) - np.linalg.norm(H[0]))
    assert d_spin <= dH * (1 + 1e3 * RTOL)
    assert d_spin > 1e3 * RTOL * np.linalg.norm(H[0])


def test_angular_momentum_is_exchanged_in_a_close_pair():
    """A pair whose spin and orbit hold comparable angular momentum (a 300 x 150 x 120 m
    ellipsoid passing 1.2 km from a 1e12 kg sphere at 5 cm/s): the change of the spin
    angular momentum equals minus the change of the orbital one, each read from the
    ephemeris, and the total is conserved to the integrator's bound.  The mutual
    potential (order 2 here) conserves the total exactly at any order (each degree is
    invariant under a rotation of the whole system); DOP853 keeps each step's local
    error below rtol of the state, so the drift of the total stays below 1e3 rtol |L|
    over the run's few hundred steps."""
    primary = att.RigidBody.from_mass_properties(att.MassProperties.solid_sphere(1e12, 500.0))
    secondary = att.RigidBody.from_mass_properties(att.MassProperties.solid_ellipsoid(
        2000.0 * 4 / 3 * np.pi * 300 * 150 * 120, [300.0, 150.0, 120.0]))
    system = att.BinarySystem(primary, secondary, order=2)
    orbit = Hyperbola(system.mu, 1200.0, 0.05)
    span = 3 * 3600.0
    rtol = 1e-11
    position, velocity = orbit.state(-span)
    state = att.BinaryState("2030-01-01", position, velocity, Rotation.identity(),
                            [0.0, 0.0, 1e-4], ATTITUDE, [2e-4, 1e-4, 4e-4])
    times = np.linspace(0.0, 2 * span, 49)
    ds = att.propagate(system, state, times, method="integrator", rtol=rtol).dataset
    L_orbit = system.reduced_mass * np.cross(ds.relative_position.values,
                                             ds.relative_velocity.values)
    H = spin_momentum(ds, secondary)
    H_primary = spin_momentum(ds, primary, index=0)
    L = ds.total_angular_momentum.values
    bound = 1e3 * rtol * np.linalg.norm(L[0])
    assert np.linalg.norm(L - L[0], axis=1).max() <= bound
    assert np.abs(H_primary - H_primary[0]).max() <= bound    # the sphere's spin stays
    dH, dL = H[-1] - H[0], L_orbit[-1] - L_orbit[0]
    assert np.linalg.norm(dH + dL) <= 2 * bound
    assert np.linalg.norm(dH) > 0.1 * np.linalg.norm(H[0])   # a real exchange


def test_a_body_at_rest_under_round_off_torques_does_not_stall_dop853():
    """A sphere primary at rest feels only round-off torques: its rate tolerance is on
    the system's scale (the Keplerian rate), so DOP853 runs (it stopped with 'step size
    less than spacing' when the tolerance was 1e-12 of a zero rate)."""
    ball = att.RigidBody.from_mass_properties(att.MassProperties.solid_sphere(1e12, 300.0))
    egg = att.RigidBody.from_mass_properties(
        att.MassProperties.solid_ellipsoid(4e9, [100.0, 80.0, 60.0]))
    system = att.BinarySystem(ball, egg)
    n = np.sqrt(system.mu / 1500.0**3)
    state = att.BinaryState("2026-12-01", [1500.0, 0, 0], [0, n * 1500.0, 0],
                            Rotation.identity(), [0, 0, 0], Rotation.identity(),
                            [0, 0, 1.3 * n])
    eph = att.propagate(system, state, np.linspace(0.0, 20000.0, 5), method="integrator",
                        rtol=1e-11)
    w1 = eph.dataset.angular_velocity.values[0]
    # a sphere feels no torque: its rate stays at round-off of the torque scale
    assert np.abs(w1).max() < 1e-12 * n

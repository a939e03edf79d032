"""Tests of attitude.orbit: Kepler's equation and Keplerian positions against closed forms
(vis-viva, apsides, Kepler's third law, conservation of energy and angular momentum), a
published example (Vallado 2013, Example 2-1), and the user-supplied paths."""

from __future__ import annotations

import astropy.units as u
import numpy as np
import pytest

from attitude.model.orbit import (
    CallablePath,
    ConstantPosition,
    KeplerOrbit,
    OrbitError,
    TabulatedPath,
    as_path,
    mean_from_eccentric,
    solve_kepler,
)

MU_EARTH = 3.986004418e14
EPS = np.finfo(float).eps


def test_vallado_example_2_1():
    """Vallado (2013), Example 2-1: M = 235.4 deg, e = 0.4 -> E = 220.512 074 767 522 deg."""
    E = solve_kepler(np.radians(235.4), 0.4)
    assert np.degrees(E) == pytest.approx(220.512074767522, abs=1e-11)
    assert isinstance(E, float)


def test_kepler_round_trip_random_eccentricities():
    """E -> M -> E for 2e5 random (E, e), e in [0, 0.99): the forward error is bounded by
    a few ulps times the condition number dE/dM = 1/(1 - e cos E)."""
    rng = np.random.default_rng(20240601)
    n = 200_000
    e = rng.uniform(0.0, 0.99, n)
    E = rng.uniform(-np.pi, np.pi, n)
    E[:2000] *= 1e-6                       # near periapsis, the ill-conditioned corner
    M = mean_from_eccentric(E, e)
    E2 = solve_kepler(M, e)
    bound = 8 * EPS * (np.abs(E) + 1.0) / (1.0 - e * np.cos(E))
    assert np.all(np.abs(E2 - E) <= bound)
    # the scalar path gives the same answers
    for k in range(0, n, 20_000):
        assert solve_kepler(float(M[k]), float(e[k])) == pytest.approx(E2[k], abs=4 * EPS)


def test_kepler_converges_in_four_iterations():
    """The starting values (Danby's, or the cubic near periapsis) put Halley's iteration in
    its cubic regime at once: four iterations give the converged answer everywhere."""
    rng = np.random.default_rng(8)
    M = np.concatenate([rng.uniform(-np.pi, np.pi, 50_000), np.logspace(-14, 0.5, 2000)])
    e = np.concatenate([rng.uniform(0.0, 0.999, 50_000), np.full(2000, 0.999)])
    np.testing.assert_array_equal(solve_kepler(M, e, max_iter=4), solve_kepler(M, e))


def test_kepler_extreme_eccentricity_and_many_turns():
    e = 0.99
    M = np.array([0.0, 1e-12, 1e-6, 1e-3, 0.1, np.pi, -np.pi / 3, 2 * np.pi * 1000 + 0.2])
    E = solve_kepler(M, e)
    assert np.all(np.abs(mean_from_eccentric(E, e) - M) <= 8 * EPS * np.maximum(np.abs(M), 1))
    assert E[0] == 0.0 and E[5] == pytest.approx(np.pi, abs=1e-15)
    # the turns are kept: E stays on the same revolution as M
    assert E[-1] == pytest.approx(2 * np.pi * 1000 + solve_kepler(0.2, e), rel=1e-15)


def test_kepler_circular_is_identity_and_shape_is_kept():
    M = np.linspace(-10, 10, 12).reshape(3, 4)
    np.testing.assert_array_equal(solve_kepler(M, 0.0), M)
    assert solve_kepler(M, np.full((3, 4), 0.3)).shape == (3, 4)


@pytest.mark.parametrize("e", [-0.1, 1.0, 1.5, np.nan])
def test_kepler_rejects_non_elliptic(e):
    with pytest.raises(OrbitError, match=r"^e: must be in \[0, 1\)"):
        solve_kepler(1.0, e)


@pytest.fixture
def molniya():
    return KeplerOrbit.from_elements(mu=MU_EARTH, a="26600 km", e=0.74, i="63.4 deg",
                                     raan="40 deg", argp="270 deg", mean_anomaly="-30 deg")


def test_from_elements_units():
    orbit = KeplerOrbit.from_elements(mu="3.986004418e14 m3/s2", a=7000 * u.km, e=0.1,
                                      i="98 deg", raan=0.5 * u.rad, argp="10 deg",
                                      mean_anomaly="1 rev")
    assert orbit.a == 7.0e6 and orbit.mu == MU_EARTH
    assert orbit.i == pytest.approx(np.radians(98.0))
    assert orbit.raan == 0.5 and orbit.mean_anomaly == pytest.approx(2 * np.pi)


def test_circular_orbit(molniya):
    orbit = KeplerOrbit(MU_EARTH, 7.0e6, 0.0, i=0.3, raan=1.0, argp=2.0)
    t = np.linspace(-3000.0, 9000.0, 97)
    r, v = orbit.state(t)
    np.testing.assert_allclose(np.linalg.norm(r, axis=-1), 7.0e6, rtol=1e-15)
    np.testing.assert_allclose(np.linalg.norm(v, axis=-1), np.sqrt(MU_EARTH / 7.0e6),
                               rtol=1e-15)
    np.testing.assert_allclose(np.sum(r * v, axis=-1), 0.0, atol=1e-14 * 7.0e6 * 7.5e3)


def test_keplers_third_law_and_periodicity(molniya):
    assert molniya.period == pytest.approx(2 * np.pi * np.sqrt(molniya.a**3 / MU_EARTH),
                                           rel=1e-15)
    assert molniya.mean_motion * molniya.period == pytest.approx(2 * np.pi, rel=1e-15)
    t = np.linspace(0.0, molniya.period, 50)
    np.testing.assert_allclose(molniya.position(t + molniya.period), molniya.position(t),
                               atol=1e-6 * molniya.a)
    # a Molniya orbit is half a sidereal day
    assert molniya.period / 3600 == pytest.approx(11.97, abs=0.05)


def test_apsides(molniya):
    n = molniya.mean_motion
    t_peri = -molniya.mean_anomaly / n                 # M = 0
    t_apo = (np.pi - molniya.mean_anomaly) / n         # M = pi
    r = np.linalg.norm(molniya.position(np.array([t_peri, t_apo])), axis=-1)
    np.testing.assert_allclose(r, [molniya.periapsis, molniya.apoapsis], rtol=1e-14)
    assert molniya.periapsis == pytest.approx(26600e3 * 0.26)
    # periapsis lies along P = the direction set by raan, i, argp
    P = molniya._frame()[0]
    np.testing.assert_allclose(molniya.position(t_peri) / r[0], P, atol=1e-13)
    # argp = 270 deg: periapsis at the southernmost point of the orbit
    assert P[2] == pytest.approx(-np.sin(np.radians(63.4)), rel=1e-14)


def test_vis_viva_energy_and_angular_momentum(molniya):
    t = np.linspace(0.0, 2 * molniya.period, 1001)
    r, v = molniya.state(t)
    rn = np.linalg.norm(r, axis=-1)
    v2 = np.sum(v * v, axis=-1)
    np.testing.assert_allclose(v2, MU_EARTH * (2 / rn - 1 / molniya.a), rtol=1e-13)
    energy = v2 / 2 - MU_EARTH / rn
    np.testing.assert_allclose(energy, molniya.specific_energy, rtol=1e-13)
    h = np.cross(r, v)
    np.testing.assert_allclose(h, np.broadcast_to(molniya.specific_angular_momentum, h.shape),
                               rtol=1e-12, atol=1e-12 * np.linalg.norm(h[0]))
    # inclination from the angular momentum
    assert np.degrees(np.arccos(h[0, 2] / np.linalg.norm(h[0]))) == pytest.approx(63.4)


def test_velocity_is_derivative_of_position(molniya):
    """Independent check: central differences of the position."""
    t = np.linspace(0.0, molniya.period, 37)
    dt = 1e-2
    numerical = (molniya.position(t + dt) - molniya.position(t - dt)) / (2 * dt)
    np.testing.assert_allclose(molniya.velocity(t), numerical, rtol=1e-7, atol=1e-4)


def test_true_anomaly(molniya):
    t = np.linspace(0.0, molniya.period, 25)
    nu = molniya.true_anomaly(t)
    r = molniya.radius(t)
    p = molniya.a * (1 - molniya.e**2)
    np.testing.assert_allclose(r, p / (1 + molniya.e * np.cos(nu)), rtol=1e-13)


def test_position_vectorised_equals_scalar(molniya):
    t = np.linspace(-5e4, 5e4, 11)
    stacked = molniya.position(t.reshape(11, 1))
    assert stacked.shape == (11, 1, 3)
    for k, tk in enumerate(t):
        np.testing.assert_allclose(stacked[k, 0], molniya.position(tk), rtol=1e-14)
    assert molniya.position(1.0).shape == (3,)


@pytest.mark.parametrize("kwargs, match", [
    ({"e": 1.2}, r"^e: must be in \[0, 1\), got 1.2; hyperbolic"),
    ({"e": -0.1}, r"^e: must be in \[0, 1\)"),
    ({"a": -7e6}, r"^a: must be a finite, positive"),
    ({"mu": 0.0}, r"^mu: must be a finite, positive"),
    ({"i": np.inf}, r"^i: must be a finite angle"),
])
def test_invalid_elements(kwargs, match):
    args = {"mu": MU_EARTH, "a": 7e6, "e": 0.0} | kwargs
    with pytest.raises(OrbitError, match=match) as info:
        KeplerOrbit(**args)
    assert isinstance(info.value, ValueError)


def test_from_elements_wrong_unit():
    with pytest.raises(OrbitError, match=r"^a: .*cannot be converted"):
        KeplerOrbit.from_elements(mu=MU_EARTH, a="7000 s")


def test_tabulated_path_interpolates_an_orbit():
    orbit = KeplerOrbit(MU_EARTH, 7.0e6, 0.05, i=0.5)
    ts = np.linspace(0.0, orbit.period, 200)
    path = TabulatedPath(ts * u.s, orbit.position(ts) / 1e3 * u.km)
    t = np.linspace(10.0, orbit.period - 10.0, 57)
    np.testing.assert_allclose(path.position(t), orbit.position(t), atol=1e-6 * orbit.a)
    np.testing.assert_allclose(path.velocity(t), orbit.velocity(t), rtol=1e-5, atol=1e-2)
    assert path.position(5.0).shape == (3,)
    with pytest.raises(OrbitError, match=r"^t: .*outside the tabulated span"):
        path.position(orbit.period + 1.0)


def test_tabulated_path_validation():
    with pytest.raises(OrbitError, match="^times: must be strictly increasing"):
        TabulatedPath([0, 1, 1, 2], np.zeros((4, 3)))
    with pytest.raises(OrbitError, match=r"^positions: expected shape \(4, 3\)"):
        TabulatedPath([0, 1, 2, 3], np.zeros((4, 2)))


def test_callable_path_vectorised_and_scalar_only():
    orbit = KeplerOrbit(MU_EARTH, 7.0e6, 0.1)
    t = np.linspace(0, 100, 5)
    vec = CallablePath(orbit.position)
    np.testing.assert_array_equal(vec.position(t), orbit.position(t))

    def scalar_only(tk):
        return [float(tk), 2.0, 3.0]                       # ignores arrays' shape

    path = CallablePath(scalar_only)
    np.testing.assert_array_equal(path.position(t)[:, 0], t)
    assert path.position(t).shape == (5, 3)


def test_as_path():
    orbit = KeplerOrbit(MU_EARTH, 7.0e6)
    assert as_path(orbit) is orbit
    assert isinstance(as_path(lambda t: np.zeros(np.shape(t) + (3,))), CallablePath)
    fixed = as_path([7e6, 0, 0])
    assert isinstance(fixed, ConstantPosition)
    assert fixed.position(np.zeros(4)).shape == (4, 3)
    with pytest.raises(OrbitError, match="^orbit: expected"):
        as_path("nowhere")

"""Radiation pressure and drag on facets (attitude.environment.radiation, .drag), each
against an independent reference: the flat-plate formulas written out face by face, the
closed-form force on a Lambertian sphere, symmetry, the table of the exponential
atmosphere, and a propagation along an SGP4 orbit."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import attitude as att
from attitude.environment import (
    AerodynamicDrag,
    ExponentialAtmosphere,
    Facets,
    SolarRadiationPressure,
    TLEOrbit,
)
from attitude.foundations.errors import ShapeModelError, TorqueConfigError
from attitude.model.surface import OpticalProperties, Surface

pytest.importorskip("sgp4")

AU = 1.495978707e11
P0 = 1367.0 / 299_792_458.0    # solar irradiance at 1 au (W/m^2) / c: the default, N/m^2
EPS = np.finfo(float).eps
ISS = ("1 25544U 98067A   24061.50000000  .00016717  00000-0  10270-3 0  9005",
       "2 25544  51.6416 247.4627 0006703 130.5360 325.0288 15.72125391563537")
MATERIALS = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (0.3, 0.5), (0.6, 0.2)]


def _directions(n, seed):
    v = np.random.default_rng(seed).normal(size=(n, 3))
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def _rotations(n, seed):
    return Rotation.random(n, random_state=seed)


def _pressure(sun, sat):
    return P0 * (AU / np.linalg.norm(np.asarray(sun) - np.asarray(sat))) ** 2


def _plate_force(area, n, s, rho_s, rho_d, p):
    """Montenbruck & Gill eq. 3.73 for one lit face: n . s > 0."""
    c = float(np.dot(n, s))
    if c <= 0:
        return np.zeros(3)
    return -p * area * c * ((1 - rho_s) * s + 2 * (rho_s * c + rho_d / 3) * n)


def _close(a, b, rtol):
    a, b = np.asarray(a), np.asarray(b)
    return np.linalg.norm(a - b, axis=-1) <= rtol * np.linalg.norm(b, axis=-1) + 1e-300


# --- radiation pressure ---------------------------------------------------------------


@pytest.mark.parametrize("rho_s, rho_d", MATERIALS)
def test_srp_on_a_plate_matches_the_flat_plate_formula(rho_s, rho_d):
    normal, centroid = np.array([0.0, 0.6, 0.8]), np.array([0.3, -1.2, 0.7])
    plate = Facets.plate(2.5, normal, centroid, specular=rho_s, diffuse=rho_d)
    sat = np.array([7.0e6, 0.0, 0.0])
    directions = _directions(40, 1)
    rotations = _rotations(40, 2)
    for d, rot in zip(directions, rotations):
        sun = AU * d                                     # never behind the Earth: no shadow
        srp = SolarRadiationPressure(plate, sun=sun, orbit=sat, shadow=None)
        s_in = (sun - sat) / np.linalg.norm(sun - sat)
        s = rot.inv().apply(s_in)
        p = _pressure(sun, sat)
        lit = normal if np.dot(normal, s) > 0 else -normal
        force = _plate_force(2.5, lit, s, rho_s, rho_d, p)
        torque = srp(0.0, rot.as_quat(), np.zeros(3), np.eye(3))
        assert _close(torque, np.cross(centroid, force), 1e-12)
        assert _close(srp.force(0.0, rot.as_quat()), force, 1e-12)


@pytest.mark.parametrize("rho_s, rho_d", MATERIALS)
def test_srp_on_a_box_matches_the_face_by_face_closed_form(rho_s, rho_d):
    size, center = np.array([1.0, 2.0, 3.0]), np.array([0.2, -0.4, 0.9])
    com = np.array([0.05, 0.1, -0.3])
    box = Facets.box(size, center, specular=rho_s, diffuse=rho_d)
    # the same box as a closed triangle mesh (two triangles per side), as photometry has it
    corners = center + (np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1],
                                  [1, 0, 1], [1, 1, 1], [0, 1, 1]]) - 0.5) * size
    faces = [[0, 2, 1], [0, 3, 2], [4, 5, 6], [4, 6, 7], [0, 1, 5], [0, 5, 4],
             [1, 2, 6], [1, 6, 5], [2, 3, 7], [2, 7, 6], [3, 0, 4], [3, 4, 7]]
    mesh = att.Polyhedron(corners, faces)
    surface = Surface.uniform(mesh, OpticalProperties(rho_s, rho_d))
    sat = np.array([0.0, 7.0e6, 0.0])
    rotations = _rotations(30, 3)
    for d, rot in zip(_directions(30, 4), rotations):
        sun = AU * d
        p = _pressure(sun, sat)
        s = rot.inv().apply((sun - sat) / np.linalg.norm(sun - sat))
        expected = np.zeros(3)
        for i in range(3):                               # the face toward the Sun on axis i
            e = np.zeros(3)
            e[i] = np.sign(s[i])
            area = np.prod(size) / size[i]
            arm = center + 0.5 * size[i] * e - com
            expected += np.cross(arm, _plate_force(area, e, s, rho_s, rho_d, p))
        for shape, surf in ((box, None), (mesh, surface)):
            srp = SolarRadiationPressure(shape, surf, sun=sun, orbit=sat, shadow=None,
                                         center_of_mass=com)
            assert _close(srp(0.0, rot.as_quat(), np.zeros(3), np.eye(3)), expected, 1e-12)


def test_srp_is_vectorised_over_epochs_and_attitudes():
    orbit = att.KeplerOrbit.from_elements(mu=3.986004418e14, a=7.0e6, e=0.001, i=0.9)
    box = Facets.box([1.0, 2.0, 3.0], [0.1, 0.2, 0.3], specular=0.2, diffuse=0.3)
    srp = SolarRadiationPressure(box, sun=[AU, 0, 0], orbit=orbit)
    t = np.linspace(0.0, 6000.0, 50)
    q = _rotations(50, 5).as_quat()
    batch = srp(t, q, np.zeros((50, 3)), np.eye(3))
    one = np.array([srp(t[k], q[k], np.zeros(3), np.eye(3)) for k in range(50)])
    assert batch.shape == (50, 3)
    np.testing.assert_allclose(batch, one, rtol=0, atol=64 * EPS * np.abs(one).max())


def test_srp_is_zero_in_the_umbra_and_full_in_light():
    box = Facets.box([1.0, 1.0, 2.0], [0.3, 0.0, 0.0])
    sun = np.array([AU, 0.0, 0.0])
    q = Rotation.from_euler("xyz", [0.3, 0.2, 0.1]).as_quat()
    for shadow in ("conical", "cylindrical"):
        dark = SolarRadiationPressure(box, sun=sun, orbit=[-7.0e6, 0, 0], shadow=shadow)
        assert np.all(dark(0.0, q, np.zeros(3), np.eye(3)) == 0.0)
        lit = SolarRadiationPressure(box, sun=sun, orbit=[0, 7.0e6, 0], shadow=shadow)
        free = SolarRadiationPressure(box, sun=sun, orbit=[0, 7.0e6, 0], shadow=None)
        np.testing.assert_array_equal(lit(0.0, q, np.zeros(3), np.eye(3)),
                                      free(0.0, q, np.zeros(3), np.eye(3)))


def test_srp_is_continuous_through_the_penumbra():
    box = Facets.box([1.0, 1.0, 2.0], [0.3, 0.0, 0.0], diffuse=0.4)
    sun = np.array([AU, 0.0, 0.0])
    # a path crossing the shadow edge 7000 km behind the Earth, 5 m between samples
    y = np.arange(6.30e6, 6.45e6, 5.0)
    path = SimpleNamespace(position=lambda t: np.stack(
        [np.full(np.shape(t), -7.0e6), 6.30e6 + 5.0 * np.asarray(t),
         np.zeros(np.shape(t))], axis=-1))
    srp = SolarRadiationPressure(box, sun=sun, orbit=path)
    free = SolarRadiationPressure(box, sun=sun, orbit=path, shadow=None)
    t = np.arange(y.size, dtype=float)
    q = np.array([0.0, 0.0, 0.0, 1.0])
    m = srp(t, q, np.zeros(3), np.eye(3))[:, 2]
    full = free(t, q, np.zeros(3), np.eye(3))[:, 2]
    frac = m / full
    assert frac[0] == 0.0 and frac[-1] == 1.0
    partial = (frac > 0) & (frac < 1)
    # the penumbra is ~2 * 7000 km * (solar radius / 1 au) = 65 km wide: thousands of
    # samples, no step larger than a few times the mean slope (5 m / 65 km)
    assert partial.sum() > 5000
    assert np.max(np.abs(np.diff(frac))) < 10 * 5.0 / 65e3
    assert np.all(np.diff(frac) >= -1e-12)                 # monotone into the light


@pytest.mark.parametrize("rho_s, rho_d", [(0.0, 0.0), (0.0, 1.0), (0.5, 0.3), (0.9, 0.1)])
def test_srp_force_on_a_sphere_is_the_lambertian_closed_form(rho_s, rho_d):
    # F = -P pi R^2 (1 + 4/9 rho_d) s: the specular part integrates to the absorbed one,
    # the diffuse part adds 2/3 rho_d * integral of cos^2 over the lit hemisphere
    radius = 1.7
    ball = att.Polyhedron.ellipsoid(radius, radius, radius, subdivisions=5)
    surface = Surface.uniform(ball, OpticalProperties(rho_s, rho_d))
    # the facets are chords: their distance from the centre sets the mesh error
    sag = 1.0 - np.min(np.abs(np.sum(ball.face_centroids * ball.face_normals, axis=1))) \
        / radius
    for d in _directions(5, 6):
        sun = AU * d
        srp = SolarRadiationPressure(ball, surface, sun=sun, orbit=[0, 0, 0], shadow=None)
        force = srp.force(0.0, [0, 0, 0, 1])
        expected = -_pressure(sun, [0, 0, 0]) * np.pi * radius**2 * (1 + 4 / 9 * rho_d) * d
        assert _close(force, expected, 4 * sag)
        assert np.linalg.norm(np.cross(force, d)) < 4 * sag * np.linalg.norm(expected)


def test_srp_and_drag_give_no_torque_on_a_centred_box():
    # A_i * h_i = V / 2 for every face: sum_k w_k r_k is parallel to s (to v)
    box = Facets.box([1.0, 2.0, 3.0], specular=0.3, diffuse=0.4)
    rot = _rotations(20, 7)
    srp = SolarRadiationPressure(box, sun=[AU, 0, 0], orbit=[0, 7e6, 0], shadow=None)
    m = srp(np.zeros(20), rot.as_quat(), np.zeros(3), np.eye(3))
    f = srp.force(np.zeros(20), rot.as_quat())
    assert np.all(np.linalg.norm(m, axis=-1) <= 16 * EPS * 3 * np.linalg.norm(f, axis=-1))
    orbit = att.KeplerOrbit.from_elements(mu=3.986004418e14, a=6.8e6, e=0.0, i=0.9)
    drag = AerodynamicDrag(box, orbit)
    m = drag(np.linspace(0, 5000, 20), rot.as_quat(), np.zeros(3), np.eye(3))
    f = drag.force(np.linspace(0, 5000, 20), rot.as_quat())
    assert np.all(np.linalg.norm(m, axis=-1) <= 16 * EPS * 3 * np.linalg.norm(f, axis=-1))


# --- drag -----------------------------------------------------------------------------


def _fixed_orbit(r, v):
    r, v = np.asarray(r, float), np.asarray(v, float)
    return SimpleNamespace(position=lambda t: np.broadcast_to(r, np.shape(t) + (3,)),
                           velocity=lambda t: np.broadcast_to(v, np.shape(t) + (3,)))


def test_drag_on_a_plate_and_a_box_matches_the_closed_form():
    r = np.array([3.0e6, -4.0e6, 4.5e6])
    v = np.array([5.0e3, 4.0e3, 1.0e3])
    altitude = np.linalg.norm(r) - 6378137.0
    rho = ExponentialAtmosphere().density(altitude)
    v_rel = v - np.cross([0, 0, 7.292115e-5], r)
    cd = 2.4
    com = np.array([0.1, 0.0, -0.2])
    normal, centroid = np.array([0.0, 0.6, 0.8]), np.array([0.3, -1.2, 0.7])
    size, center = np.array([1.0, 2.0, 3.0]), np.array([0.2, -0.4, 0.9])
    plate = AerodynamicDrag(Facets.plate(2.5, normal, centroid), _fixed_orbit(r, v),
                            cd=cd, center_of_mass=com)
    box = AerodynamicDrag(Facets.box(size, center), _fixed_orbit(r, v), cd=cd,
                          center_of_mass=com)
    for rot in _rotations(30, 8):
        u = rot.inv().apply(v_rel)
        q_dyn = 0.5 * rho * np.dot(u, u) * cd
        u_hat = u / np.linalg.norm(u)
        c = abs(np.dot(normal, u_hat))
        f_plate = -q_dyn * 2.5 * c * u_hat
        assert _close(plate(0.0, rot.as_quat(), np.zeros(3), np.eye(3)),
                      np.cross(centroid - com, f_plate), 1e-12)
        assert _close(plate.force(0.0, rot.as_quat()), f_plate, 1e-12)
        expected = np.zeros(3)
        for i in range(3):
            e = np.zeros(3)
            e[i] = np.sign(u_hat[i])
            area = np.prod(size) / size[i]
            f = -q_dyn * area * abs(u_hat[i]) * u_hat
            expected += np.cross(center + 0.5 * size[i] * e - com, f)
        assert _close(box(0.0, rot.as_quat(), np.zeros(3), np.eye(3)), expected, 1e-12)


def test_exponential_atmosphere_reproduces_its_table():
    atm = ExponentialAtmosphere()
    # Vallado (2013) Table 8-4, rows typed independently of the module
    for h0, rho0, scale in ((0, 1.225, 7.249), (150, 2.070e-9, 22.523),
                            (400, 3.725e-12, 58.515), (1000, 3.019e-15, 268.0)):
        assert atm(h0 * 1e3) == pytest.approx(rho0, rel=4 * EPS)
        h = h0 + 0.4 * scale
        assert atm(h * 1e3) == pytest.approx(rho0 * np.exp(-0.4), rel=16 * EPS)
    # inside a layer the density follows that layer: 425 km is in the 400 km layer
    assert atm(425e3) == pytest.approx(3.725e-12 * np.exp(-25 / 58.515), rel=16 * EPS)
    # the layers nearly join: the table is a fit to one smooth profile
    for h0, _, _ in atm.table[1:]:
        below, at = atm(h0 * 1e3 - 1e-3), atm(h0 * 1e3)
        assert abs(below / at - 1) < 0.1
    with pytest.raises(TorqueConfigError, match="increase") as err:
        ExponentialAtmosphere(((100, 1e-7, 6.0), (90, 1e-6, 6.0)))
    assert err.value.key == "table"


# --- bad input ------------------------------------------------------------------------


@pytest.mark.parametrize("build, key", [
    (lambda: Facets([1.0, 0.0], [[1, 0, 0], [0, 1, 0]], np.zeros((2, 3))), "areas"),
    (lambda: Facets([1.0], [[0, 0, 0]], np.zeros((1, 3))), "normals"),
    (lambda: Facets.plate(1.0, [1, 0, 0], specular=-0.1), "specular"),
    (lambda: Facets.plate(1.0, [1, 0, 0], specular=0.7, diffuse=0.5), "diffuse"),
    (lambda: SolarRadiationPressure(Facets.box([1, 1, 1]), sun=[AU, 0, 0],
                                    orbit=[7e6, 0, 0], pressure=-1.0), "pressure"),
    (lambda: SolarRadiationPressure(Facets.box([1, 1, 1]), sun=[AU, 0, 0],
                                    orbit=[7e6, 0, 0], shadow="square"), "shadow"),
    (lambda: SolarRadiationPressure(Facets.box([1, 1, 1]), sun=[AU, 0, 0],
                                    orbit=[7e6, 0, 0], center_of_mass=[0, 1]),
     "center_of_mass"),
    (lambda: AerodynamicDrag(Facets.box([1, 1, 1]), _fixed_orbit([7e6, 0, 0], [0, 7e3, 0]),
                             cd=-2.2), "cd"),
    (lambda: AerodynamicDrag(Facets.box([1, 1, 1]), _fixed_orbit([7e6, 0, 0], [0, 7e3, 0]),
                             density=lambda h: -1e-12 * np.ones_like(h)), "density"),
    (lambda: AerodynamicDrag(Facets.box([1, 1, 1]), [7e6, 0, 0]), "orbit"),
])
def test_bad_input_is_a_keyed_torque_config_error(build, key):
    with pytest.raises(TorqueConfigError) as err:
        build()
    assert err.value.key == key


def test_negative_density_during_a_run_is_named():
    def density(h):                      # fine at the probe altitudes, negative below 150 km
        return np.where(np.asarray(h) < 150e3, -1e-11, 1e-12)
    drag = AerodynamicDrag(Facets.box([1, 1, 1]), _fixed_orbit([6.45e6, 0, 0], [0, 7e3, 0]),
                           density=density)
    with pytest.raises(TorqueConfigError, match="density model gives") as err:
        drag(0.0, [0, 0, 0, 1], np.zeros(3), np.eye(3))
    assert err.value.key == "density"


def test_negative_optical_fraction_of_a_material_is_named():
    with pytest.raises(ShapeModelError) as err:
        OpticalProperties(specular=-0.2)
    assert err.value.key == "specular"


# --- hooks and a propagation along an SGP4 orbit --------------------------------------


@pytest.fixture(scope="module")
def iss():
    return TLEOrbit(*ISS)


def test_shifted_models_read_their_paths_later(iss):
    box = Facets.box([1.0, 2.0, 3.0], [0.1, 0.2, 0.3], specular=0.2, diffuse=0.3)
    sun = att.environment.SunPath(iss.epoch)
    t = np.linspace(0.0, 3000.0, 7)
    q = _rotations(7, 9).as_quat()
    for model in (SolarRadiationPressure(box, sun=sun, orbit=iss),
                  AerodynamicDrag(box, iss)):
        later = model.shifted(500.0)
        np.testing.assert_array_equal(later(t, q, np.zeros(3), np.eye(3)),
                                      model(t + 500.0, q, np.zeros(3), np.eye(3)))
        body = att.RigidBody.from_principal_moments([10.0, 20.0, 25.0])
        rate = model.characteristic_rate(t, q, np.zeros(3), body)
        largest, bound = model.largest_torque(t), model.torque_bound(t)
        assert rate == pytest.approx(max(np.sqrt(largest / 10.0), 2 * np.pi / iss.period),
                                     rel=0.01)       # the SGP4 orbit is not quite circular
        m = model(t, q, np.zeros(3), body)
        assert np.all(np.linalg.norm(m, axis=-1) <= bound)
        # the largest torque over 20000 random attitudes, at the epoch of the largest
        # pressure: within the 4000-direction lattice's resolution (1.6 deg to the
        # nearest node, a few % of a torque that turns with the direction)
        k = int(np.argmax(model.pressure_at(t)))
        many = _rotations(20000, 11).as_quat()
        sampled = np.linalg.norm(model(np.full(20000, t[k]), many, np.zeros(3), body),
                                 axis=-1).max()
        assert abs(sampled / largest - 1) < 0.05
        assert largest <= bound


def test_propagation_along_the_iss_orbit(iss):
    body = att.RigidBody.from_principal_moments([40.0, 60.0, 75.0])
    state = att.AttitudeState.from_quaternion([0.0, 0.0, 0.0, 1.0], epoch=iss.epoch,
                                              omega_body=[0.02, 0.05, -0.03])
    sun = att.environment.SunPath(iss.epoch)
    times = np.linspace(0.0, 600.0, 7)

    def run(com):
        box = Facets.box([1.0, 1.5, 2.0], specular=0.3, diffuse=0.3)
        torques = [SolarRadiationPressure(box, sun=sun, orbit=iss, center_of_mass=com),
                   AerodynamicDrag(box, iss, center_of_mass=com)]
        eph = att.propagate(body, state, times, torques=torques, method="integrator",
                            rtol=1e-11)
        return np.linalg.norm(eph.dataset["angular_momentum"].values, axis=-1)

    centred = run((0.0, 0.0, 0.0))
    # centred box: no torque, |L| constant to the integrator's tolerance
    assert np.max(np.abs(centred / centred[0] - 1)) < 1e-9
    # the same box 0.3 m off its centre of mass: the torques do change |L|
    offset = run((0.3, 0.0, 0.0))
    assert np.max(np.abs(offset / offset[0] - 1)) > 1e-6


def test_one_epoch_fast_paths_agree_with_the_arrays():
    from attitude.environment import illumination
    rng = np.random.default_rng(10)
    sun = np.array([1.496e11, 2e9, -1e9])
    r = np.concatenate([rng.normal(size=(3000, 3)) * 1e6 + [-7e6, 6.37e6, 0.0],
                        rng.normal(size=(300, 3)) * 7e6])
    for model in ("conical", "cylindrical"):
        vec = illumination(r, sun, model)
        one = np.array([illumination(x, sun, model) for x in r])
        # arccos near +-1 turns an ulp of its argument into ~sqrt(eps) of angle
        np.testing.assert_allclose(one, vec, rtol=0, atol=64 * np.sqrt(EPS))
    atm = ExponentialAtmosphere()
    h = np.linspace(-10e3, 1500e3, 997)
    np.testing.assert_allclose([atm(x) for x in h], atm(h), rtol=8 * EPS, atol=0)


def test_one_epoch_table_lookup_is_the_spline():
    from attitude.environment import TimeTable
    table = TimeTable(lambda t: np.stack([np.sin(t / 300), np.cos(t / 70), t / 1e3], -1),
                      spacing=10.0, segment=400.0)
    t = np.concatenate([np.linspace(-900.0, 2000.0, 1001), [0.0, 400.0, 399.999999]])
    many, rates = table(t), table.rate(t)
    one = np.array([table(x) for x in t])
    one_rate = np.array([table.rate(x) for x in t])
    # Horner's rule and scipy's evaluation of the same cubic: a few ulps of the terms
    np.testing.assert_allclose(one, many, rtol=0, atol=16 * EPS)
    np.testing.assert_allclose(one_rate, rates, rtol=0, atol=16 * EPS / 10.0 * 3)
    assert table(5.0) is not table(5.0)            # the cached value is not shared

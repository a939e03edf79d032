"""Photometry: facet brightness against closed forms (the disk-integrated phase
functions of a sphere, the projected area of an ellipsoid), the scattering laws'
limits and symmetries, the geometry, the lightcurve dataset, and bad input."""

from __future__ import annotations

import numpy as np
import pytest
from astropy.time import Time
from scipy.spatial.transform import Rotation

import attitude as att
from attitude.foundations.errors import PhotometryError, ShapeModelError
from attitude.model.orbit import KeplerOrbit
from attitude.photometry import (
    AshikhminShirley,
    FacetMaterials,
    Geometry,
    Hapke,
    Lambert,
    Lightcurve,
    LommelSeeliger,
    Phong,
    facet_brightness,
    lightcurve,
    scattering_law,
)
from attitude.photometry.geometry import AU
from attitude.photometry.scattering import chandrasekhar_h


@pytest.fixture(scope="module")
def fine_sphere():
    return att.Polyhedron.ellipsoid(1.0, 1.0, 1.0, subdivisions=6)   # 81 920 faces


def _phase_geometry(alpha, seed=1):
    """Sun and observer unit vectors at phase angles ``alpha`` in a randomly oriented
    scattering plane (so that the mesh's symmetry planes do not line up with it)."""
    R = Rotation.random(random_state=seed)
    sun = np.tile([1.0, 0.0, 0.0], (len(alpha), 1))
    obs = np.stack([np.cos(alpha), np.sin(alpha), 0 * alpha], axis=1)
    return R.apply(sun), R.apply(obs)


def test_sphere_phase_functions_match_closed_forms(fine_sphere):
    """Lambert: [sin a + (pi - a) cos a]/pi; Lommel-Seeliger: 1 - sin(a/2) tan(a/2)
    ln cot(a/4) (e.g. Kaasalainen et al. 2001; Muinonen & Lumme 2015), 1e-4 relative
    for 1-150 deg.  The faceting error is O(h^2) ~ 4e-5 on this mesh."""
    alpha = np.deg2rad(np.concatenate([[0.0], np.arange(1.0, 150.5, 1.0)]))
    sun, obs = _phase_geometry(alpha)
    a = alpha[1:]
    lam = (np.sin(a) + (np.pi - a) * np.cos(a)) / np.pi
    ls = 1 - np.sin(a / 2) * np.tan(a / 2) * np.log(1 / np.tan(a / 4))
    for law, closed, albedo in (("lambert", lam, 2 / 3), ("lommel-seeliger", ls, 1 / 8)):
        flux, _ = facet_brightness(fine_sphere, sun, obs, law)
        np.testing.assert_allclose(flux[1:] / flux[0], closed, rtol=1e-4)
        # geometric albedo of the sphere: 2/3 (Lambert), w/8 (Lommel-Seeliger)
        assert flux[0] == pytest.approx(albedo, rel=1e-4)


def test_ls_lambert_is_the_sum_of_its_parts():
    shape = att.Polyhedron.ellipsoid(3.0, 2.0, 1.0, subdivisions=2)
    rng = np.random.default_rng(4)
    sun = Rotation.random(20, random_state=5).apply([1.0, 0, 0])
    obs = Rotation.random(20, random_state=6).apply([1.0, 0, 0])
    keep = np.einsum("ij,ij->i", sun, obs) > -0.9
    sun, obs = sun[keep], obs[keep]
    c, w = rng.uniform(0.05, 0.5), 0.7
    both, _ = facet_brightness(shape, sun, obs, scattering_law("ls-lambert", c=c, albedo=w))
    ls, _ = facet_brightness(shape, sun, obs, LommelSeeliger(albedo=w))
    lam, _ = facet_brightness(shape, sun, obs, Lambert(albedo=w))
    np.testing.assert_allclose(both, ls + c / 4 * lam, rtol=1e-12, atol=1e-15)


def test_ellipsoid_at_opposition_follows_its_projected_area():
    """Lommel-Seeliger at zero phase: f = (w/8) mu, so the flux is (w/8) x projected
    area / (pi R^2); for an ellipsoid the projected area along u is
    pi a b c sqrt(ux^2/a^2 + uy^2/b^2 + uz^2/c^2).  A principal-axis spin about c with
    the Sun and observer in the equator gives the classic double-peaked curve."""
    a, b, c = 3.0, 2.0, 1.5
    shape = att.Polyhedron.ellipsoid(a, b, c, subdivisions=5)
    body = att.RigidBody.from_principal_moments([b**2 + c**2, a**2 + c**2, a**2 + b**2])
    period = 3600.0
    state = att.AttitudeState("2030-01-01", Rotation.identity(), [0, 0, 2 * np.pi / period])
    t = np.linspace(0.0, period, 37)
    eph = att.propagate(body, state, t)
    lc = lightcurve(eph, shape, Geometry(sun=[1.0, 0, 0], observer=[1.0, 0, 0]),
                    law="lommel-seeliger")
    theta = 2 * np.pi * t / period                # the sun seen from the body: angle -theta
    area = np.pi * a * b * c * np.sqrt(np.cos(theta) ** 2 / a**2 + np.sin(theta) ** 2 / b**2)
    flux = lc.dataset.flux.values
    np.testing.assert_allclose(flux / flux[0], area / area[0], rtol=3e-4)
    amplitude = 2.5 * np.log10(a / b)             # mag, the textbook amplitude at zero phase
    assert lc.amplitude() == pytest.approx(amplitude, rel=1e-3)


def test_vectorised_equals_per_epoch():
    shape = att.Polyhedron.ellipsoid(3.0, 2.0, 1.0, subdivisions=2)
    sun = Rotation.random(7, random_state=1).apply([1.0, 0, 0])
    obs = Rotation.random(7, random_state=2).apply([0.0, 1.0, 0])
    for law in ("lambert", "ls-lambert", "hapke", "phong", "ashikhmin-shirley"):
        stacked, _ = facet_brightness(shape, sun, obs, law, chunk_elements=3 * 320)
        single = [facet_brightness(shape, sun[k:k + 1], obs[k:k + 1], law)[0][0]
                  for k in range(7)]
        np.testing.assert_allclose(stacked, single, rtol=1e-13, atol=1e-16)


def test_facet_contributions_sum_to_flux():
    shape = att.Polyhedron.ellipsoid(2.0, 1.0, 1.0, subdivisions=2)
    mats = FacetMaterials([Lambert(0.2), Phong(0.1, 0.6, 20)], np.arange(320) % 2)
    sun = Rotation.random(5, random_state=3).apply([1.0, 0, 0])
    flux, facet = facet_brightness(shape, sun, sun, mats, facet_contributions=True)
    np.testing.assert_allclose(facet.sum(axis=1), flux, rtol=1e-13)


def test_hapke_limits():
    """w -> 0, isotropic, no surge: Lommel-Seeliger; the H-function approximation
    against Chandrasekhar's exact H(1) = 2.9078 for w = 1 (Hapke 2002: < 1 %)."""
    mu0 = np.linspace(0.05, 1, 9)
    mu = mu0[::-1].copy()
    h = Hapke(w=1e-8, xi=0.0, B0=0.0)(mu0.copy(), mu.copy(), 0.3)
    ls = LommelSeeliger(albedo=1e-8)(mu0.copy(), mu.copy(), 0.3)
    np.testing.assert_allclose(h, ls, rtol=1e-7)
    assert float(chandrasekhar_h(1.0, 1.0)) == pytest.approx(2.9078, rel=0.01)
    # the zeroth moment, exact for isotropic scattering (Chandrasekhar 1960, ch. V):
    # int_0^1 H(mu) dmu = 2 (1 - sqrt(1 - w)) / w
    x = (np.arange(20000) + 0.5) / 20000
    for w in (0.3, 0.7, 1.0):
        assert np.mean(chandrasekhar_h(x, w)) == pytest.approx(
            2 * (1 - np.sqrt(1 - w)) / w, rel=0.01)


def test_specular_laws():
    mu0 = np.array([0.3, 0.7, 0.9])
    mu = np.array([0.8, 0.2, 0.9])
    ca = np.array([0.1, -0.2, 0.62])
    # reciprocity: swapping Sun and observer leaves Ashikhmin-Shirley unchanged
    law = AshikhminShirley(0.3, 0.5, 80)
    np.testing.assert_allclose(law(mu0.copy(), mu.copy(), ca), law(mu.copy(), mu0.copy(), ca),
                               rtol=1e-14)
    # Phong without its specular lobe is a Lambert surface of albedo Rd
    np.testing.assert_allclose(Phong(0.4, 0.0, 10)(mu0.copy(), mu.copy(), ca),
                               Lambert(0.4)(mu0.copy(), mu.copy(), ca), rtol=1e-15)
    # energy: the Ashikhmin-Shirley albedo at normal incidence is at most 1
    th = np.linspace(0, np.pi / 2, 400)[1:]
    ph = np.linspace(0, 2 * np.pi, 801)[:-1]
    T, P = np.meshgrid(th, ph)
    mu_e = np.cos(T).ravel()
    # sun at the zenith: cos(alpha) = mu
    f = AshikhminShirley(0.5, 0.5, 50)(np.ones_like(mu_e), mu_e.copy(), mu_e)
    # f = pi rho mu0 mu; albedo = int rho mu dOmega = int f/pi dOmega
    albedo = np.sum(f / np.pi * np.sin(T).ravel()) * (th[1] - th[0]) * (ph[1] - ph[0])
    assert 0.5 < albedo <= 1.0


def test_geometry_from_orbits_light_time_and_distances():
    """Target on a 2 AU circular orbit, observer on a 1 AU circular orbit, both at
    longitude 0 at t = 0 (opposition): Delta = 1 AU up to the observer's motion during
    the light time, r = 2 AU, phase angle ~ v tau / Delta."""
    mu = 1.32712440018e20
    target = KeplerOrbit(mu=mu, a=2 * AU)
    observer = KeplerOrbit(mu=mu, a=1 * AU)
    geom = Geometry.from_orbit(target, [0.0], observer)
    tau = float(geom.light_time[0])
    v = np.sqrt(mu / AU)
    assert float(geom.sun_distance[0]) == pytest.approx(2 * AU, rel=1e-12)
    assert tau == pytest.approx(AU / att.photometry.geometry.SPEED_OF_LIGHT, rel=1e-6)
    assert float(geom.phase_angle[0]) == pytest.approx(v * tau / AU, rel=1e-3)


def test_geometry_from_earth_ephemeris():
    orbit = KeplerOrbit.from_elements(mu="1.32712440018e20 m3/s2", a="0.9224 AU",
                                      e=0.1914, i="3.34 deg", raan="204 deg",
                                      argp="126 deg", mean_anomaly="10 deg")
    t = np.linspace(0, 30 * 86400.0, 5)
    geom = Geometry.from_orbit(orbit, t, "earth", epoch=Time("2029-03-01", scale="tdb"))
    # Earth's heliocentric distance is 0.983..1.017 AU
    earth = geom.sun_distance[:, None] * -geom.sun + \
        geom.observer_distance[:, None] * geom.observer
    r_earth = np.linalg.norm(earth, axis=1) / AU
    assert np.all((r_earth > 0.98) & (r_earth < 1.02))
    np.testing.assert_allclose(geom.light_time, geom.observer_distance / 299_792_458.0,
                               rtol=1e-4)
    # the same epochs as an astropy Time array
    from astropy.time import TimeDelta

    when = Time("2029-03-01", scale="tdb") + TimeDelta(t, format="sec")
    again = Geometry.from_orbit(orbit, when, "earth")
    np.testing.assert_allclose(again.observer, geom.observer, rtol=0, atol=1e-12)


def test_netcdf_round_trip(tmp_path):
    lc = Lightcurve.from_arrays(np.arange(4.0), flux=[1.0, 0.5, 0.25, 0.5],
                                phase_angle=0.1, epoch=Time("2030-01-01T00:00:00",
                                                            scale="tdb"), frame="ICRF")
    path = lc.to_netcdf(tmp_path / "lc.nc")
    back = Lightcurve.from_netcdf(path)
    np.testing.assert_array_equal(back.dataset.flux.values, lc.dataset.flux.values)
    assert back.dataset.magnitude.attrs["units"] == "mag"
    assert back.epoch.isot == lc.epoch.isot and back.epoch.scale == "tdb"
    assert not list(tmp_path.glob(".*.tmp"))


@pytest.mark.parametrize("kwargs, match", [
    ({"sun": [0, 0, 0], "observer": [1, 0, 0]}, "zero vector"),
    ({"sun": [1, 0, 0], "observer": [-2, 0, 0]}, "opposite the Sun"),
    ({"sun": [[1, 0, 0]] * 3, "observer": [[1, 0, 0]] * 2}, "epochs"),
])
def test_bad_geometry(kwargs, match):
    with pytest.raises(PhotometryError, match=match):
        Geometry(**kwargs)


def test_bad_laws_and_shapes():
    with pytest.raises(PhotometryError, match="unknown scattering law 'lamber'"):
        scattering_law("lamber")
    with pytest.raises(PhotometryError, match="albedo: must be in"):
        scattering_law("lommel-seeliger", albedo=-0.1)
    with pytest.raises(PhotometryError, match="unknown parameter"):
        scattering_law("hapke", albedo=0.1)
    open_box = [[0, 2, 1], [0, 3, 2], [4, 5, 6], [4, 6, 7]]
    cube = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1],
            [0, 1, 1]]
    with pytest.raises(ShapeModelError, match="not closed"):
        att.Polyhedron(cube, open_box)


def _two_spheres(subdivisions=3, gap=3.0):
    one = att.Polyhedron.ellipsoid(1.0, 1.0, 1.0, subdivisions=subdivisions)
    n = len(one.vertices)
    vertices = np.vstack([one.vertices, one.vertices + [gap, 0.0, 0.0]])
    return att.Polyhedron(vertices, np.vstack([one.faces, one.faces + n])), one


def test_shadows_two_spheres_in_line():
    """Two equal spheres on the x axis, Sun and observer along +x: the rear sphere is in
    the front one's shadow, so the shadowed flux is one sphere's (and twice that
    without shadows).  Off the axis, neither is hidden."""
    pytest.importorskip("embreex")
    pair, one = _two_spheres()
    along = np.array([[1.0, 0.0, 0.0]])
    single, _ = facet_brightness(one, along, along, "lommel-seeliger")
    unshadowed, _ = facet_brightness(pair, along, along, "lommel-seeliger")
    shadowed, _ = facet_brightness(pair, along, along, "lommel-seeliger", shadows=True)
    # fluxes are relative to the volume-equivalent sphere: two spheres -> 2**(2/3)
    scale = 2 ** (2 / 3)
    assert unshadowed[0] * scale == pytest.approx(2 * single[0], rel=1e-12)
    assert shadowed[0] * scale == pytest.approx(single[0], rel=2e-3)
    side = np.array([[0.0, 0.0, 1.0]])
    free, _ = facet_brightness(pair, side, side, "lommel-seeliger", shadows=True)
    assert free[0] * scale == pytest.approx(2 * single[0], rel=1e-12)


def test_shadows_without_embree_name_the_extra(monkeypatch):
    import sys

    monkeypatch.setitem(sys.modules, "embreex", None)
    shape = att.Polyhedron.ellipsoid(1.0, 1.0, 1.0, subdivisions=1)
    with pytest.raises(att.MissingDependencyError, match=r"attitude-dynamics\[shadows\]"):
        facet_brightness(shape, [[1.0, 0, 0]], [[1.0, 0, 0]], shadows=True)


def test_surface_properties_drive_the_brdf():
    """A surface of rho_s = 0 and rho_d = A under Phong is a Lambert surface of albedo A;
    bad fractions are refused."""
    from attitude.model.surface import OpticalProperties, Surface

    shape = att.Polyhedron.ellipsoid(2.0, 1.0, 1.0, subdivisions=2)
    surf = Surface(shape, (OpticalProperties(0.0, 0.3), OpticalProperties(0.0, 0.5)),
                   np.arange(len(shape.faces)) % 2)
    mats = FacetMaterials.from_surface(surf, "phong")
    sun = Rotation.random(4, random_state=8).apply([1.0, 0, 0])
    obs = Rotation.random(4, random_state=9).apply([1.0, 0, 0])
    got, facets = facet_brightness(shape, sun, obs, mats, facet_contributions=True)
    lam, lam_f = facet_brightness(shape, sun, obs, "lambert", facet_contributions=True)
    np.testing.assert_allclose(facets, lam_f * surf.diffuse, rtol=1e-13, atol=1e-16)
    np.testing.assert_allclose(got, facets.sum(axis=1), rtol=1e-13)
    assert np.all(got < lam)
    with pytest.raises(ShapeModelError, match="exceeds 1"):
        OpticalProperties(0.7, 0.4)


def test_lightcurve_checks_epochs_and_frame():
    body = att.RigidBody.from_principal_moments([1.0, 2.0, 2.5])
    state = att.AttitudeState("2030-01-01", Rotation.identity(), [0, 0, 1e-3], frame="ICRF")
    eph = att.propagate(body, state, [0.0, 10.0, 20.0])
    shape = att.Polyhedron.ellipsoid(2.0, 1.5, 1.0, subdivisions=1)
    with pytest.raises(PhotometryError, match="3"):
        lightcurve(eph, shape, Geometry(sun=[[1.0, 0, 0]] * 2, observer=[1.0, 0, 0]))
    with pytest.raises(PhotometryError, match="frame"):
        lightcurve(eph, shape, Geometry(sun=[1.0, 0, 0], observer=[1.0, 0, 0],
                                        frame="ECLIPJ2000"))
    per_epoch = Geometry(sun=[[1.0, 0, 0]] * 3, observer=[[0.0, 1.0, 0]] * 3)
    const = Geometry(sun=[1.0, 0, 0], observer=[0.0, 1.0, 0])
    np.testing.assert_allclose(lightcurve(eph, shape, per_epoch).dataset.flux,
                               lightcurve(eph, shape, const).dataset.flux, rtol=1e-14)


def test_a_string_epoch_is_the_same_instant_in_a_state_and_a_lightcurve(tmp_path):
    """A plain ISO 8601 epoch is read by the one reader (quantities.to_time) in its one
    default scale, TDB, by AttitudeState and by Lightcurve.from_arrays alike (the latter
    read it as UTC: 69 s apart in 2030)."""
    text = "2030-01-01T00:00:00"
    state = att.AttitudeState(text, Rotation.identity(), [0.0, 0.0, 1e-3])
    lc = Lightcurve.from_arrays([0.0, 10.0], magnitude=[1.0, 1.2], epoch=text)
    assert state.epoch.scale == lc.epoch.scale == "tdb"
    assert abs((lc.epoch - state.epoch).to_value("s")) < 1e-9
    back = Lightcurve.from_netcdf(lc.to_netcdf(tmp_path / "lc.nc"))
    assert abs((back.epoch - state.epoch).to_value("s")) < 1e-9
    # an explicit scale is kept: the same wall-clock text in UTC is another instant
    utc = Lightcurve.from_arrays([0.0], magnitude=[1.0], epoch=Time(text, scale="utc"))
    assert utc.epoch.scale == "utc"
    assert (utc.epoch - state.epoch).to_value("s") == pytest.approx(69.184, abs=1e-3)

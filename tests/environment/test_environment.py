"""The Earth-orbit environment against independent implementations.

- SGP4 positions against skyfield's own SGP4 + TEME -> GCRS chain (1 m);
- the IGRF field against ppigrf evaluated directly at the Earth-fixed position that
  astropy's own transform gives, and turned back by astropy (1 nT);
- the Sun against astropy's ephemeris directly, the shadow fraction against its
  limiting cases and its continuity through the penumbra.
"""

from pathlib import Path

import numpy as np
import pytest
from astropy import units as u
from astropy.coordinates import GCRS, ITRS, CartesianRepresentation, get_body
from astropy.time import Time, TimeDelta

from attitude.foundations.errors import OrbitError

sgp4 = pytest.importorskip("sgp4")
ppigrf = pytest.importorskip("ppigrf")

from attitude.environment import IGRF, SunPath, TLEOrbit, illumination  # noqa: E402
from attitude.environment.frames import inertial_to_earth_fixed  # noqa: E402

ISS = ("1 25544U 98067A   24061.50000000  .00016717  00000-0  10270-3 0  9005",
       "2 25544  51.6416 247.4627 0006703 130.5360 325.0288 15.72125391563537")
T = np.linspace(0.0, 2 * 86400.0, 37) + 13.7   # off the nodes, across a segment boundary


def test_tle_positions_match_skyfield_to_a_metre():
    skyfield_api = pytest.importorskip("skyfield.api")
    ts = skyfield_api.load.timescale(builtin=True)
    sat = skyfield_api.EarthSatellite(*ISS, ts=ts)
    orbit = TLEOrbit(*ISS)
    times = orbit.epoch + TimeDelta(T, format="sec")
    reference = sat.at(ts.from_astropy(times)).position.m.T     # GCRS, m
    err = np.linalg.norm(orbit.position(T) - reference, axis=-1)
    assert err.max() < 1.0, err.max()


def test_tle_velocity_is_the_derivative_of_the_position():
    orbit = TLEOrbit(*ISS)
    h = 0.5
    fd = (orbit.position(T + h) - orbit.position(T - h)) / (2 * h)
    # central difference error h^2/6 |r'''| ~ 0.04 * 7e6 * n^3 ~ 4e-4 m/s
    assert np.abs(fd - orbit.velocity(T)).max() < 1e-3


@pytest.mark.parametrize("lines, match", [
    ((ISS[0][:-1], ISS[1]), "69 characters"),
    ((ISS[0][:-1] + "0", ISS[1]), "checksum"),
    ((ISS[1], ISS[0]), "swapped"),
    ((ISS[0], "2 25545" + ISS[1][7:68] + "8"), "different satellites"),
    ((ISS[0], 42), "string"),
])
def test_malformed_tle_is_a_keyed_orbit_error(lines, match):
    with pytest.raises(OrbitError, match=match) as err:
        TLEOrbit(*lines)
    assert err.value.key.startswith("tle")


def test_unknown_frame_is_named():
    with pytest.raises(OrbitError, match="GCRF") as err:
        TLEOrbit(*ISS, frame="J2001")
    assert err.value.key == "frame"


def test_eme2000_differs_from_gcrf_by_the_frame_bias():
    gcrf, eme = TLEOrbit(*ISS), TLEOrbit(*ISS, frame="EME2000")
    r1, r2 = gcrf.position(T), eme.position(T)
    angle = np.arccos(np.clip(np.sum(r1 * r2, -1) / np.linalg.norm(r1, axis=-1)
                              / np.linalg.norm(r2, axis=-1), -1, 1))
    # the IAU 2000 frame bias is 23 mas = 1.1e-7 rad (at most, depending on direction)
    assert angle.max() < 1.2e-7 and angle.max() > 1e-8


def _igrf_direct(position, times):
    """ppigrf at astropy's own Earth-fixed position, turned back by astropy (per point)."""
    out = []
    for r, t in zip(position, times):
        gcrs = GCRS(CartesianRepresentation(r * u.m), obstime=t)
        x, y, z = gcrs.transform_to(ITRS(obstime=t)).cartesian.xyz.to_value(u.m)
        rr = np.sqrt(x * x + y * y + z * z)
        b_r, b_t, b_p = ppigrf.igrf_gc(rr / 1e3, np.degrees(np.arccos(z / rr)),
                                       np.degrees(np.arctan2(y, x)), t.utc.datetime)
        st, ct = np.hypot(x, y) / rr, z / rr
        cp, sp = x / np.hypot(x, y), y / np.hypot(x, y)
        b = (float(b_r[0]) * np.array([st * cp, st * sp, ct])
             + float(b_t[0]) * np.array([ct * cp, ct * sp, -st])
             + float(b_p[0]) * np.array([-sp, cp, 0.0]))
        back = ITRS(CartesianRepresentation(b * u.m), obstime=t).transform_to(
            GCRS(obstime=t)).cartesian.xyz.to_value(u.m)
        out.append(back * 1e-9)
    return np.array(out)


def test_igrf_along_a_tle_orbit_matches_ppigrf_to_one_nanotesla():
    orbit = TLEOrbit(*ISS)
    field = IGRF(orbit)
    t = T[::4]
    times = orbit.epoch + TimeDelta(t, format="sec")
    reference = _igrf_direct(orbit.position(t), times)
    err = np.linalg.norm(field(t) - reference, axis=-1)
    assert err.max() < 1e-9, err.max()
    assert np.linalg.norm(reference, axis=-1).min() > 1.5e-5      # a real LEO field


def test_igrf_degree_one_is_close_to_the_tilted_dipole():
    from attitude.model.orbit import KeplerOrbit
    from attitude.model.torques import TiltedDipoleField
    epoch = Time("2024-03-01T00:00:00", scale="utc")
    leo = KeplerOrbit.from_elements(mu=3.986004418e14, a="6871 km", i="51.6 deg")
    dipole = IGRF(leo, epoch=epoch, max_degree=1)
    era = float(epoch.earth_rotation_angle(0).to_value(u.rad))
    tilted = TiltedDipoleField(leo, rotation_angle=era)
    t = np.linspace(0, 6000, 25)
    b1, b2 = dipole(t), tilted(t)
    # the tilted dipole's pole (IGRF-13, 2020) and moment are rounded: a few per cent
    rel = np.linalg.norm(b1 - b2, axis=-1) / np.linalg.norm(b1, axis=-1)
    assert rel.max() < 0.05


def test_igrf_outside_its_span_is_an_error():
    from attitude.model.orbit import KeplerOrbit
    leo = KeplerOrbit.from_elements(mu=3.986004418e14, a="6871 km")
    field = IGRF(leo, epoch=Time("2031-01-01", scale="utc"))
    with pytest.raises(OrbitError, match="outside IGRF-14"):
        field(0.0)
    with pytest.raises(OrbitError, match="epoch"):
        IGRF(leo)


def test_earth_fixed_rotation_matches_astropy_between_the_nodes():
    times = Time("2024-03-01T00:00:00", scale="utc") + TimeDelta(T, format="sec")
    m = inertial_to_earth_fixed(times)
    r = np.array([7e6, 1e6, -2e6])
    for k in range(0, T.size, 6):
        ref = GCRS(CartesianRepresentation(r * u.m), obstime=times[k]).transform_to(
            ITRS(obstime=times[k])).cartesian.xyz.to_value(u.m)
        assert np.linalg.norm(m[k] @ r - ref) < 1e-3     # 1 mm at 7000 km (1.4e-10 rad)


def test_sun_path_matches_astropy_directly():
    epoch = Time("2024-06-01T00:00:00", scale="utc")
    sun = SunPath(epoch)
    t = np.array([0.0, 1234.5, 86400.0 * 3.3])
    ref = get_body("sun", epoch + TimeDelta(t, format="sec")).cartesian.xyz.to_value(u.m).T
    rel = np.linalg.norm(sun.position(t) - ref, axis=-1) / np.linalg.norm(ref, axis=-1)
    assert rel.max() < 1e-9


def test_shadow_models_limits_and_penumbra_continuity():
    r_sun = np.array([1.496e11, 0.0, 0.0])
    r = 7e6
    angles = np.linspace(0, 2 * np.pi, 200001)
    pos = np.stack([r * np.cos(angles), r * np.sin(angles), 0 * angles], axis=-1)
    conical = illumination(pos, r_sun)
    cylindrical = illumination(pos, r_sun, "cylindrical")
    assert conical.min() == 0.0 and conical.max() == 1.0
    assert set(np.unique(cylindrical)) == {0.0, 1.0}
    # continuous through the penumbra: no jump larger than the slope allows
    assert np.abs(np.diff(conical)).max() < 0.01
    penumbra = (conical > 0) & (conical < 1)
    assert penumbra.sum() > 10
    # umbra + penumbra straddle the cylinder's edge
    dark = cylindrical == 0
    assert np.all(conical[dark & ~penumbra] == 0.0) or dark.sum() > 0
    # fraction of the orbit in the cylindrical shadow: asin(R/r)/pi
    expected = np.arcsin(6378137.0 / r) / np.pi
    assert abs(dark.mean() - expected) < 1e-4
    with pytest.raises(OrbitError, match="conical"):
        illumination(pos[:1], r_sun, "umbra")


def test_annular_eclipse_fraction():
    # far behind a small occulter: the Sun's disk larger than the Earth's
    r_sun = np.array([1.496e11, 0.0, 0.0])
    far = np.array([-3.0e9, 0.0, 0.0])
    a = np.arcsin(6.957e8 / np.linalg.norm(r_sun - far))
    b = np.arcsin(6378137.0 / 3.0e9)
    assert illumination(far, r_sun) == pytest.approx(1 - b * b / (a * a), rel=1e-12)


def test_eddy_current_spin_down_in_igrf_follows_the_averaged_closed_form():
    """A conducting sphere in the IGRF field along a TLE orbit: dw/dt = -(M/I) A(t) w with
    A = |B|^2 - B B^T, so to first order in the slow decay w(T) = expm(-(M/I) int A dt) w0
    (the integral sampled on the field itself, independently of the propagator)."""
    from scipy.integrate import trapezoid
    from scipy.linalg import expm
    from scipy.spatial.transform import Rotation

    import attitude as att
    from attitude.model.torques import EddyCurrentDamping

    orbit = TLEOrbit(*ISS)
    field = IGRF(orbit)
    radius, sigma, inertia = 1.0, 3.5e7, 375.0            # e-folding about half a day
    torque = EddyCurrentDamping.solid_sphere(radius, sigma, field)
    moment = 2 * np.pi / 15 * sigma * radius**5
    body = att.RigidBody.from_principal_moments([inertia] * 3)
    w0 = np.array([0.01, -0.004, 0.006])
    state = att.AttitudeState(orbit.epoch, Rotation.identity(), w0, frame="GCRF")
    duration = 21600.0
    eph = att.propagate(body, state, [0.0, duration], torques=[torque],
                        method="integrator", rtol=1e-10)
    w_end = np.asarray(eph.dataset["angular_velocity"])[-1]
    # the sphere's attitude does not matter: body rates and inertial rates decay alike,
    # so compare magnitudes (and the closed form is in inertial axes)
    t = np.linspace(0.0, duration, 10801)
    b = field(t)
    a = (np.einsum("ni,ni->n", b, b)[:, None, None] * np.eye(3)
         - b[:, :, None] * b[:, None, :])
    predicted = expm(-(moment / inertia) * trapezoid(a, t, axis=0)) @ w0
    decay = np.linalg.norm(w0) - np.linalg.norm(predicted)
    assert decay > 0.2 * np.linalg.norm(w0)                       # a real spin-down
    assert abs(np.linalg.norm(w_end) - np.linalg.norm(predicted)) < 0.01 * decay


def test_scenario_keys_tle_orbit_and_igrf_field(tmp_path, capsys):
    """`orbit = { tle = [...] }` and `field = "igrf"` in a [[torques]] table: the run
    builds a TLEOrbit and an IGRF field (the same eddy-current torque as from Python), and
    a corrupted element set exits 2 naming the key."""
    from attitude.app.cli import main
    from attitude.app.scenario import load_scenario
    from attitude.model.torques import EddyCurrentDamping
    path = Path(__file__).parents[1] / "data" / "igrf_tle_despin.toml"
    sc = load_scenario(path)
    torque = sc.torques[0]
    assert isinstance(torque, EddyCurrentDamping)
    assert isinstance(torque.field, IGRF) and isinstance(torque.field.orbit, TLEOrbit)
    direct = IGRF(TLEOrbit(*ISS, epoch=sc.state.epoch))
    assert np.abs(torque.field(T[:5]) - direct(T[:5])).max() < 1e-15
    bad = path.read_text().replace("0  9005", "0  9006")          # checksum broken
    (tmp_path / "bad.toml").write_text(bad)
    assert main(["run", str(tmp_path / "bad.toml"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "torques[0].orbit.tle[0]" in err and "checksum" in err

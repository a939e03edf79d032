"""Reading SPICE C-kernels: Ephemeris.from_spice, formats.spice_read.read_ck and
``attitude convert MISSION.bc OUT``; CKs written by write_ck and by spiceypy's own ckw03
from an analytic rotation."""

import numpy as np
import pytest
from astropy.time import Time
from scipy.spatial.transform import Rotation

import attitude as att

sp = pytest.importorskip("spiceypy", reason="spiceypy not installed (optional extra "
                         "'spice': pip install 'attitude-dynamics[spice]')")

from attitude.app.cli import main  # noqa: E402
from attitude.formats.spice import leapseconds_kernel_text, write_ck  # noqa: E402
from attitude.formats.spice_read import read_ck  # noqa: E402
from attitude.model.spice_ck import DIFFERENCE_STEP  # noqa: E402

EPS = np.finfo(float).eps
J2000 = Time("2000-01-01T12:00:00", scale="tdb")
#: ET is a float64 near 7.7e8 s: one ulp is 1.2e-7 s.
ET_ULP = float(np.spacing(7.7e8))


def angle_between(q1, q2):
    """Rotation angle between two stacks of unit quaternions (either sign), computed
    from the norm of the vector part of q1^-1 q2: accurate near 0 (no arccos)."""
    rel = Rotation.from_quat(q1).inv() * Rotation.from_quat(q2)
    x = rel.as_quat()
    return 2.0 * np.arctan2(np.linalg.norm(x[:, :3], axis=1), np.abs(x[:, 3]))


@pytest.fixture
def body():
    return att.RigidBody.from_principal_moments([0.61, 0.965, 1.0], name="tumbler")


@pytest.fixture
def eph(body):
    state = att.AttitudeState(Time("2029-04-13T01:02:03.125", scale="tdb"),
                              Rotation.from_euler("ZXZ", [0.3, 1.1, -0.7]),
                              [0.02, 0.003, 0.05], frame="ICRF")
    return att.propagate(body, state, np.arange(0.0, 3600.0, 10.0))


@pytest.fixture
def files(eph, tmp_path):
    return write_ck(eph, tmp_path / "eph.bc", body_id=-999)


@pytest.fixture(autouse=True)
def clean_pool():
    """The reader must leave the kernel pool as it found it: empty here."""
    sp.kclear()
    yield
    assert sp.ktotal("ALL") == 0, "from_spice left kernels loaded"


# --- written by write_ck, read back ------------------------------------------------------
def test_round_trip_at_the_records(eph, files):
    back = att.Ephemeris.from_spice(files.ck, files.sclk, files.lsk, "J2000")
    assert len(back) == len(eph) and back.frame == "J2000" and back.time_scale == "TDB"
    # the records themselves: only the roundings of m2q/q2m and of the transposition
    assert angle_between(back.dataset.quaternion.values,
                         eph.dataset.quaternion.values).max() < 1e-12
    # omega_body = C (R omega): a few roundings of two 3x3 products
    w = eph.dataset.angular_velocity.values
    np.testing.assert_allclose(back.dataset.angular_velocity.values, w, rtol=0,
                               atol=16 * EPS * np.abs(w).max())
    # the time stamps: ET from the SCLK, a float64 (1 ulp), epoch kept to the ns
    dt = (back.times - eph.times).to_value("s")
    assert np.abs(dt).max() <= ET_ULP + 1e-9
    ds = back.dataset
    assert ds.attrs["angular_velocity_source"] == "the CK angular velocity (ckgpav)"
    assert ds.attrs["ck_instrument_id"] == -999000 and ds.attrs["sclk_id"] == -999
    assert ds.attrs["inertia_known"] == 0 and "inertia" not in ds.attrs
    assert np.isnan(ds.angular_momentum.values).all()
    assert np.isnan(ds.kinetic_energy.values).all()


def test_the_body_gives_momentum_and_energy(eph, files, body):
    back = att.Ephemeris.from_spice(files.ck, files.sclk, files.lsk, body=body)
    assert back.dataset.attrs["inertia_known"] == 1
    np.testing.assert_allclose(back.body.principal_moments, body.principal_moments)
    L = eph.dataset.angular_momentum.values
    np.testing.assert_allclose(back.dataset.angular_momentum.values, L, rtol=0,
                               atol=1e-12 * np.abs(L).max())
    # and with_body on the bodyless one gives the same
    bodyless = att.Ephemeris.from_spice(files.ck, files.sclk, files.lsk)
    np.testing.assert_allclose(bodyless.with_body(body).dataset.kinetic_energy.values,
                               back.dataset.kinetic_energy.values, rtol=1e-15)


def test_off_the_records_is_the_constant_rate_interpolation(eph, files):
    """With a step, samples between records are CK type 3's interpolation: the
    rotation at constant rate from one record to the next (scipy's Slerp)."""
    from scipy.spatial.transform import Slerp

    start = eph.times[0] + 3.3 * att_u("s")
    back = att.Ephemeris.from_spice(files.ck, files.sclk, files.lsk, start=start.tdb,
                                    stop=eph.times[-1], step="7 s", kernels=[files.fk],
                                    instrument="SC_BODY_1")
    assert len(back) == int((3590 - 3.3) // 7) + 1
    assert back.dataset.attrs["body_frame"] == "SC_BODY_1"
    t = (back.times - eph.times[0]).to_value("s")
    expected = Slerp(eph.time - eph.time[0], eph.rotation)(t).as_quat()
    # the sample times carry ET's rounding (1 ulp, 1.2e-7 s) at |omega| <= 0.06 rad/s
    w_max = np.linalg.norm(eph.dataset.angular_velocity.values, axis=1).max()
    assert angle_between(back.dataset.quaternion.values, expected).max() < \
        2 * ET_ULP * w_max + 1e-12


def att_u(unit):
    from astropy import units as u

    return u.Unit(unit)


def test_frames_and_time_strings(eph, files):
    """Read in ECLIPJ2000: the attitude is the J2000 one seen from the ecliptic frame;
    start/stop as UTC strings or with a TDB scale word."""
    tdb0 = eph.times[0].tdb.isot
    j2000 = att.Ephemeris.from_spice(files.ck, files.sclk, files.lsk, "J2000",
                                     start=f"{tdb0} TDB", step=60)
    ecl = att.Ephemeris.from_spice(files.ck, files.sclk, files.lsk, "ECLIPJ2000",
                                   start=eph.times[0].utc.isot, step="1 min")
    assert ecl.frame == "ECLIPJ2000" and len(ecl) == len(j2000) == 60
    assert abs((ecl.times[0] - j2000.times[0]).to_value("s")) < 1e-6
    m = Rotation.from_matrix(np.array(sp_pxform("J2000", "ECLIPJ2000")))
    expected = (m * j2000.rotation).as_quat()
    # |omega| 0.054 rad/s times the 1e-6 s of the UTC round trip
    assert angle_between(ecl.dataset.quaternion.values, expected).max() < 1e-7
    # body-frame rates do not depend on the inertial frame
    np.testing.assert_allclose(ecl.dataset.angular_velocity.values,
                               j2000.dataset.angular_velocity.values, atol=1e-8)


def sp_pxform(a, b):
    return sp.pxform(a, b, 0.0)      # inertial to inertial: no kernels needed


def test_read_ck_finds_the_companion_kernels(eph, files, tmp_path, body):
    back = read_ck(files.ck, body=body)
    assert len(back) == len(eph) and back.dataset.attrs["body_frame"] == "SC_BODY_1"
    alone = tmp_path / "alone"
    alone.mkdir()
    (alone / "eph.bc").write_bytes(files.ck.read_bytes())
    with pytest.raises(att.EphemerisFormatError, match="SCLK kernel of clock -999.*eph.tsc"):
        read_ck(alone / "eph.bc")
    back = read_ck(alone / "eph.bc", sclk=files.sclk)      # the LSK: the default one
    assert len(back) == len(eph)


def test_errors_name_the_missing_piece(eph, files, tmp_path):
    read = att.Ephemeris.from_spice
    with pytest.raises(att.EphemerisFormatError, match="SCLK kernel of clock -999") as err:
        read(files.ck)
    assert err.value.key == "sclk" and err.value.path == str(files.ck)
    with pytest.raises(att.EphemerisFormatError, match="outside the coverage") as err:
        read(files.ck, files.sclk, start="2029-04-13T00:00:00", step=10)
    # the coverage is named: first and last record, TDB
    assert "2029-04-13T01:02:03.125 .. 2029-04-13T02:01:53.125 TDB" in str(err.value)
    with pytest.raises(att.EphemerisFormatError, match="outside the coverage"):
        read(files.ck, files.sclk, stop="2029-04-14T00:00:00 TDB")
    with pytest.raises(att.EphemerisFormatError, match="'FOO' is unknown"):
        read(files.ck, files.sclk, frame="FOO")
    with pytest.raises(att.EphemerisFormatError, match="not inertial"):
        read(files.ck, files.sclk, frame="IAU_EARTH")
    with pytest.raises(att.EphemerisFormatError, match="'SC_BODY_1' is unknown.*--kernel"):
        read(files.ck, files.sclk, instrument="SC_BODY_1")         # no FK loaded
    with pytest.raises(att.EphemerisFormatError, match="no data for CK structure -5"):
        read(files.ck, files.sclk, instrument=-5)
    with pytest.raises(att.EphemerisFormatError, match="no such file"):
        read(tmp_path / "missing.bc", files.sclk)
    with pytest.raises(att.EphemerisFormatError, match="not a SPICE C-kernel"):
        read(files.sclk, files.sclk)
    with pytest.raises(att.EphemerisFormatError, match="step"):
        read(files.ck, files.sclk, step="-3 s")


# --- written by spiceypy's ckw03 from an analytic rotation --------------------------------
TICKS = 1000.0                         # ticks per second of the test's own clock
CLOCK, STRUCTURE = -77, -77001         # ckmeta: the clock of -77001 is -77001 / 1000


def sclk_text(et0):
    return f"""KPL/SCLK
\\begindata
SCLK_KERNEL_ID           = ( @2000-01-01/12:00 )
SCLK_DATA_TYPE_77        = ( 1 )
SCLK01_TIME_SYSTEM_77    = ( 1 )
SCLK01_N_FIELDS_77       = ( 2 )
SCLK01_MODULI_77         = ( 1000000000 1000 )
SCLK01_OFFSETS_77        = ( 0 0 )
SCLK01_OUTPUT_DELIM_77   = ( 1 )
SCLK_PARTITION_START_77  = ( 0.0 )
SCLK_PARTITION_END_77    = ( 1.0D12 )
SCLK01_COEFFICIENTS_77   = ( 0.0 {et0!r} 1.0 )
\\begintext
"""


def uniform_rotation(t, r0, omega):
    """R(t) = R0 exp(t [omega]x): spin at constant body rate omega about a fixed axis."""
    return r0 * Rotation.from_rotvec(np.outer(t, omega))


@pytest.fixture
def analytic_ck(tmp_path):
    """A type 3 CK written by ckw03 (not by attitude), records every 10 s for 20 min, of
    a uniform spin about a tilted axis, in ECLIPJ2000, in two segments (one with
    angular velocity, one without, so that both paths are read)."""
    et0 = 9.1234567e8
    r0 = Rotation.from_euler("ZYX", [0.4, -0.3, 1.2])
    omega = 0.045 * np.array([np.sin(0.5), 0.3, np.cos(0.5)])       # body frame, rad/s
    t = np.arange(0.0, 1201.0, 10.0)
    R = uniform_rotation(t, r0, omega)
    q = R.as_quat()
    quats = np.column_stack([q[:, 3], -q[:, :3]])                  # C-matrix, scalar first
    quats *= np.sign(quats[:, :1])                                 # continuous: w > 0 here
    avv = R.apply(np.tile(omega, (len(t), 1)))                     # inertial components
    (tmp_path / "own.tsc").write_text(sclk_text(et0))
    (tmp_path / "own.tls").write_text(leapseconds_kernel_text())
    path = tmp_path / "own.bc"
    handle = sp.ckopn(str(path), "test", 0)
    half = len(t) // 2
    for sl, rates in ((slice(0, half + 1), True), (slice(half, None), False)):
        ticks = t[sl] * TICKS
        sp.ckw03(handle, ticks[0], ticks[-1], STRUCTURE, "ECLIPJ2000", rates, "seg",
                 len(ticks), ticks, quats[sl], avv[sl], 1, [ticks[0]])
    sp.ckcls(handle)
    sp.kclear()
    return {"ck": path, "sclk": tmp_path / "own.tsc", "lsk": tmp_path / "own.tls",
            "et0": et0, "r0": r0, "omega": omega, "t_max": 1200.0, "split": t[half]}


def test_analytic_rotation_written_by_ckw03(analytic_ck):
    """Type 3 interpolates from one record to the next at the constant rate that joins
    them (CK Required Reading).  For a uniform rotation R0 exp(t [w]x) the rotation
    between records is exactly exp(dt [w]x), so the interpolation is exact between and
    at the records: what remains is rounding, of the records (eps), of SPICE's
    axis-angle step and q2m (a few eps), and of the reference exp(t [w]x) itself,
    whose angle |w| t reaches 54 rad (eps |w| t_max).  Bound: 8 eps (1 + |w| t_max).
    The sample times are ET differences (exact) from the first sample, which is the
    clock's tick 0, and ticks = 1000 (ET - ET0): rounded at 1e-16 relative."""
    c = analytic_ck
    w = np.linalg.norm(c["omega"])
    bound = 8 * EPS * (1 + w * c["t_max"])
    # read in J2000 (the CK is in ECLIPJ2000): SPICE rotates; the reference too
    eph = att.Ephemeris.from_spice(c["ck"], c["sclk"], c["lsk"], "J2000", step="3.7 s")
    et = (eph.times - J2000).to_value("s")
    t = et - c["et0"]
    assert t[0] == 0.0 and len(eph) == int(1200 // 3.7) + 1
    m = Rotation.from_matrix(sp_pxform("ECLIPJ2000", "J2000"))
    expected = m * uniform_rotation(eph.time, c["r0"], c["omega"])
    angle = angle_between(eph.dataset.quaternion.values, expected.as_quat())
    assert angle.max() < bound, (angle.max(), bound)
    # rates: first half from the CK's angular velocity (ckgpav: linear interpolation of
    # equal records, then C @ av, a few eps |w|); second half differentiated from the
    # attitude (central difference over +-h: exact for a uniform rotation but for the
    # attitude's rounding, 2 * 8 eps / (2 h))
    rates = eph.dataset.angular_velocity.values
    assert "central differences" in eph.dataset.attrs["angular_velocity_source"]
    err = np.linalg.norm(rates - c["omega"], axis=1)
    assert err.max() < 16 * EPS / DIFFERENCE_STEP
    # the first half alone has rates in every segment: read with ckgpav
    first = att.Ephemeris.from_spice(c["ck"], c["sclk"], c["lsk"], "J2000", step="3.7 s",
                                     stop=(J2000 + (c["et0"] + 500.0) * att_u("s")))
    assert first.dataset.attrs["angular_velocity_source"].endswith("(ckgpav)")
    err = np.linalg.norm(first.dataset.angular_velocity.values - c["omega"], axis=1)
    assert err.max() < 16 * EPS * w
    # at the records (no step): the records themselves, rounded
    records = att.Ephemeris.from_spice(c["ck"], c["sclk"], c["lsk"], "ECLIPJ2000")
    assert len(records) == 121                       # the shared boundary record once
    expected = uniform_rotation(records.time, c["r0"], c["omega"])
    assert angle_between(records.dataset.quaternion.values,
                         expected.as_quat()).max() < bound


def test_a_wrong_convention_would_be_seen(analytic_ck):
    """The test above can fail: the C-matrix itself (inertial -> body) is far from the
    body -> inertial attitude."""
    c = analytic_ck
    eph = att.Ephemeris.from_spice(c["ck"], c["sclk"], c["lsk"], "ECLIPJ2000", step=60)
    expected = uniform_rotation(eph.time, c["r0"], c["omega"])
    assert angle_between(eph.rotation.inv().as_quat(), expected.as_quat()).max() > 0.1


def test_several_structures_ask_for_one(analytic_ck, files, tmp_path):
    """A CK with two structures: the reader asks which, naming them."""
    c = analytic_ck
    path = tmp_path / "two.bc"
    handle = sp.ckopn(str(path), "two", 0)
    q = np.array([[1.0, 0, 0, 0], [1.0, 0, 0, 0]])
    for inst in (STRUCTURE, -77002):
        sp.ckw03(handle, 0.0, 1000.0, inst, "J2000", False, "s", 2, [0.0, 1000.0], q,
                 np.zeros((2, 3)), 1, [0.0])
    sp.ckcls(handle)
    sp.kclear()
    with pytest.raises(att.EphemerisFormatError, match="-77002, -77001|-77001, -77002"):
        att.Ephemeris.from_spice(path, c["sclk"], c["lsk"])
    eph = att.Ephemeris.from_spice(path, c["sclk"], c["lsk"], instrument=-77002)
    assert len(eph) == 2 and np.allclose(eph.dataset.angular_velocity.values, 0.0)


# --- the command line ---------------------------------------------------------------------
def test_convert_bc_to_netcdf_and_classify(body, tmp_path, capsys):
    state = att.AttitudeState(Time("2029-04-13T01:02:03.125", scale="tdb"),
                              Rotation.from_euler("ZXZ", [0.3, 1.1, -0.7]),
                              [0.02, 0.003, 0.05], frame="ICRF")
    eph = att.propagate(body, state, np.arange(0.0, 12000.0, 20.0))   # 6 polhode cycles
    nc = tmp_path / "eph.nc"
    eph.to_netcdf(nc)
    assert main(["convert", str(nc), str(tmp_path / "ck.bc"), "--object-id", "-42"]) == 0
    assert main(["convert", str(tmp_path / "ck.bc"), str(tmp_path / "back.nc")]) == 0
    assert main(["convert", str(tmp_path / "ck.bc"), str(tmp_path / "back.aem"),
                 "--step", "60 s", "--frame", "ECLIPJ2000"]) == 0
    capsys.readouterr()
    assert main(["classify", str(tmp_path / "back.nc")]) == 2
    err = capsys.readouterr().err
    assert "--body" in err and "--inertia" in err and len(err.strip().splitlines()) == 1
    moments = ",".join(repr(float(m)) for m in body.principal_moments)
    assert main(["classify", str(tmp_path / "back.nc"), "--inertia", moments, "--json"]) == 0
    got = __import__("json").loads(capsys.readouterr().out)
    want = att.classify(eph)
    assert got["regime"] == want.regime
    for key, period in want.periods.items():
        assert got["periods"][key] == pytest.approx(period, rel=1e-9)
    back = att.formats.read_aem(tmp_path / "back.aem")
    assert back.frame == "ECLIPJ2000" and len(back) == 200


@pytest.mark.parametrize("extra, message", [
    ([], "SCLK kernel of clock -999"),
    (["--start", "2020-01-01T00:00:00"], "outside the coverage"),
    (["--frame", "NOT_A_FRAME"], "'NOT_A_FRAME' is unknown"),
    (["--instrument", "NOT_A_FRAME"], "'NOT_A_FRAME' is unknown"),
    (["--step", "ten"], "step"),
])
def test_bad_ck_inputs_exit_2_with_one_line(files, tmp_path, capsys, extra, message):
    lone = tmp_path / "lone.bc"
    lone.write_bytes(files.ck.read_bytes())
    args = ["convert", str(lone), str(tmp_path / "x.nc"), *extra]
    if extra:
        args += ["--sclk", str(files.sclk)]
    assert main(args) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and message in err and str(lone) in err
    assert not (tmp_path / "x.nc").exists()


def test_ck_options_need_a_ck(eph, tmp_path, capsys):
    nc = eph.to_netcdf(tmp_path / "eph.nc")
    assert main(["convert", str(nc), str(tmp_path / "x.aem"), "--sclk", "a.tsc"]) == 2
    assert "--sclk: options for reading a SPICE C-kernel" in capsys.readouterr().err


def test_help_names_bc():
    from attitude.app.cli import build_parser

    text = build_parser()._subparsers._group_actions[0].choices["convert"].format_help()
    assert "mission.bc" in text and "--sclk" in text and "--step" in text


def test_without_spiceypy_the_error_says_how_to_install(files, tmp_path, monkeypatch, capsys):
    """spiceypy hidden (an import of it fails, as when the extra is not installed): a
    MissingDependencyError naming the extra, exit 2 from the command line."""
    monkeypatch.setitem(__import__("sys").modules, "spiceypy", None)
    with pytest.raises(att.MissingDependencyError, match=r"attitude-dynamics\[spice\]"):
        att.Ephemeris.from_spice(files.ck, files.sclk)
    assert main(["convert", str(files.ck), str(tmp_path / "x.nc")]) == 2
    assert "pip install" in capsys.readouterr().err

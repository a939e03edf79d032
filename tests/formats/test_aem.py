"""CCSDS Attitude Ephemeris Messages (CCSDS 504.0-B-2): write, read, conventions, errors.

Independent references used here:

* the standard's own definitions, typed into the tests from its annex F (the frame
  transformation matrix of a quaternion, F2; the Euler angle matrices, F3; the spin
  example, F5.4), never through ``attitude``'s own conversion code;
* AEM files written by other people (see ``tests/data/README.md``): the standard's
  examples and GSFC's Magnetospheric Multiscale message, whose ``QUATERNION/ANGVEL`` and
  ``EULER_ANGLE/ANGVEL`` segments give one attitude history twice;
* a hand-made version 1 file (scalar first, ``B2A``) checked by geometry;
* the ``ccsds-ndm`` package (xsdata models generated from the official NDM/XML 4.0.0
  schemas), when installed, as an independent XML reader and writer.
"""

import re
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest
from astropy.time import Time, TimeDelta
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

import attitude as att
from attitude.formats import aem_message, aem_write
from attitude.formats.aem import AEM_WRITE_TYPES, convert, read_aem, write_aem
from attitude.foundations.errors import AttitudeWarning, EphemerisFormatError

from ..aem_fixture import CASES, frozen_ephemeris
from ..tolerances import FEW_OPS, assert_agree

DATA = Path(__file__).parents[1] / "data"
FORMS = {"kvn": ".aem", "xml": ".xml"}


# --- fixtures -----------------------------------------------------------------------
@pytest.fixture(scope="module")
def body():
    return att.RigidBody.from_principal_moments([0.61, 0.965, 1.0], name="apophis-like")


@pytest.fixture(scope="module")
def tumbling(body):
    """A short-axis-mode tumbler, integrated (independent of the exact solution)."""
    state = att.AttitudeState(Time("2029-04-13T00:00:00.123456789", scale="tdb"),
                              Rotation.from_euler("ZXZ", [30, 40, 50], degrees=True),
                              np.radians([0.2, 0.05, 3.0]), frame="ICRF")
    return att.propagate(body, state, np.linspace(0.0, 600.0, 11), method="integrator")


@pytest.fixture(scope="module")
def random_eph(body):
    """Random attitudes and rates at irregular times over 12 days: every digit matters."""
    rng = np.random.default_rng(20240117)
    t = np.sort(np.concatenate([[0.0, 0.123456789, 1.5], rng.uniform(2.0, 1.0e6, 40)]))
    q = Rotation.random(len(t), random_state=rng).as_quat()
    w = rng.normal(scale=0.3, size=(len(t), 3)) * 10.0 ** rng.integers(-6, 1, (len(t), 1))
    return att.Ephemeris.from_arrays(
        t, q, w, body=body, frame="EME2000",
        epoch=Time("2031-07-02T12:34:56.987654321", scale="tdb"))


def _data_lines(path):
    lines = Path(path).read_text().splitlines()
    a, b = lines.index("DATA_START"), lines.index("DATA_STOP")
    return [ln.split() for ln in lines[a + 1:b]]


def _meta(path):
    out = {}
    for ln in Path(path).read_text().splitlines():
        m = re.match(r"^([A-Z_0-9]+)\s*=\s*(.*)$", ln)
        if m:
            out.setdefault(m.group(1), m.group(2).strip())
    return out


def _max_time_error(a: Time, b: Time) -> float:
    return float(np.max(np.abs((a - b).to_value("s"))))


# --- round trips (the acceptance criteria) ------------------------------------
@pytest.mark.parametrize("form", FORMS)
def test_netcdf_aem_netcdf_round_trip(random_eph, body, tmp_path, form):
    """netCDF -> AEM -> netCDF: quaternions to 1e-15, epochs to 1e-9 s."""
    nc = random_eph.to_netcdf(tmp_path / "in.nc")
    out = convert(nc, tmp_path / f"eph{FORMS[form]}", object_name="probe")
    back_nc = convert(out, tmp_path / "back.nc", body=body)
    back = att.Ephemeris.from_netcdf(back_nc)
    ref = random_eph.dataset
    assert np.max(np.abs(back.dataset.quaternion.values - ref.quaternion.values)) <= 1e-15
    np.testing.assert_allclose(back.dataset.angular_velocity.values,
                               ref.angular_velocity.values, rtol=2e-15, atol=0)
    assert _max_time_error(back.times, random_eph.times) <= 1e-9
    assert back.frame == "EME2000" and back.time_scale == "TDB"
    # the body was given: momentum and energy are the original ones
    L, L0 = back.dataset.angular_momentum.values, ref.angular_momentum.values
    assert np.max(np.linalg.norm(L - L0, axis=1) / np.linalg.norm(L0, axis=1)) < 1e-14
    assert back.dataset.attrs["inertia_known"] == 1


@pytest.mark.parametrize("form", FORMS)
@pytest.mark.parametrize("kind", AEM_WRITE_TYPES)
def test_every_attitude_type_round_trips(tumbling, body, tmp_path, kind, form):
    path = write_aem(tumbling, tmp_path / f"eph{FORMS[form]}", attitude_type=kind,
                     euler_rot_seq="ZXZ")
    assert _meta(path)["ATTITUDE_TYPE"] == kind if form == "kvn" else True
    back = read_aem(path, body=body)
    angle = (back.rotation.inv() * tumbling.rotation).magnitude().max()
    # quaternions are written as they are; Euler angles go through degrees and trig
    assert angle <= (1e-15 if kind.startswith("QUATERNION") else 1e-13)
    assert _max_time_error(back.times, tumbling.times) <= 1e-9
    w, w0 = back.dataset.angular_velocity.values, tumbling.dataset.angular_velocity.values
    if kind in ("QUATERNION", "EULER_ANGLE"):
        assert np.all(np.isnan(w))
        assert back.dataset.attrs["angular_velocity_source"] == "not in the AEM (NaN)"
    else:
        np.testing.assert_allclose(w, w0, rtol=1e-13, atol=1e-17)


def test_euler_round_trip_at_gimbal_lock(body, tmp_path):
    """At gimbal lock the angles are not unique, but they still give the rotation."""
    rot = Rotation.from_euler("ZXZ", [[20.0, 0.0, 0.0], [10.0, 180.0, 5.0]], degrees=True)
    eph = att.Ephemeris.from_arrays([0.0, 1.0], rot.as_quat(), np.zeros((2, 3)), body=body,
                                    epoch=Time("2030-01-01", scale="tt"), frame="ICRF")
    back = read_aem(write_aem(eph, tmp_path / "e.aem", attitude_type="EULER_ANGLE/ANGVEL"))
    assert (back.rotation.inv() * rot).magnitude().max() < 1e-13
    with pytest.raises(EphemerisFormatError, match="gimbal lock"):
        write_aem(eph, tmp_path / "d.aem", attitude_type="EULER_ANGLE/DERIVATIVE")


# --- conventions, checked against the standard's definitions ----------------------------
def _m_ba(q1, q2, q3, qc):
    """CCSDS 504.0-B-2 annex F2: X_B = M_BA X_A for the quaternion from A to B."""
    return np.array([
        [q1**2 - q2**2 - q3**2 + qc**2, 2 * (q1 * q2 + q3 * qc), 2 * (q1 * q3 - q2 * qc)],
        [2 * (q1 * q2 - q3 * qc), -q1**2 + q2**2 - q3**2 + qc**2, 2 * (q2 * q3 + q1 * qc)],
        [2 * (q1 * q3 + q2 * qc), 2 * (q2 * q3 - q1 * qc), -q1**2 - q2**2 + q3**2 + qc**2]])


def _passive(axis, deg):
    """Annex F3.2: the frame transformation of one rotation (X_new = C X_old)."""
    c, s = np.cos(np.radians(deg)), np.sin(np.radians(deg))
    return {"X": np.array([[1, 0, 0], [0, c, s], [0, -s, c]]),
            "Y": np.array([[c, 0, -s], [0, 1, 0], [s, 0, c]]),
            "Z": np.array([[c, s, 0], [-s, c, 0], [0, 0, 1]])}[axis]


@pytest.fixture
def turned(body):
    """Body x along inertial +y (turned +90 deg about z), spinning 1 deg/s about body x."""
    q = [[0.0, 0.0, np.sqrt(0.5), np.sqrt(0.5)]]
    return att.Ephemeris.from_arrays(
        [0.0], q, [[np.radians(1.0), 0.0, 0.0]], body=body, frame="ICRF",
        epoch=Time("2030-01-01T00:00:00", scale="tdb"))


def test_written_quaternion_is_the_rotation_from_inertial_a_to_body_b(turned, tmp_path):
    path = write_aem(turned, tmp_path / "e.aem")
    meta = _meta(path)
    assert meta["REF_FRAME_A"] == "ICRF" and meta["REF_FRAME_B"] == "SC_BODY_1"
    epoch, *values = _data_lines(path)[0]
    q1, q2, q3, qc, wx, wy, wz = map(float, values)
    # the annex F2 matrix of the file's quaternion takes inertial (A) coordinates to body
    # (B) coordinates: inertial +y is the body x axis
    np.testing.assert_allclose(_m_ba(q1, q2, q3, qc) @ [0.0, 1.0, 0.0], [1.0, 0.0, 0.0],
                               atol=1e-15)
    assert qc > 0.7                        # scalar last (version 2)
    # angular velocity in deg/s, components in the body frame (ANGVEL_FRAME = REF_FRAME_B)
    assert meta["ANGVEL_FRAME"] == "SC_BODY_1"
    assert (wx, wy, wz) == (1.0, 0.0, 0.0)


def test_angular_velocity_in_frame_a(turned, tmp_path):
    path = write_aem(turned, tmp_path / "e.aem", angvel_frame="REF_FRAME_A")
    assert _meta(path)["ANGVEL_FRAME"] == "ICRF"
    w = np.array(_data_lines(path)[0][5:], dtype=float)
    np.testing.assert_allclose(w, [0.0, 1.0, 0.0], atol=1e-15)    # body x = inertial y
    back = read_aem(path)
    np.testing.assert_allclose(back.dataset.angular_velocity.values[0],
                               [np.radians(1.0), 0.0, 0.0], atol=1e-18)


@pytest.mark.parametrize("seq, angles", [("ZXZ", (30.0, 20.0, 10.0)),
                                         ("XYZ", (10.0, 20.0, 30.0)),     # annex F3.2
                                         ("YXY", (-26.78, 46.26, 144.10))])
def test_euler_angles_follow_annex_f3(body, tmp_path, seq, angles):
    """Build the body frame from the standard's successive frame rotations, then check
    that the file holds exactly those angles."""
    m_ba = np.eye(3)
    for axis, deg in zip(seq, angles):
        m_ba = _passive(axis, deg) @ m_ba          # M_BA = C3 C2 C1
    body_to_inertial = Rotation.from_matrix(m_ba.T)
    eph = att.Ephemeris.from_arrays([0.0], body_to_inertial.as_quat()[None], np.zeros((1, 3)),
                                    body=body, frame="ICRF",
                                    epoch=Time("2030-01-01", scale="tdb"))
    path = write_aem(eph, tmp_path / "e.aem", attitude_type="EULER_ANGLE", euler_rot_seq=seq)
    assert _meta(path)["EULER_ROT_SEQ"] == seq
    np.testing.assert_allclose(np.array(_data_lines(path)[0][1:], dtype=float), angles,
                               atol=1e-12)


def test_version_1_digit_sequences_are_accepted(tumbling, tmp_path):
    path = write_aem(tumbling, tmp_path / "e.aem", attitude_type="EULER_ANGLE",
                     euler_rot_seq="313")
    assert _meta(path)["EULER_ROT_SEQ"] == "ZXZ"


def test_derivatives_match_finite_differences(body, tmp_path):
    """Q_DOT and ANGLE_DOT written from omega agree with central differences of the
    written quaternions and angles (an independent check of q_dot = q omega / 2 and of
    the Euler kinematics)."""
    state = att.AttitudeState(Time("2030-01-01", scale="tdb"),
                              Rotation.from_euler("ZXZ", [20, 50, 30], degrees=True),
                              np.radians([1.0, 0.5, 4.0]), frame="ICRF")
    h = 1e-3
    eph = att.propagate(body, state, [0.0, h, 2 * h], method="integrator")
    for kind, n in (("QUATERNION/DERIVATIVE", 4), ("EULER_ANGLE/DERIVATIVE", 3)):
        rows = np.array([r[1:] for r in _data_lines(
            write_aem(eph, tmp_path / "d.aem", attitude_type=kind))], dtype=float)
        finite = (rows[2, :n] - rows[0, :n]) / (2 * h)
        np.testing.assert_allclose(rows[1, n:], finite, rtol=1e-5, atol=1e-9)


def test_spin_example_of_annex_f5_4(tmp_path):
    """SPIN_ALPHA = 0, SPIN_DELTA = 80, SPIN_ANGLE = 45 deg: the standard gives the
    quaternion 0.0805, 0.0334, 0.9204, 0.3812 and the spin axis 0.1736, 0, 0.9848."""
    text = _v2("ATTITUDE_TYPE = SPIN", ["2024-01-01T00:00:00 0.0 80.0 45.0 6.0"])
    eph = read_aem(_write(tmp_path, text))
    q = eph.dataset.quaternion.values[0]
    np.testing.assert_allclose(q * np.sign(q[3]), [0.0805, 0.0334, 0.9204, 0.3812],
                               atol=6e-5)
    np.testing.assert_allclose(eph.rotation[0].apply([0, 0, 1]), [0.1736, 0.0, 0.9848],
                               atol=6e-5)
    np.testing.assert_allclose(eph.dataset.angular_velocity.values[0],
                               [0.0, 0.0, np.radians(6.0)], atol=1e-15)


# --- files written by others ------------------------------------------------------------
def test_standard_example_g4_version_2(tmp_path):
    eph = read_aem(DATA / "ccsds_504_0_b_2_fig_g4_mgs.aem")
    ds = eph.dataset
    assert (eph.frame, eph.time_scale, len(eph)) == ("EME2000", "UTC", 8)
    assert ds.attrs["epoch"] == "1996-11-28T21:29:07.255500000"
    assert ds.attrs["aem_object_name"] == "MARS_GLOBAL_SURVEYOR"
    assert ds.attrs["body_frame"] == "SC_BODY_1" and ds.attrs["aem_version"] == "2.0"
    assert ds.aem_segment.values.tolist() == [0] * 4 + [1] * 4
    start2 = Time("1996-12-18T12:05:00.5555", scale="utc") - eph.epoch
    assert abs(eph.time[4] - start2.to_value("s")) < 1e-9
    q = np.array([0.56748, 0.03146, 0.45689, 0.68427])
    np.testing.assert_allclose(ds.quaternion.values[0], q / np.linalg.norm(q), atol=1e-15)
    assert np.all(np.isnan(ds.angular_velocity.values))
    # the two segments survive a write and a read
    back = read_aem(write_aem(eph, tmp_path / "mgs.xml"))
    assert back.dataset.aem_segment.values.tolist() == [0] * 4 + [1] * 4
    assert back.dataset.attrs["aem_object_name"] == "MARS_GLOBAL_SURVEYOR"
    assert np.abs(back.dataset.quaternion.values - ds.quaternion.values).max() <= 1e-15
    assert _max_time_error(back.times, eph.times) <= 1e-9


def test_version_1_example_agrees_with_version_2(tmp_path):
    """QUATERNION_TYPE = LAST and ATTITUDE_DIR = A2B of version 1 mean what version 2
    means: the first segment of the two transcriptions is the same."""
    v1 = read_aem(DATA / "orekit_AEMExample_v1_mgs.aem")
    v2 = read_aem(DATA / "ccsds_504_0_b_2_fig_g4_mgs.aem", segment=0)
    assert v1.dataset.attrs["aem_version"] == "1.0"
    np.testing.assert_array_equal(v1.dataset.quaternion.values[:4],
                                  v2.dataset.quaternion.values)
    assert _max_time_error(v1.times[:4], v2.times) == 0.0


def test_spinner_kvn_and_xml_examples_agree():
    kvn = read_aem(DATA / "ccsds_504_0_b_2_fig_g5_st5_spin.aem")
    xml = read_aem(DATA / "ccsds_504_0_b_2_fig_g11_st5_spin.xml")
    assert len(kvn) == 8 and len(xml) == 4 and xml.dataset.attrs["aem_form"] == "XML"
    assert kvn.frame == "J2000" and kvn.dataset.attrs["epoch"].startswith("2006-03-31T05")
    np.testing.assert_array_equal(kvn.dataset.quaternion.values[:4],
                                  xml.dataset.quaternion.values)
    np.testing.assert_array_equal(kvn.dataset.angular_velocity.values[:4],
                                  xml.dataset.angular_velocity.values)
    # annex F5.2: the body z axis (spin axis) points to right ascension alpha, dec. delta
    a, d = np.radians(268.62511), np.radians(68.448486)
    np.testing.assert_allclose(kvn.rotation[0].apply([0, 0, 1]),
                               [np.cos(d) * np.cos(a), np.cos(d) * np.sin(a), np.sin(d)],
                               atol=1e-15)
    assert np.degrees(kvn.dataset.angular_velocity.values[0, 2]) == pytest.approx(-109.96528)


def test_mms_quaternion_and_euler_segments_give_the_same_attitude():
    """GSFC's message gives one MMS attitude history as QUATERNION/ANGVEL and as
    EULER_ANGLE/ANGVEL (ZXZ): intrinsic rotations from A to B make them agree to the
    printed precision (6 decimals), an extrinsic reading would be 48 deg off."""
    path = DATA / "orekit_AEMExample17_gsfc_mms.aem"
    quat = read_aem(path, segment=3)
    euler = read_aem(path, segment=4)
    assert quat.dataset.attrs["aem_attitude_type"] == "QUATERNION/ANGVEL"
    assert euler.dataset.attrs["aem_attitude_type"] == "EULER_ANGLE/ANGVEL"
    assert quat.time_scale == "TAI"
    assert quat.dataset.attrs["epoch"] == "2023-02-23T00:00:09.150001000"
    assert (quat.rotation.inv() * euler.rotation).magnitude().max() < 3e-6
    np.testing.assert_array_equal(quat.dataset.angular_velocity.values,
                                  euler.dataset.angular_velocity.values)
    spin = np.linalg.norm(quat.dataset.angular_velocity.values, axis=1)
    assert np.all(np.abs(spin * 60 / (2 * np.pi) - 3.05) < 0.01)          # ~3 rpm
    for k, kind in enumerate(["EULER_ANGLE/DERIVATIVE", "SPIN/NUTATION_MOM", "QUATERNION"]):
        eph = read_aem(path, segment=k)
        assert eph.dataset.attrs["aem_attitude_type"] == kind
    # the segments overlap in time: reading them all at once is refused, naming the line
    lines = path.read_text().splitlines()
    line = next(i for i, s in enumerate(lines, 1) if s.startswith(
        "2023-01-01T00:00:00.0000  10.00000  30.00000"))
    with pytest.raises(EphemerisFormatError, match=f"line {line}: EPOCH: time goes backwards"):
        read_aem(path)


def test_version_1_scalar_first_b2a_by_hand():
    """tests/data/README.md derives what each line means from the definition of the
    quaternion (the rotation carrying the start frame's axes onto the end frame's)."""
    eph = read_aem(DATA / "v1_first_b2a_handmade.aem")
    rot = eph.rotation
    assert eph.frame == "EME2000" and eph.time_scale == "TAI" and len(eph) == 5
    # line 1: identity; line 2: body x = inertial +y
    np.testing.assert_allclose(rot[0].as_matrix(), np.eye(3), atol=1e-15)
    np.testing.assert_allclose(rot[1].apply([1, 0, 0]), [0, 1, 0], atol=1e-15)
    # line 3: body x, y, z = inertial y, z, x
    np.testing.assert_allclose(rot[2].apply(np.eye(3)), [[0, 1, 0], [0, 0, 1], [1, 0, 0]],
                               atol=1e-15)
    # segment 2 (REF_FRAME_A is the body, A2B, with derivatives): spin about z at 0.01 rad/s
    for k, t in ((3, 180.0), (4, 240.0)):
        assert eph.time[k] == t
        phi = 0.01 * t
        np.testing.assert_allclose(rot[k].apply([1, 0, 0]), [np.cos(phi), np.sin(phi), 0],
                                   atol=1e-15)
        np.testing.assert_allclose(eph.dataset.angular_velocity.values[k], [0, 0, 0.01],
                                   atol=1e-17)
    assert np.all(np.isnan(eph.dataset.angular_velocity.values[:3]))


V1_XML = """<?xml version="1.0" encoding="UTF-8"?>
<aem id="CCSDS_AEM_VERS" version="1.0">
  <header><CREATION_DATE>2025-001T00:00:00</CREATION_DATE><ORIGINATOR>T</ORIGINATOR></header>
  <body>
    <segment>
      <metadata>
        <OBJECT_NAME>HANDMADE</OBJECT_NAME><OBJECT_ID>2025-000A</OBJECT_ID>
        <REF_FRAME_A>EME2000</REF_FRAME_A><REF_FRAME_B>SC_BODY_1</REF_FRAME_B>
        <ATTITUDE_DIR>B2A</ATTITUDE_DIR><TIME_SYSTEM>TT</TIME_SYSTEM>
        <START_TIME>2025-001T00:00:00</START_TIME><STOP_TIME>2025-001T00:00:00</STOP_TIME>
        <ATTITUDE_TYPE>QUATERNION</ATTITUDE_TYPE><QUATERNION_TYPE>FIRST</QUATERNION_TYPE>
      </metadata>
      <data>
        <attitudeState><quaternionState><EPOCH>2025-001T00:00:00</EPOCH>
          <quaternion><QC>0.7071067811865476</QC><Q1>0.0</Q1><Q2>0.0</Q2>
          <Q3>-0.7071067811865476</Q3></quaternion></quaternionState></attitudeState>
      </data>
    </segment>
    <segment>
      <metadata>
        <OBJECT_NAME>HANDMADE</OBJECT_NAME><OBJECT_ID>2025-000A</OBJECT_ID>
        <REF_FRAME_A>EME2000</REF_FRAME_A><REF_FRAME_B>SC_BODY_1</REF_FRAME_B>
        <ATTITUDE_DIR>A2B</ATTITUDE_DIR><TIME_SYSTEM>TT</TIME_SYSTEM>
        <START_TIME>2025-001T00:01:00</START_TIME><STOP_TIME>2025-001T00:01:00</STOP_TIME>
        <ATTITUDE_TYPE>EULER_ANGLE</ATTITUDE_TYPE><EULER_ROT_SEQ>312</EULER_ROT_SEQ>
      </metadata>
      <data>
        <attitudeState><eulerAngle><EPOCH>2025-001T00:01:00</EPOCH><rotationAngles>
          <rotation1 angle="Z_ANGLE" units="deg">90</rotation1>
          <rotation2 angle="X_ANGLE" units="deg">90</rotation2>
          <rotation3 angle="Y_ANGLE" units="deg">0</rotation3>
        </rotationAngles></eulerAngle></attitudeState>
      </data>
    </segment>
  </body>
</aem>
"""


def test_version_1_xml(tmp_path):
    """Version 1 XML: the quaternion components are named, so their order does not
    matter, and B2A inverts (the data carry the body axes onto the inertial ones: -90 deg
    about z, so body x = inertial +y).  Euler 312 with Z 90, X 90 (intrinsic, A onto B):
    by hand R = Rz(90) Rx(90) takes x -> y, y -> z, z -> x."""
    eph = read_aem(_write(tmp_path, V1_XML, "v1.xml"))
    assert eph.time_scale == "TT" and eph.dataset.attrs["aem_version"] == "1.0"
    np.testing.assert_allclose(eph.rotation[0].apply([1, 0, 0]), [0, 1, 0], atol=1e-15)
    np.testing.assert_allclose(eph.rotation[1].apply(np.eye(3)),
                               [[0, 1, 0], [0, 0, 1], [1, 0, 0]], atol=1e-15)


def test_version_1_rate_types_are_read_without_their_rates(tmp_path):
    text = _v1("ATTITUDE_TYPE = QUATERNION/RATE\nQUATERNION_TYPE = LAST\n"
               "RATE_FRAME = REF_FRAME_B",
               ["2024-01-01T00:00:00 0.0 0.0 0.0 1.0 1.0 2.0 3.0"])
    with pytest.warns(AttitudeWarning, match="ambiguous"):
        eph = read_aem(_write(tmp_path, text))
    assert np.all(np.isnan(eph.dataset.angular_velocity.values))


# --- written files: form and content ------------------------------------------------------
def test_kvn_layout_follows_the_standard(tumbling, tmp_path):
    path = write_aem(tumbling, tmp_path / "e.aem", object_name="Apophis", object_id="2004 MN4",
                     center_name="sun", message_id="T-1", comments=["test file"],
                     interpolation_method="HERMITE", interpolation_degree=5)
    lines = path.read_text().splitlines()
    assert lines[0] == "CCSDS_AEM_VERS = 2.0" and lines[1] == "COMMENT test file"
    assert all(len(ln) <= 254 and ln.isascii() for ln in lines)
    keys = [m.group(1) for ln in lines if (m := re.match(r"^([A-Z_0-9]+)\s+=", ln))]
    assert keys == ["CCSDS_AEM_VERS", "CREATION_DATE", "ORIGINATOR", "MESSAGE_ID",
                    "OBJECT_NAME", "OBJECT_ID", "CENTER_NAME", "REF_FRAME_A", "REF_FRAME_B",
                    "TIME_SYSTEM", "START_TIME", "STOP_TIME", "ATTITUDE_TYPE", "ANGVEL_FRAME",
                    "INTERPOLATION_METHOD", "INTERPOLATION_DEGREE"]     # table 4-2, 4-3 order
    meta = _meta(path)
    assert meta["OBJECT_NAME"] == "APOPHIS" and meta["CENTER_NAME"] == "sun"   # 6.8.6
    assert meta["TIME_SYSTEM"] == "TDB" and meta["ATTITUDE_TYPE"] == "QUATERNION/ANGVEL"
    rows = _data_lines(path)
    assert meta["START_TIME"] == rows[0][0] == "2029-04-13T00:00:00.123456789"
    assert meta["STOP_TIME"] == rows[-1][0] == "2029-04-13T00:10:00.123456789"
    number = re.compile(r"^[+-]?\d+\.\d+(e[+-]\d+)?$")                 # 6.8.4
    for row in rows:
        assert len(row) == 8 and re.fullmatch(r"\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d\.\d{9}", row[0])
        for v in row[1:]:
            assert number.match(v) and sum(c.isdigit() for c in v.split("e")[0]) <= 16, v
    assert lines.index("META_START") < lines.index("META_STOP") < lines.index("DATA_START")
    assert lines[-1] == "DATA_STOP"


def test_xml_is_well_formed_and_structured(tumbling, tmp_path):
    path = write_aem(tumbling, tmp_path / "e.xml", attitude_type="QUATERNION/ANGVEL")
    root = ET.parse(path).getroot()
    assert root.tag == "aem" and root.attrib["id"] == "CCSDS_AEM_VERS"
    assert root.attrib["version"] == "2.0"
    assert [c.tag for c in root] == ["header", "body"]
    assert [c.tag for c in root.find("header")] == ["CREATION_DATE", "ORIGINATOR"]
    segment = root.find("body/segment")
    assert [c.tag for c in segment] == ["metadata", "data"]
    meta = [c.tag for c in segment.find("metadata") if c.tag != "COMMENT"]
    assert meta == ["OBJECT_NAME", "OBJECT_ID", "REF_FRAME_A", "REF_FRAME_B", "TIME_SYSTEM",
                    "START_TIME", "STOP_TIME", "ATTITUDE_TYPE", "ANGVEL_FRAME"]
    states = segment.findall("data/attitudeState")
    assert len(states) == len(tumbling)
    state = states[3].find("quaternionAngVel")
    assert [c.tag for c in state] == ["EPOCH", "quaternion", "angVel"]
    assert [c.tag for c in state.find("quaternion")] == ["Q1", "Q2", "Q3", "QC"]
    assert [c.tag for c in state.find("angVel")] == ["ANGVEL_X", "ANGVEL_Y", "ANGVEL_Z"]
    assert {c.attrib["units"] for c in state.find("angVel")} == {"deg/s"}
    q = [float(c.text) for c in state.find("quaternion")]
    assert np.abs(q - tumbling.dataset.quaternion.values[3]).max() <= 1e-16


def test_xml_is_read_by_an_independent_schema_based_parser(tumbling, tmp_path):
    ndm_io = pytest.importorskip("ccsds_ndm.ndm_io")
    for kind in AEM_WRITE_TYPES:
        path = write_aem(tumbling, tmp_path / "e.xml", attitude_type=kind)
        msg = ndm_io.NdmIo().from_path(path)
        seg = msg.body.segment[0]
        assert seg.metadata.attitude_type.value == kind
        states = seg.data.attitude_state
        assert len(states) == len(tumbling)
        if kind == "QUATERNION/ANGVEL":
            s = states[5].quaternion_ang_vel
            q = [s.quaternion.q1, s.quaternion.q2, s.quaternion.q3, s.quaternion.qc]
            assert np.abs(q - tumbling.dataset.quaternion.values[5]).max() <= 1e-16
            w = [s.ang_vel.angvel_x.value, s.ang_vel.angvel_y.value, s.ang_vel.angvel_z.value]
            np.testing.assert_allclose(np.radians(w),
                                       tumbling.dataset.angular_velocity.values[5], rtol=1e-15)


def test_xml_written_by_independent_software_is_read(tmp_path):
    """An AEM built and serialised by ccsds-ndm (its own writer and schema models)."""
    pytest.importorskip("ccsds_ndm")
    from ccsds_ndm.mapping import NDMFileFormats
    from ccsds_ndm.models.ndmxml4 import ndmxml_4_0_0_aem_2_0 as m
    from ccsds_ndm.models.ndmxml4 import ndmxml_4_0_0_common_4_0 as c
    from ccsds_ndm.models.ndmxml4.ndmxml_4_0_0_master_4_0 import Aem
    from ccsds_ndm.ndm_io import NdmIo

    rot = Rotation.from_euler("XYZ", [[10, 20, 30], [11, 21, 31]], degrees=True)
    states = []
    for k, q in enumerate(rot.as_quat().tolist()):
        states.append(c.AttitudeStateType(quaternion_ang_vel=c.QuaternionAngVelType(
            epoch=f"2024-02-29T23:59:5{k}.25",
            quaternion=c.QuaternionType(q1=q[0], q2=q[1], q3=q[2], qc=q[3]),
            ang_vel=c.AngVelType(angvel_x=c.AngVelComponentType(value=1.0),
                                 angvel_y=c.AngVelComponentType(value=-2.0),
                                 angvel_z=c.AngVelComponentType(value=0.5)))))
    meta = m.AemMetadata(object_name="OTHER", object_id="2024-010B", ref_frame_a="GCRF",
                         ref_frame_b="SC_BODY_2", time_system="TT",
                         start_time="2024-02-29T23:59:50.25", stop_time="2024-02-29T23:59:51.25",
                         attitude_type=c.AttitudeTypeType.QUATERNION_ANGVEL_1,
                         angvel_frame="SC_BODY_2")
    msg = Aem(header=c.AdmHeader(creation_date="2024-03-01T00:00:00", originator="OTHER"),
              body=m.AemBody(segment=[m.AemSegment(metadata=meta,
                                                   data=m.AemData(attitude_state=states))]))
    path = tmp_path / "other.xml"
    path.write_text(NdmIo().to_string(msg, NDMFileFormats.XML))
    eph = read_aem(path)
    assert (eph.frame, eph.time_scale, eph.dataset.attrs["body_frame"]) == ("GCRF", "TT",
                                                                           "SC_BODY_2")
    assert (eph.rotation.inv() * rot).magnitude().max() < 1e-15
    np.testing.assert_allclose(eph.dataset.angular_velocity.values[1],
                               np.radians([1.0, -2.0, 0.5]), rtol=1e-15)
    assert eph.time.tolist() == [0.0, 1.0]


# --- time systems ------------------------------------------------------------------------------
def test_time_system_conversion_through_astropy(tumbling, tmp_path):
    path = write_aem(tumbling, tmp_path / "e.aem", time_system="UTC")
    rows = _data_lines(path)
    assert rows[0][0] == tumbling.times[0].utc.isot[:23] + rows[0][0][23:]
    assert abs((Time(rows[0][0], scale="utc") - tumbling.times[0]).to_value("s")) < 1e-9
    back = read_aem(path)
    assert back.time_scale == "UTC"
    assert _max_time_error(back.times, tumbling.times) <= 1e-9


def test_gps_time_is_tai_minus_19_s(body, tmp_path):
    epoch = Time("2024-06-01T00:00:00", scale="tai")
    eph = att.Ephemeris.from_arrays([0.0, 1.0], [[0, 0, 0, 1.0]] * 2, np.zeros((2, 3)),
                                    body=body, frame="ICRF", epoch=epoch)
    path = write_aem(eph, tmp_path / "gps.aem", time_system="GPS")
    assert _data_lines(path)[0][0] == "2024-05-31T23:59:41.000000000"
    back = read_aem(path)
    assert back.time_scale == "TAI" and back.dataset.attrs["aem_time_system"] == "GPS"
    assert _max_time_error(back.times, eph.times) == 0.0
    # written again, it stays GPS
    assert _meta(write_aem(back, tmp_path / "again.aem"))["TIME_SYSTEM"] == "GPS"


def test_leap_second_epochs(body, tmp_path):
    epoch = Time("2016-12-31T23:59:59.5", scale="utc")
    eph = att.Ephemeris.from_arrays([0.0, 1.0, 2.0], [[0, 0, 0, 1.0]] * 3, np.zeros((3, 3)),
                                    body=body, frame="ICRF", epoch=epoch)
    path = write_aem(eph, tmp_path / "leap.aem")
    assert [r[0] for r in _data_lines(path)] == [
        "2016-12-31T23:59:59.500000000", "2016-12-31T23:59:60.500000000",
        "2017-01-01T00:00:00.500000000"]
    assert read_aem(path).time.tolist() == [0.0, 1.0, 2.0]


def test_ut1_conversion_is_refused(tumbling, tmp_path):
    with pytest.raises(EphemerisFormatError, match="UT1"):
        write_aem(tumbling, tmp_path / "e.aem", time_system="UT1")


# --- reading options ---------------------------------------------------------------------------
def test_without_a_body_inertia_is_unknown(tumbling, body, tmp_path):
    path = write_aem(tumbling, tmp_path / "e.aem")
    eph = read_aem(path)
    ds = eph.dataset
    assert ds.attrs["inertia_known"] == 0 and "inertia" not in ds.attrs
    assert np.all(np.isnan(ds.angular_momentum.values))
    assert np.all(np.isnan(ds.kinetic_energy.values))
    with pytest.raises(EphemerisFormatError, match="inertia"):
        eph.body
    with_body = read_aem(path, body=body)
    L = with_body.rotation.apply(ds.angular_velocity.values @ body.inertia.T)
    assert_agree(with_body.dataset.angular_momentum.values, L, ulps=FEW_OPS,
                 magnitude=np.linalg.norm(L, axis=-1, keepdims=True), what="L")
    assert with_body.body.principal_moments.tolist() == body.principal_moments.tolist()
    # the same afterwards: Ephemeris.with_body on what was read without one
    later = eph.with_body(body)
    L = with_body.dataset.angular_momentum.values
    assert_agree(later.dataset.angular_momentum.values, L, ulps=FEW_OPS,
                 magnitude=np.linalg.norm(L, axis=-1, keepdims=True), what="L")
    E = with_body.dataset.kinetic_energy.values
    assert_agree(later.dataset.kinetic_energy.values, E, ulps=FEW_OPS, magnitude=E, what="E")
    assert later.dataset.attrs["inertia_known"] == 1
    assert later.body.principal_moments.tolist() == body.principal_moments.tolist()


def test_angular_velocity_estimated_from_attitudes(body, tmp_path):
    state = att.AttitudeState(Time("2030-01-01", scale="tdb"),
                              Rotation.from_euler("ZXZ", [20, 50, 30], degrees=True),
                              np.radians([1.0, 0.5, 4.0]), frame="ICRF")
    eph = att.propagate(body, state, np.arange(0.0, 20.0, 0.5), method="integrator")
    path = write_aem(eph, tmp_path / "q.aem", attitude_type="QUATERNION")
    est = read_aem(path, angular_velocity="estimate")
    assert "estimated" in est.dataset.attrs["angular_velocity_source"]
    w, w0 = est.dataset.angular_velocity.values, eph.dataset.angular_velocity.values
    err = np.linalg.norm(w - w0, axis=1) / np.linalg.norm(w0, axis=1)
    assert err[1:-1].max() < 1e-4 and err.max() < 2e-2      # central inside, one-sided ends
    with pytest.raises(EphemerisFormatError, match="angular_velocity="):
        read_aem(path, angular_velocity="guess")


def test_segment_selection(tmp_path):
    path = DATA / "ccsds_504_0_b_2_fig_g4_mgs.aem"
    second = read_aem(path, segment=1)
    assert len(second) == 4 and second.dataset.aem_segment.values.tolist() == [1] * 4
    assert second.dataset.attrs["epoch"] == "1996-12-18T12:05:00.555500000"
    both = read_aem(path, segment=[0, 1])
    assert len(both) == 8
    with pytest.raises(EphemerisFormatError, match="has 2 segment"):
        read_aem(path, segment=2)


def test_segments_may_touch_but_not_overlap(tmp_path):
    seg = _segment("2024-01-01T00:01:00 0.0 0.0 0.0 1.0 0.0 0.0 0.0",
                   "2024-01-01T00:02:00 0.0 0.0 0.0 1.0 0.0 0.0 0.0")
    text = _v2("ATTITUDE_TYPE = QUATERNION/ANGVEL\nANGVEL_FRAME = SC_BODY_1",
               ["2024-01-01T00:00:00 0.0 0.0 0.0 1.0 0.0 0.0 0.0",
                "2024-01-01T00:01:00 0.0 0.0 0.0 1.0 0.0 0.0 0.0"]) + seg
    eph = read_aem(_write(tmp_path, text))
    assert eph.time.tolist() == [0.0, 60.0, 60.0, 120.0]
    assert eph.dataset.aem_segment.values.tolist() == [0, 0, 1, 1]


def test_combined_ndm_with_one_aem(tmp_path, tumbling):
    inner = write_aem(tumbling, tmp_path / "e.xml").read_text().split("\n", 1)[1]
    text = '<?xml version="1.0" encoding="UTF-8"?>\n<ndm>\n' + inner + "</ndm>\n"
    eph = read_aem(_write(tmp_path, text, "ndm.xml"))
    assert len(eph) == len(tumbling)


# --- convert -------------------------------------------------------------------------------------
def test_convert_dispatches_on_suffix(tumbling, body, tmp_path):
    nc = tumbling.to_netcdf(tmp_path / "e.nc")
    xml = convert(nc, tmp_path / "e.xml", object_id="2029-001A", attitude_type="QUATERNION")
    assert xml.read_text().startswith("<?xml")
    kvn = convert(xml, tmp_path / "e.aem", body=body, attitude_type="EULER_ANGLE")
    assert _meta(kvn)["OBJECT_ID"] == "2029-001A"
    with pytest.raises(EphemerisFormatError, match="unknown output format"):
        convert(nc, tmp_path / "e.csv")
    with pytest.raises(EphemerisFormatError, match="not a netCDF file"):
        convert(nc, tmp_path / "e.aem", segment=0)
    with pytest.raises(EphemerisFormatError, match="not a netCDF file"):
        convert(kvn, tmp_path / "back.nc", object_name="x")


# --- writer errors -------------------------------------------------------------------------------
def test_writer_refuses_what_an_aem_cannot_hold(tumbling, body, tmp_path):
    batch = att.propagate([body, body], [tumbling_state(), tumbling_state()], [0.0, 1.0],
                          method="integrator")
    with pytest.raises(EphemerisFormatError, match="batch"):
        write_aem(batch, tmp_path / "b.aem")
    with pytest.raises(EphemerisFormatError, match="relabel"):
        write_aem(tumbling, tmp_path / "e.aem", ref_frame_a="EME2000")
    with pytest.raises(EphemerisFormatError, match="REF_FRAME_B"):
        write_aem(tumbling, tmp_path / "e.aem", ref_frame_b="ICRF")
    with pytest.raises(EphemerisFormatError, match="cannot tell the AEM form"):
        write_aem(tumbling, tmp_path / "e.dat")
    with pytest.raises(EphemerisFormatError, match="write one of"):
        write_aem(tumbling, tmp_path / "e.aem", attitude_type="SPIN")
    with pytest.raises(EphemerisFormatError, match="printable ASCII"):
        write_aem(tumbling, tmp_path / "e.aem", object_name="Ω-sat")
    with pytest.raises(EphemerisFormatError, match="together"):
        write_aem(tumbling, tmp_path / "e.aem", interpolation_method="LAGRANGE")
    with pytest.raises(EphemerisFormatError, match="non-negative integer"):
        write_aem(tumbling, tmp_path / "e.aem", interpolation_method="LAGRANGE",
                  interpolation_degree="seven")
    assert not list(tmp_path.glob("e.*"))             # nothing half-written


def test_no_rates_means_quaternion_by_default(tumbling, tmp_path):
    path = write_aem(tumbling, tmp_path / "q.aem", attitude_type="QUATERNION")
    no_rates = read_aem(path)
    assert _meta(write_aem(no_rates, tmp_path / "again.aem"))["ATTITUDE_TYPE"] == "QUATERNION"
    with pytest.raises(EphemerisFormatError, match="needs the angular velocity"):
        write_aem(no_rates, tmp_path / "w.aem", attitude_type="QUATERNION/ANGVEL")


def tumbling_state():
    return att.AttitudeState(Time("2030-01-01", scale="tdb"), Rotation.identity(),
                             [0.0, 0.1, 0.2], frame="ICRF")


# --- reader errors: each names the line and the keyword -------------------------------------------
_HEADER = "CCSDS_AEM_VERS = 2.0\nCREATION_DATE = 2024-01-01T00:00:00\nORIGINATOR = TEST\n"
_META = ("OBJECT_NAME = SAT\nOBJECT_ID = 2024-001A\nREF_FRAME_A = ICRF\n"
         "REF_FRAME_B = SC_BODY_1\nTIME_SYSTEM = UTC\nSTART_TIME = 2024-01-01T00:00:00\n"
         "STOP_TIME = 2024-01-01T00:02:00\n")


def _segment(*rows, meta=_META, kind="ATTITUDE_TYPE = QUATERNION/ANGVEL\n"
             "ANGVEL_FRAME = SC_BODY_1"):
    return ("\nMETA_START\n" + meta + kind + "\nMETA_STOP\n\nDATA_START\n"
            + "".join(r + "\n" for r in rows) + "DATA_STOP\n")


def _v2(kind, rows, meta=_META):
    return _HEADER + _segment(*rows, meta=meta, kind=kind)


def _v1(kind, rows):
    return (_HEADER.replace("2.0", "1.0")
            + _segment(*rows, meta=_META + "ATTITUDE_DIR = A2B\n", kind=kind))


def _write(tmp_path, text, name="t.aem"):
    path = tmp_path / name
    path.write_text(text)
    return path


# A valid file; line numbers:  1 CCSDS_AEM_VERS, 5 META_START, 6 OBJECT_NAME, 7 OBJECT_ID,
# 8 REF_FRAME_A, 10 TIME_SYSTEM, 13 ATTITUDE_TYPE, 14 ANGVEL_FRAME, 15 META_STOP,
# 17 DATA_START, 18-20 data, 21 DATA_STOP.
VALID = _v2("ATTITUDE_TYPE = QUATERNION/ANGVEL\nANGVEL_FRAME = SC_BODY_1",
            ["2024-01-01T00:00:00 0.0 0.0 0.0 1.0 0.1 0.2 0.3",
             "2024-01-01T00:01:00 0.0 0.0 0.6 0.8 0.1 0.2 0.3",
             "2024-01-01T00:02:00 0.6 0.0 0.0 0.8 0.1 0.2 0.3"])


def _edit(line: int, new: str | None) -> str:
    lines = VALID.splitlines()
    if new is None:
        del lines[line - 1]
    else:
        lines[line - 1] = new
    return "\n".join(lines) + "\n"


def test_valid_template_reads(tmp_path):
    lines = VALID.splitlines()
    assert lines[12] == "ATTITUDE_TYPE = QUATERNION/ANGVEL" and lines[20] == "DATA_STOP"
    eph = read_aem(_write(tmp_path, VALID))
    assert len(eph) == 3 and eph.frame == "ICRF"


BAD_FILES = [
    # (line, new text, expected line, keyword, message fragment)
    (1, "CCSDS_AEM_VERS = 3.0", 1, "CCSDS_AEM_VERS", "version '3.0' is not supported"),
    (1, "CCSDS_OEM_VERS = 2.0", 1, "CCSDS_AEM_VERS", "CCSDS OEM message"),
    (3, "", 5, "ORIGINATOR", "mandatory header keyword missing"),
    (7, "", 15, "OBJECT_ID", "mandatory keyword missing"),
    (10, "TIME_SYSTEM = MET", 10, "TIME_SYSTEM", "'MET' is not supported"),
    (8, "REF_FRAME_A = LVLH", 8, "REF_FRAME_A", "neither of them is an inertial frame"),
    (9, "REF_FRAME_B = EME2000", 8, "REF_FRAME_A", "both of them"),
    (13, "ATTITUDE_TYPE = QUATERNIONS", 13, "ATTITUDE_TYPE",
     "'QUATERNIONS' is not an AEM version 2.0 attitude type"),
    (13, "ATTITUDE_TYPE = QUATERNION/RATE", 13, "ATTITUDE_TYPE", "version 1.0 type"),
    (14, "QUATERNION_TYPE = LAST", 14, "QUATERNION_TYPE", "version 1.0 keyword"),
    (14, "FOO = 1", 14, "FOO", "not an AEM version 2.0 metadata keyword"),
    (14, "OBJECT_NAME = AGAIN", 14, "OBJECT_NAME", "appears twice"),
    (14, "", 15, "ANGVEL_FRAME", "mandatory for ATTITUDE_TYPE"),
    (14, "ANGVEL_FRAME = INSTRUMENT_A", 14, "ANGVEL_FRAME", "third frame"),
    (17, "", 18, "DATA_START", "data line without DATA_START"),
    (18, "24-01-01T00:00:00 0.0 0.0 0.0 1.0 0.1 0.2 0.3", 18, "EPOCH",
     "is not a CCSDS time"),
    (18, "2024-13-01T00:00:00 0.0 0.0 0.0 1.0 0.1 0.2 0.3", 18, "EPOCH",
     "is not a valid time"),
    (19, "2024-01-01T00:01:00 0.0 0.0 0.6 0.9 0.1 0.2 0.3", 19, "Q1 Q2 Q3 QC",
     r"norm 1.08166538, not 1 within 1e-05"),
    (19, "2024-01-01T00:01:00 0.0 0.0 0.6 O.8 0.1 0.2 0.3", 19, "QC", "'O.8' is not a number"),
    (19, "2024-01-01T00:01:00 nan 0.0 0.6 0.8 0.1 0.2 0.3", 19, "Q1", "NaN and infinities"),
    (19, "2024-01-01T00:01:00 0.0 0.0 0.6 0.8 0.1 0.2", 19, "QUATERNION/ANGVEL",
     "a data line needs 8 fields"),
    (20, "2024-01-01T00:00:30 0.6 0.0 0.0 0.8 0.1 0.2 0.3", 20, "EPOCH",
     "time goes back from the previous data line"),
    (20, "2024-01-01T00:01:00 0.6 0.0 0.0 0.8 0.1 0.2 0.3", 20, "EPOCH", "time repeats"),
    (20, "META_START", 20, "META_START", "expected a data line or DATA_STOP"),
    (21, None, 20, "DATA_STOP", "missing at the end of the file"),
]


@pytest.mark.parametrize("line, new, at, keyword, message", BAD_FILES)
def test_bad_kvn_files_name_line_and_keyword(tmp_path, line, new, at, keyword, message):
    path = _write(tmp_path, _edit(line, new))
    with pytest.raises(EphemerisFormatError,
                       match=f"t.aem, line {at}: {re.escape(keyword)}: .*{message}") as info:
        read_aem(path)
    assert (info.value.line, info.value.keyword) == (at, keyword)


def test_euler_metadata_errors(tmp_path):
    rows = ["2024-01-01T00:00:00 10.0 20.0 30.0"]
    with pytest.raises(EphemerisFormatError, match="line 14: EULER_ROT_SEQ: mandatory"):
        read_aem(_write(tmp_path, _v2("ATTITUDE_TYPE = EULER_ANGLE", rows)))
    with pytest.raises(EphemerisFormatError, match="line 14: EULER_ROT_SEQ: 'ZZX'"):
        read_aem(_write(tmp_path, _v2("ATTITUDE_TYPE = EULER_ANGLE\nEULER_ROT_SEQ = ZZX",
                                      rows)))


def test_version_1_errors(tmp_path):
    rows = ["2024-01-01T00:00:00 1.0 0.0 0.0 0.0"]
    with pytest.raises(EphemerisFormatError, match="line 15: QUATERNION_TYPE: mandatory"):
        read_aem(_write(tmp_path, _v1("ATTITUDE_TYPE = QUATERNION", rows)))
    with pytest.raises(EphemerisFormatError, match="line 15: ANGVEL_FRAME: is an AEM "
                                                   "version 2.0 keyword"):
        read_aem(_write(tmp_path, _v1("ATTITUDE_TYPE = QUATERNION\nANGVEL_FRAME = X", rows)))
    missing_dir = _v1("ATTITUDE_TYPE = QUATERNION\nQUATERNION_TYPE = FIRST", rows).replace(
        "ATTITUDE_DIR = A2B\n", "")
    with pytest.raises(EphemerisFormatError, match="line 15: ATTITUDE_DIR: mandatory"):
        read_aem(_write(tmp_path, missing_dir))


def _line(text: str, start: str, nth: int = 1) -> int:
    """Number of the nth line of ``text`` that starts with ``start``."""
    hits = [i for i, s in enumerate(text.splitlines(), 1) if s.strip().startswith(start)]
    return hits[nth - 1]


def test_segments_going_backwards_or_changing_frames(tmp_path):
    text = VALID + _segment("2023-12-31T00:00:00 0.0 0.0 0.0 1.0 0.0 0.0 0.0")
    at = _line(text, "2023-12-31T00:00:00")
    with pytest.raises(EphemerisFormatError, match=f"line {at}: EPOCH: time goes backwards"):
        read_aem(_write(tmp_path, text))
    text = VALID + _segment("2024-01-02T00:00:00 0.0 0.0 0.0 1.0 0.0 0.0 0.0",
                            meta=_META.replace("ICRF", "EME2000"))
    at = _line(text, "REF_FRAME_A", 2)
    with pytest.raises(EphemerisFormatError, match=f"line {at}: REF_FRAME_A: inertial frame "
                                                   "EME2000 differs from ICRF"):
        read_aem(_write(tmp_path, text))


def _xml(tmp_path, tumbling, old, new, count=1):
    """The written XML with the regular expression ``old`` replaced."""
    text = write_aem(tumbling, tmp_path / "ok.xml").read_text()
    bad, n = re.subn(old, new, text, count=count)
    assert n == count
    return _write(tmp_path, bad, "bad.xml"), text


def test_bad_xml_files_name_line_and_element(tmp_path, tumbling):
    path, text = _xml(tmp_path, tumbling, "</STOP_TIME>", "</STOP>")
    at = _line(text, "<STOP_TIME>")
    with pytest.raises(EphemerisFormatError, match=f"bad.xml, line {at}: XML: not well-formed"):
        read_aem(path)
    path, text = _xml(tmp_path, tumbling, 'version="2.0"', 'version="3.0"')
    with pytest.raises(EphemerisFormatError, match=r"line 2: CCSDS_AEM_VERS: version '3.0'"):
        read_aem(path)
    path, text = _xml(tmp_path, tumbling, '<ANGVEL_Z units="deg/s">[^<]*</ANGVEL_Z>', "")
    at = _line(text, "<attitudeState>")
    with pytest.raises(EphemerisFormatError, match=f"line {at}: ANGVEL_Z: missing from "
                                                   "<quaternionAngVel>"):
        read_aem(path)
    path, text = _xml(tmp_path, tumbling, 'ANGVEL_X units="deg/s"', 'ANGVEL_X units="rad/s"')
    with pytest.raises(EphemerisFormatError, match=f"line {at}: ANGVEL_X: units='rad/s'"):
        read_aem(path)
    path, text = _xml(tmp_path, tumbling, "quaternionAngVel>", "eulerAngle>", 2)
    with pytest.raises(EphemerisFormatError, match=f"line {at}: QUATERNION/ANGVEL: "
                                                   "<attitudeState> must hold one"):
        read_aem(path)
    path, text = _xml(tmp_path, tumbling, "<OBJECT_ID>UNKNOWN</OBJECT_ID>", "")
    at = _line(text, "<metadata>")
    with pytest.raises(EphemerisFormatError, match=f"line {at}: OBJECT_ID: mandatory"):
        read_aem(path)
    with pytest.raises(EphemerisFormatError, match=r"line 2: ndm: a combined NDM"):
        read_aem(_write(tmp_path, "<?xml version='1.0'?>\n<ndm>\n</ndm>\n", "bad.xml"))
    with pytest.raises(EphemerisFormatError, match="DOCTYPE"):
        read_aem(_write(tmp_path, "<?xml version='1.0'?>\n<!DOCTYPE aem [<!ENTITY a 'b'>]>"
                        "\n<aem/>\n", "bad.xml"))


def test_missing_file(tmp_path):
    with pytest.raises(EphemerisFormatError, match="no such file"):
        read_aem(tmp_path / "nothing.aem")


def test_data_outside_start_stop_time_warns(tmp_path):
    text = VALID.replace("STOP_TIME = 2024-01-01T00:02:00", "STOP_TIME = 2024-01-01T00:01:00")
    with pytest.warns(AttitudeWarning, match="line 12: STOP_TIME"):
        read_aem(_write(tmp_path, text))


# --- numbers ---------------------------------------------------------------------------------
@settings(max_examples=300, deadline=None)
@given(st.floats(allow_nan=False, allow_infinity=False, min_value=-1e300, max_value=1e300))
def test_numbers_have_at_most_16_digits_and_read_back(x):
    s = aem_message._fmt(x)
    mantissa = s.split("e")[0]
    assert re.fullmatch(r"-?\d+\.\d+", mantissa) and sum(c.isdigit() for c in mantissa) <= 16
    y = float(s)
    assert y == x or abs(y - x) <= 5.6e-16 * abs(x)


def test_chunked_writing_keeps_every_line(tumbling, tmp_path, monkeypatch):
    monkeypatch.setattr(aem_message, "_CHUNK", 3)
    path = write_aem(tumbling, tmp_path / "e.aem")
    epochs = [r[0] for r in _data_lines(path)]
    expected = tumbling.times.copy()
    expected.precision = 9
    assert epochs == list(expected.isot)
    assert _max_time_error(read_aem(path).times, tumbling.times + TimeDelta(0, format="sec")
                           ) <= 1e-9


# --- output frozen before the writer was split into steps ------------------------------
@pytest.mark.parametrize("name", ["written_by_attitude_0_3.aem", "written_by_attitude_0_3.xml",
                                  "written_by_attitude_0_3_q.aem"])
def test_output_is_byte_identical_to_the_frozen_files(tmp_path, name):
    """Files written by the writer before its refactoring (tests/data/README.md): the same
    ephemeris and options give the same bytes, except the CREATION_DATE (now)."""
    out = write_aem(frozen_ephemeris(), tmp_path / name, **CASES[name])
    stamp = re.compile(rb"(CREATION_DATE\s*[=>]\s*)\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d")
    expected = stamp.sub(rb"\1<now>", (DATA / name).read_bytes())
    assert stamp.sub(rb"\1<now>", out.read_bytes()) == expected
    back = read_aem(out)                 # and it reads back to the same attitudes
    np.testing.assert_array_equal(back.dataset.quaternion.values,
                                  frozen_ephemeris().dataset.quaternion.values)


def test_a_crash_while_writing_leaves_no_file_and_keeps_the_old_one(tumbling, tmp_path,
                                                                    monkeypatch):
    """The data lines fail half-way (the header is already written): no AEM, no temporary
    file, and a file already at the destination is untouched."""
    real = aem_write.format_epoch
    calls = {"n": 0}

    def failing(times, digits=9):
        calls["n"] += 1
        if calls["n"] > 2:             # START_TIME and STOP_TIME pass, the data fail
            raise KeyboardInterrupt("simulated crash")
        return real(times, digits)

    monkeypatch.setattr(aem_write, "format_epoch", failing)      # START/STOP_TIME
    monkeypatch.setattr(aem_message, "format_epoch", failing)    # the data lines
    with pytest.raises(KeyboardInterrupt):
        write_aem(tumbling, tmp_path / "crash.aem")
    assert list(tmp_path.iterdir()) == []
    (tmp_path / "crash.xml").write_text("old")
    calls["n"] = 0
    with pytest.raises(KeyboardInterrupt):
        write_aem(tumbling, tmp_path / "crash.xml")
    assert [p.name for p in tmp_path.iterdir()] == ["crash.xml"]
    assert (tmp_path / "crash.xml").read_text() == "old"


def test_errors_take_the_one_error_shape(tmp_path):
    path = _write(tmp_path, "CCSDS_AEM_VERS = 3.0\n", "v3.aem")
    with pytest.raises(EphemerisFormatError) as info:
        read_aem(path)
    err = info.value
    assert (err.key, err.path, err.line) == ("CCSDS_AEM_VERS", str(path), 1)
    assert str(err) == f"{path}, line 1: CCSDS_AEM_VERS: {err.reason}"
    assert err.reason.startswith("version '3.0' is not supported")

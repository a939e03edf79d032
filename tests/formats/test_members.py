"""One body of a batch or binary file, written where one object goes: Ephemeris.member,
``attitude convert --body NAME|I`` to CCSDS AEM and to a SPICE C-kernel, read back."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import attitude as att
from attitude.app.cli import main
from attitude.formats.aem import read_aem


@pytest.fixture(scope="module")
def binary_file(tmp_path_factory):
    ball = att.RigidBody.from_mass_properties(att.MassProperties.solid_sphere(5e11, 400.0),
                                              name="Didymos")
    egg = att.RigidBody.from_mass_properties(
        att.MassProperties.solid_ellipsoid(4.3e9, [103.16, 79.35, 66.13]), name="Dimorphos")
    system = att.BinarySystem(ball, egg)
    n = np.sqrt(system.mu / 1190.0**3)
    state = att.BinaryState("2026-12-01", [1190.0, 0, 0], [0, n * 1190.0, 0],
                            Rotation.from_euler("x", 5.0, degrees=True), [0, 0, 7.7e-4],
                            Rotation.from_euler("z", 15.0, degrees=True), [0, 0, n])
    eph = att.propagate(system, state, np.linspace(0.0, 7200.0, 25), method="integrator",
                        rtol=1e-10)
    return eph, eph.to_netcdf(tmp_path_factory.mktemp("binary") / "binary.nc")


def test_member_by_name_and_index_carries_its_mass_properties(binary_file):
    eph, _ = binary_file
    second = eph.member("secondary")
    assert not second.is_batch
    assert eph.member(1).dataset.identical(second.dataset)
    assert eph.member("Dimorphos").dataset.identical(second.dataset)     # its body_name
    body = second.body
    assert body.name == "Dimorphos" and body.mass == pytest.approx(4.3e9, rel=1e-15)
    np.testing.assert_array_equal(second.dataset.quaternion.values,
                                  eph.dataset.quaternion.values[1])
    np.testing.assert_allclose(body.principal_moments,
                               eph.dataset.principal_moments.values[1], rtol=0, atol=0)
    with pytest.raises(att.EphemerisFormatError,
                       match="names Didymos, Dimorphos, primary, secondary"):
        eph.member("moon")
    with pytest.raises(att.EphemerisFormatError, match="indices 0..1"):
        eph.member(2)


def test_convert_body_to_aem_round_trip(binary_file, tmp_path, capsys):
    eph, nc = binary_file
    out = tmp_path / "dimorphos.aem"
    assert main(["convert", str(nc), str(out), "--body", "secondary"]) == 0
    back = read_aem(out)
    truth = eph.member("secondary")
    angle = (back.rotation * truth.rotation.inv()).magnitude()
    assert angle.max() < 1e-12          # the AEM's 16 digits: a few ulps of the quaternion
    # without --body: one line that says how
    assert main(["convert", str(nc), str(tmp_path / "x.aem")]) == 2
    assert "--body NAME|INDEX" in capsys.readouterr().err


def test_convert_body_to_ck_round_trip(binary_file, tmp_path):
    pytest.importorskip("spiceypy", reason="the optional extra 'spice'")
    eph, nc = binary_file
    ck = tmp_path / "didymos.bc"
    assert main(["convert", str(nc), str(ck), "--body", "primary", "--object-id", "-658"]) == 0
    back = att.Ephemeris.from_spice(ck, ck.with_suffix(".tsc"), ck.with_suffix(".tls"),
                                    "J2000")
    truth = eph.member("primary")
    angle = (back.rotation * truth.rotation.inv()).magnitude()
    assert len(back) == len(truth) and angle.max() < 1e-12

"""``attitude classify EPH.nc --body SCENARIO.toml`` / ``--inertia``: the body of an
ephemeris that carries none (read from a CCSDS AEM or a SPICE CK)."""

import json

import numpy as np
import pytest
from astropy.time import Time
from scipy.spatial.transform import Rotation

import attitude as att
from attitude.app.cli import main
from attitude.formats.aem import read_aem, write_aem

MOMENTS = [0.61, 0.965, 1.0]

SCENARIO = """
[scenario]
name = "the body"

[body]
principal_moments = { value = [0.61, 0.965, 1.0], unit = "kg m2" }

[state]
epoch = "2030-01-01T00:00:00"
omega_body = { value = [1.0, 0.0, 3.0], unit = "deg/s" }

[propagation]
duration = "1 h"
step = "1 min"
"""


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """The same motion with its body (``with.nc``) and without (``without.nc``, through
    an AEM), and the classification of the first."""
    folder = tmp_path_factory.mktemp("classify")
    body = att.RigidBody.from_principal_moments(MOMENTS)
    state = att.AttitudeState(Time("2030-01-01T00:00:00", scale="tdb"),
                              Rotation.from_euler("ZXZ", [0.3, 1.1, -0.7]),
                              [0.02, 0.003, 0.05], frame="ICRF")
    eph = att.propagate(body, state, np.arange(0.0, 12000.0, 20.0))
    eph.to_netcdf(folder / "with.nc")
    write_aem(eph, folder / "eph.aem")
    read_aem(folder / "eph.aem").to_netcdf(folder / "without.nc")
    (folder / "body.toml").write_text(SCENARIO)
    return folder, att.classify(eph)


def classify_json(capsys, *args):
    capsys.readouterr()
    code = main(["classify", *map(str, args), "--json"])
    out, err = capsys.readouterr()
    return code, (json.loads(out) if code == 0 else None), err


def same_classification(got, want):
    assert got["regime"] == want.regime
    assert set(got["periods"]) == set(want.periods)
    for key, period in want.periods.items():
        # the AEM keeps the quaternions to 1e-16 and rates to 17 digits
        assert got["periods"][key] == pytest.approx(period, rel=1e-9)


def test_without_a_body_the_message_says_how_to_give_one(files, capsys):
    folder, _ = files
    code, _, err = classify_json(capsys, folder / "without.nc")
    assert code == 2
    assert len(err.strip().splitlines()) == 1 and "without.nc" in err
    assert "--body SCENARIO.toml" in err and "--inertia" in err


@pytest.mark.parametrize("option", [
    ["--inertia", "0.61,0.965,1.0"],
    ["--inertia", "[0.61, 0, 0, 0, 0.965, 0, 0, 0, 1.0]"],   # the tensor, row-major
    ["--inertia", "6.1e-7,9.65e-7,1e-6 kg km2"],             # a unit
    ["--body", "body.toml"],
])
def test_the_given_body_classifies_as_the_original(files, capsys, option):
    folder, want = files
    if option[0] == "--body":
        option = ["--body", folder / option[1]]
    code, got, err = classify_json(capsys, folder / "without.nc", *option)
    assert code == 0, err
    same_classification(got, want)
    # L^2 / 2E in kg m2: the moments were read in SI whatever their unit
    assert got["dynamic_inertia"] == pytest.approx(want.dynamic_inertia, rel=1e-12)


def test_the_given_body_replaces_the_files(files, capsys):
    """An ephemeris with a body: --inertia replaces it (here twice the moments: the same
    periods, twice L^2/2E)."""
    folder, want = files
    code, got, err = classify_json(capsys, folder / "with.nc", "--inertia", "1.22,1.93,2.0")
    assert code == 0, err
    same_classification(got, want)
    assert got["dynamic_inertia"] == pytest.approx(2 * want.dynamic_inertia, rel=1e-12)


@pytest.mark.parametrize("option, message", [
    (["--inertia", "1,2"], "3 principal moments"),
    (["--inertia", "a,b,c"], "3 principal moments"),
    (["--inertia", "1,2,3 m/s"], "--inertia"),
    (["--inertia", "1,1,5"], "triangle"),                     # not a physical body
    (["--inertia", "1,2,3", "--body", "body.toml"], "not both"),
    (["--body", "missing.toml"], "no such file"),
])
def test_bad_bodies_exit_2_with_one_line(files, capsys, option, message):
    folder, _ = files
    option = [folder / o if str(o).endswith(".toml") else o for o in option]
    code, _, err = classify_json(capsys, folder / "without.nc", *option)
    assert code == 2
    assert len(err.strip().splitlines()) == 1 and message in err, err
    assert "Traceback" not in err


def test_an_ensemble_scenario_has_no_single_body(files, capsys):
    folder, _ = files
    ensemble = folder / "ensemble.toml"
    ensemble.write_text(SCENARIO.replace(
        "[body]\nprincipal_moments = { value = [0.61, 0.965, 1.0], unit = \"kg m2\" }\n", "")
        + '\n[ensemble]\nsize = 4\nseed = 1\nprincipal_moments = [0.61, 0.965, 1.0]\n')
    code, _, err = classify_json(capsys, folder / "without.nc", "--body", ensemble)
    assert code == 2 and len(err.strip().splitlines()) == 1
    assert "ensemble" in err


def test_a_ck_is_converted_first(tmp_path, capsys):
    ck = tmp_path / "mission.bc"
    ck.write_bytes(b"DAF/CK  " + bytes(1016))
    code, _, err = classify_json(capsys, ck)
    assert code == 2 and "attitude convert" in err and "--inertia" in err

"""The ``attitude`` command: exit codes, one-line errors, outputs (run as a real
subprocess through the installed console script or ``python -m attitude``)."""

import json
import subprocess
import sys
from pathlib import Path

import pytest

from tests.app.test_scenario import GOOD, write

ROOT = Path(__file__).resolve().parents[2]


def attitude(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "attitude", *map(str, args)],
                          capture_output=True, text=True, cwd=cwd)


def test_run_prints_summary_and_writes_outputs(tmp_path):
    path = write(tmp_path, GOOD)
    out = tmp_path / "other.nc"
    report = tmp_path / "r.json"
    proc = attitude("run", path, "-o", out, "--report", report)
    assert proc.returncode == 0, proc.stderr
    assert "regime SAM" in proc.stdout and f"Wrote      {out}" in proc.stdout
    assert out.is_file() and not (tmp_path / "out.nc").exists()
    data = json.loads(report.read_text())
    assert data["scenario"] == "test body" and data["outputs"] == [str(out)]


@pytest.mark.parametrize("text", [
    GOOD.replace("[1.0, 2.0, 3.0]", "[1.0, 1.0, 3.0]"),      # non-physical body
    GOOD.replace('"10 s"', '"10 furlongs"'),                  # unparseable unit
    GOOD.replace('step = "10 s"', ""),                        # missing key
    GOOD.replace("[state]", "[state]\nspin = 3"),             # unknown key
    "this is not toml",
])
def test_bad_scenarios_exit_2_with_one_line(tmp_path, text):
    path = write(tmp_path, text)
    proc = attitude("run", path)
    assert proc.returncode == 2
    assert proc.stdout == ""
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and str(path) in lines[0], proc.stderr
    assert "Traceback" not in proc.stderr


def test_failed_expectation_exits_1(tmp_path):
    path = write(tmp_path, GOOD + '\n[expect]\nregime = "LAM"\n')
    proc = attitude("run", path, "--quiet")
    assert proc.returncode == 1
    proc = attitude("run", tmp_path / "missing.toml")
    assert proc.returncode == 2 and "no such file" in proc.stderr


def test_help_teaches_with_an_example():
    proc = attitude("run", "--help")
    assert proc.returncode == 0 and "attitude run scenarios/" in proc.stdout


@pytest.mark.slow      # every shipped scenario in a subprocess (CI also runs attitude check)
def test_shipped_scenarios_run(tmp_path):
    for path in sorted((ROOT / "scenarios").glob("*.toml")):
        proc = attitude("run", path, "-o", tmp_path / (path.stem + ".nc"), "--quiet")
        assert proc.returncode == 0, (path, proc.stderr)


def test_convert_round_trip_through_aem_kvn_and_xml(tmp_path):
    """netCDF -> AEM KVN -> AEM XML -> netCDF from the command line keeps the quaternions
    to 1e-15 (CCSDS 504.0-B-2 allows 16 significant digits)."""
    import numpy as np

    import attitude as att

    nc = tmp_path / "a.nc"
    assert attitude("run", write(tmp_path, GOOD), "-o", nc, "--quiet").returncode == 0
    for src, dst in (("a.nc", "a.aem"), ("a.aem", "a.xml"), ("a.xml", "b.nc")):
        options = [] if dst.endswith(".nc") else ["--object-id", "TEST-1"]
        proc = attitude("convert", tmp_path / src, tmp_path / dst, *options)
        assert proc.returncode == 0, proc.stderr
    assert "CCSDS_AEM_VERS = 2.0" in (tmp_path / "a.aem").read_text()
    a, b = att.Ephemeris.from_netcdf(nc), att.Ephemeris.from_netcdf(tmp_path / "b.nc")
    np.testing.assert_allclose(b.dataset.quaternion, a.dataset.quaternion, rtol=0, atol=1e-15)
    np.testing.assert_allclose(b.time, a.time, rtol=0, atol=1e-9)


def test_convert_bad_input_exits_2(tmp_path):
    bad = tmp_path / "bad.aem"
    bad.write_text("CCSDS_AEM_VERS = 9.9\n")
    proc = attitude("convert", bad, tmp_path / "x.nc")
    assert proc.returncode == 2 and "line 1" in proc.stderr and "Traceback" not in proc.stderr
    proc = attitude("convert", tmp_path / "missing.nc", tmp_path / "x.aem")
    assert proc.returncode == 2 and "no such file" in proc.stderr


def test_classify_prints_table_and_json(tmp_path):
    nc = tmp_path / "a.nc"
    fine = GOOD.replace('step = "10 s"', 'step = "0.5 s"')   # 10 deg per sample
    assert attitude("run", write(tmp_path, fine), "-o", nc, "--quiet").returncode == 0
    proc = attitude("classify", nc)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.split()[:2] == ["regime", "SAM"]
    proc = attitude("classify", nc, "--json")
    data = json.loads(proc.stdout)
    assert data["regime"] == "SAM" and set(data["periods"]) >= {"polhode", "precession"}


def test_classify_bad_files_exit_2(tmp_path):
    proc = attitude("classify", tmp_path / "missing.nc")
    assert proc.returncode == 2 and "no such file" in proc.stderr
    short = tmp_path / "short.nc"
    text = GOOD.replace('duration = "2 min"', 'duration = "20 s"')
    assert attitude("run", write(tmp_path, text), "-o", short, "--quiet").returncode == 0
    proc = attitude("classify", short)      # far less than one polhode cycle
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1


def test_convert_to_spice_ck_reads_back_with_spiceypy(tmp_path, monkeypatch):
    """attitude convert OUT.bc writes a CK that SPICE itself reads back (ckgp): the
    C-matrix is the inverse of our body -> inertial rotation."""
    spice = pytest.importorskip("spiceypy")
    import numpy as np

    import attitude as att

    nc = tmp_path / "a.nc"
    assert attitude("run", write(tmp_path, GOOD), "-o", nc, "--quiet").returncode == 0
    proc = attitude("convert", nc, tmp_path / "a.bc", "--object-id", "-77")
    assert proc.returncode == 0, proc.stderr
    eph = att.Ephemeris.from_netcdf(nc)
    monkeypatch.chdir(tmp_path)          # the meta-kernel's PATH_VALUES is its own folder
    spice.furnsh("a.tm")
    try:
        from astropy.time import Time  # ephemeris time: TDB seconds past J2000 (SPICE)

        et = (eph.times[5].tdb - Time("2000-01-01T12:00:00", scale="tdb")).sec
        sclk = spice.sce2c(-77, et)
        cmat, _ = spice.ckgp(-77000, sclk, 0.0, "J2000")   # raises if not found
        expected = eph.rotation[5].as_matrix().T
        np.testing.assert_allclose(cmat, expected, atol=1e-7)   # float64 ET resolution
    finally:
        spice.kclear()

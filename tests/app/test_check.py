"""``attitude check``: runs the scenarios with an [expect] table (in parallel), one line
per expectation, ``N passed, M failed``, exit 1 on a failure and 2 on a malformed file."""

from tests.app.test_cli import attitude
from tests.app.test_scenario import GOOD, write

PASSING = GOOD + '\n[expect]\nregime = "SAM"\nenergy_rel_drift = { max = 1e-10 }\n'


def test_check_passes_and_writes_nothing(tmp_path):
    write(tmp_path, PASSING, "a.toml")
    write(tmp_path, GOOD, "no_expect.toml")          # skipped: no [expect]
    proc = attitude("check", tmp_path)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    lines = proc.stdout.strip().splitlines()
    assert lines[0].startswith("pass ") and "a.toml" in lines[0] and "regime" in lines[0]
    assert "no_expect" not in proc.stdout
    assert lines[-1].startswith("2 passed, 0 failed")
    assert not list(tmp_path.glob("*.nc"))


def test_check_failure_exits_1_with_readable_line(tmp_path):
    write(tmp_path, PASSING, "a.toml")
    bad = write(tmp_path, GOOD + '\n[expect]\nregime = "LAM"\n'
                'polhode = { value = 1, unit = "s", rel_tol = 0.01 }\n', "b.toml")
    proc = attitude("check", tmp_path, "--jobs", "2", "--times")
    assert proc.returncode == 1, proc.stdout + proc.stderr
    fails = [ln for ln in proc.stdout.splitlines() if ln.startswith("FAIL")]
    assert len(fails) == 2 and all(str(bad) in ln for ln in fails)
    assert "regime: expected LAM, got SAM" in fails[0]
    assert "+/- 0.01 s" in fails[1]
    assert "2 passed, 2 failed" in proc.stdout
    assert proc.stdout.count("time  ") == 2


def test_check_malformed_file_exits_2_and_reports_the_others(tmp_path):
    write(tmp_path, PASSING, "a.toml")
    bad = write(tmp_path, PASSING.replace("[state]", "[state]\nspin = 3"), "b.toml")
    proc = attitude("check", tmp_path / "a.toml", bad, tmp_path / "missing.toml", "-j", "2")
    assert proc.returncode == 2
    assert "2 passed, 0 failed" in proc.stdout
    assert f"{bad}: state.spin" in proc.stderr and "missing.toml" in proc.stderr
    assert "Traceback" not in proc.stderr


def test_check_nothing_to_check_exits_2(tmp_path):
    write(tmp_path, GOOD, "no_expect.toml")
    proc = attitude("check", tmp_path)
    assert proc.returncode == 2 and "no scenario with an [expect] table" in proc.stderr


def test_check_help_teaches_with_an_example():
    proc = attitude("check", "--help")
    assert proc.returncode == 0 and "attitude check scenarios/" in proc.stdout

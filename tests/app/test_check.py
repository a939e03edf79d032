"""``attitude check``: runs the scenarios with an [expect] table (in parallel), one line
per expectation, ``N passed, M failed``, exit 1 on a failure and 2 on a malformed file."""

import os
from pathlib import Path

import pytest

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


def _check_in_process(capsys, *args):
    from attitude.app.cli import main
    code = main(["check", *map(str, args), "--jobs", "1"])
    out = capsys.readouterr()
    return code, out.out, out.err


def test_check_reports_each_unreadable_file_once_and_checks_the_rest(tmp_path, capsys):
    """Files that are not scenarios at all -- Latin-1 text, binary bytes, a folder named
    x.toml, a pipe -- are each one line on stderr naming the file and why, counted in the tally;
    the good file is still checked, the exit code is 2 (bad input), not 3."""
    write(tmp_path, PASSING, "a.toml")
    (tmp_path / "latin1.toml").write_bytes('[scenario]\nname = "Éole"\n'.encode("latin-1"))
    (tmp_path / "binary.toml").write_bytes(bytes(range(256)) * 4)
    (tmp_path / "x.toml").mkdir()
    os.mkfifo(tmp_path / "pipe.toml")                   # would block a reader opening it
    code, out, err = _check_in_process(capsys, tmp_path)
    assert code == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 4 and all(ln.startswith("attitude: error: ") for ln in lines)
    assert sum(f"{tmp_path / 'pipe.toml'}: is a pipe" in ln for ln in lines) == 1
    assert sum(f"{tmp_path / 'latin1.toml'}: not UTF-8 text (byte 0xc9" in ln
               for ln in lines) == 1
    assert sum(f"{tmp_path / 'binary.toml'}: not UTF-8" in ln for ln in lines) == 1
    assert sum(f"{tmp_path / 'x.toml'}: is a folder" in ln for ln in lines) == 1
    assert "internal error" not in err and "Traceback" not in err
    assert "ERROR" not in out and str(tmp_path / "latin1.toml") not in out   # once only
    assert out.strip().splitlines()[-1].startswith("2 passed, 0 failed, 4 errors (5 scenarios")


def test_check_counts_a_missing_file_among_the_errors(tmp_path, capsys):
    write(tmp_path, PASSING, "a.toml")
    code, out, err = _check_in_process(capsys, tmp_path / "a.toml", tmp_path / "gone.toml")
    assert code == 2 and err.count("gone.toml") == 1
    assert "2 passed, 0 failed, 1 error (1 scenarios" in out


@pytest.mark.skipif(not Path("/proc/self/mem").exists(), reason="needs Linux /proc")
def test_check_reports_an_unreadable_file(tmp_path, capsys):
    """A file whose read fails (here /proc/self/mem, which refuses a read at offset 0 even
    to root, behind a link named like a scenario): one line with the system's reason."""
    write(tmp_path, PASSING, "a.toml")
    (tmp_path / "unreadable.toml").symlink_to("/proc/self/mem")
    code, out, err = _check_in_process(capsys, tmp_path)
    assert code == 2, err
    assert err.count("unreadable.toml") == 1 and "cannot read the file" in err
    assert "2 passed, 0 failed, 1 error" in out

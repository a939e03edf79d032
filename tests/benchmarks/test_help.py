"""Every benchmark script answers ``--help`` with what it measures and exits, without
running (issue 26: ``python benchmarks/freebody.py --help`` ran the benchmark)."""

import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
SCRIPTS = sorted(p for p in (ROOT / "benchmarks").glob("*.py") if not p.name.startswith("_"))

#: Seconds a --help may take: the script's imports (numpy, scipy, attitude: about a
#: second alone, several on a loaded 2-core machine), never a benchmark's run.
HELP_SECONDS = 60.0


def test_there_are_benchmarks():
    assert len(SCRIPTS) >= 10


@pytest.mark.parametrize("script", SCRIPTS, ids=lambda p: p.name)
def test_help_explains_and_exits_without_running(script):
    env = {**os.environ, "PYTHONPATH": str(ROOT), "ATTITUDE_QUIET": "1"}
    start = time.monotonic()
    out = subprocess.run([sys.executable, str(script), "--help"], cwd=ROOT, env=env,
                         capture_output=True, text=True, timeout=HELP_SECONDS)
    assert time.monotonic() - start < HELP_SECONDS
    assert out.returncode == 0, out.stderr[-500:]
    # argparse prints the help and exits: anything a benchmark printed would come first
    assert out.stdout.startswith("usage:"), out.stdout[:300]
    assert out.stderr == ""
    usage, description, *rest = out.stdout.split("\n\n")
    assert len(description.split()) >= 5 and "options:" in out.stdout


def test_help_of_the_script_of_the_issue():
    out = subprocess.run([sys.executable, str(ROOT / "benchmarks" / "freebody.py"), "--help"],
                         cwd=ROOT, capture_output=True, text=True, timeout=HELP_SECONDS,
                         env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert out.returncode == 0
    assert "Speed of ``propagate`` on a batch" in out.stdout
    assert "bodies/s" not in out.stdout

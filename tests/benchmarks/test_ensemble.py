"""Smoke test of ``benchmarks/ensemble.py --quick`` (about 15 s: it starts a 2-worker
LocalCluster and writes a small netCDF file through it)."""

import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.slow      # a benchmark script's smoke run (CI runs the slow tier)

pytest.importorskip("distributed")
pytest.importorskip("psutil")

SCRIPT = Path(__file__).resolve().parents[2] / "benchmarks" / "ensemble.py"


def test_ensemble_benchmark_quick_runs_and_prints_its_tables():
    out = subprocess.run([sys.executable, str(SCRIPT), "--quick"], capture_output=True,
                         text=True, timeout=300)
    assert out.returncode == 0, out.stderr[-2000:]
    text = out.stdout
    assert "| 1 process, dask chunks, synchronous scheduler | 2.0e+05 |" in text
    assert "| local_cluster(2): 2 worker processes x 1 thread | 2.0e+05 |" in text
    assert "efficiency" in text and "the two modes agree to" in text
    assert "| peak RSS of this (client) process |" in text
    assert "last sample finite: True" in text

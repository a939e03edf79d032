"""Smoke test of ``benchmarks/perturbed.py --quick`` with Basilisk absent (~10 s).

The benchmark must run without Basilisk, say so, print its Markdown tables with finite
errors and times, and write its JSON record; the quick run's numbers are also checked
against what the physics fixes: the splitting rows pass the 1e-6 rad target against
DOP853 (they are chosen to), and eddy currents alone in a uniform field keep the
inertial ``L . B`` (the torque ``(M (w x B)) x B`` is normal to B) to round-off.
"""

import json
import math
import os
import subprocess
import sys
from pathlib import Path

import pytest

from ..tolerances import EPS, SPLITTING_STEP

SCRIPT = Path(__file__).resolve().parents[2] / "benchmarks" / "perturbed.py"


def table_rows(text):
    """The data rows of every Markdown table: ``(tool, setting, error, wall)`` strings."""
    rows = []
    for line in text.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if (not line.startswith("| ") or len(cells) != 4 or cells[0] == "tool"
                or set(cells[0]) <= set("-:")):
            continue
        rows.append(cells)
    return rows


@pytest.mark.slow      # a benchmark script's smoke run (CI runs the slow tier)
def test_perturbed_benchmark_quick_without_basilisk(tmp_path):
    out_json = tmp_path / "perturbed.json"
    env = {k: v for k, v in os.environ.items() if k != "BSK_PYTHON"}
    out = subprocess.run([sys.executable, str(SCRIPT), "--quick", "--no-basilisk",
                          "--json", str(out_json)], capture_output=True, text=True,
                         timeout=300, env=env)
    assert out.returncode == 0, out.stderr[-2000:]
    text = out.stdout
    assert "Basilisk: ABSENT" in text and "no Basilisk rows" in text
    assert "machine: " in text

    rows = table_rows(text)
    assert len(rows) >= 4, text
    assert not any(r[0].startswith("Basilisk") for r in rows)
    for tool, setting, error, wall in rows:
        assert math.isfinite(float(error)), (tool, setting, error)
        assert math.isfinite(float(wall)) and float(wall) > 0.0, (tool, setting, wall)

    record = json.loads(out_json.read_text())
    assert record["quick"] is True and record["basilisk_python"] is None
    a_rows = record["case_A"]["rows"]
    assert a_rows and all(r["error_rad"] <= record["target_rad"] for r in a_rows)
    # the automatic choice (nothing given) is recorded: its method and why
    auto = [r for r in a_rows if r["tool"].startswith("attitude, automatic")]
    assert len(auto) == 1 and auto[0]["method"] in ("splitting", "integrator")
    assert auto[0]["reason"]
    c = record["case_C"]
    # L . B: each step adds at most SPLITTING_STEP ulp of |L| (tests/tolerances.py)
    steps = c["first_span_s"] / c["step_s"]
    assert c["L_dot_B_relative_drift"] < steps * SPLITTING_STEP * EPS
    assert c["L_relative_decay"] > 0.0          # while |L| itself is damped

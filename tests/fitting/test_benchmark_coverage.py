"""Smoke test of ``benchmarks/fitting_coverage.py --quick`` (about 10 s: 4 attitude-data
and 2 lightcurve fits, and the convergence of one case of each kind at two noise levels):
it runs, its tables parse, and its JSON record agrees with the printed table."""

import json
import re
import subprocess
import sys
from pathlib import Path

import pytest
from scipy.stats import binomtest

SCRIPT = Path(__file__).resolve().parents[2] / "benchmarks" / "fitting_coverage.py"


def _table(text: str, header: str) -> list[list[str]]:
    lines = text.splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith(header))
    rows = []
    for line in lines[start + 2:]:
        if not line.startswith("|"):
            break
        rows.append([c.strip() for c in line.strip("|").split("|")])
    return rows


@pytest.mark.slow      # a benchmark script's smoke run (CI runs the slow tier)
def test_fitting_coverage_quick_runs_and_its_tables_parse(tmp_path):
    out_json = tmp_path / "coverage.json"
    out = subprocess.run([sys.executable, str(SCRIPT), "--quick", "--json", str(out_json)],
                         capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr[-2000:]
    text = out.stdout
    assert text.count("machine: ") == 1 and "QUICK RUN" in text
    record = json.loads(out_json.read_text())
    assert record["quick"] and len(record["cases"]["attitude"]) == 4
    assert len(record["cases"]["lightcurve"]) == 2

    rows = _table(text, "| 2-sigma coverage")
    labels = [r[0] for r in rows]
    assert labels[:8] == ["RA of L", "Dec of L", "E/E0", "A/C", "B/C", "P_phi", "phi0",
                          "psi0"]
    assert "all 8 inside (cases)" in labels and "(case, parameter) instances" in labels
    cell = re.compile(r"^(\d+\.\d) \[(\d+), (\d+)\]$")
    for row in rows[:10]:
        assert len(row) == 7
        for c in row[1:]:
            if c == "-":
                continue
            m = cell.match(c)
            assert m, c
            value, lo, hi = map(float, m.groups())
            assert 0 <= lo <= value <= hi <= 100
    # the attitude "both" column against the record: k of n and its Clopper-Pearson
    # interval (an independent computation of the same binomial interval)
    inst = record["summary"]["attitude"]["both"]["instances"]
    ci = binomtest(inst["k"], inst["n"]).proportion_ci(0.95, method="exact")
    row = rows[labels.index("(case, parameter) instances")]
    value, lo, hi = map(float, cell.match(row[3]).groups())
    assert value == round(100 * inst["k"] / inst["n"], 1)
    assert (lo, hi) == (round(100 * ci.low), round(100 * ci.high))
    assert inst["n"] == 8 * record["summary"]["attitude"]["both"]["successful"]

    conv = _table(text, "| data | case | regime |")
    assert [r[0] for r in conv] == ["attitude", "lightcurve"]
    for row, rec in zip(conv, record["convergence"]):
        errors = [float(c.split()[0]) for c in row[3:-1]]
        assert len(errors) == 2 and all(e > 0 for e in errors)
        # the same noise realisation scaled by 1e-1 and 1e-3: the error scales with it
        # (the estimator is linear in the noise where the noise is small)
        assert abs(float(row[-1]) - 1.0) < 0.1
        assert float(row[-1]) == round(rec["slope"], 3)

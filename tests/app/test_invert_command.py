"""``attitude invert``: a scenario file of lightcurves in, shape, state and fitted curves out;
the state it writes propagates with ``attitude run``; bad input exits 2 with one line."""

from __future__ import annotations

import json

import numpy as np
import pytest

from attitude.app.cli import main
from attitude.inversion.invert import _example_observations
from attitude.model.shape import Polyhedron

AU = 1.495978707e11


def _write_damit(path, observations):
    """The observations as a DAMIT / convexinv file (JD in TDB, vectors in au)."""
    lines = [str(len(observations))]
    for obs in observations:
        lines.append(f"{len(obs)} 0")
        sun, seen = obs.sun_and_observer()
        for jd, y, s, o in zip(obs.times.tdb.jd, obs.brightness, sun, seen):
            lines.append(f"{jd:.10f} {y:.12g} " + " ".join(f"{v:.12g}" for v in (*s, *o)))
    path.write_text("\n".join(lines) + "\n")


@pytest.fixture
def scenario(tmp_path):
    _write_damit(tmp_path / "lcs.txt", _example_observations())
    path = tmp_path / "demo.toml"
    path.write_text('''
[scenario]
name = "demo"
[inversion]
lightcurves = "lcs.txt"
time_scale = "tdb"
period = "2 h"
poles = 10
rows = 4
degree = 2
[expect]
period = { value = 2.0, unit = "h", rel_tol = 1e-9 }
pole = { longitude = 28.64789, latitude = 57.29578, tolerance = 0.01 }
rms = { max = 1e-6 }
''')
    return path


def test_invert_writes_shape_state_and_curves_and_meets_its_expectations(scenario, capsys):
    report = scenario.parent / "report.json"
    assert main(["invert", str(scenario), "--report", str(report)]) == 0
    out = capsys.readouterr().out
    assert "pole (28.65, 57.30) deg" in out and "FAIL" not in out
    data = json.loads(report.read_text())
    assert all(e["ok"] for e in data["expect"]) and len(data["expect"]) == 3
    shape = Polyhedron.from_obj(scenario.parent / "demo_shape.obj")
    assert shape.volume == pytest.approx(1.0, rel=1e-9)
    curves = np.genfromtxt(scenario.parent / "demo_lightcurves.csv", delimiter=",",
                           names=True)
    assert curves.size == 180
    np.testing.assert_allclose(curves["model"], curves["data"], rtol=1e-6)


def test_the_inverted_state_propagates(scenario, capsys):
    assert main(["invert", str(scenario), "--quiet"]) == 0
    state = scenario.parent / "demo_state.toml"
    out = scenario.parent / "demo_state.nc"
    assert main(["run", str(state), "-o", str(out), "--quiet"]) == 0
    assert out.exists()


@pytest.mark.parametrize("edit, key", [
    (("lightcurves = \"lcs.txt\"", "lightcurves = \"missing.txt\""), "missing.txt"),
    (("poles = 10", "poles = 0"), "inversion.poles"),
    (("period = \"2 h\"", "period = \"2 kg\""), "inversion.period"),
    (("rows = 4", "rows = 4\nrowz = 3"), "rowz"),
])
def test_bad_inversion_scenarios_exit_2_with_one_line(scenario, capsys, edit, key):
    scenario.write_text(scenario.read_text().replace(*edit))
    assert main(["invert", str(scenario)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and key in err[0] and "Traceback" not in err[0]


def test_check_runs_inversion_scenarios(scenario, capsys):
    assert main(["check", str(scenario)]) == 0
    out = capsys.readouterr().out
    assert out.count("pass  ") == 3 and "pole" in out


def test_each_command_points_to_the_other_for_the_wrong_kind_of_scenario(scenario, capsys):
    assert main(["run", str(scenario)]) == 2
    assert "attitude invert" in capsys.readouterr().err
    assert main(["invert", "scenarios/dzhanibekov.toml"]) == 2
    assert "attitude run" in capsys.readouterr().err

"""``attitude invert``: a scenario file of lightcurves in, shape, state and fitted curves out;
the state it writes propagates with ``attitude run``; bad input exits 2 with one line."""

from __future__ import annotations

import json
import re

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


# ------------------------------------------------------------ ALCDEF + [inversion.orbit]
ALCDEF_SCENARIO = '''
[scenario]
name = "synthetic ALCDEF"
[inversion]
lightcurves = "synthetic.alcdef"
period = "{period} s"
poles = 10
rows = 4
degree = 2
[inversion.orbit]
epoch = "2026-03-01T00:00:00"
time_scale = "tdb"
a = "2.2 AU"
e = 0.12
i = "9 deg"
raan = "80 deg"
argp = "30 deg"
mean_anomaly = "150 deg"
[expect]
period = {{ value = 7200.0, unit = "s", rel_tol = 1e-10 }}
pole = {{ longitude = {lon}, latitude = {lat}, tolerance = 1e-4 }}
rms = {{ max = 1e-7 }}
'''


@pytest.fixture(scope="module")
def alcdef_scenario(tmp_path_factory):
    """The synthetic ALCDEF file of tests/inversion/test_geometry_orbit.py (six nights of
    a convex body on a known orbit) with its scenario; the tolerances are derived there."""
    from tests.inversion import test_geometry_orbit as syn

    folder = tmp_path_factory.mktemp("alcdef")
    times = syn.observer_times()
    syn.write_alcdef(folder / "synthetic.alcdef", times, syn.synthetic_magnitudes(times))
    lon, lat = np.degrees(syn.POLE)
    path = folder / "alcdef.toml"
    path.write_text(ALCDEF_SCENARIO.format(period=syn.PERIOD * 1.000001, lon=lon, lat=lat))
    return path


def test_invert_an_alcdef_file_with_its_orbit(alcdef_scenario, capsys):
    report = alcdef_scenario.parent / "report.json"
    assert main(["invert", str(alcdef_scenario), "-o", str(alcdef_scenario.parent / "out"),
                 "--report", str(report)]) == 0
    data = json.loads(report.read_text())
    assert [e["ok"] for e in data["expect"]] == [True] * 3
    curves = np.genfromtxt(alcdef_scenario.parent / "out_lightcurves.csv", delimiter=",",
                           names=True)
    assert curves.size == 240 and set(curves["lightcurve"]) == set(range(1, 7))


@pytest.mark.parametrize("edit, where", [
    # a NaN magnitude: the file and its line
    (None, "bad.alcdef: line 9:"),
    # no geometry: an ALCDEF file without the orbit
    ((re.compile(r"\[inversion.orbit\].*?\[expect\]", re.S), "[expect]"),
     "bad.toml: inversion.orbit: the ALCDEF file synthetic.alcdef has no geometry"),
])
def test_bad_alcdef_inversions_exit_2_naming_file_and_line(alcdef_scenario, capsys, edit,
                                                          where):
    text = alcdef_scenario.read_text()
    path = alcdef_scenario.parent / "bad.toml"
    if edit is None:
        lines = (alcdef_scenario.parent / "synthetic.alcdef").read_text().splitlines()
        lines[8] = lines[8].split("|")[0] + "|nan|0.01"
        (alcdef_scenario.parent / "bad.alcdef").write_text("\n".join(lines) + "\n")
        text = text.replace("synthetic.alcdef", "bad.alcdef")
    else:
        text = edit[0].sub(edit[1], text)
    path.write_text(text)
    assert main(["invert", str(path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and where in err[0] and "Traceback" not in err[0]


def _one_night(alcdef_scenario, period: str, degree: int):
    """The scenario with the first night alone (40 points over 6 h)."""
    lines = (alcdef_scenario.parent / "synthetic.alcdef").read_text().splitlines()
    one = lines[:lines.index("ENDDATA") + 1]
    (alcdef_scenario.parent / "one.alcdef").write_text("\n".join(one) + "\n")
    path = alcdef_scenario.parent / "one.toml"
    text = re.sub(r'period = "[^"]*"', f'period = "{period}"', alcdef_scenario.read_text(),
                  count=1)
    path.write_text(text.replace("synthetic.alcdef", "one.alcdef")
                    .replace("degree = 2", f"degree = {degree}"))
    return path


def test_a_single_session_too_short_for_the_period_exits_2(alcdef_scenario, capsys):
    assert main(["invert", str(_one_night(alcdef_scenario, "8 h", 2))]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "one.toml: inversion.period: one.alcdef: session 0 (line 1)" \
        in err[0] and "6 h cannot give a period of 8 h" in err[0]


def test_fewer_points_than_parameters_exits_2(alcdef_scenario, capsys):
    assert main(["invert", str(_one_night(alcdef_scenario, "5 h", 6))]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and ("one.toml: inversion.lightcurves: one.alcdef: 40 points for "
                              "52 parameters") in err[0]


def test_a_tumbler_starts_from_a_scenarios_body_and_state(tmp_path, capsys):
    """``start_from``: the [body] and [state] of a scenario file (ICRF, 1.3 d before the
    data) start the tumbler's fit, which returns to the noise-free truth."""
    from attitude.inversion.invert import _example_tumbler
    from attitude.inversion.observations import engine_blocks
    from attitude.model.state import format_epoch
    from tests.inversion.test_observations_start import body_and_state

    obs, truth = _example_tumbler()
    _write_damit(tmp_path / "tumbler.txt", obs)
    body, state = body_and_state(truth, engine_blocks(obs))
    vector = ", ".join
    q = vector(repr(float(x)) for x in state.attitude.as_quat())
    (tmp_path / "guess.toml").write_text(f'''
[scenario]
name = "guess"
[body]
inertia = [{", ".join(f"[{vector(repr(float(x)) for x in row)}]" for row in body.inertia)}]
[state]
epoch = "{format_epoch(state.epoch.tdb)}"
time_scale = "tdb"
frame = "ICRF"
attitude = {{ quaternion_scalar_last = [{q}] }}
omega_body = {{ value = [{vector(repr(float(x)) for x in state.omega_body)}], unit = "rad/s" }}
[propagation]
duration = "1 h"
step = "60 s"
''')
    path = tmp_path / "tumbler.toml"
    path.write_text('''
[scenario]
name = "tumbler"
[inversion]
lightcurves = "tumbler.txt"
time_scale = "tdb"
rotation = "tumbling"
start_from = "guess.toml"
alternatives = false
rows = 4
degree = 2
[expect]
period = { value = 2.0, unit = "h", rel_tol = 1e-9 }
rms = { max = 1e-9 }
''')
    report = tmp_path / "report.json"
    assert main(["invert", str(path), "--quiet", "--report", str(report)]) == 0
    assert [e["ok"] for e in json.loads(report.read_text())["expect"]] == [True, True]


def test_plot_writes_the_figures(scenario, capsys):
    pytest.importorskip("matplotlib")
    scenario.write_text(scenario.read_text().replace("degree = 2", "degree = 2\n"
                                                     "map_longitudes = 6\nmap_latitudes = 3"))
    assert main(["invert", str(scenario), "--plot"]) == 0
    out = capsys.readouterr().out
    for name in ("demo_fit.png", "demo_pole_map.png", "demo_shape_view.png"):
        path = scenario.parent / name
        assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and f"wrote {path}" in out
    assert not (scenario.parent / "demo_periodogram.png").exists()    # no scan ran


def test_invert_reports_its_stages_unless_quiet(scenario, capsys, monkeypatch):
    """The pole search reports its starts on stderr (issue 26: inversion stages), with
    every report shown at once (the defaults wait a second); ``--quiet`` prints nothing."""
    from attitude.foundations import progress

    monkeypatch.setattr(progress, "DELAY", 0.0)
    monkeypatch.setattr(progress, "INTERVAL", 0.0)
    assert main(["invert", str(scenario)]) == 0
    err = capsys.readouterr().err.splitlines()
    assert any(ln.startswith("attitude: pole search: done, 10 of 10 pole starts in ")
               for ln in err), err
    assert main(["invert", str(scenario), "--quiet"]) == 0
    assert capsys.readouterr() == ("", "")

"""Scenario files with an [ensemble] table: sampled populations and tables of bodies,
validation before any work, expectations on regime fractions and median periods."""

import json
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

import attitude as att
from attitude import ensemble as en
from attitude.app.scenario import load_scenario, run_scenario
from attitude.model.freebody import diagnose

ROOT = Path(__file__).resolve().parents[2]

SAMPLED = """
[scenario]
name = "cloud"

[state]
epoch = "2029-03-14T00:00:00"
frame = "ECLIPJ2000"

[ensemble]
size = 60
seed = 7

[ensemble.mean]
angular_momentum_ra = "250 deg"
angular_momentum_dec = "-75 deg"
energy_ratio = 1.024
ratio_a = 0.61
ratio_b = 0.965
precession_period = "27.38 h"

[ensemble.sigma]
energy_ratio = 0.0043
precession_period = "0.0233 h"

[propagation]
duration = "5 d"
step = "6 h"

[output]
netcdf = "cloud.nc"

[expect]
regime = "SAM"
precession = { value = 27.38, unit = "h", rel_tol = 0.002 }
[expect.regime_fractions]
SAM = { value = 1.0, abs_tol = 0.05 }
"""


def write(tmp_path, text, name="s.toml"):
    path = tmp_path / name
    path.write_text(text)
    return path


def test_sampled_ensemble_scenario_runs_and_checks(tmp_path):
    sc = load_scenario(write(tmp_path, SAMPLED))
    assert len(sc.ensemble) == 60 and sc.ensemble.frame == "ECLIPJ2000"
    # the nominal member is the published state
    assert diagnose(sc.body, sc.state).periods["precession"] == pytest.approx(98568.0)
    res = run_scenario(sc)
    assert res.ok, res.expectations
    rep = res.report()
    assert rep["ensemble"]["size"] == 60 and rep["ensemble"]["valid"] == 60
    assert rep["ensemble"]["regime_fractions"] == {"SAM": 1.0}
    # the median precession period is that of the drawn periods
    drawn = sc.ensemble.parameters["precession_period"]
    assert rep["periods"]["precession"] == pytest.approx(np.median(drawn), rel=1e-10)
    assert rep["conservation"]["energy_rel_drift"] < 1e-12
    back = att.Ephemeris.from_netcdf(tmp_path / "cloud.nc")
    assert back.dataset.sizes["body"] == 60
    assert back.dataset.parameter_energy_ratio.values[0] == 1.024
    # the same seed gives the same file contents
    again = run_scenario(load_scenario(tmp_path / "s.toml"), netcdf=tmp_path / "again.nc")
    np.testing.assert_array_equal(
        att.Ephemeris.from_netcdf(again.outputs[0]).dataset.quaternion.values,
        back.dataset.quaternion.values)


def test_a_wrong_regime_fraction_fails_the_check_with_a_readable_line(tmp_path):
    path = write(tmp_path, SAMPLED.replace("SAM = { value = 1.0", "LAM = { value = 0.5"))
    out = subprocess.run([sys.executable, "-m", "attitude", "check", str(path)],
                         capture_output=True, text=True, timeout=120)
    assert out.returncode == 1, out.stdout + out.stderr
    line = next(x for x in out.stdout.splitlines() if "regime_fractions.LAM" in x)
    assert "FAIL" in line and "0.5" in line


def test_table_ensemble_scenario_and_invalid_rows(tmp_path):
    (tmp_path / "debris.csv").write_text(
        "name,A,B,C,wx [deg/s],wy [deg/s],wz [deg/s]\n"
        "good-1,10,12,15,0.5,0.1,2.0\n"
        "bad-1,1,1,3,0,0,1\n"
        "good-2,3,4,5,0.01,1,0\n")
    text = """
[state]
epoch = "2030-01-01T00:00:00"
frame = "GCRF"
[ensemble]
table = "debris.csv"
[propagation]
duration = "1 h"
step = "1 min"
[expect]
energy_rel_drift = { max = 1e-12 }
[expect.regime_fractions]
SAM = { value = 0.5, abs_tol = 0.01 }
LAM = { value = 0.5, abs_tol = 0.01 }
"""
    sc = load_scenario(write(tmp_path, text))
    assert sc.ensemble.names == ("good-1", "bad-1", "good-2")
    res = run_scenario(sc, netcdf=tmp_path / "debris.nc")
    assert res.ok, res.expectations
    rep = res.report()["ensemble"]
    assert list(rep["invalid"]) == ["1"] and "triangle" in rep["invalid"]["1"]
    assert rep["spread_at_end_deg"] == {}          # a catalogue has no nominal member
    ds = att.Ephemeris.from_netcdf(tmp_path / "debris.nc").dataset
    assert ds.status.values.tolist() == [0, 1, 0]


@pytest.mark.parametrize("change, key, message", [
    ("[state]\n", "body", "not with [ensemble]"),
    ('seed = 7\n', "ensemble.seed", "missing key"),
    ('energy_ratio = 1.024\n', "ensemble.mean.energy_ratio", "missing key"),
    ('ratio_a = 0.61\n', "ensemble.mean.ratio_aa", "did you mean 'ratio_a'"),
    ('precession_period = "0.0233 h"\n', "ensemble.sigma.precession_period",
     "cannot be converted"),
    ('frame = "ECLIPJ2000"\n', "state.omega_body", "not with [ensemble]"),
    ('model = "x"\n', "ensemble.model", "unknown"),
])
def test_bad_ensemble_tables_fail_naming_the_key(tmp_path, change, key, message):
    text = SAMPLED
    if change == "[state]\n":
        text = text.replace(change, '[body]\nprincipal_moments = [1, 2, 3]\n[state]\n')
    elif change == 'seed = 7\n':
        text = text.replace(change, "")
    elif change == 'energy_ratio = 1.024\n':
        text = text.replace(change, "").replace("energy_ratio = 0.0043\n", "")
    elif change == 'ratio_a = 0.61\n':
        text = text.replace(change, "ratio_aa = 0.61\n")
    elif change == 'precession_period = "0.0233 h"\n':
        text = text.replace(change, 'precession_period = "0.0233 kg"\n')
    elif change == 'frame = "ECLIPJ2000"\n':
        text = text.replace(change, change + "omega_body = [0, 0, 1]\n")
    else:
        text = text.replace("size = 60\n", "size = 60\n" + change)
    path = write(tmp_path, text)
    with pytest.raises(att.ScenarioError) as exc:
        load_scenario(path)
    assert key in str(exc.value) and message in str(exc.value), str(exc.value)
    out = subprocess.run([sys.executable, "-m", "attitude", "run", str(path)],
                         capture_output=True, text=True, timeout=120)
    assert out.returncode == 2 and key in out.stderr


def test_shipped_apophis_ensemble_scenario_is_fast_and_passes():
    sc = load_scenario(ROOT / "scenarios" / "apophis_ensemble.toml")
    with warnings.catch_warnings():
        warnings.simplefilter("error", en.InvalidBodiesWarning)
        res = run_scenario(sc, write_outputs=False)
    assert res.ok, res.expectations
    spread = res.report()["ensemble"]["spread_at_end_deg"]
    # a month of uncertainty growth: the cloud has lost the rotation phase
    assert spread["0.9"] > 90


@pytest.mark.slow      # a long study (> 9 s); the slow tier, which CI runs
def test_run_with_workers_on_a_local_cluster(tmp_path):
    pytest.importorskip("distributed")
    path = write(tmp_path, SAMPLED)
    report = tmp_path / "r.json"
    out = subprocess.run([sys.executable, "-m", "attitude", "run", str(path), "--workers",
                          "2", "--report", str(report), "--quiet"], capture_output=True,
                         text=True, timeout=300)
    assert out.returncode == 0, out.stdout + out.stderr
    rep = json.loads(report.read_text())
    single = run_scenario(load_scenario(path), write_outputs=False).report()
    assert rep["ensemble"]["regime_fractions"] == single["ensemble"]["regime_fractions"]
    assert rep["periods"] == pytest.approx(single["periods"], rel=1e-12)
    assert rep["ensemble"]["spread_at_end_deg"] == pytest.approx(
        single["ensemble"]["spread_at_end_deg"], abs=1e-6)
    ds = att.Ephemeris.from_netcdf(tmp_path / "cloud.nc").dataset
    assert ds.sizes["body"] == 60 and (ds.status.values == 0).all()


def test_classify_command_on_an_ensemble_file(tmp_path):
    path = write(tmp_path, SAMPLED.replace('duration = "5 d"', 'duration = "20 d"')
                 .replace("[ensemble.sigma]", "[ensemble.sigma]\nratio_b = 0.01"))
    sc = load_scenario(path)
    res = run_scenario(sc)
    out = subprocess.run([sys.executable, "-m", "attitude", "classify",
                          str(tmp_path / "cloud.nc"), "--json"], capture_output=True,
                         text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    doc = json.loads(out.stdout)
    # classified from the propagated motion = the analytic labels of the initial states
    analytic = en.diagnose_ensemble(sc.ensemble).regime.values
    got = [b["regime"] for b in doc["bodies"]]
    assert got == analytic.tolist()
    assert "LAM" in got and "SAM" in got
    assert doc["regime_fractions"] == pytest.approx(res.ensemble["regime_fractions"])


def test_classify_ensemble_reports_invalid_and_unclassified_bodies():
    with pytest.warns(en.InvalidBodiesWarning):
        ens = att.Ensemble.from_arrays(
            principal_moments=[[1.0, 2.0, 2.5], [1.0, 1.0, 3.0]],
            omega_body=[[0.1, 0.0, 0.2], [0.1, 0.0, 0.2]], epoch="2030-01-01")
    table = en.classify_ensemble(att.propagate(ens, np.linspace(0.0, 2000.0, 400)))
    assert table.regime.values.tolist() == ["SAM", "invalid"]
    short = en.classify_ensemble(att.propagate(ens, [0.0]))
    assert short.regime.values[0] == "unclassified" and "sample" in short.reason.values[0]

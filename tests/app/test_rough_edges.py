"""What a newcomer trips on (issue 26), on the command line: a closed pipe, an output
suffix the command cannot write, the posterior's path, a step longer than the run,
expectations without units, the fitted scenario's unlabelled radians, CSV sessions
renumbered."""

import os
import re
import subprocess
import sys
import tomllib
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from scipy.spatial.transform import Rotation

import attitude as att
from attitude.app.cli import EXIT_BROKEN_PIPE, OUTPUT_SUFFIXES, main
from attitude.app.scenario import load_scenario
from attitude.foundations import progress
from tests.app.test_scenario import GOOD, write

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture
def ephemeris(tmp_path):
    body = att.RigidBody.from_principal_moments([0.61, 0.965, 1.0])
    state = att.AttitudeState("2029-04-13", Rotation.identity(), [0.02, 0.0, 0.1])
    return att.propagate(body, state, np.arange(0.0, 3000.0, 10.0)).to_netcdf(
        tmp_path / "eph.nc")


# --- 1. a closed pipe ------------------------------------------------------------------

def test_a_reader_that_leaves_early_ends_the_command_quietly(ephemeris):
    """``attitude classify X.nc --json | head -1``: the reader is gone before the output
    comes (closed here before the command writes, so that the write must fail: a
    reader that had taken everything already would prove nothing).  No traceback, no
    'Broken pipe', the exit code of a command killed by SIGPIPE."""
    read, write_end = os.pipe()
    os.close(read)                                  # the reader left
    proc = subprocess.run([sys.executable, "-m", "attitude", "classify", str(ephemeris),
                           "--json"], stdout=write_end, stderr=subprocess.PIPE, text=True,
                          env={**os.environ, "PYTHONPATH": str(ROOT)}, timeout=300)
    os.close(write_end)
    assert proc.stderr == ""
    assert proc.returncode == EXIT_BROKEN_PIPE == 141


def test_a_reader_that_takes_one_line_through_a_real_pipe(ephemeris):
    """The shell's pipeline itself: ``| head -1`` gets the first line, and whether the
    command was still writing or not, stderr stays empty."""
    cmd = (f"{sys.executable} -m attitude classify {ephemeris} --json | head -1; "
           "echo \"status ${PIPESTATUS[0]}\"")
    proc = subprocess.run(["bash", "-c", cmd], capture_output=True, text=True,
                          env={**os.environ, "PYTHONPATH": str(ROOT)}, timeout=300)
    first, status = proc.stdout.splitlines()
    assert first == "{" and proc.stderr == ""
    assert status in ("status 0", "status 141")


# --- 2. output suffixes ------------------------------------------------------------------

@pytest.mark.parametrize("command, args", [
    ("run", ["scenarios/apophis.toml"]),
    ("lightcurve", ["scenarios/apophis_lightcurve.toml"]),
    ("section", ["scenarios/hyperion_section.toml"]),
    ("fit", ["scenarios/tumbler_fit.toml"]),
])
def test_an_output_suffix_the_command_cannot_write_is_bad_input(command, args, tmp_path,
                                                                capsys):
    target = tmp_path / "x.txt"
    assert main([command, *args, "-o", str(target)]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and str(target) in err and "'.txt'" in err
    for suffix in OUTPUT_SUFFIXES[command]:
        assert suffix in err
    assert not target.exists()


def test_convert_lists_what_it_writes(ephemeris, tmp_path, capsys):
    assert main(["convert", str(ephemeris), str(tmp_path / "eph.txt")]) == 2
    err = capsys.readouterr().err
    assert all(s in err for s in (".nc", ".aem", ".xml", ".bc"))
    assert not (tmp_path / "eph.txt").exists()


def test_the_accepted_suffixes_are_written(tmp_path, capsys):
    path = write(tmp_path, GOOD)
    assert main(["run", str(path), "-o", str(tmp_path / "x.nc"), "--quiet"]) == 0
    assert (tmp_path / "x.nc").is_file()


# --- 3. the posterior follows -o -------------------------------------------------------

FIT = """
[scenario]
name = "small fit"
[body]
principal_moments = [0.6, 0.9, 1.0]
[state]
epoch = "2029-04-13T00:00:00"
attitude = { quaternion_scalar_last = [0, 0, 0, 1] }
omega_body = [0.05, 0.1, 1.0]
[propagation]
duration = "20 s"
step = "1 s"
[observations]
attitude = { file = "q.csv", sigma = "0.01 deg" }
free = ["phi0", "psi0"]
multistart = false
posterior = { walkers = 6, steps = 40, seed = 1, netcdf = "beside_scenario.nc" }
"""


@pytest.fixture
def fit_scenario(tmp_path):
    body = att.RigidBody.from_principal_moments([0.6, 0.9, 1.0])
    state = att.AttitudeState("2029-04-13T00:00:00", Rotation.identity(), [0.05, 0.1, 1.0])
    t = np.linspace(0.0, 20.0, 41)
    q = att.propagate(body, state, t).dataset.quaternion.values
    rows = "".join(f"{a:.3f}," + ",".join(f"{x:.12f}" for x in r) + "\n"
                   for a, r in zip(t, q))
    (tmp_path / "q.csv").write_text("t,qx,qy,qz,qw\n" + rows)
    return write(tmp_path, FIT, "fit.toml")


def test_fit_posterior_follows_o_and_labels_units(fit_scenario, tmp_path, capsys,
                                                  monkeypatch):
    monkeypatch.setattr(progress, "DELAY", 0.0)          # every step would be shown
    out = tmp_path / "results" / "best.toml"
    assert main(["fit", str(fit_scenario), "-o", str(out), "--posterior"]) == 0
    std = capsys.readouterr()
    posterior = out.with_name("best_posterior.nc")
    assert posterior.is_file() and out.is_file()
    assert not (tmp_path / "beside_scenario.nc").exists()
    assert not list(tmp_path.glob("*posterior*"))
    assert f"wrote {posterior}" in std.out
    # the first line says how the solver stopped, in FitResult.status's words
    assert std.out.splitlines()[0].startswith(("small fit: converged (",
                                               "small fit: max_nfev at an acceptable chi2 ("))
    with xr.open_dataset(posterior) as ds:
        assert set(ds.data_vars) == {"phi0", "psi0", "regime"} and ds.sizes["walker"] == 6
    # the fitted scenario's comments: every parameter with its unit, angles in degrees
    comments = [ln for ln in out.read_text().splitlines() if ln.startswith("#   ")]
    units = {ln.split()[1]: ln.split("+-")[1].split()[1] for ln in comments}
    assert units == {"angular_momentum_ra": "deg", "angular_momentum_dec": "deg",
                     "energy_ratio": "(E/E0)", "ratio_a": "(A/C)", "ratio_b": "(B/C)",
                     "precession_period": "s", "phi0": "deg", "psi0": "deg"}
    fitted = tomllib.loads(out.read_text())
    ratio = float(next(ln for ln in comments if "ratio_a" in ln).split()[3])
    inertia = np.array(fitted["body"]["inertia"])
    assert ratio == pytest.approx(inertia[0, 0] / inertia[2, 2], rel=1e-9)
    # progress of the MCMC steps, and emcee's words replaced by one line of ours
    assert "attitude: posterior (MCMC):" in std.err
    assert "attitude: fit (least squares):" in std.err          # the starts, then the chain
    assert "integrated autocorrelation time" not in std.err
    notes = [ln for ln in std.err.splitlines() if "note" in ln]
    assert len(notes) <= 1 and all(ln.startswith("attitude: note: ") for ln in notes)


def test_fit_quiet_says_nothing_on_stderr(fit_scenario, tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(progress, "DELAY", 0.0)
    out = tmp_path / "q" / "best.toml"
    assert main(["fit", str(fit_scenario), "-o", str(out), "--posterior", "--quiet"]) == 0
    assert capsys.readouterr() == ("", "")
    assert out.with_name("best_posterior.nc").is_file()


def test_fit_posterior_without_o_goes_where_the_table_says(fit_scenario, tmp_path, capsys):
    assert main(["fit", str(fit_scenario), "--quiet"]) == 0     # [observations.posterior]
    assert (tmp_path / "beside_scenario.nc").is_file()
    assert (tmp_path / "fit_fit.toml").is_file()


# --- 4. a step longer than the duration ---------------------------------------------------

def test_a_step_longer_than_the_duration_names_both_keys(tmp_path, capsys):
    path = write(tmp_path, GOOD.replace('step = "10 s"', 'step = "3 min"'))
    with pytest.raises(att.ScenarioError) as err:
        load_scenario(path)
    assert err.value.key == "propagation.step" and "propagation.duration" in str(err.value)
    assert main(["run", str(path)]) == 2
    line = capsys.readouterr().err
    assert line.count("\n") == 1 and "propagation.step" in line and "duration" in line
    # equal is a run of two epochs
    assert load_scenario(write(tmp_path, GOOD.replace('"10 s"', '"2 min"'), "eq.toml")
                         ).times.tolist() == [0.0, 120.0]


# --- 5. units and digits -----------------------------------------------------------------

LIGHTCURVE = """
[scenario]
name = "spinning ellipsoid"
[body]
principal_moments = [1.0, 2.0, 2.5]
[state]
epoch = "2024-01-01"
omega_body = { value = [0, 0, 1], unit = "cycle/h" }
[propagation]
duration = "3 h"
step = "2 min"
[photometry]
shape = "ellipsoid"
subdivisions = 1
law = "lambert"
sun = [1.0, 0.0, 0.3]
observer = [1.0, 0.2, 0.3]
periods = 1
order = 2
[expect]
lightcurve_period = { value = 1.0, unit = "h", rel_tol = 1e-3 }
lightcurve_amplitude = { value = 0.5, unit = "mag", abs_tol = 1.0 }
"""


def test_lightcurve_expectations_carry_units_and_sensible_digits(tmp_path, capsys):
    path = write(tmp_path, LIGHTCURVE)
    assert main(["lightcurve", str(path), "-o", str(tmp_path / "lc.nc")]) == 0
    lines = [ln.strip() for ln in capsys.readouterr().out.splitlines()]
    period = next(ln for ln in lines if "lightcurve_period" in ln)
    amplitude = next(ln for ln in lines if "lightcurve_amplitude" in ln)
    assert period.startswith("ok   lightcurve_period: expected 1 +/- 0.001 h, got ")
    assert amplitude.startswith("ok   lightcurve_amplitude: expected 0.5 +/- 1 mag, got ")
    for line, unit in ((period, "h"), (amplitude, "mag")):
        got = re.fullmatch(rf".*, got (\S+) {unit}", line).group(1)
        digits = len(got.replace(".", "").replace("-", "").lstrip("0"))
        assert 1 <= digits <= 5, line       # +/- 0.001 of 1 h: 5 digits are all it tells


def test_measured_digits_follow_the_tolerance():
    from attitude.app.commands.common import expectation_line
    line = expectation_line({"key": "lightcurve_period", "expected": 30.54, "unit": "h",
                             "tolerance": 0.0611, "got": 30.54029651019184, "ok": True})
    assert line == "ok   lightcurve_period: expected 30.54 +/- 0.0611 h, got 30.54 h"
    bound = expectation_line({"key": "energy_rel_drift", "expected": 1e-12,
                              "got": 1.234567e-15, "ok": True})
    assert bound == "ok   energy_rel_drift: expected <= 1e-12, got 1.23e-15"


@pytest.mark.parametrize("column, expected", [
    (["1", "1", "2", "3"], [1, 1, 2, 3]),              # the file's numbers, kept
    (["7", "7", "3", "3"], [7, 7, 3, 3]),
    (["A", "A", "B", "C"], [0, 0, 1, 2]),              # labels: numbered in sorted order
])
def test_csv_sessions_keep_the_file_numbers(tmp_path, column, expected):
    rows = "".join(f"{60000.0 + k / 10:.1f},{15.0 + k / 10:.2f},{s}\n"
                   for k, s in enumerate(column))
    path = tmp_path / "lc.csv"
    path.write_text("mjd,mag,session\n" + rows)
    assert att.read_lightcurve(path).dataset.session.values.tolist() == expected


"""The spin period of a run and its trend (attitude.spindown), the [expect] keys on them,
and the published tumblers (scenarios/larets_spindown.toml, stella_spindown.toml,
envisat_spindown.toml; docs/environment.md, "Published tumblers").

References: closed forms (a straight line, an exact exponential and its discrete
least-squares slope by geometric sums, a sphere's exponential eddy-current spin-down in a
uniform field), a second method (scipy's linregress for the standard error) and the
published e-folding times of Kucharski et al. (2014).
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from scipy import stats

import attitude as att
from attitude.analysis.spindown import fit_spin_trend, spin_period_series, spin_trend
from attitude.app.cli import main
from attitude.app.scenario import load_scenario, run_scenario
from attitude.foundations.errors import DiagnosticsError, InsufficientDataError, ScenarioError
from attitude.model.torques import EddyCurrentDamping, UniformField
from tests.tolerances import EPS

ROOT = Path(__file__).resolve().parents[2]
DAY = 86400.0


# --- the fit against closed forms ----------------------------------------------------

def test_a_straight_line_gives_its_slope_and_no_error():
    t = np.linspace(0.0, 2 * DAY, 97)
    slope = 0.075 / DAY                                  # +75 ms/day (Envisat)
    trend = fit_spin_trend(t, 134.74 + slope * t)
    # a few roundings of numbers of size P ~ 135 s over a span of 2 days
    tol = 64 * EPS * 135.0 / (2 * DAY)
    assert abs(trend.trend - slope) <= tol
    assert trend.trend_stderr <= tol
    assert trend.period_start == 134.74
    assert abs(trend.period_end - (134.74 + 0.15)) <= 8 * EPS * 135.0
    assert trend.samples == 97 and trend.span == 2 * DAY
    # e-folding of a straight line from ln P: P / (dP/dt) at the middle, to second order
    # in the relative change over the run (0.11 %): (dP/dt / P_mid) = 1 / tau (1 + O(d^2))
    p_mid = 134.74 + slope * DAY
    assert abs(trend.efolding * slope / p_mid - 1.0) < (0.15 / 134.74) ** 2


def test_an_exponential_gives_its_e_folding_time_and_the_discrete_slope():
    """P = P0 x^i on t_i = i h (x = exp(h / tau)): ln P is a straight line, so the
    e-folding time is tau; the least-squares slope of P itself is, by the geometric sums
    S0 = sum x^i and S1 = sum i x^i, P0 (S1 - m S0) / (h n (n^2 - 1) / 12), m = (n-1)/2."""
    tau, h, n, p0 = 2.0 * DAY, 0.25 * DAY, 13, 2.0
    t = h * np.arange(n)
    trend = fit_spin_trend(t, p0 * np.exp(t / tau))
    assert abs(trend.efolding / tau - 1.0) <= 64 * EPS * n
    assert trend.efolding_stderr <= 64 * EPS * n * tau
    x = math.exp(h / tau)
    s0 = (x**n - 1.0) / (x - 1.0)
    s1 = x * (1.0 - n * x ** (n - 1) + (n - 1) * x**n) / (1.0 - x) ** 2
    m = (n - 1) / 2.0
    slope = p0 * (s1 - m * s0) / (h * n * (n * n - 1) / 12.0)
    # the geometric sums lose ~ x^n / (x - 1)^2 ulps to cancellation
    assert abs(trend.trend / slope - 1.0) <= 64 * EPS * x**n / (x - 1.0) ** 2
    assert trend.trend_stderr > 0                        # P is not a straight line


def test_spin_up_gives_a_negative_e_folding_time():
    t = np.linspace(0.0, DAY, 25)
    trend = fit_spin_trend(t, 10.73 * np.exp(-t / (30 * DAY)))   # Topex-like spin-up
    assert abs(trend.efolding / (-30 * DAY) - 1.0) <= 64 * EPS * 25
    assert trend.trend < 0 and trend.trend_ms_per_day < 0


def test_standard_error_agrees_with_scipy_linregress():
    rng = np.random.default_rng(17)
    t = np.sort(rng.uniform(0.0, 3 * DAY, 200))
    p = 20.0 + 1e-6 * t + rng.normal(0.0, 0.01, t.size)
    trend = fit_spin_trend(t, p)
    ref = stats.linregress(t, p)
    assert abs(trend.trend / ref.slope - 1.0) < 1e-9
    assert abs(trend.trend_stderr / ref.stderr - 1.0) < 1e-9
    ref_log = stats.linregress(t, np.log(p))
    assert abs(trend.efolding * ref_log.slope - 1.0) < 1e-9
    assert abs(trend.efolding_stderr / (ref_log.stderr / ref_log.slope**2) - 1.0) < 1e-9


def test_bad_series_are_clear_errors():
    with pytest.raises(InsufficientDataError, match="at least 3"):
        fit_spin_trend([0.0, 1.0], [1.0, 1.0])
    with pytest.raises(InsufficientDataError):
        fit_spin_trend([5.0, 5.0, 5.0], [1.0, 2.0, 3.0])
    with pytest.raises(DiagnosticsError, match="finite and positive"):
        fit_spin_trend([0.0, 1.0, 2.0], [1.0, np.inf, 1.0])
    with pytest.raises(DiagnosticsError, match="3 epochs but period has 2"):
        fit_spin_trend([0.0, 1.0, 2.0], [1.0, 1.0])


# --- a propagated sphere against the closed form ---------------------------------------

def _sphere_run(omega, tau_steps=100):
    """A sphere (I = 0.1 kg m^2, m = 20 S m^4) in a uniform 30 uT field along x:
    omega_perp(t) = omega_perp0 exp(-t / tau), tau = I / (m B^2) = 64.3 d, omega_par
    kept.  Splitting step tau / tau_steps: its Runge-Kutta kick (order 4) is off by
    (h / tau)^5 / 120 per step, (t / tau) (h / tau)^4 / 120 = 3e-12 over the run."""
    moment, m, b = 0.1, 20.0, 3e-5
    tau = moment / (m * b * b)
    body = att.RigidBody.from_principal_moments([moment] * 3)
    damper = EddyCurrentDamping(m, UniformField([b, 0.0, 0.0]))
    state = att.AttitudeState.from_quaternion([0, 0, 0, 1], epoch="2030-01-01",
                                              omega_body=omega)
    t = np.linspace(0.0, 2 * DAY, 49)
    eph = att.propagate(body, state, t, torques=[damper], step=tau / tau_steps)
    return eph, t, tau


@pytest.mark.slow      # a long study (> 9 s); the slow tier, which CI runs
def test_sphere_spin_down_follows_the_closed_form():
    eph, t, tau = _sphere_run([0.0, 0.0, 2.0])                # spin across the field
    trend = spin_trend(eph)
    assert abs(trend.efolding / tau - 1.0) < 1e-8
    exact = fit_spin_trend(t, 2 * np.pi / 2.0 * np.exp(t / tau))
    assert abs(trend.trend / exact.trend - 1.0) < 1e-8
    assert abs(trend.period_end / (np.pi * np.exp(t[-1] / tau)) - 1.0) < 1e-8


def test_sphere_with_a_spin_along_the_field_keeps_that_part():
    eph, t, tau = _sphere_run([1.0, 0.0, 2.0])                # 1 rad/s along B
    omega = np.sqrt(1.0 + 4.0 * np.exp(-2 * t / tau))
    assert np.max(np.abs(spin_period_series(eph) * omega / (2 * np.pi) - 1.0)) < 1e-8
    trend, exact = spin_trend(eph), fit_spin_trend(t, 2 * np.pi / omega)
    assert abs(trend.trend / exact.trend - 1.0) < 1e-7
    assert abs(trend.efolding / exact.efolding - 1.0) < 1e-7
    assert trend.efolding > tau                                # slower than exp(-t/tau)


def test_a_tumbler_period_is_constant_without_torques():
    """2 pi |L| / 2E is a constant of the torque-free motion, unlike 2 pi / |omega|."""
    body = att.RigidBody.from_principal_moments([0.61, 0.965, 1.0])
    state = att.AttitudeState.from_quaternion([0, 0, 0, 1], epoch="2029-04-13",
                                              omega_body=[0.02, 0.0, 0.1])
    eph = att.propagate(body, state, np.linspace(0.0, 3000.0, 301))
    p = spin_period_series(eph)
    omega = np.linalg.norm(eph.dataset["angular_velocity"].values, axis=1)
    assert np.ptp(2 * np.pi / omega) > 1e-3 * p[0]           # |omega| nutates
    assert np.ptp(p) <= 1e-12 * p[0]                          # E and |L| do not


# --- [expect] keys, summary and report ------------------------------------------------

_SPHERE = """
[body]
principal_moments = [0.1, 0.1, 0.1]

[state]
epoch = "2030-01-01T00:00:00"
time_scale = "tt"
omega_body = [0.0, 0.0, 2.0]

[propagation]
duration = "2 d"
step = "1 h"
integrator_step = "1600 s"

[[torques]]
type = "eddy_current"
magnetic_tensor = 20.0
field = {{ model = "uniform", vector = {{ value = [30000, 0, 0], unit = "nT" }} }}

[expect]
{expect}
"""


def _write(tmp_path, expect: str) -> Path:
    path = tmp_path / "sphere.toml"
    path.write_text(_SPHERE.format(expect=expect))
    return path


def test_expect_keys_check_the_spin_period_and_its_trend(tmp_path):
    tau_d = 0.1 / (20.0 * 3e-5**2) / DAY                       # 64.3 d
    p_end = math.pi * math.exp(2.0 / tau_d)
    # dP/dt of the exact exponential sampled hourly, as the run samples it
    t = np.arange(0.0, 2 * DAY + 1, 3600.0)
    slope = fit_spin_trend(t, math.pi * np.exp(t / (tau_d * DAY))).trend_ms_per_day
    path = _write(tmp_path, f"""
spin_period = {{ value = {p_end:.9f}, rel_tol = 1e-6 }}
spin_period_trend = {{ value = {slope / 1000:.12g}, unit = "s/day", rel_tol = 1e-6 }}
spin_down_efolding = {{ value = {tau_d * 24:.9f}, unit = "h", rel_tol = 1e-6 }}
""")
    result = run_scenario(load_scenario(path), write_outputs=False)
    got = {e["key"]: e for e in result.expectations}
    assert set(got) == {"spin_period", "spin_period_trend", "spin_down_efolding"}
    assert all(e["ok"] for e in result.expectations), result.expectations
    assert got["spin_period"]["at"] == "end" and got["spin_period"]["unit"] == "s"
    report = result.report()["spin"]
    assert abs(report["efolding_days"] / tau_d - 1.0) < 1e-6
    assert report["samples"] == 49
    json.dumps(report)                                          # plain JSON types


def test_expect_spin_period_at_start_and_a_failure(tmp_path, capsys):
    path = _write(tmp_path, 'spin_period = { value = 3.2, at = "start", rel_tol = 1e-3 }')
    assert main(["check", str(path)]) == 1                      # pi s, not 3.2 s
    out = capsys.readouterr().out
    assert "FAIL" in out and "spin_period (at start): expected 3.2" in out and "got 3.142 s" in out


@pytest.mark.parametrize("expect, key", [
    ('spin_period_trend = { value = 1.0, unit = "kg", rel_tol = 0.1 }',
     "expect.spin_period_trend.unit"),
    ('spin_down_efolding = { value = 1.0, unit = "m", rel_tol = 0.1 }',
     "expect.spin_down_efolding.unit"),
    ('spin_period = { value = 1.0, at = "middle", rel_tol = 0.1 }', "expect.spin_period.at"),
    ('spin_period = { value = 1.0 }', "expect.spin_period"),
])
def test_bad_spin_expectations_name_the_key(tmp_path, capsys, expect, key):
    path = _write(tmp_path, expect)
    with pytest.raises(ScenarioError, match=key.replace(".", r"\.")):
        load_scenario(path)
    assert main(["check", str(path)]) == 2
    assert key in capsys.readouterr().err


def test_run_summary_reports_the_spin_trend(tmp_path, capsys):
    path = _write(tmp_path, 'spin_down_efolding = { value = 64.3, rel_tol = 0.01 }')
    report = tmp_path / "report.json"
    assert main(["run", str(path), "--report", str(report), "-o",
                 str(tmp_path / "out.nc")]) == 0
    doc = json.loads(report.read_text())
    assert set(doc["spin"]) >= {"period_start", "period_end", "trend", "trend_stderr",
                                "trend_ms_per_day", "efolding", "efolding_days"}
    spin = [line for line in capsys.readouterr().out.splitlines()
            if line.startswith("Spin")]
    assert len(spin) == 1 and "ms/day" in spin[0] and "e-folding 64.3 d" in spin[0]


# --- the published tumblers ------------------------------------------------------------

_KUCHARSKI_2014 = {"larets_spindown": 1 / 0.0197066, "stella_spindown": 1 / 0.00431232}


@pytest.mark.parametrize("name", sorted(_KUCHARSKI_2014))
def test_sphere_conductivity_reproduces_the_published_e_folding(name):
    """The effective conductivity in each sphere scenario is what the closed form
    tau = I / (m s.K.s), m = (2 pi / 15) sigma R^5, needs for the published e-folding
    time, with K = <B^2 1 - B B^T> the IGRF field tensor averaged along the scenario's
    orbit (three days, as the scenario files say) and s the spin axis."""
    sc = load_scenario(ROOT / "scenarios" / f"{name}.toml")
    damper = sc.torques[0]
    t = np.arange(0.0, 3 * DAY, 20.0)
    b = damper.field(t)
    b2 = np.einsum("ij,ij->i", b, b)
    s = np.asarray(sc.state.omega_body, dtype=float)
    s = sc.state.attitude.apply(s / np.linalg.norm(s))          # inertial spin axis
    kss = float(np.mean(b2 - (b @ s) ** 2))
    tau = sc.body.principal_moments[2] / (float(damper.magnetic_tensor) * kss) / DAY
    # sigma is rounded to 3 digits in the file: 0.1 %
    assert abs(tau / _KUCHARSKI_2014[name] - 1.0) < 2e-3


def test_stella_end_to_end():
    result = run_scenario(load_scenario(ROOT / "scenarios" / "stella_spindown.toml"),
                          write_outputs=False)
    assert result.ok, result.expectations
    assert abs(result.spin.efolding / DAY / _KUCHARSKI_2014["stella_spindown"] - 1) < 0.02

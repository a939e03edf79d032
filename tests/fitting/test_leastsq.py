"""Fitting rotation states to observations: closed loops on synthetic data.

The truth is a known torque-free state; observations are synthesised from it with the
exact solution and Gaussian noise of known sigma; the fit starts from a perturbed guess.
Independent checks: the coverage of the 2-sigma intervals (a Gaussian 95.4 %), the
convergence to the truth as the noise vanishes, the periods of the fitted state against
the observed ones, and the parameter round trip through a state.

The studies over many random cases assert statistics with bounds from their
distributions (binomial counts, chi^2 quantiles), each with a false-alarm probability
``ALPHA``, whatever path the optimiser takes on a given CPU and BLAS: a fit may stop
converged or out of evaluations at an acceptable chi^2 (both are fits of the data), and
one that does not fit the data must say so in its status.
"""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import attitude as att
from attitude.fitting import PARAMETERS, free_parameters
from attitude.fitting.synthetic import (
    noisy_attitudes,
    parameter_differences,
    perturbed_state,
    random_state,
    synthetic_lightcurve,
)
from attitude.foundations.errors import AttitudeError
from tests.fitting.fit_statistics import (
    FITTED,
    assert_status_is_consistent,
    chi2_bounds,
    coverage_floor,
    fit_to_its_end,
    most_unfitted,
)

BODY = att.RigidBody.from_principal_moments([0.6, 0.9, 1.0])
EPOCH = "2029-04-13T00:00:00"


def _state(rng, regime):
    """A random SAM or LAM state of BODY (C/B = 1.111 is the separatrix)."""
    return random_state(BODY, regime, rng, epoch=EPOCH)


def test_parameters_round_trip_through_a_state():
    rng = np.random.default_rng(3)
    for regime in ("SAM", "LAM"):
        state = _state(rng, regime)
        p, model = free_parameters(BODY, state)
        body2, state2 = model.body_and_state([p[k] for k in PARAMETERS])
        np.testing.assert_allclose(body2.principal_moments, BODY.principal_moments,
                                   rtol=1e-12)
        np.testing.assert_allclose(state2.omega_body, state.omega_body, rtol=0,
                                   atol=1e-12 * np.linalg.norm(state.omega_body))
        angle = (state2.attitude.inv() * state.attitude).magnitude()
        assert angle < 1e-12


def test_forward_model_equals_propagate():
    rng = np.random.default_rng(4)
    t = np.linspace(0.0, 60.0, 7)
    for regime in ("SAM", "LAM"):
        state = _state(rng, regime)
        p, model = free_parameters(BODY, state)
        q, w = model.evaluate(np.array([[p[k] for k in PARAMETERS]]), t)
        eph = att.propagate(BODY, state, t).dataset
        angle = (Rotation.from_quat(q[0]).inv()
                 * Rotation.from_quat(eph["quaternion"].values)).magnitude()
        # both are the exact solution; the parameterisation adds a few ulps per turn
        assert angle.max() < 1e-11
        np.testing.assert_allclose(w[0], eph["angular_velocity"].values, rtol=0,
                                   atol=1e-11 * np.abs(w).max())


@pytest.mark.parametrize("regime", ["SAM", "LAM"])
def test_two_sigma_intervals_cover_the_truth(regime):
    """25 random states per regime (50 in all), attitude data with 0.05 deg noise: the
    fits fit the data (statuses in FITTED but for the binomial few whose chi^2 exceeds
    the acceptable quantile; chi^2 within its distribution's range), find the regime, and
    the fraction of (case, parameter) pairs inside the 2-sigma interval is above the
    binomial floor of a Gaussian's 95.4 % (about 91 % for 200 pairs)."""
    rng = np.random.default_rng(11 if regime == "SAM" else 12)
    sigma = np.radians(0.05)
    t = np.linspace(0.0, 30.0, 60)
    inside, unfitted, n_cases = [], [], 25
    for _ in range(n_cases):
        truth = _state(rng, regime)
        q = noisy_attitudes(att.propagate(BODY, truth, t).dataset["quaternion"].values, sigma, rng)
        guess = perturbed_state(truth, rng, 0.01)
        res = fit_to_its_end(att.AttitudeObservations(t, q, sigma), BODY, guess)
        if res.status not in FITTED:
            unfitted.append((res.status, res.chi2))
            continue
        assert res.regime == regime
        lo, hi = chi2_bounds(res.dof, n_cases)
        assert lo < res.chi2 < hi, (res.chi2, res.dof)
        p_true, _ = free_parameters(BODY, truth)
        d = parameter_differences(res.parameters, p_true)
        inside += [abs(d[name]) <= 2 * res.uncertainties[name] for name in PARAMETERS]
    assert len(unfitted) <= most_unfitted(n_cases), unfitted
    assert np.mean(inside) >= coverage_floor(len(inside)), np.mean(inside)


def test_noise_free_fit_converges_to_the_truth():
    rng = np.random.default_rng(5)
    truth = _state(rng, "LAM")
    t = np.linspace(0.0, 30.0, 40)
    q = att.propagate(BODY, truth, t).dataset["quaternion"].values
    res = att.fit(att.AttitudeObservations(t, q, "1e-6 deg"), BODY,
                  perturbed_state(truth, rng, 0.02))
    p_true, _ = free_parameters(BODY, truth)
    for name in ("energy_ratio", "ratio_a", "ratio_b", "precession_period"):
        assert res.parameters[name] == pytest.approx(p_true[name], rel=1e-8)
    assert (res.state.attitude.inv() * truth.attitude).magnitude() < 1e-8
    assert res.alternatives[0][0] == pytest.approx(res.chi2, rel=1e-6, abs=1e-9)


def test_rates_and_periods_mix():
    rng = np.random.default_rng(6)
    truth = _state(rng, "SAM")
    t = np.linspace(0.0, 20.0, 30)
    eph = att.propagate(BODY, truth, t).dataset
    d = att.diagnose(BODY, truth)
    sigma_w = 1e-6
    obs = [att.AngularVelocityObservations(
               t, eph["angular_velocity"].values + sigma_w * rng.standard_normal((30, 3)),
               sigma_w),
           att.PeriodObservations(precession=(d.periods["precession"], 1e-3))]
    res = att.fit(obs, BODY, perturbed_state(truth, rng, 0.01),
                  free=["energy_ratio", "ratio_a", "ratio_b", "precession_period", "psi0"],
                  multistart=False)
    p_true, _ = free_parameters(BODY, truth)
    for name in res.free:
        assert abs(res.parameters[name] - p_true[name]) < 4 * res.uncertainties[name] + 1e-12


def test_apophis_periods_give_back_its_energy_ratio():
    """scenarios/apophis.toml (Pravec et al. 2014): its body and state reproduce its
    published periods; fitted to those periods (P_phi = 27.38 +- 0.07 h, P_psi = 263 +-
    6 h) with the moment ratios fixed, E/E0 and P_phi come back within their sigmas."""
    from attitude.app.scenario import load_scenario
    sc = load_scenario("scenarios/apophis.toml")
    d = att.diagnose(sc.body, sc.state)
    assert d.periods["precession"] / 3600 == pytest.approx(27.38, rel=0.01)
    assert d.periods["rotation"] / 3600 == pytest.approx(263.0, rel=0.03)
    p_true, _ = free_parameters(sc.body, sc.state)
    guess = att.AttitudeState(sc.state.epoch, sc.state.attitude, sc.state.omega_body * 1.01)
    obs = att.PeriodObservations(precession=("27.38 h", "0.07 h"), rotation=("263 h", "6 h"))
    both = att.fit(obs, sc.body, guess, free=["energy_ratio", "precession_period"])
    # two periods cannot tell SAM from LAM: both fit exactly, and the result says so
    assert {regime for chi2, regime in both.alternatives if chi2 < 1.0} == {"SAM", "LAM"}, \
        both.alternatives
    res = att.fit(obs, sc.body, guess, free=["energy_ratio", "precession_period"],
                  multistart=False)
    assert res.regime == "SAM"
    assert abs(res.parameters["energy_ratio"] - p_true["energy_ratio"]) \
        < 3 * res.uncertainties["energy_ratio"]
    assert res.parameters["precession_period"] / 3600 == pytest.approx(27.38, abs=0.2)


def test_posterior_sampling_brackets_the_fit():
    pytest.importorskip("emcee")
    rng = np.random.default_rng(8)
    truth = _state(rng, "SAM")
    t = np.linspace(0.0, 20.0, 30)
    sigma = np.radians(0.1)
    q = noisy_attitudes(att.propagate(BODY, truth, t).dataset["quaternion"].values, sigma, rng)
    free = ["energy_ratio", "precession_period"]
    res = att.fit(att.AttitudeObservations(t, q, sigma), BODY, truth, free=free)
    post = att.sample_posterior(res, n_walkers=8, n_steps=300, rng=1)
    assert post.samples["energy_ratio"].shape == (225, 8)
    lo, mid, hi = post.intervals(0.95)["energy_ratio"]
    # the 95 % interval of a Gaussian posterior is about +- 1.96 sigma of the fit
    width = (hi - lo) / (2 * 1.96 * res.uncertainties["energy_ratio"])
    assert 0.5 < width < 2.0
    assert abs(mid - res.parameters["energy_ratio"]) < res.uncertainties["energy_ratio"]
    assert post.regime_fractions == {"SAM": 1.0}
    assert 0.1 < post.acceptance_fraction < 0.9


@pytest.mark.parametrize("kwargs, match", [
    (dict(free=["spin_rate"]), "unknown parameter"),
    (dict(free=list(PARAMETERS) * 1), "residuals"),
])
def test_bad_fit_requests_are_keyed_errors(kwargs, match):
    obs = att.PeriodObservations(precession=("27.38 h", "0.07 h"))
    state = att.AttitudeState(EPOCH, Rotation.identity(), [0.1, 0.2, 1.0])
    with pytest.raises(AttitudeError, match=match) as err:
        att.fit(obs, BODY, state, **kwargs)
    assert err.value.key == "free"


@pytest.mark.parametrize("make, key", [
    (lambda: att.AttitudeObservations([0.0], [[0, 0, 0, 0]], "1 deg"), "quaternions"),
    (lambda: att.AttitudeObservations([0.0, 1.0], [[0, 0, 0, 1]], "1 deg"), "times"),
    (lambda: att.AttitudeObservations([0.0], [[0, 0, 0, 1]], "-1 deg"), "sigma"),
    (lambda: att.AngularVelocityObservations([0.0], [[0, 0, np.nan]], 1e-3), "omega"),
    (lambda: att.PeriodObservations(wobble=(1.0, 0.1)), "wobble"),
    (lambda: att.PeriodObservations(precession=(1.0,)), "precession"),
    (lambda: att.PeriodObservations(precession=("1 h", "1 kg")), "precession.sigma"),
])
def test_bad_observations_name_the_field(make, key):
    with pytest.raises(AttitudeError) as err:
        make()
    assert err.value.key == key


def test_a_fit_that_does_not_converge_says_so():
    rng = np.random.default_rng(9)
    truth = _state(rng, "SAM")
    t = np.linspace(0.0, 20.0, 30)
    q = att.propagate(BODY, truth, t).dataset["quaternion"].values
    res = att.fit(att.AttitudeObservations(t, q, "0.01 deg"), BODY,
                  perturbed_state(truth, rng, 0.2), max_nfev=2, multistart=False)
    assert not res.success and res.status == "max_nfev"
    assert "maximum number of function evaluations" in res.message
    assert_status_is_consistent(res)


def _noisy_sam(seed):
    """``(rng, truth, observations)``: a random SAM state of BODY and 30 attitudes of it
    over 20 s with 0.05 deg of Gaussian noise, from the seed."""
    rng = np.random.default_rng(seed)
    truth = _state(rng, "SAM")
    t = np.linspace(0.0, 20.0, 30)
    sigma = np.radians(0.05)
    q = noisy_attitudes(att.propagate(BODY, truth, t).dataset["quaternion"].values,
                        sigma, rng)
    return rng, truth, att.AttitudeObservations(t, q, sigma)


def test_a_fit_out_of_evaluations_continued_fits_the_data():
    """The fit of test_a_fit_that_does_not_converge_says_so stopped after 2 evaluations,
    continued from where it stopped (fit_to_its_end): it fits the data, its chi^2 within
    the range of its distribution, like the uninterrupted fit's."""
    rng, truth, obs = _noisy_sam(9)
    guess = perturbed_state(truth, rng, 0.2)
    stopped = att.fit(obs, BODY, guess, max_nfev=2, multistart=False)
    assert stopped.status == "max_nfev"
    res = fit_to_its_end(obs, BODY, guess, max_nfev=2)
    assert res.status in FITTED and res.regime == "SAM", res.message
    lo, hi = chi2_bounds(res.dof, 1)
    assert lo < res.chi2 < hi, (res.chi2, res.dof)


def test_out_of_evaluations_at_an_acceptable_chi2_says_so():
    """Started at the truth with data of known noise, the solver stopped after its first
    evaluations: chi^2 is that of the truth, chi^2(n)-distributed, below the acceptable
    quantile of chi^2(dof) (by 1.6 sigma of the sum for this noise realisation; its
    value at the truth is seeded, so no CPU path changes it by more than round-off)."""
    _, truth, obs = _noisy_sam(10)
    res = att.fit(obs, BODY, truth, max_nfev=1, multistart=False)
    assert res.status == "max_nfev at an acceptable chi2" and not res.success
    assert_status_is_consistent(res)
    assert f"for {res.dof} degrees of freedom" in res.message
    assert "raise max_nfev" in res.message


def test_apophis_from_its_own_syntheticsynthetic_lightcurve():
    """scenarios/apophis.toml (Pravec et al. 2014), its homogeneous ellipsoid, 600
    magnitudes (0.01 mag) over 20 days at 20 deg phase: E/E0, A/C and B/C come back
    within 3 sigma, and the uncertainty of E/E0 is below the published 0.013."""
    from attitude.app.scenario import load_scenario
    sc = load_scenario("scenarios/apophis.toml")
    shape = att.Polyhedron.ellipsoid_from_moments(sc.body.principal_moments, subdivisions=2)
    geom = att.Geometry(sun=[1.0, 0.0, 0.0], observer=[np.cos(0.35), np.sin(0.35), 0.1])
    rng = np.random.default_rng(1)
    t = np.sort(rng.uniform(0.0, 20 * 86400.0, 600))
    mag = synthetic_lightcurve(sc.body, sc.state, t, geom, shape, 0.01, rng)
    guess = att.AttitudeState(sc.state.epoch, sc.state.attitude
                              * Rotation.from_rotvec([0.02, -0.01, 0.01]),
                              sc.state.omega_body * [1.003, 0.997, 1.002])
    res = att.fit(att.LightcurveObservations(t, mag, 0.01, geom, shape), sc.body, guess,
                  multistart=False)
    assert_status_is_consistent(res)
    assert res.status in FITTED and res.regime == "SAM", res.message
    p_true, _ = free_parameters(sc.body, sc.state)
    for name in ("energy_ratio", "ratio_a", "ratio_b"):
        assert abs(res.parameters[name] - p_true[name]) < 3 * res.uncertainties[name], name
    assert 0 < res.uncertainties["energy_ratio"] < 0.013
    lo, hi = chi2_bounds(res.dof, 1)
    assert lo < res.chi2 < hi, (res.chi2, res.dof)


@pytest.mark.slow      # a long study (> 9 s); the slow tier, which CI runs
def test_two_sigma_intervals_cover_the_truth_with_lightcurves():
    """12 random states (6 SAM, 6 LAM) seen as lightcurves of a triaxial ellipsoid
    (0.02 mag): the (case, parameter) pairs inside 2 sigma above the binomial floor of a
    Gaussian's 95.4 %.  L is kept more than 30 deg from the inertial pole, where the
    parameterisation is singular (RA of L and phi0 turn about the same axis there; see
    attitude.fitting.parameters).  A fit may stop converged or out of evaluations at an
    acceptable chi^2 (both fit the data, whichever path the optimiser took on this CPU);
    one out of evaluations at a higher chi^2 is continued from where it stopped (where a
    path runs out depends on the CPU: fit_to_its_end); one that does not fit the data
    says so: a local minimum of the 80-facet mesh's kinked chi^2 (facets crossing the
    terminator and the limb), at most 2 of the 12 (the allowance for such minima from a
    0.3 % start: one here, at chi^2 ~1e4, which other starts do not leave either)."""
    shape = att.Polyhedron.ellipsoid_from_moments(BODY.principal_moments, subdivisions=1)
    geom = att.Geometry(sun=[1.0, 0.0, 0.0], observer=[np.cos(0.4), np.sin(0.4), 0.2])
    rng = np.random.default_rng(21)
    t = np.linspace(0.0, 120.0, 300)
    sigma = 0.02
    inside, unfitted = [], []
    for regime in ("SAM", "LAM") * 6:
        truth = random_state(BODY, regime, rng, epoch=EPOCH, max_abs_dec=np.radians(60))
        mag = synthetic_lightcurve(BODY, truth, t, geom, shape, sigma, rng)
        # reported for what it is, never a silent answer; continued where it ran out
        res = fit_to_its_end(att.LightcurveObservations(t, mag, sigma, geom, shape), BODY,
                             perturbed_state(truth, rng, 0.003))
        if res.status not in FITTED:
            unfitted.append((res.status, res.chi2, res.dof))
            continue
        assert res.regime == regime
        p_true, _ = free_parameters(BODY, truth)
        d = parameter_differences(res.parameters, p_true)
        inside += [abs(d[name]) <= 2 * res.uncertainties[name] for name in PARAMETERS]
    assert len(unfitted) <= 2, unfitted
    assert np.mean(inside) >= coverage_floor(len(inside)), np.mean(inside)


def test_attitude_fit_cli_end_to_end(tmp_path, capsys):
    """scenarios/tumbler_fit.toml: its first guess fitted to its CSV of quaternions; the
    fitted scenario loads, and holds the moment ratios the data were made with (A/C =
    0.6, B/C = 0.9) within 4 sigma of the printed uncertainties."""
    from attitude.app.cli import main
    from attitude.app.scenario import load_scenario
    out = tmp_path / "fitted.toml"
    assert main(["fit", "scenarios/tumbler_fit.toml", "-o", str(out), "--plot"]) == 0
    assert (tmp_path / "fitted_residuals.png").stat().st_size > 1000
    text = capsys.readouterr().out
    assert "converged" in text and "regime LAM" in text
    fitted = load_scenario(out)
    p, _ = free_parameters(fitted.body, fitted.state)
    sigma = {line.split()[0]: float(line.split()[3]) for line in text.splitlines()
             if line.strip().startswith(("ratio_a", "ratio_b"))}
    assert abs(p["ratio_a"] - 0.6) < 4 * sigma["ratio_a"]
    assert abs(p["ratio_b"] - 0.9) < 4 * sigma["ratio_b"]


def test_attitude_fit_bad_observations_exit_2(tmp_path, capsys):
    from attitude.app.cli import main
    (tmp_path / "q.csv").write_text("t,qx,qy,qz\n0,0,0,0\n")
    text = open("scenarios/tumbler_fit.toml").read().replace(
        "data/tumbler_quaternions.csv", "q.csv")
    (tmp_path / "s.toml").write_text(text)
    assert main(["fit", str(tmp_path / "s.toml")]) == 2
    err = capsys.readouterr().err
    assert "observations.attitude.file" in err and "qw" in err and "Traceback" not in err


@pytest.mark.parametrize("text, words", [
    ("", ["empty file", "qw"]),                                   # numpy warned, then crashed
    ("# only a comment\n", ["empty file"]),
    ("t,qx,qy,qz,qw\n", ["no samples after the header"]),
    ("t,qx,qy,qz,qw\n0,0,0,0,1\n1,\"\",0,0,1\n", ["line 3", "not a number"]),   # a text field
    ("t,qx,qy,qz,qw\n0,0,0,0,1\n1,0.1,x#!,0,1\n", ["line 3", "not a number"]),
    ("t,qx,qy,qz,qw\n0,0,0,0,1\n1,0,0,0\n", ["line 3", "expected 5 fields"]),
    ("t,qx,qy,qz,qw\nnan,0,0,0,1\n", ["line 2", "not finite"]),
    ("t,qx,qy,qz,qw\n0,0,0,1e999,1\n", ["line 2", "not finite"]),
    ("t,qx,qy,qz,qw\n0,0,0,0,0\n", ["line 2", "quaternion is zero"]),
    ("time,qx,qy,qz,qw\n2026-11-25T00:00:00,0,0,0,1\n2026-13-25,0,0,0,1\n",
     ["line 3", "ISO 8601"]),
    (b"t,qx,qy,qz,qw\n0,0,0,0,1\n\x00\xff\xfe\n", ["line 3", "expected 5 fields"]),
])
def test_a_broken_samples_file_is_one_keyed_error_naming_the_line(tmp_path, text, words):
    """Each broken quaternion file: a ScenarioError keyed observations.attitude.file
    that names the file (and the line), with no warning of numpy on the way."""
    import warnings

    from attitude.fitting.config import parse_observations
    from attitude.foundations.errors import ScenarioError
    (tmp_path / "q.csv").write_bytes(text if isinstance(text, bytes) else text.encode())
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(ScenarioError) as err:
            parse_observations({"attitude": {"file": "q.csv", "sigma": 1e-3}}, tmp_path,
                               tmp_path / "fit.toml")
    assert err.value.key == "observations.attitude.file"
    assert "q.csv" in err.value.reason and all(w in err.value.reason for w in words)

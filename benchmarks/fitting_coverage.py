"""Fitting, closed loop: coverage of the 2-sigma intervals and convergence as the noise
vanishes (issue 16, "Numbers it must show").

Every case is the loop of tests/fitting/test_leastsq.py, drawn with the same generators
(:mod:`attitude.fitting.synthetic`): a hidden torque-free state of the body A:B:C =
0.6:0.9:1.0 (:func:`~attitude.fitting.synthetic.random_state`: uniformly random
attitude, rates 0.3 N(0, 1) rad/s with the C (SAM) or A (LAM) component x 4, kept if
more than 0.1 from the separatrix), observations synthesised from it with the exact
solution and Gaussian noise, and ``att.fit`` (all eight parameters free,
``multistart=False``) from a perturbed guess
(:func:`~attitude.fitting.synthetic.perturbed_state`).  Cases alternate SAM, LAM, SAM,
...; case ``i`` of data kind ``k`` is drawn from ``default_rng([seed, k, i])`` (its noise
from ``default_rng([seed, k, i, 1])``), so any case can be re-run alone.

* attitude data: 60 quaternions over 30 s, 0.05 deg per axis; guess perturbed by 0.01
  (rad and relative);
* lightcurve data: 300 magnitudes over 120 s, 0.02 mag, of the 1280-facet ellipsoid of
  the same moments (``--subdivisions 3``; the tests use the 80-facet one, 1) with the
  default law of LightcurveObservations, Sun along x, observer
  along (cos 0.4, sin 0.4, 0.2) (phase angle 25 deg); L drawn at |dec| <= 60 deg (the
  parameterisation by the direction of L is singular at the poles: see
  attitude.fitting.parameters); guess perturbed by 0.003.

Part 1, coverage: for each case and parameter, whether ``|fitted - true| <= 2 sigma``
(angles wrapped), with the fit's success flag and chi2.  Coverage per parameter, of the
cases with all eight inside, of the (case, parameter) instances, and of the joint test
``d^T C^-1 d <= chi2_8(95 %)`` (C the fit's covariance) and of the likelihood-ratio test
``chi2(truth) - chi2(fit) <= chi2_8(95 %)`` (which needs no quadratic approximation of
chi2, so it tells intervals that are too narrow from fits that went astray), each with
its Clopper-Pearson 95 % interval; SAM and LAM apart and together.  A Gaussian gives
95.4 % per parameter, 95 % for the joint and likelihood-ratio tests, and for all eight at
once the mean over the cases of P(all |z_i| <= 2) under each fit's own correlation matrix
(Monte Carlo), printed as the expectation.  Fits reported unsuccessful are left out of
the coverage and counted apart.

Part 2, convergence: the first 3 cases of each kind again, with the same noise
realisation scaled by 1e-1, 1e-2, 1e-3, 1e-4: the error of the point estimate, the
largest ``|fitted - true| / sigma_nominal`` over the parameters (``sigma_nominal`` = the
fit's sigma / the scale), and the slope of log error against log noise (1 for an
estimator whose error is proportional to the noise).

    python benchmarks/fitting_coverage.py                 # 50 + 50 cases (minutes)
    python benchmarks/fitting_coverage.py --cases 20 --seed 3
    python benchmarks/fitting_coverage.py --subdivisions 1   # the tests' 80 facets
    python benchmarks/fitting_coverage.py --quick         # smoke run, seconds

Writes ``benchmarks/results/fitting_coverage.json`` (``--json`` elsewhere), atomically.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import scipy
from scipy.stats import binomtest, chi2

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

from _machine import cpu_name  # noqa: E402  (benchmarks/_machine.py)

import attitude as att  # noqa: E402
from attitude.fitting import PARAMETERS, free_parameters  # noqa: E402
from attitude.fitting.synthetic import (  # noqa: E402
    noisy_attitudes,
    parameter_differences,
    perturbed_state,
    random_state,
    synthetic_lightcurve,
)
from attitude.model.ephemeris import write_atomically  # noqa: E402

BODY = att.RigidBody.from_principal_moments([0.6, 0.9, 1.0])
EPOCH = "2029-04-13T00:00:00"
KINDS = ("attitude", "lightcurve")
LEVELS = (1e-1, 1e-2, 1e-3, 1e-4)
SHORT = {"angular_momentum_ra": "RA of L", "angular_momentum_dec": "Dec of L",
         "energy_ratio": "E/E0", "ratio_a": "A/C", "ratio_b": "B/C",
         "precession_period": "P_phi", "phi0": "phi0", "psi0": "psi0"}


class Setup:
    """The observation design of each data kind (module docstring)."""

    sigma_att = np.radians(0.05)
    t_att = np.linspace(0.0, 30.0, 60)
    sigma_lc = 0.02
    t_lc = np.linspace(0.0, 120.0, 300)
    shape = None                           # set by main (--subdivisions)
    geom = att.Geometry(sun=[1.0, 0.0, 0.0], observer=[np.cos(0.4), np.sin(0.4), 0.2])
    max_dec_lc = np.radians(60.0)
    perturb = {"attitude": 0.01, "lightcurve": 0.003}


def draw_case(kind: str, i: int, seed: int):
    """Case ``i`` of ``kind``: regime, hidden state, first guess."""
    rng = np.random.default_rng([seed, KINDS.index(kind), i])
    regime = ("SAM", "LAM")[i % 2]
    max_dec = Setup.max_dec_lc if kind == "lightcurve" else None
    truth = random_state(BODY, regime, rng, epoch=EPOCH, max_abs_dec=max_dec)
    guess = perturbed_state(truth, rng, Setup.perturb[kind])
    return regime, truth, guess


def observe(kind: str, truth, i: int, seed: int, scale: float = 1.0):
    """The noisy observations of ``truth``, noise of ``scale`` x the nominal sigma (the
    same standard-normal draws at every scale)."""
    rng = np.random.default_rng([seed, KINDS.index(kind), i, 1])
    if kind == "attitude":
        q = att.propagate(BODY, truth, Setup.t_att).dataset["quaternion"].values
        sigma = scale * Setup.sigma_att
        return att.AttitudeObservations(Setup.t_att, noisy_attitudes(q, sigma, rng), sigma)
    sigma = scale * Setup.sigma_lc
    mag = synthetic_lightcurve(BODY, truth, Setup.t_lc, Setup.geom, Setup.shape, sigma, rng)
    return att.LightcurveObservations(Setup.t_lc, mag, sigma, Setup.geom, Setup.shape)


def p_all_inside(cov: np.ndarray, rng, n: int = 20000) -> float:
    """P(all |z_i| <= 2) for z ~ N(0, correlation of ``cov``), Monte Carlo."""
    s = np.sqrt(np.diag(cov))
    if not np.all(s > 0):
        return float("nan")
    corr = cov / np.outer(s, s)
    w, v = np.linalg.eigh(0.5 * (corr + corr.T))
    z = rng.standard_normal((n, len(s))) * np.sqrt(np.clip(w, 0, None)) @ v.T
    return float(np.mean(np.all(np.abs(z) <= 2, axis=1)))


def run_case(kind: str, i: int, seed: int) -> dict:
    regime, truth, guess = draw_case(kind, i, seed)
    obs = observe(kind, truth, i, seed)
    start = time.perf_counter()
    res = att.fit(obs, BODY, guess, multistart=False)
    elapsed = time.perf_counter() - start
    p_true, _ = free_parameters(BODY, truth)
    d = parameter_differences(res.parameters, p_true)
    sig = np.array([res.uncertainties[n] for n in PARAMETERS])
    dv = np.array([d[n] for n in PARAMETERS])
    with np.errstate(divide="ignore", invalid="ignore"):
        z = dv / sig
    try:
        mahal = float(dv @ np.linalg.solve(res.covariance, dv))
    except np.linalg.LinAlgError:
        mahal = float("nan")
    r_true = res.objective.residuals(np.array([p_true[n] for n in PARAMETERS]))[0, :-1]
    delta_chi2 = float(r_true @ r_true) - res.chi2
    return {"kind": kind, "index": i, "regime": regime, "fitted_regime": res.regime,
            "success": res.success, "message": res.message if not res.success else "",
            "chi2": res.chi2, "dof": res.dof,
            "dec_deg": float(np.degrees(p_true["angular_momentum_dec"])),
            "z": dict(zip(PARAMETERS, map(float, z))),
            "inside": {n: bool(abs(d[n]) <= 2 * res.uncertainties[n]) for n in PARAMETERS},
            "mahalanobis2": mahal, "joint_inside": bool(mahal <= chi2.ppf(0.95, 8)),
            "delta_chi2_truth": delta_chi2,
            "likelihood_ratio_inside": bool(delta_chi2 <= chi2.ppf(0.95, 8)),
            "p_all_inside_gauss": p_all_inside(res.covariance,
                                               np.random.default_rng([seed, 99, i])),
            "fit_seconds": elapsed}


def proportion(k: int, n: int) -> dict:
    """k of n with the Clopper-Pearson 95 % interval."""
    if n == 0:
        return {"k": 0, "n": 0, "fraction": float("nan"), "ci95": [float("nan")] * 2}
    ci = binomtest(k, n).proportion_ci(0.95, method="exact")
    return {"k": int(k), "n": int(n), "fraction": k / n, "ci95": [ci.low, ci.high]}


def summarise(cases: list[dict]) -> dict:
    ok = [c for c in cases if c["success"]]
    out = {"cases": len(cases), "successful": len(ok),
           "regime_recovered": sum(c["fitted_regime"] == c["regime"] for c in ok)}
    for n in PARAMETERS:
        out[n] = proportion(sum(c["inside"][n] for c in ok), len(ok))
    out["all_parameters"] = proportion(sum(all(c["inside"].values()) for c in ok), len(ok))
    out["instances"] = proportion(sum(sum(c["inside"].values()) for c in ok),
                                  len(ok) * len(PARAMETERS))
    out["joint_chi2"] = proportion(sum(c["joint_inside"] for c in ok), len(ok))
    out["likelihood_ratio"] = proportion(sum(c["likelihood_ratio_inside"] for c in ok),
                                         len(ok))
    out["gauss_all_parameters"] = float(np.nanmean([c["p_all_inside_gauss"] for c in ok])) \
        if ok else float("nan")
    pulls = [(c["chi2"] - c["dof"]) / np.sqrt(2 * c["dof"]) for c in ok]
    out["chi2_pull_median"] = float(np.median(pulls)) if ok else float("nan")
    out["chi2_pull_within_3"] = proportion(sum(abs(p) <= 3 for p in pulls), len(ok))
    return out


def cell(p: dict) -> str:
    if not p["n"]:
        return "-"
    lo, hi = p["ci95"]
    return f"{100 * p['fraction']:.1f} [{100 * lo:.0f}, {100 * hi:.0f}]"


def print_coverage(summary: dict):
    cols = [(k, r) for k in KINDS for r in ("SAM", "LAM", "both")]
    print("| 2-sigma coverage, % [95 % CI] | " + " | ".join(
        f"{k} {r} (n={summary[k][r]['successful']})" for k, r in cols) + " |")
    print("| --- |" + " ---: |" * len(cols))
    for n in PARAMETERS:
        print(f"| {SHORT[n]} | " + " | ".join(cell(summary[k][r][n]) for k, r in cols) + " |")
    rows = (("all 8 inside (cases)", "all_parameters"), ("(case, parameter) instances",
            "instances"), ("joint d'C^-1 d <= chi2_8(95 %)", "joint_chi2"),
            ("chi2(truth) - chi2(fit) <= chi2_8(95 %)", "likelihood_ratio"),
            ("chi2 within dof +- 3 sqrt(2 dof)", "chi2_pull_within_3"))
    for label, key in rows:
        print(f"| {label} | " + " | ".join(cell(summary[k][r][key]) for k, r in cols) + " |")
    print("| Gaussian expectation, all 8 inside | " + " | ".join(
        f"{100 * summary[k][r]['gauss_all_parameters']:.1f}" for k, r in cols) + " |")
    print("| fits reported successful | " + " | ".join(
        f"{summary[k][r]['successful']}/{summary[k][r]['cases']}" for k, r in cols) + " |")
    print("| fitted regime = true regime | " + " | ".join(
        f"{summary[k][r]['regime_recovered']}/{summary[k][r]['successful']}"
        for k, r in cols) + " |")


def convergence(kind: str, i: int, seed: int, levels) -> dict:
    regime, truth, guess = draw_case(kind, i, seed)
    p_true, _ = free_parameters(BODY, truth)
    rows = []
    for level in levels:
        res = att.fit(observe(kind, truth, i, seed, level), BODY, guess, multistart=False)
        d = parameter_differences(res.parameters, p_true)
        nominal = {n: res.uncertainties[n] / level for n in PARAMETERS}
        err = max(abs(d[n]) / nominal[n] for n in PARAMETERS)
        rows.append({"level": level, "success": res.success, "error_nominal_sigmas": err,
                     "energy_ratio_error": abs(d["energy_ratio"]),
                     "max_z": max(abs(d[n]) / res.uncertainties[n] for n in PARAMETERS)})
    x = np.log10([r["level"] for r in rows])
    y = np.log10([r["error_nominal_sigmas"] for r in rows])
    slope = float(np.polyfit(x, y, 1)[0]) if len(rows) > 1 else float("nan")
    return {"kind": kind, "index": i, "regime": regime, "rows": rows, "slope": slope}


def machine() -> dict:
    try:
        commit = subprocess.run(["git", "-C", str(HERE), "rev-parse", "--short", "HEAD"],
                                capture_output=True, text=True, timeout=10).stdout.strip()
    except OSError:
        commit = ""
    return {"cpu": cpu_name(), "cores": os.cpu_count(), "python": platform.python_version(),
            "numpy": np.__version__, "scipy": scipy.__version__,
            "attitude": getattr(att, "__version__", "?"), "commit": commit or "?",
            "load_average_1min": os.getloadavg()[0]}


def parse_args(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--cases", type=int, default=50,
                   help="cases per data kind (default 50; SAM and LAM alternate)")
    p.add_argument("--seed", type=int, default=2026, help="seed of the case draws")
    p.add_argument("--convergence-cases", type=int, default=3,
                   help="cases per data kind in the convergence part (default 3)")
    p.add_argument("--subdivisions", type=int, default=3,
                   help="of the lightcurve's ellipsoid: 1280 facets at 3 (default), 80 at 1")
    p.add_argument("--quick", action="store_true",
                   help="smoke run: 4 attitude and 2 lightcurve cases (80 facets), "
                        "convergence on one case of each kind at two noise levels")
    p.add_argument("--json", default=str(HERE / "results" / "fitting_coverage.json"),
                   help="where to write the results (default "
                        "benchmarks/results/fitting_coverage.json)")
    args = p.parse_args(argv)
    if args.cases < 1 or args.convergence_cases < 0 or not 0 <= args.subdivisions <= 4:
        p.exit(2, "fitting_coverage.py: --cases must be >= 1, --convergence-cases >= 0 "
               "and --subdivisions in 0..4\n")
    if args.quick:
        args.subdivisions = 1
    return args


def main(argv=None):
    args = parse_args(argv)
    n_cases = {"attitude": 4, "lightcurve": 2} if args.quick else dict.fromkeys(
        KINDS, args.cases)
    n_conv = 1 if args.quick else args.convergence_cases
    levels = (1e-1, 1e-3) if args.quick else LEVELS
    Setup.shape = att.Polyhedron.ellipsoid_from_moments(BODY.principal_moments,
                                                        subdivisions=args.subdivisions)
    start = time.perf_counter()
    cases = {}
    for kind in KINDS:
        cases[kind] = []
        for i in range(n_cases[kind]):
            c = run_case(kind, i, args.seed)
            cases[kind].append(c)
            print(f"{kind} case {i:2d} {c['regime']}: success {c['success']}, chi2/dof "
                  f"{c['chi2']:.1f}/{c['dof']}, dec {c['dec_deg']:+.0f} deg, inside "
                  f"{sum(c['inside'].values())}/8, {c['fit_seconds']:.1f} s", flush=True)
    t_cov = time.perf_counter() - start
    summary = {k: {r: summarise([c for c in cases[k] if r in ("both", c["regime"])])
                   for r in ("SAM", "LAM", "both")} for k in KINDS}
    conv = [convergence(k, i, args.seed, levels) for k in KINDS for i in range(n_conv)]
    elapsed = time.perf_counter() - start
    info = machine()

    print(f"\nmachine: {info['cpu']}, {info['cores']} cores; Python {info['python']}, numpy "
          f"{info['numpy']}, scipy {info['scipy']}; attitude {info['attitude']} "
          f"({info['commit']}); load average {info['load_average_1min']:.1f}")
    if args.quick:
        print("QUICK RUN: a few cases, not the benchmark's numbers")
    print(f"\n1. Coverage: {n_cases['attitude']} attitude-data and {n_cases['lightcurve']} "
          f"lightcurve cases ({len(Setup.shape.faces)} facets; seed {args.seed}), all 8 "
          "parameters free; successful fits only; Gaussian: 95.4 % per parameter, 95 % "
          f"joint ({t_cov:.0f} s)")
    print_coverage(summary)
    for kind in KINDS:
        for c in cases[kind]:
            if not c["success"]:
                print(f"- {kind} case {c['index']} ({c['regime']}) reported unsuccessful: "
                      f"{c['message'][:160]}")
    print(f"\n2. Convergence: noise scaled by {', '.join(f'{x:g}' for x in levels)}; error "
          "= max over the parameters of |fitted - true| / sigma_nominal")
    print("| data | case | regime | " + " | ".join(f"error at {x:g}" for x in levels)
          + " | slope of log error vs log noise |")
    print("| --- | ---: | --- |" + " ---: |" * len(levels) + " ---: |")
    for c in conv:
        print(f"| {c['kind']} | {c['index']} | {c['regime']} | " + " | ".join(
            f"{r['error_nominal_sigmas']:.3g}" + ("" if r["success"] else " (unsuccessful)")
            for r in c["rows"]) + f" | {c['slope']:.3f} |")
    print(f"\ntotal {elapsed:.0f} s")
    record = {"benchmark": "fitting_coverage", "quick": args.quick, "seed": args.seed,
              "facets": len(Setup.shape.faces),
              "machine": info, "cases": cases, "summary": summary, "convergence": conv,
              "levels": list(levels), "elapsed_s": elapsed,
              "date_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())}
    text = json.dumps(record, indent=1, default=float, allow_nan=True)
    path = write_atomically(args.json, lambda tmp: tmp.write_text(text))
    print(f"results: {path}")


if __name__ == "__main__":
    main()

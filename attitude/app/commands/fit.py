"""``attitude fit``: the rotation state fitted to a scenario's ``[observations]``."""

from __future__ import annotations

import contextlib
import logging
import sys
from pathlib import Path

from ...fitting import fit, sample_posterior
from ...fitting.config import fitted_scenario
from ...fitting.plot import corner_figure, residual_figure
from ...model.ephemeris import write_atomically
from ...propagation.compiled import quiet_compiles
from ..scenario import load_scenario
from .common import EXIT_EXPECTATION, EXIT_INPUT, EXIT_OK

#: Nothing public: :func:`attitude.app.cli.main` runs ``command(args)`` (the command line
#: is the interface, tested in tests/app/test_cli.py).
__all__ = []


def command(args) -> int:
    """``attitude fit``; its ``--quiet`` also silences the kernels' compile notice."""
    with quiet_compiles(args.quiet):
        return _fit(args)


def _posterior_path(args, cfg) -> Path:
    """Where the MCMC samples go: beside ``-o`` and named from it when it is given
    (``out/best.toml`` -> ``out/best_posterior.nc``), else ``[observations.posterior]
    .netcdf`` or ``SCENARIO_posterior.nc``."""
    if args.output:
        out = Path(args.output)
        return out.with_name(f"{out.stem}_posterior.nc")
    if cfg.posterior_netcdf is not None:
        return Path(cfg.posterior_netcdf)
    scenario = Path(args.scenario)
    return scenario.with_name(f"{scenario.stem}_posterior.nc")


@contextlib.contextmanager
def _emcee_log():
    """emcee's log messages (the chain shorter than 50 autocorrelation times, ...) kept
    from stderr and collected, so that the command says it once in its own words."""
    logger = logging.getLogger("emcee")
    notes: list[str] = []

    class Collect(logging.Handler):
        def emit(self, record):
            notes.append(record.getMessage())

    handler, propagate = Collect(logging.WARNING), logger.propagate
    logger.addHandler(handler)
    logger.propagate = False
    try:
        yield notes
    finally:
        logger.removeHandler(handler)
        logger.propagate = propagate


def _short_chain_note(post, n_steps: int, notes: list[str]) -> str:
    """One line for what emcee logged (in practice: a chain too short to estimate its
    autocorrelation time well)."""
    taus = [t for t in post.autocorrelation_time.values() if t == t]
    if any("autocorrelation" in n for n in notes) and taus:
        return (f"attitude: note: the posterior chain ({n_steps} steps) is shorter than "
                f"50 autocorrelation times (up to {max(taus):.3g} steps): its intervals are "
                "rough; raise [observations.posterior].steps")
    return "attitude: note: emcee: " + "; ".join(dict.fromkeys(" ".join(n.split())
                                                             for n in notes))


def _fit(args) -> int:
    scenario = load_scenario(args.scenario)
    cfg = scenario.observations
    if cfg is None:
        print(f"attitude: error: {args.scenario}: observations: the scenario has no "
              "[observations] table (attitude, rates, periods or lightcurve)", file=sys.stderr)
        return EXIT_INPUT
    result = fit(list(cfg.observations), scenario.body, scenario.state, free=cfg.free,
                 multistart=cfg.multistart)
    target = Path(args.output) if args.output else cfg.output
    text = fitted_scenario(result, name=scenario.name, duration=scenario.duration,
                           step=scenario.step, source=Path(args.scenario).name)
    written = [write_atomically(target, lambda tmp: Path(tmp).write_text(text))]
    post = None
    if args.posterior or cfg.posterior is not None:
        opts = cfg.posterior or {}
        n_steps = opts.get("steps", 1000)
        with _emcee_log() as notes:
            post = sample_posterior(result, n_walkers=opts.get("walkers", 32),
                                    n_steps=n_steps, rng=opts.get("seed"),
                                    progress=not args.quiet)
        if notes and not args.quiet:
            print(_short_chain_note(post, n_steps, notes), file=sys.stderr)
        nc = _posterior_path(args, cfg)
        written.append(write_atomically(nc, lambda tmp: post.samples.to_netcdf(tmp)))
    if args.plot:
        stem = target.with_suffix("")
        figures = [("residuals", residual_figure(result))]
        if post is not None:
            figures.append(("corner", corner_figure(post)))
        for name, fig in figures:
            png = Path(f"{stem}_{name}.png")
            written.append(write_atomically(
                png, lambda tmp, fig=fig: fig.savefig(tmp, format="png", dpi=120)))
    if not args.quiet:
        status = result.status if result.success else result.status.upper()
        print(f"{scenario.name}: {status} ({result.message})")
        print(result.summary())
        if len(result.alternatives) > 1:
            alts = ", ".join(f"{r} chi2 {c:.4g}" for c, r in result.alternatives)
            print(f"  optima from the {len(result.alternatives)} starts: {alts}")
        for k, lc in enumerate(result.lightcurve_offsets()):
            print(f"  lightcurve {k} offsets (mag, one per session):")
            for label, b, s in zip(lc["session"], lc["offset"], lc["sigma"]):
                print(f"    session {label}  {b:.5f} +- {s:.2g} mag")
        if post is not None:
            print(f"  posterior: regime fractions {post.regime_fractions}, acceptance "
                  f"{post.acceptance_fraction:.2f}")
        for path in written:
            print(f"wrote {path}")
    return EXIT_OK if result.success else EXIT_EXPECTATION

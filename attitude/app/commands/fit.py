"""``attitude fit``: the rotation state fitted to a scenario's ``[observations]``."""

from __future__ import annotations

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
        post = sample_posterior(result, n_walkers=opts.get("walkers", 32),
                                n_steps=opts.get("steps", 1000), rng=opts.get("seed"))
        nc = cfg.posterior_netcdf or Path(args.scenario).with_suffix(".posterior.nc")
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
        print(f"{scenario.name}: {'converged' if result.success else 'NOT CONVERGED'} "
              f"({result.message})")
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

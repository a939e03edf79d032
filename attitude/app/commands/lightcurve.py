"""``attitude lightcurve``: a scenario's synthetic lightcurve and its periods
(photometry, issue 15)."""

from __future__ import annotations

import json
import sys
from pathlib import Path

from ...model.ephemeris import write_atomically
from ...photometry.config import run_lightcurve
from ...photometry.plot import save_lightcurve_figures
from ...propagation.compiled import quiet_compiles
from ..scenario import load_scenario
from .common import EXIT_EXPECTATION, EXIT_INPUT, EXIT_OK, expectation_line

#: Nothing public: :func:`attitude.app.cli.main` runs ``command(args)`` (the command line
#: is the interface, tested in tests/app/test_cli.py).
__all__ = []


def command(args) -> int:
    """``attitude lightcurve``; its ``--quiet`` also silences the kernels' compile notice."""
    with quiet_compiles(args.quiet):
        return _lightcurve(args)


def _lightcurve(args) -> int:
    scenario = load_scenario(args.scenario)
    if scenario.photometry is None:
        print(f"attitude: error: {args.scenario}: photometry: the scenario has no "
              "[photometry] table", file=sys.stderr)
        return EXIT_INPUT
    result = run_lightcurve(scenario, scenario.photometry, output=args.output)
    if args.plot:
        stem = Path(result.outputs[0] if result.outputs else scenario.path).with_suffix("")
        result.outputs.extend(save_lightcurve_figures(result.lightcurve, result.fit, stem))
    report = result.report()
    if args.report:
        text = json.dumps({"scenario": scenario.name, **report}, indent=2, default=float)
        write_atomically(Path(args.report), lambda tmp: Path(tmp).write_text(text + "\n"))
    if not args.quiet:
        fit = result.fit
        periods = ", ".join(f"P{k + 1} = {p / 3600:.6g} +/- {s / 3600:.2g} h" for k, (p, s)
                            in enumerate(zip(fit.periods, fit.uncertainties)))
        print(f"{scenario.name}: {len(result.lightcurve)} epochs, amplitude "
              f"{report['amplitude_mag']:.3f} mag, rms of the fit {fit.rms:.2g} mag")
        print(f"  periods: {periods}")
        print(f"  lightcurve period (double-peaked, 2/f of the strongest term "
              f"{fit.strongest}): {fit.lightcurve_period / 3600:.6g} h")
        for e in result.expect:          # as attitude run: units, the check's digits
            print(f"  {expectation_line(e)}")
        for path in result.outputs:
            print(f"  wrote {path}")
    return EXIT_OK if result.ok else EXIT_EXPECTATION

"""``attitude invert``: shape, pole and period from lightcurves alone (issue 27)."""

from __future__ import annotations

import json
from pathlib import Path

from ...inversion.config import load_inversion, run_inversion
from ...inversion.plot import pole_map, save_inversion_figures
from ...model.ephemeris import write_atomically
from ..scenario import load_scenario
from .common import EXIT_EXPECTATION, EXIT_OK, expectation_line

#: Nothing public: :func:`attitude.app.cli.main` runs ``command(args)`` (the command line
#: is the interface, tested in tests/app/test_invert_command.py).
__all__ = []


def start_from_scenario(path) -> tuple:
    """``(body, state)`` of a scenario file, for ``[inversion] start_from``."""
    scenario = load_scenario(path)
    return scenario.body, scenario.state


def command(args) -> int:
    """``attitude invert``."""
    scenario = load_inversion(args.scenario)
    run = run_inversion(scenario, output=args.output, load_start=start_from_scenario)
    res = run.result
    if args.plot:                       # matplotlib: a missing one is bad input (exit 2)
        stem = Path(str(run.outputs[0])[:-len("_shape.obj")])
        cfg = scenario.inversion
        grid = pole_map(run.observations, res, n_longitude=cfg["map_longitudes"],
                        n_latitude=cfg["map_latitudes"])
        run.outputs.extend(save_inversion_figures(run.observations, res, stem, pole=grid))
    if args.report:
        report = {"scenario": run.name, "regime": res.regime, "period": res.period,
                  "pole": list(res.pole), "rms": res.rms, "chi2": res.chi2,
                  "dark_facet": res.dark_facet, "spin_axis_tilt_deg": res.spin_axis_tilt,
                  "alternatives": [{"chi2": c, "solution": s} for c, s in res.alternatives],
                  "expect": run.expect, "outputs": [str(p) for p in run.outputs]}
        text = json.dumps(report, indent=2, default=float)
        write_atomically(Path(args.report), lambda tmp: Path(tmp).write_text(text + "\n"))
    if not args.quiet:
        lon, lat = res.pole
        tumbler = getattr(res.fit, "periods", None) is not None
        if tumbler:                        # a non-principal-axis state: L, P_phi, P_psi
            fit, p = res.fit, res.fit.parameters
            print(f"{run.name}: {res.regime} tumbler, L toward ({lon:.2f}, {lat:.2f}) deg "
                  f"(ecliptic J2000), P_phi {fit.periods['precession'] / 3600:.7g} h, "
                  f"P_psi {fit.periods['rotation'] / 3600:.7g} h, rms {res.rms:.4g}")
            print(f"  E/E0 {p['energy_ratio']:.5f}, A/C {p['ratio_a']:.4f}, B/C "
                  f"{p['ratio_b']:.4f}; the shape at uniform density: A/C "
                  f"{fit.shape_ratios[0]:.4f}, B/C {fit.shape_ratios[1]:.4f}")
        else:
            print(f"{run.name}: pole ({lon:.2f}, {lat:.2f}) deg (ecliptic J2000), sidereal "
                  f"period {res.period / 3600:.9g} h, rms {res.rms:.4g}, dark facet "
                  f"{100 * res.dark_facet:.2f} %")
            print(f"  spin axis {res.spin_axis_tilt:.2f} deg from the shape's axis of "
                  "largest inertia (uniform density)")
        for chi2, text in res.alternatives:
            print(f"  alternative: {text}, chi2 {chi2:.6g} (best {res.chi2:.6g})")
        for e in run.expect:
            print(f"  {expectation_line(e)}")
        for path in run.outputs:
            print(f"  wrote {path}")
    return EXIT_OK if run.ok else EXIT_EXPECTATION


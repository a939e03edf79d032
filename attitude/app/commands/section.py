"""``attitude section``: the spin-orbit surface of section of a scenario (the
spin-orbit wing, issue 19)."""

from __future__ import annotations

import dataclasses
import sys
import time
from pathlib import Path

from ...model.ephemeris import write_atomically
from ...propagation.compiled import quiet_compiles
from ...spinorbit import section as spinorbit_section
from ..scenario import load_scenario
from .common import EXIT_INPUT, EXIT_OK

#: Nothing public: :func:`attitude.app.cli.main` runs ``command(args)`` (the command line
#: is the interface, tested in tests/app/test_cli.py).
__all__ = []


def command(args) -> int:
    """``attitude section``; its ``--quiet`` also silences the kernels' compile notice."""
    with quiet_compiles(args.quiet):
        return _section(args)


def _section(args) -> int:
    scenario = load_scenario(args.scenario)
    if scenario.section is None:
        print(f"attitude: error: {args.scenario}: section: the scenario has no [section] "
              "table (angles, rates, n_orbits)", file=sys.stderr)
        return EXIT_INPUT
    cfg = scenario.section
    if args.orbits is not None:
        if args.orbits < 1:
            print("attitude: error: --orbits: must be at least 1", file=sys.stderr)
            return EXIT_INPUT
        cfg = dataclasses.replace(cfg, n_orbits=args.orbits)
    target = Path(args.output) if args.output else (
        cfg.netcdf or Path(args.scenario).with_suffix(".section.nc"))
    so = spinorbit_section.spin_orbit_of(scenario.body, scenario.torques)
    start = time.perf_counter()
    sec = spinorbit_section.run_section(so, cfg)
    elapsed = time.perf_counter() - start
    written = [spinorbit_section.write_section(sec, target)]
    if args.plot:
        fig = spinorbit_section.section_figure(
            sec, centres=spinorbit_section.island_centres(so))
        png = target.with_suffix(".png")
        written.append(write_atomically(png, lambda tmp: fig.savefig(tmp, format="png",
                                                                      dpi=150)))
    if not args.quiet:
        chaotic = int(sec["chaotic"].sum()) if "chaotic" in sec else 0
        print(f"{scenario.name}: {sec.sizes['initial']} initial conditions x "
              f"{sec.sizes['orbit'] - 1} orbits in {elapsed:.1f} s; omega0 = "
              f"{so.omega0:.4g}, e = {so.e:.4g}; chaotic: {chaotic}")
        for path in written:
            print(f"wrote {path}")
    return EXIT_OK

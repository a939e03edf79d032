"""Hyperion's surface of section in one batch (issue 19): 400 initial conditions x 200
orbits of the planar spin-orbit problem (Wisdom, Peale & Mignard 1984: e = 0.1,
omega0 = 0.89), each classified regular / chaotic by the finite-time Lyapunov test
against its e = 0 control.  Prints the time and the verdicts by region, and writes
docs/figures/spinorbit_hyperion_section.png and (optionally) the netCDF.

    python benchmarks/spinorbit.py [--orbits 200] [--grid 20] [--nc section.nc]
"""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

import numpy as np
import xarray as xr

import attitude as att
from attitude.spinorbit import periodic_orbit
from attitude.spinorbit.section import island_centres, section_figure, write_section

ROOT = Path(__file__).resolve().parents[1]


def hyperion() -> att.SpinOrbit:
    orbit = att.KeplerOrbit.from_elements(mu="3.7931e16 m3/s2", a="1.4811e9 m", e=0.1)
    return att.SpinOrbit.from_omega0(0.89, orbit, name="Hyperion (WPM 1984)")


def main(argv=None) -> None:
    try:
        from _machine import cpu_name
    except ImportError:  # run from elsewhere
        def cpu_name():
            return "unknown CPU"
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--orbits", type=int, default=200)
    ap.add_argument("--grid", type=int, default=20, help="grid points per axis")
    ap.add_argument("--nc", default=None)
    ap.add_argument("--figure", default=str(ROOT / "docs" / "figures" /
                                            "spinorbit_hyperion_section.png"))
    args = ap.parse_args(argv)
    so = hyperion()
    # the grid: angles over a half turn at periapsis, spin rates 0 .. 3.5 n
    angles = np.linspace(-math.pi / 2, math.pi / 2, args.grid, endpoint=False)
    rates = np.linspace(0.0, 3.5, args.grid)
    A, R = np.meshgrid(angles, rates, indexing="ij")
    t0 = time.perf_counter()
    sec = so.surface_of_section(A.ravel(), R.ravel(), n_orbits=args.orbits)
    elapsed = time.perf_counter() - t0
    chaotic = sec["chaotic"].values
    r0 = sec["initial_rate"].values
    print(f"{cpu_name()}: {chaotic.size} initial conditions x {args.orbits} orbits "
          f"(+ {chaotic.size} e = 0 controls, tangent equations) in one batch: "
          f"{elapsed:.1f} s")
    print(f"chaotic: {int(chaotic.sum())} of {chaotic.size}")
    for lo, hi in ((0.0, 0.4), (0.4, 2.4), (2.4, 3.0), (3.0, 3.51)):
        m = (r0 >= lo) & (r0 < hi)
        print(f"  initial rate in [{lo}, {hi}): {int(chaotic[m].sum())}/{int(m.sum())} "
              "chaotic")
    if args.nc:
        print("wrote", write_section(sec, args.nc))
    # the figure adds a few orbits around the p:q periodic orbits that exist and are
    # stable in the plane (a uniform grid misses the small islands); not timed above
    seeds_a, seeds_r = [], []
    print("p:q periodic orbits at periapsis (planar; |trace| < 2 is an island):")
    for p, q in ((1, 2), (1, 1), (3, 2), (2, 1), (5, 2)):
        try:
            th, w, mono = periodic_orbit(so.omega0, so.e, p, q)
        except att.SpinOrbitError:
            print(f"  {p}:{q}: no periodic orbit found from the resonance centre")
            continue
        tr = float(np.trace(mono))
        print(f"  {p}:{q}: angle {math.degrees(th):6.1f} deg, rate {w:.4f}, "
              f"trace {tr:+.3f} ({'island' if abs(tr) < 2 else 'unstable'})")
        if abs(tr) < 2:
            for dw in (0.01, 0.03, 0.06):
                seeds_a.append(th)
                seeds_r.append(w + dw)
    islands = so.surface_of_section(seeds_a, seeds_r, n_orbits=args.orbits)
    both = xr.concat([sec, islands], dim="initial")
    fig = section_figure(both, centres=island_centres(so), title=(
        f"Hyperion (e = 0.1, omega0 = 0.89): {args.orbits} orbits, "
        f"{int(chaotic.sum())}/{chaotic.size} chaotic (grey)"))
    fig.savefig(args.figure, dpi=100)
    print("wrote", args.figure)


if __name__ == "__main__":
    main()

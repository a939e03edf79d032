"""Memory of the compiled torque tables of a batch: one copy per body against one shared.

``N`` bodies (different inertias) on ONE TLE orbit (the ISS's) under gravity gradient,
aerodynamic drag, solar radiation pressure (the Sun's tabulated path, conical shadow)
and a residual magnetic dipole in IGRF, over ``--days``: the compiled forms that the
compiled loops read (``attitude.propagation.compiled_torques``).  Before: each body
laid out on its own (``compile_torques`` per body, as the splitting and DOP853 batches
did), every body holding its own copy of the TLE, Sun and IGRF cubics; after: the batch
in one ``params`` array (``compile_torques_shared``, what they do now), the tables once
and each body's own numbers (inertia, facets) after them.  Memory by ``tracemalloc``
(the Python allocations retained by the compiled forms; the environment's own tables,
built once by a warm-up and shared by both, are not counted).  Then a check that a
short batch run gives the same bits both ways.

    python benchmarks/batch_tables.py                  # 100 bodies, 30 days
    python benchmarks/batch_tables.py --bodies 10 --days 2

Prints a table; ``--json`` writes the figures (atomically).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
import tracemalloc

import numpy as np
from scipy.spatial.transform import Rotation

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from _machine import cpu_name  # noqa: E402  (benchmarks/_machine.py)

import attitude as att  # noqa: E402
from attitude.environment import (  # noqa: E402
    IGRF,
    AerodynamicDrag,
    Facets,
    SolarRadiationPressure,
    SunPath,
    TLEOrbit,
)
from attitude.model.ephemeris import write_atomically  # noqa: E402
from attitude.model.torques import EARTH_MU, GravityGradient, MagneticDipole  # noqa: E402
from attitude.propagation.compiled_torques import (  # noqa: E402
    compile_torques,
    compile_torques_shared,
)

ISS = ("1 25544U 98067A   24061.50000000  .00016717  00000-0  10270-3 0  9005",
       "2 25544  51.6416 247.4627 0006703 130.5360 325.0288 15.72125391563537")
DAY = 86400.0


def setup(n_bodies: int):
    """The bodies (boxes of different proportions) and the torques on one TLE orbit."""
    orbit = TLEOrbit(*ISS)
    sun = SunPath(orbit.epoch)
    plate = Facets.plate(2.0, [1.0, 0.0, 0.0], centroid=[0.0, 0.3, 0.0])
    torques = [GravityGradient(EARTH_MU, orbit),
               AerodynamicDrag(plate, orbit),
               SolarRadiationPressure(plate, sun=sun, orbit=orbit),
               MagneticDipole([0.0, 0.0, 0.5], IGRF(orbit))]
    rng = np.random.default_rng(1)
    bodies = [att.RigidBody.from_parts([att.MassProperties.solid_box(
        100.0, [0.5 + 0.2 * rng.random(), 1.0 + 0.2 * rng.random(), 2.0])])
        for _ in range(n_bodies)]
    return orbit, bodies, torques


def retained(fn):
    """``(result, bytes retained by it, peak bytes while it ran, wall s)``."""
    tracemalloc.start()
    tracemalloc.reset_peak()
    before = tracemalloc.get_traced_memory()[0]
    t0 = time.perf_counter()
    out = fn()
    wall = time.perf_counter() - t0
    now, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    return out, now - before, peak - before, wall


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--bodies", type=int, default=100, help="bodies in the batch (100)")
    p.add_argument("--days", type=float, default=30.0, help="span of the run, days (30)")
    p.add_argument("--check-bodies", type=int, default=3,
                   help="bodies of the short run compared bit for bit (3)")
    p.add_argument("--json", default=None, help="write the figures to this file")
    args = p.parse_args(argv)
    if args.bodies < 1 or args.days <= 0 or args.check_bodies < 1:
        p.exit(2, "batch_tables.py: --bodies, --days and --check-bodies must be positive\n")
    orbit, bodies, torques = setup(args.bodies)
    span = (0.0, args.days * DAY)
    print(f"{cpu_name()}, {os.cpu_count()} cores; {args.bodies} bodies, one TLE orbit, "
          f"{args.days:g} days", flush=True)
    t0 = time.perf_counter()
    warm = compile_torques(torques, bodies[0], t_span=span)   # builds the tables once
    print(f"environment tables over the span (SGP4, Sun, IGRF): {time.perf_counter() - t0:.1f}"
          f" s; one body's compiled form {warm.params.nbytes / 1e6:.1f} MB", flush=True)
    del warm
    per_body, mem_before, peak_before, wall_before = retained(
        lambda: [compile_torques(torques, b, t_span=span) for b in bodies])
    numbers_before = sum(c.params.size for c in per_body)
    del per_body
    shared, mem_after, peak_after, wall_after = retained(
        lambda: compile_torques_shared([torques], bodies, t_span=span))
    numbers_after = shared[0][0].params.size
    del shared
    rows = [("one copy per body (before)", mem_before, peak_before, numbers_before,
             wall_before),
            ("one shared block (now)", mem_after, peak_after, numbers_after, wall_after)]
    print("\n| layout | retained (MB) | peak while building (MB) | numbers | build (s) |")
    print("| --- | ---: | ---: | ---: | ---: |")
    for name, mem, peak, numbers, wall in rows:
        print(f"| {name} | {mem / 1e6:.1f} | {peak / 1e6:.1f} | {numbers} | {wall:.2f} |")
    print(f"\nratio {mem_before / max(mem_after, 1):.3g}; per body "
          f"{mem_before / args.bodies / 1e6:.2f} MB before, "
          f"{mem_after / args.bodies / 1e6:.3f} MB now")

    # the same bits: a short batch run against the bodies one by one (one hour)
    n = min(args.check_bodies, args.bodies)
    rng = np.random.default_rng(2)
    states = [att.AttitudeState(orbit.epoch, Rotation.random(random_state=rng),
                                rng.normal(size=3) * 0.01) for _ in range(n)]
    t = np.arange(0.0, 3601.0, 600.0)
    same = True
    for method, kw in (("splitting", {"step": 10.0}), ("integrator", {"rtol": 1e-10})):
        batch = att.propagate(bodies[:n], states, t, torques=torques, method=method, **kw)
        for i in range(n):
            one = att.propagate(bodies[i], states[i], t, torques=torques, method=method, **kw)
            same &= np.array_equal(batch.dataset.quaternion.values[i],
                                   one.dataset.quaternion.values)
    print(f"batch of {n} against the bodies one by one (splitting and DOP853, 1 h): "
          f"{'identical' if same else 'DIFFERENT'}")
    if args.json:
        record = {"benchmark": "batch_tables", "cpu": cpu_name(), "cores": os.cpu_count(),
                  "bodies": args.bodies, "days": args.days,
                  "rows": [{"layout": r[0], "retained_bytes": r[1], "peak_bytes": r[2],
                            "numbers": r[3], "build_s": r[4]} for r in rows],
                  "identical": bool(same)}
        write_atomically(args.json, lambda tmp: tmp.write_text(json.dumps(record, indent=1)))
    return 0 if same else 1


if __name__ == "__main__":
    sys.exit(main())

"""Events on the compiled DOP853 (issue 26): an event run against a plain run.

For each case, the wall time (best of ``--repeat``) of

- the plain compiled DOP853 run (``integrate_reference``, no events),
- the same run with events, compiled (``integrate_reference_events``: the event
  functions at each accepted step, crossings located on the dense output),
- the same events run by scipy's ``solve_ivp`` (``compiled=False``, the path taken
  before, and still without numba or with an event in Python),

and the largest difference of the event times between the compiled and scipy's paths.
Cases:

1. ``damper``: a long-axis spinner with an internal damper (Explorer 1's flip,
   ``EnergyDissipation``), its momentum drifting from A to C: nine nutation angles
   (10 to 90 deg from A) crossed back and forth, non-terminal;
2. ``gravity gradient``: a 0.5 x 1 x 2 m box tumbling in low Earth orbit, its nutation
   angle from C (7 to 29 deg) crossing 15 and 25 deg, non-terminal, over 6 h.

Run from the repository root (writes ``benchmarks/results/events.json``)::

    python benchmarks/events.py            # ~1 minute
    python benchmarks/events.py --quick    # a shorter span, one repeat
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), ".."))

from _machine import cpu_name  # noqa: E402  (benchmarks/_machine.py)

import attitude as att  # noqa: E402
from attitude.model.orbit import KeplerOrbit  # noqa: E402
from attitude.model.torques import EARTH_MU, GravityGradient  # noqa: E402
from attitude.propagation.events import nutation_crossing  # noqa: E402
from attitude.propagation.reference import (  # noqa: E402
    integrate_reference,
    integrate_reference_events,
)

RESULTS = Path(__file__).parent / "results" / "events.json"


def cases(quick: bool) -> dict:
    """``name -> (body, q0, w0, times, torques, events, rtol)``."""
    scale = 0.25 if quick else 1.0
    spinner = att.RigidBody.from_principal_moments([1.0, 1.2, 1.5])
    span = 2000.0 * scale
    damper = (spinner, [0.0, 0.0, 0.0, 1.0], [0.5, 0.02, 0.02],
              np.linspace(0.0, span, int(span / 2) + 1),
              [att.torques.EnergyDissipation(time_constant=200.0)],
              [nutation_crossing(np.radians(a), "A", terminal=False)
               for a in range(10, 91, 10)], 1e-12)
    # a 100 kg box 0.5 x 1 x 2 m: m (b^2 + c^2) / 12 about each axis
    box = att.RigidBody.from_principal_moments(
        100.0 / 12.0 * np.array([1.0 + 0.25, 0.25 + 4.0, 1.0 + 4.0]))
    orbit = KeplerOrbit.from_elements(mu=EARTH_MU, a="7000 km", e=0.001, i="51.6 deg")
    span = 6 * 3600.0 * scale
    gg = (box, [0.1, 0.2, 0.3, 0.927], np.radians([0.3, 0.5, 1.0]),
          np.linspace(0.0, span, int(span / 10) + 1), [GravityGradient(orbit=orbit)],
          [nutation_crossing(np.radians(a), "C", terminal=False) for a in (15.0, 25.0)],
          1e-10)
    return {"damper": damper, "gravity gradient": gg}


def best_time(run, repeat: int):
    """(best wall time over ``repeat`` runs, the last result)."""
    best, out = np.inf, None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = run()
        best = min(best, time.perf_counter() - t0)
    return best, out


def measure(case, repeat: int) -> dict:
    body, q0, w0, t, torques, events, rtol = case
    q0 = np.asarray(q0, float) / np.linalg.norm(q0)
    kw = {"torques": torques, "rtol": rtol}
    integrate_reference_events(body, q0, w0, t[:3], events, **kw)     # compile, once
    plain, _ = best_time(lambda: integrate_reference(body, q0, w0, t, **kw), repeat)
    compiled, (_, _, rec_c) = best_time(
        lambda: integrate_reference_events(body, q0, w0, t, events, compiled=True, **kw),
        repeat)
    scipy, (_, _, rec_s) = best_time(
        lambda: integrate_reference_events(body, q0, w0, t, events, compiled=False, **kw), 1)
    te_c = np.array([r[0] for r in rec_c])
    te_s = np.array([r[0] for r in rec_s])
    same = te_c.size == te_s.size
    return {"span_s": float(t[-1]), "outputs": int(t.size), "events": len(events),
            "crossings": int(te_c.size), "crossings_scipy": int(te_s.size), "rtol": rtol,
            "plain_s": plain, "events_compiled_s": compiled, "events_scipy_s": scipy,
            "events_over_plain": compiled / plain, "scipy_over_compiled": scipy / compiled,
            "max_event_time_difference_s": float(np.max(np.abs(te_c - te_s)))
            if same and te_c.size else None}


def write_atomically(path: Path, data: dict) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.NamedTemporaryFile("w", dir=path.parent, delete=False,
                                     suffix=".tmp") as f:
        json.dump(data, f, indent=1)
    os.replace(f.name, path)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true", help="shorter spans, one repeat")
    parser.add_argument("--repeat", type=int, default=3, help="runs per timing (best)")
    parser.add_argument("--no-write", action="store_true", help="do not write the JSON")
    args = parser.parse_args(argv)
    repeat = 1 if args.quick else args.repeat
    results = {name: measure(case, repeat) for name, case in cases(args.quick).items()}
    print(f"Events on the compiled DOP853: {cpu_name()}, {platform.python_version()}"
          f"{' (--quick)' if args.quick else ''}\n")
    print("| case | span | outputs | crossings | plain (s) | events, compiled (s) | "
          "ratio | events, scipy (s) | max |te_c - te_s| (s) |")
    print("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    for name, r in results.items():
        diff = r["max_event_time_difference_s"]
        print(f"| {name} | {r['span_s']:.0f} s | {r['outputs']} | {r['crossings']} | "
              f"{r['plain_s']:.4f} | {r['events_compiled_s']:.4f} | "
              f"{r['events_over_plain']:.2f} | {r['events_scipy_s']:.3f} | "
              f"{'-' if diff is None else f'{diff:.1e}'} |")
    if not args.quick and not args.no_write:
        write_atomically(RESULTS, {"machine": cpu_name(), "quick": args.quick,
                                   "cases": results})
    return 0


if __name__ == "__main__":
    sys.exit(main())

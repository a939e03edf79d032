"""Where the splitting beats the compiled DOP853: spin rate against the torque's pace.

A 100 kg box (0.5 x 1 x 2 m) in gravity gradient on a 7000 km orbit for one hour, outputs
every minute, spun at 1 to 360 deg/s about a skew axis.  Each method at its cheapest
setting whose largest attitude error is <= 1e-6 rad: the splitting (order 4, the largest
passing step of a scan) and DOP853 (``method="integrator"``, compiled with numba when it is
installed; the loosest passing rtol).  The reference is the order-6 splitting at a short
step (``h |omega| <= 0.17``); its error is bounded by its distance to the same at twice
the step (64 times its truncation error), and it is checked against another method,
DOP853 at rtol 1e-13, whose own error grows with the turns (~5e-8 rad at 360 deg/s):
both distances are printed.

Then the automatic choice (``propagate`` with torques and nothing else: the cheaper method
at the default accuracy, attitude/propagation/choice.py) against each method at its
cheapest setting of the same scans whose error is at most the automatic result's ("at the
same accuracy"): ``automatic time / best time`` should stay <= 1.1.  The choice's own
cost (``choose_method`` alone, part of the automatic run's time) is timed too.

Times: every timed run is the same call, ``att.propagate(body, state, times, torques=...)``
with the same outputs (the automatic one with nothing else, the others with their
setting), so each covers the same work.  Each is called once untimed, then all are
called in turn for up to 15 rounds (fewer where a round would be long: the rounds are
reported) and each keeps its least time: the rounds share the load of a busy machine
alike, and the least time is the one least disturbed by it.  The tables give the CPU
time of this process (``time.process_time``: it leaves out the time spent waiting for a
core, most of the wall time on a loaded machine; the JSON has both).

    python benchmarks/spin_crossover.py
    python benchmarks/spin_crossover.py --rates 1 10 --repeats 5   # partial: not written

Writes ``benchmarks/results/spin_crossover.json`` atomically.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from _machine import cpu_name  # noqa: E402
from perturbed import attitude_error, quaternions  # noqa: E402  (same folder)

import attitude as att  # noqa: E402
from attitude.model.ephemeris import write_atomically  # noqa: E402
from attitude.model.orbit import KeplerOrbit  # noqa: E402
from attitude.model.torques import EARTH_MU, GravityGradient  # noqa: E402
from attitude.propagation.choice import choose_method  # noqa: E402
from attitude.propagation.compiled import NUMBA  # noqa: E402

HERE = Path(__file__).resolve().parent
TARGET = 1e-6
RATES_DEG = (1.0, 10.0, 60.0, 360.0)
STEPS = (600.0, 300.0, 120.0, 60.0, 30.0, 20.0, 15.0, 10.0, 7.5, 5.0, 3.0, 2.0, 1.5, 1.0,
         0.75, 0.5, 0.3, 0.2, 0.15, 0.1)
RTOLS = (1e-6, 1e-7, 1e-8, 3e-9, 1e-9, 3e-10, 1e-10, 3e-11, 1e-11, 3e-12, 1e-12)
#: Timed rounds of each row (fewer where one round would take more than
#: ROUND_BUDGET_S / REPEATS: the slow rows, whose times are long enough to be stable).
REPEATS = 15
ROUND_BUDGET_S = 30.0


def error(eph, q_ref) -> float:
    return attitude_error(quaternions(eph), q_ref)


def interleaved_minimum(runs: dict, repeats: int) -> tuple[dict, dict, int]:
    """``({name: least CPU time}, {name: least wall time}, rounds)``: one untimed call of
    each, then ``repeats`` rounds that call each in turn, so that every run meets the
    same load of a shared machine; the least time of each over the rounds (noise only
    adds).  The CPU time of this process (``time.process_time``) leaves out the time
    the process waits for a core, which the wall time of a loaded machine is mostly."""
    first = {}
    for name, run in runs.items():
        t0 = time.perf_counter()
        run()
        first[name] = time.perf_counter() - t0
    rounds = max(3, min(repeats, int(ROUND_BUDGET_S / max(sum(first.values()), 1e-9))))
    cpu, wall = dict.fromkeys(runs, np.inf), dict.fromkeys(runs, np.inf)
    for _ in range(rounds):
        for name, run in runs.items():
            c0, t0 = time.process_time(), time.perf_counter()
            run()
            wall[name] = min(wall[name], time.perf_counter() - t0)
            cpu[name] = min(cpu[name], time.process_time() - c0)
    return cpu, wall, rounds


class Scan:
    """Errors of each setting of a method (computed once), and the cheapest setting
    (the first of the scan, which goes from cheap to dear) within a bound."""

    def __init__(self, body, state, times, torques, q_ref, method: str):
        self.key, self.values = ("step", STEPS) if method == "splitting" else ("rtol", RTOLS)
        self.args = (body, state, times)
        self.torques, self.q_ref, self.method = torques, q_ref, method
        self.errors = {}

    def run_of(self, value):
        kwargs = ({"method": "splitting", "order": 4, "step": value}
                  if self.method == "splitting" else {"method": "integrator", "rtol": value})
        return lambda: att.propagate(*self.args, torques=self.torques, **kwargs)

    def cheapest(self, bound: float):
        for v in self.values:
            if v not in self.errors:
                self.errors[v] = error(self.run_of(v)(), self.q_ref)
            if self.errors[v] <= bound:
                return v
        return None


def one_rate(rate_deg, repeats=REPEATS):
    orbit = KeplerOrbit(EARTH_MU, 7.0e6, 0.001)
    body = att.RigidBody.from_parts([att.MassProperties.solid_box(100.0, [0.5, 1.0, 2.0])])
    torques = [GravityGradient(EARTH_MU, orbit)]
    axis = np.array([0.2, 0.3, 0.93]) / np.linalg.norm([0.2, 0.3, 0.93])
    state = att.AttitudeState("2030-01-01", Rotation.from_euler("xyz", [0.4, -0.2, 0.3]),
                              np.radians(rate_deg) * axis)
    times = np.arange(0.0, 3600.0 + 1.0, 60.0)
    # the reference: the order-6 splitting at a short step (h |omega| <= 0.17 rad);
    # its error is bounded by its distance to the same at twice the step (2^6 = 64
    # times its truncation error) and checked against another method, DOP853 at rtol
    # 1e-13 (whose own error grows as rtol N^1.8 with the turns N: ~5e-8 rad over the
    # 3600 turns of 360 deg/s, where it no longer checks the reference)
    h6 = min(0.5, 10.0 / rate_deg)

    def order6(h):
        eph = att.propagate(body, state, times, torques=torques, method="splitting",
                            order=6, step=h)
        return np.asarray(eph.dataset.quaternion.values)

    q_ref = order6(h6)
    dop = att.propagate(body, state, times, torques=torques, method="integrator", rtol=1e-13)
    result = {"rate_deg_s": rate_deg,
              "reference": {"method": "splitting", "order": 6, "step_s": h6},
              "reference_vs_twice_its_step": attitude_error(order6(2.0 * h6), q_ref),
              "reference_vs_dop853_rtol_1e-13": error(dop, q_ref)}

    def auto():
        return att.propagate(body, state, times, torques=torques)

    q0, w0 = state.attitude.as_quat()[None], np.asarray(state.omega_body)[None]
    choice = choose_method([body], q0, w0, times, torques)
    eph = auto()
    result["automatic"] = {"method": eph.dataset.attrs["method"],
                           "reason": eph.dataset.attrs["method_reason"],
                           "rtol": choice.rtol, "step_s": choice.step,
                           "error_rad": error(eph, q_ref)}
    # "the same accuracy": the automatic result's error, or the reference's own
    # uncertainty (twice its distance to itself at twice the step) where that is larger
    same = max(result["automatic"]["error_rad"],
               2.0 * result["reference_vs_twice_its_step"])
    scans = {name: Scan(body, state, times, torques, q_ref, name)
             for name in ("splitting", "dop853")}
    runs = {"automatic": auto,
            "choice alone": lambda: choose_method([body], q0, w0, times, torques)}
    settings = {}
    for target, label in ((same, "at_automatic_accuracy"), (TARGET, "at_target")):
        for name, scan in scans.items():
            v = scan.cheapest(target)
            if v is not None:
                settings[(label, name)] = v
                runs[f"{name} {scan.key} {v:g}"] = scan.run_of(v)
    cpu, wall, rounds = interleaved_minimum(runs, repeats)
    result["automatic"].update(cpu_s=cpu["automatic"], wall_s=wall["automatic"])
    result["choice_s"] = cpu["choice alone"]
    result["timing"] = {"rounds": rounds, "statistic": "least CPU time (cpu_s) and least "
                        "wall time (wall_s) over the rounds, each round calling every run "
                        "in turn after one untimed call; ratios of CPU times"}
    for label in ("at_automatic_accuracy", "at_target"):
        result[label] = {}
        for name, scan in scans.items():
            v = settings.get((label, name))
            if v is not None:
                run = f"{name} {scan.key} {v:g}"
                result[label][name] = {scan.key: v, "error_rad": scan.errors[v],
                                       "cpu_s": cpu[run], "wall_s": wall[run]}
    same = [c["cpu_s"] for c in result["at_automatic_accuracy"].values()]
    result["automatic_over_best"] = (cpu["automatic"] / min(same) if same
                                     else float("nan"))
    return result


def _cell(c, key):
    return (f"{key} {c[key]:g}: {c['error_rad']:.1e} rad, {c['cpu_s'] * 1e3:.1f} ms"
            if c else "none reaches it")


def main(rates=RATES_DEG, repeats=REPEATS, write=True):
    rows = []
    print(f"{cpu_name()}, {os.cpu_count()} cores; DOP853 {'compiled' if NUMBA else 'scipy'}; "
          f"load average {os.getloadavg()[0]:.1f}; times: the least CPU time of up to "
          f"{repeats} interleaved rounds", flush=True)
    for rate in rates:
        rows.append(one_rate(rate, repeats))
        print(f"  {rate:g} deg/s done ({rows[-1]['timing']['rounds']} rounds)", flush=True)
    print("\n| spin (deg/s) | splitting order 4 | DOP853 | DOP853 time / splitting time |")
    print("| ---: | --- | --- | ---: |")
    for r in rows:
        s, d = r["at_target"].get("splitting"), r["at_target"].get("dop853")
        ratio = f"{d['cpu_s'] / s['cpu_s']:.2g}" if s and d else "n/a"
        print(f"| {r['rate_deg_s']:g} | {_cell(s, 'step')} | {_cell(d, 'rtol')} | {ratio} |")
    print("\n| spin (deg/s) | automatic | its choice alone | splitting at its accuracy | "
          "DOP853 at its accuracy | automatic / best | rounds |")
    print("| ---: | --- | ---: | --- | --- | ---: | ---: |")
    for r in rows:
        a, same = r["automatic"], r["at_automatic_accuracy"]
        setting = (f"DOP853, rtol {a['rtol']:.2g}" if a["method"] == "integrator"
                   else f"splitting, step {a['step_s']:.3g} s")
        print(f"| {r['rate_deg_s']:g} | {setting}: {a['error_rad']:.1e} rad, "
              f"{a['cpu_s'] * 1e3:.1f} ms | {r['choice_s'] * 1e3:.2f} ms | "
              f"{_cell(same.get('splitting'), 'step')} | {_cell(same.get('dop853'), 'rtol')} "
              f"| {r['automatic_over_best']:.2f} | {r['timing']['rounds']} |")
    print("\nreference: the order-6 splitting at step "
          + ", ".join(f"{r['reference']['step_s']:.3g}" for r in rows) + " s; against itself "
          "at twice the step: " + ", ".join(f"{r['reference_vs_twice_its_step']:.1e}"
                                            for r in rows)
          + " rad; against DOP853 at rtol 1e-13: "
          + ", ".join(f"{r['reference_vs_dop853_rtol_1e-13']:.1e}" for r in rows) + " rad")
    if not write:
        print("results not written (a partial run: --rates or --repeats given)")
        return
    text = json.dumps({"benchmark": "spin_crossover", "cpu": cpu_name(),
                       "cores": os.cpu_count(), "numba": NUMBA,
                       "load_average": os.getloadavg()[0], "repeats": repeats,
                       "rows": rows}, indent=1)
    path = write_atomically(HERE / "results" / "spin_crossover.json",
                            lambda tmp: tmp.write_text(text))
    print(f"results: {path}")


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__,   # --help: what it measures
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--rates", type=float, nargs="+", metavar="DEG_S",
                        help="spins to run (deg/s; a partial run, not written)")
    parser.add_argument("--repeats", type=int, default=REPEATS,
                        help=f"timed rounds per row (default {REPEATS}; other values: "
                             "not written)")
    args = parser.parse_args()
    main(tuple(args.rates or RATES_DEG), args.repeats,
         write=args.rates is None and args.repeats == REPEATS)

"""Convex inversion against DAMIT's convexinv on the same lightcurves, in one run.

Both programs invert (43) Ariadne's 37 relative lightcurves (tests/data/inversion/, the
convexinv test file) from the same period, Lommel-Seeliger + 0.1 Lambert, a Gaussian image
of 8 rows per octant and harmonics of degree 6; convexinv from its own input file's pole
start (220, 0) deg with 50 iterations, attitude from its pole starts over the sphere (and
the mirror), and once from convexinv's start with 50 model evaluations (the like-for-like
timing). Reported: pole, period, rms (relative flux) and CPU time of each.

convexinv is built from source outside the repository (GPL-2; nothing of it is copied)::

    # fetch github:mkretlow/DAMIT-convex, then: cd DAMIT-convex/convexinv && make
    python benchmarks/inversion.py --convexinv /path/to/DAMIT-convex/convexinv/convexinv

Without --convexinv only attitude runs.
"""

from __future__ import annotations

import argparse
import json
import resource
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np

from attitude.inversion import (
    ConvexModel,
    GaussianImage,
    fit_convex,
    invert,
    read_damit_lightcurves,
)

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "tests" / "data" / "inversion" / "ariadne_lcs_rel.txt"
PERIOD_H = 5.76198

CONVEXINV_INPUT = f"""220 1 inital lambda [deg] (0/1 - fixed/free)
0 1 initial beta [deg] (0/1 - fixed/free)
{PERIOD_H} 1 inital period [hours] (0/1 - fixed/free)
0 zero time [JD]
0 initial rotation angle [deg]
0.1 convexity regularization
6 6 degree and order of spherical harmonics expansion
8 number of rows
0.5 0 phase funct. param. 'a' (0/1 - fixed/free)
0.1 0 phase funct. param. 'd' (0/1 - fixed/free)
-0.5 0 phase funct. param. 'k' (0/1 - fixed/free)
0.1 0 Lambert coefficient 'c' (0/1 - fixed/free)
50 iteration stop condition
"""


def run_attitude(poles: int) -> dict:
    start = time.process_time()
    res = invert(read_damit_lightcurves(DATA), "principal", period=PERIOD_H * 3600,
                 poles=poles, max_iterations=60)
    return {"pole_deg": list(res.pole), "period_h": res.period / 3600, "rms": res.rms,
            "dark_facet": res.dark_facet, "cpu_s": time.process_time() - start,
            "mirror": res.alternatives[0][1], "poles": poles}


def run_attitude_single() -> dict:
    """One fit from convexinv's start, as convexinv runs: the like-for-like timing."""
    start = time.process_time()
    model = ConvexModel(read_damit_lightcurves(DATA), GaussianImage(8, 6))
    fit = fit_convex(model, np.radians(220.0), 0.0, PERIOD_H * 3600, max_iterations=50)
    return {"pole_deg": list(fit.pole), "period_h": fit.period / 3600, "rms": fit.rms,
            "dark_facet": fit.dark_facet, "cpu_s": time.process_time() - start,
            "evaluations": fit.n_evaluations}


def run_convexinv(exe: Path) -> dict:
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        (tmp / "input").write_text(CONVEXINV_INPUT)
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        with open(DATA) as data:
            proc = subprocess.run([str(exe), "-v", "-o", "areas", "-p", "par", "input",
                                   "out_lcs"], stdin=data, cwd=tmp, capture_output=True,
                                  text=True, check=True)
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        lon, lat, period = map(float, (tmp / "par").read_text().split()[:3])
        model = np.loadtxt(tmp / "out_lcs")
    # the rms of the relative residuals, as attitude computes it (each curve over its mean)
    observations = read_damit_lightcurves(DATA)
    resid, start = [], 0
    for obs in observations:
        m = model[start:start + len(obs)]
        start += len(obs)
        resid.append(obs.brightness / obs.brightness.mean() - m / m.mean())
    rms = float(np.sqrt(np.mean(np.concatenate(resid) ** 2)))
    return {"pole_deg": [lon, lat], "period_h": period, "rms": rms,
            "cpu_s": (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime),
            "log_tail": proc.stdout.strip().splitlines()[-3:]}


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--convexinv", type=Path, help="path of the built convexinv")
    parser.add_argument("--poles", type=int, default=6, help="attitude's pole starts")
    parser.add_argument("--json", type=Path, help="also write the results here")
    args = parser.parse_args(argv)
    results = {"attitude (one start)": run_attitude_single(),
               "attitude (invert)": run_attitude(args.poles)}
    if args.convexinv:
        results["convexinv"] = run_convexinv(args.convexinv)
    for name, r in results.items():
        print(f"{name:20s} pole ({r['pole_deg'][0]:.2f}, {r['pole_deg'][1]:.2f}) deg  "
              f"P {r['period_h']:.7f} h  rms {r['rms']:.4f}  CPU {r['cpu_s']:.1f} s")
    if args.json:
        args.json.write_text(json.dumps(results, indent=2) + "\n")


if __name__ == "__main__":
    main()

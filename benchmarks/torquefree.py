"""Speed of the exact torque-free propagator (issue 4, §4).

Prints, for one process on this machine:

* epochs per second of :func:`attitude.propagation.torquefree.free_rotation` for 1 body x 1e6
  epochs and for 1e4 bodies x 100 epochs (target >= 1e6 each);
* the same work with scipy's DOP853 at ``rtol=1e-12`` (the reference numerical
  propagator: Euler's equations + quaternion kinematics), extrapolated from a measured
  fraction of it, and the speed-up;
* our time divided by a bare ``scipy.special.ellipj`` call on the same number of
  points (the practical floor; target <= 4).

Run from the repository root::

    python benchmarks/torquefree.py
"""

from __future__ import annotations

import argparse
import math
import os
import platform
import sys
import time

import numpy as np
import scipy
from scipy import special as sp
from scipy.integrate import solve_ivp

sys.path.insert(0, os.path.join(os.path.dirname(__file__), ".."))

from _machine import cpu_name  # noqa: E402  (benchmarks/_machine.py)

from attitude.model.freebody import branch_of  # noqa: E402
from attitude.propagation.torquefree import free_rotation  # noqa: E402


def best_of(fn, repeat=3):
    best = math.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def dop853(I, w, q, t):
    A, B, C = I

    def rhs(_, y):
        w1, w2, w3, x, yq, z, s = y
        return [(B - C) / A * w2 * w3, (C - A) / B * w3 * w1, (A - B) / C * w1 * w2,
                0.5 * (s * w1 + yq * w3 - z * w2), 0.5 * (s * w2 - x * w3 + z * w1),
                0.5 * (s * w3 + x * w2 - yq * w1), -0.5 * (x * w1 + yq * w2 + z * w3)]
    return solve_ivp(rhs, (t[0], t[-1]), np.concatenate([w, q]), method="DOP853", rtol=1e-12,
                     atol=1e-14 * np.linalg.norm(w), t_eval=t)


def main():
    print(f"machine: {cpu_name()}, {os.cpu_count()} cores (one process used); "
          f"python {platform.python_version()}, numpy {np.__version__}, scipy {scipy.__version__}")
    print()
    rows = []

    # --- 1 body x 1e6 epochs: Apophis-like SAM (Pravec et al. 2014: E/E0 = 1.024,
    #     P_phi ~ 27 h), one epoch every 10 minutes for 19 years ----------------------
    I1 = np.array([0.61, 0.965, 1.0])
    x = 0.024 / (0.61 * (1 - 1.024 * 0.61))
    w1 = np.array([math.sqrt(x), 0.0, 1.0]) * 2 * math.pi / (27.38 * 3600) * 0.9
    q1 = np.array([0.0, 0.0, 0.0, 1.0])
    t1 = np.arange(1_000_000) * 600.0
    ours1 = best_of(lambda: free_rotation(I1, q1, w1, t1))
    frac = 50
    ts = t1[: len(t1) // frac]
    dop1 = best_of(lambda: dop853(I1, w1, q1, ts), repeat=1) * frac
    m1 = float(np.clip(0.3, 0, 1))
    u = np.linspace(0.0, 40.0, t1.size)
    ell1 = best_of(lambda: sp.ellipj(u, m1))
    rows.append(("1 body x 1e6 epochs", t1.size, ours1, dop1,
                 f"DOP853 timed on 1/{frac} of the span, x{frac}", ell1))

    # --- 1e4 bodies x 100 epochs: random triaxial bodies and states ---------------
    rng = np.random.default_rng(42)
    n, T = 10_000, 100
    a = rng.uniform(0.3, 1.0, n)
    b = rng.uniform(a, 1.0)
    I2 = np.stack([a, b, np.ones(n)], axis=1)
    w2 = rng.normal(size=(n, 3)) * 1e-3
    q2 = rng.normal(size=(n, 4))
    q2 /= np.linalg.norm(q2, axis=1, keepdims=True)
    t2 = np.linspace(0.0, 3e4, T)
    ours2 = best_of(lambda: free_rotation(I2, q2, w2, t2))
    sub = 100
    dop2 = best_of(lambda: [dop853(I2[i], w2[i], q2[i], t2) for i in range(sub)], repeat=1)
    dop2 *= n / sub
    mm = rng.uniform(0.0, 1.0, n * T)
    uu = rng.uniform(0.0, 4.0, n * T)
    ell2 = best_of(lambda: sp.ellipj(uu, mm))
    kinds = dict(zip(*np.unique(branch_of(I2, w2), return_counts=True)))
    rows.append((f"1e4 bodies x 100 epochs ({', '.join(f'{v} {k}' for k, v in kinds.items())})",
                 n * T, ours2, dop2, f"DOP853 timed on {sub} bodies, x{n // sub}", ell2))

    print("| case | ours (s) | epochs/s | DOP853 rtol 1e-12 (s) | speed-up | "
          "ours / bare ellipj |")
    print("|---|---:|---:|---:|---:|---:|")
    for name, N, ours, dop, note, ell in rows:
        print(f"| {name} | {ours:.3f} | {N / ours:.2e} | {dop:.1f} ({note}) | "
              f"{dop / ours:.0f}x | {ours / ell:.2f} ({ell:.3f} s) |")
    print()
    ok = all(N / ours >= 1e6 and ours / ell <= 4 for _, N, ours, _, _, ell in rows)
    print("targets (>= 1e6 epochs/s, <= 4x ellipj):", "met" if ok else "NOT met")


if __name__ == "__main__":
    argparse.ArgumentParser(description=__doc__,   # --help: what it measures, then exit
                            formatter_class=argparse.RawDescriptionHelpFormatter
                            ).parse_args()
    main()

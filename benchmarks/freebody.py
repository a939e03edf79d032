"""Speed of ``propagate`` on a batch given as Python lists (issue 14, item 5).

Prints, for one process on this machine, 2000 bodies (random triaxial inertia tensors
in random body frames) x 100 epochs, torque-free:

* ``att.propagate(bodies, states, times)`` with ``bodies`` and ``states`` Python lists
  (the states share one epoch object, as a script that builds them in a loop does);
* a loop of single runs ``att.propagate(body, state, times)`` (timed on a subset and
  scaled), and the speed-up of the batch over it (target >= 20x);
* the exact kernel alone, :func:`attitude.propagation.torquefree.free_rotation`, on the
  same principal-frame arrays (the floor), and the batch's epochs per second (target
  >= 1.5e6).

Run from the repository root::

    python benchmarks/freebody.py
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
from astropy.time import Time
from scipy.spatial.transform import Rotation

sys.path.insert(0, os.path.join(os.path.dirname(__file__), ".."))

from _machine import cpu_name  # noqa: E402  (benchmarks/_machine.py)

import attitude as att  # noqa: E402
from attitude.model.body import as_bodies, to_principal_frame  # noqa: E402
from attitude.model.state import stack_states  # noqa: E402
from attitude.propagation.torquefree import free_rotation  # noqa: E402


def best_of(fn, repeat=5):
    best = math.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def population(n: int, seed: int = 7):
    """Random triaxial bodies in random body frames and tumbling states."""
    rng = np.random.default_rng(seed)
    epoch = Time("2029-04-13T00:00:00", scale="tdb")
    bodies, states = [], []
    for _ in range(n):
        a = rng.uniform(0.5, 1.0)
        b = rng.uniform(max(a, 1.0 - a), 1.0)          # A <= B <= C = 1, A + B >= C
        R = Rotation.random(random_state=rng).as_matrix()
        bodies.append(att.RigidBody(R @ np.diag([a, b, 1.0]) @ R.T))
        states.append(att.AttitudeState(epoch, Rotation.random(random_state=rng),
                                        rng.normal(size=3) * 1e-3))
    return bodies, states


def main():
    print(f"machine: {cpu_name()}, {os.cpu_count()} cores (one process used); "
          f"python {platform.python_version()}, numpy {np.__version__}, scipy {scipy.__version__}")
    n, T = 2000, 100
    bodies, states = population(n)
    times = np.linspace(0.0, 3e4, T)

    bb, _ = as_bodies(bodies)
    _, _, q0, w0 = stack_states(states)
    qp, wp = to_principal_frame(q0, w0, bb.body_to_principal)
    # batch and kernel timed alternately (best of 9 each), so that both see the same
    # load of a shared machine
    batch = kernel = math.inf
    for _ in range(9):
        batch = min(batch, best_of(lambda: att.propagate(bodies, states, times), 1))
        kernel = min(kernel, best_of(
            lambda: free_rotation(bb.principal_moments, qp, wp, times), 1))
    sub = 200
    single = best_of(lambda: [att.propagate(b, s, times)
                              for b, s in zip(bodies[:sub], states[:sub])], repeat=2) * n / sub

    print()
    print("| case (2000 bodies x 100 epochs, torque-free) | time | epochs/s | relative |")
    print("| --- | ---: | ---: | ---: |")
    print(f"| `propagate(bodies, states, times)` from lists | {batch:.3f} s | "
          f"{n * T / batch:.2e} | 1 |")
    print(f"| loop of single `propagate(body, state, times)` | {single:.2f} s | "
          f"{n * T / single:.2e} | {single / batch:.0f}x slower |")
    print(f"| exact kernel alone (`free_rotation` on arrays) | {kernel:.3f} s | "
          f"{n * T / kernel:.2e} | {kernel / batch:.2f} |")
    print()
    ok = single / batch >= 20 and n * T / batch >= 1.5e6
    print("targets (>= 20x a loop of singles, >= 1.5e6 epochs/s):", "met" if ok else "NOT met")


if __name__ == "__main__":
    argparse.ArgumentParser(description=__doc__,   # --help: what it measures, then exit
                            formatter_class=argparse.RawDescriptionHelpFormatter
                            ).parse_args()
    main()

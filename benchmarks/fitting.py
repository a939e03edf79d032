"""Fitting: forward-model evaluations per second, one parameter vector at a time and
batched over the walkers of an MCMC step (issue: fitting).

Model: the exact torque-free solution at 1000 observation epochs (the forward model of
attitude.fitting), for one parameter vector per call (the loop a least-squares solver or a
plain sampler makes) and for 64 vectors per call (emcee with vectorize=True).

    python benchmarks/fitting.py
"""

from __future__ import annotations

import time

import numpy as np
from _machine import cpu_name
from scipy.spatial.transform import Rotation

import attitude as att
from attitude.fitting import PARAMETERS, free_parameters

N_EPOCHS, N_WALKERS = 1000, 64


def best_of(fn, n=5):
    times = []
    for _ in range(n):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return min(times)


def main():
    body = att.RigidBody.from_principal_moments([0.6, 0.9, 1.0])
    state = att.AttitudeState("2029-04-13", Rotation.from_rotvec([0.3, -0.2, 1.0]),
                              [0.05, 0.1, 1.0])
    p, model = free_parameters(body, state)
    x = np.array([p[k] for k in PARAMETERS])
    rng = np.random.default_rng(0)
    walkers = x + 1e-4 * np.abs(x) * rng.standard_normal((N_WALKERS, x.size))
    t = np.linspace(0.0, 100.0, N_EPOCHS)
    loop = best_of(lambda: [model.evaluate(w[None], t) for w in walkers], n=3)
    batch = best_of(lambda: model.evaluate(walkers, t))
    print(f"machine: {cpu_name()}")
    print(f"forward model (attitude and rates at {N_EPOCHS} epochs), {N_WALKERS} walkers")
    print("| evaluation | model evaluations / s |")
    print("| --- | ---: |")
    print(f"| one vector per call (loop) | {N_WALKERS / loop:,.0f} |")
    print(f"| {N_WALKERS} vectors per call (batch) | {N_WALKERS / batch:,.0f} |")
    print(f"| batch / loop | {loop / batch:.1f}x |")


if __name__ == "__main__":
    main()

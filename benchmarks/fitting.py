"""Fitting: forward-model evaluations per second, one parameter vector at a time and
batched over the walkers of an MCMC step (issue: fitting).

Models: (1) attitudes and rates from the exact torque-free solution at 1000 observation
epochs; (2) a 1000-point lightcurve of a 1280-facet ellipsoid (the exact solution, then
the facet brightness under Lommel-Seeliger + 0.1 Lambert): for one parameter vector per
call (the loop a least-squares solver or a plain sampler makes) and for 64 vectors per
call (emcee with vectorize=True).

    python benchmarks/fitting.py
"""

from __future__ import annotations

import argparse
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

    shape = att.Polyhedron.ellipsoid_from_moments(body.principal_moments, subdivisions=3)
    geom = att.Geometry(sun=[1.0, 0.0, 0.0], observer=[np.cos(0.35), np.sin(0.35), 0.1])
    obs = att.LightcurveObservations(t, np.zeros(t.size), 0.01, geom, shape)

    def magnitudes(x):
        q, _ = model.evaluate(x, t)
        return obs.model_magnitudes(q)

    loop = best_of(lambda: [magnitudes(w[None]) for w in walkers], n=2)
    batch = best_of(lambda: magnitudes(walkers), n=2)
    print()
    print(f"lightcurve model: {N_EPOCHS} epochs, {len(shape.faces)} facets, {N_WALKERS} walkers")
    print("| evaluation | model evaluations / s |")
    print("| --- | ---: |")
    print(f"| one vector per call (loop) | {N_WALKERS / loop:,.1f} |")
    print(f"| {N_WALKERS} vectors per call (batch) | {N_WALKERS / batch:,.1f} |")
    print(f"| batch / loop | {loop / batch:.1f}x |")


if __name__ == "__main__":
    argparse.ArgumentParser(description=__doc__,   # --help: what it measures, then exit
                            formatter_class=argparse.RawDescriptionHelpFormatter
                            ).parse_args()
    main()

"""Facet-epochs per second of the synthetic lightcurve (docs/photometry.md quotes these).

Convex case: Lommel-Seeliger + Lambert over a ~5000-facet ellipsoid and 1e4 epochs,
no shadows, compared with a bare numpy loop of the same arithmetic.  Shadowed case:
the same with ray-cast self-shadowing (embree), over fewer epochs.

Run: ``PYTHONPATH=. python benchmarks/photometry.py [--epochs N] [--shadow-epochs N]``.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from _machine import cpu_name
from scipy.spatial.transform import Rotation

import attitude as att
from attitude.photometry import facet_brightness


def best_of(fn, repeat=3):
    """Best wall time and the CPU time of that run (on a shared machine the CPU time
    shows what the code costs, the wall time what other processes left of it)."""
    best = (np.inf, np.inf)
    for _ in range(repeat):
        t0, c0 = time.perf_counter(), time.process_time()
        fn()
        best = min(best, (time.perf_counter() - t0, time.process_time() - c0))
    return best


def bare_numpy(normals, areas, s, o, c=0.1):
    """The reference: one (epochs x facets) pass, no chunking."""
    mu0 = np.maximum(s @ normals.T, 0.0)
    mu = np.maximum(o @ normals.T, 0.0)
    return (mu0 * mu * (1.0 / (mu0 + mu + 1e-300) + c)) @ areas


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--epochs", type=int, default=10_000)
    parser.add_argument("--shadow-epochs", type=int, default=200)
    args = parser.parse_args()
    # 4 x 4**4 x 20 / 4 = 5120 faces: an icosphere of 4 subdivisions
    shape = att.Polyhedron.ellipsoid(3.0, 2.0, 1.5, subdivisions=4)
    n_f = len(shape.faces)
    sun = Rotation.random(args.epochs, random_state=1).apply([1.0, 0, 0])
    obs = Rotation.random(args.epochs, random_state=2).apply([1.0, 0, 0])
    law = att.photometry.LommelSeeligerLambert(c=0.1)

    convex, convex_cpu = best_of(lambda: facet_brightness(shape, sun, obs, law))
    bare, bare_cpu = best_of(lambda: bare_numpy(shape.face_normals, shape.face_areas,
                                                sun, obs))
    work = n_f * args.epochs
    rate = work / convex
    print(f"CPU: {cpu_name()}; load average {open('/proc/loadavg').read().split()[0]}")
    print(f"convex, LS + 0.1 L, {n_f} facets x {args.epochs} epochs: {convex:.3f} s wall, "
          f"{rate:.3g} facet-epochs/s ({work / convex_cpu:.3g} per CPU-second); bare "
          f"numpy, one pass: {work / bare:.3g}/s ({work / bare_cpu:.3g} per CPU-second)")
    try:
        k = args.shadow_epochs
        shadowed, _ = best_of(lambda: facet_brightness(shape, sun[:k], obs[:k], law,
                                                       shadows=True), repeat=2)
        srate = n_f * k / shadowed
        print(f"shadows (embree), {n_f} facets x {k} epochs: {shadowed:.3f} s, "
              f"{srate:.3g} facet-epochs/s, {rate / srate:.0f}x slower than convex")
    except att.MissingDependencyError as err:
        print(f"shadows: skipped ({err})")


if __name__ == "__main__":
    main()

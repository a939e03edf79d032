"""Measured orders of convergence of the splitting integrator (docs/integrators.md).

The attitude error at the last output against DOP853 at ``rtol = 1e-13``, for halving
steps, and the least-squares slope of log(error) against log(step):

* a triaxial body (1, 1.7, 2.2) tumbling at |omega| = 3.7e-3 rad/s in gravity gradient on a
  7000 km, e = 0.1 orbit, 6000 s (the set-up of ``tests/propagation/test_splitting.py``),
  alone and with
  internal dissipation (tau = 2000 s and 100 s);
* internal dissipation alone: the same body relaxing from a long-axis spin
  (omega = (1, 0.05, 0.05) rad/s, tau = 10 s, 30 s), where the internal kick
  (Runge-Kutta on the rates and the attitude increment, then the inertial L restored)
  carries the whole perturbation; the largest drift of the inertial L over the run is
  printed too.

Run from the repository root::

    python benchmarks/measured_orders.py        # ~1 minute
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import time

import numpy as np
import scipy
from scipy.spatial.transform import Rotation

sys.path.insert(0, os.path.join(os.path.dirname(__file__), ".."))

from _machine import cpu_name  # noqa: E402  (benchmarks/_machine.py)

import attitude as att  # noqa: E402
from attitude.model.orbit import KeplerOrbit  # noqa: E402
from attitude.model.torques import EnergyDissipation, GravityGradient  # noqa: E402
from attitude.propagation.reference import integrate_reference  # noqa: E402
from attitude.propagation.splitting import integrate_splitting  # noqa: E402

MU = 3.986004418e14
BODY = att.RigidBody.from_principal_moments([1.0, 1.7, 2.2])
Q0 = Rotation.from_euler("xyz", [0.3, 0.2, 0.1]).as_quat()


def _error(q, q_ref):
    return float((Rotation.from_quat(q).inv() * Rotation.from_quat(q_ref)).magnitude().max())


def _rows(label, w0, t, torques, schemes, steps):
    q_ref, _ = integrate_reference(BODY, Q0, w0, t, torques=torques, rtol=1e-13)
    out = []
    for scheme in schemes:
        errors, drift = [], 0.0
        for h in steps:
            q, w = integrate_splitting(BODY, Q0, w0, t, torques=torques, step=h, order=None,
                                       scheme=scheme)
            errors.append(_error(q, q_ref))
            L = Rotation.from_quat(q).apply(w @ BODY.inertia.T)
            drift = max(drift, float(np.abs(L - L[0]).max() / np.linalg.norm(L[0])))
        slope = np.polyfit(np.log(steps), np.log(errors), 1)[0]
        cells = " | ".join(f"{e:.1e}" for e in errors)
        # the inertial L is an invariant only when every torque is internal
        kept = f"{drift:.0e}" if all(m.internal for m in torques) else "(external torque)"
        out.append(f"| {label} | {scheme} | {cells} | {slope:.2f} | {kept} |")
    return out


def main() -> None:
    start = time.time()
    print(f"{cpu_name()}, Python {platform.python_version()}, numpy {np.__version__}, "
          f"scipy {scipy.__version__}\n")
    gg = GravityGradient(MU, KeplerOrbit(MU, 7.0e6, 0.1))
    t = np.array([0.0, 6000.0])
    w_gg = np.array([1e-3, -2e-3, 3e-3])
    steps = [200.0, 100.0, 50.0, 25.0]
    head = "| torques | scheme | " + " | ".join(f"h = {h:g} s" for h in steps) + \
        " | slope | inertial L drift |"
    print(head)
    print("| --- | --- | " + " | ".join("---:" for _ in steps) + " | ---: | ---: |")
    for line in _rows("gravity gradient", w_gg, t, [gg],
                      ["strang", "blanes-moan", "blanes-moan-rkn", "yoshida6"], steps):
        print(line)
    for tau in (2000.0, 100.0):
        for line in _rows(f"+ internal dissipation tau = {tau:g} s", w_gg, t,
                          [gg, EnergyDissipation(tau)], ["strang", "blanes-moan", "yoshida6"],
                          steps):
            print(line)
    print()
    steps = [0.4, 0.2, 0.1, 0.05]
    print("| torques | scheme | " + " | ".join(f"h = {h:g} s" for h in steps) +
          " | slope | inertial L drift |")
    print("| --- | --- | " + " | ".join("---:" for _ in steps) + " | ---: | ---: |")
    for line in _rows("internal dissipation alone, tau = 10 s", [1.0, 0.05, 0.05],
                      np.array([0.0, 30.0]), [EnergyDissipation(10.0)],
                      ["strang", "blanes-moan", "yoshida6"], steps):
        print(line)
    print(f"\n({time.time() - start:.0f} s)")


if __name__ == "__main__":
    argparse.ArgumentParser(description=__doc__,   # --help: what it measures, then exit
                            formatter_class=argparse.RawDescriptionHelpFormatter
                            ).parse_args()
    main()

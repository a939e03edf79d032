"""Cost of one torque evaluation: the compiled kernel against the Python model call
(issue 18: perturbed propagation at compiled speed).

Gravity gradient of a satellite with a full inertia tensor on a Keplerian orbit (7000
km, e = 0.01, i = 51.6 deg), the same plus eddy currents in the tilted dipole, and
solar radiation pressure (conical shadow) plus drag on a box on the ISS orbit (a TLE,
tabulated): per call, the Python model (``model(t, q, w, body)``), ``body_torque``
called from Python (numba's dispatch included) and ``body_torque`` called from a
compiled loop (what the compiled splitting loop pays).  Each row is the best of 5
repetitions, in CPU time (the machine may be shared).

Measured (AMD EPYC, 2 cores shared, load ~6; numba 0.68), ns per call:

    case                             Python model  kernel from Py  kernel in loop
    gravity gradient, Kepler orbit          24869             776             226
    + eddy currents, tilted dipole          65715            1011             437
    radiation + drag, TLE, 6 facets         49940             989             382

    python benchmarks/compiled_torques.py [--calls N]
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from _machine import cpu_name

from attitude import RigidBody
from attitude.environment import (
    AerodynamicDrag,
    Facets,
    SolarRadiationPressure,
    SunPath,
    TLEOrbit,
)
from attitude.model.orbit import KeplerOrbit
from attitude.model.torques import EARTH_MU, EddyCurrentDamping, GravityGradient, TiltedDipoleField
from attitude.propagation import compiled_torques
from attitude.propagation.compiled_torques import NUMBA, compile_torques

ISS = ("1 25544U 98067A   24061.50000000  .00016717  00000-0  10270-3 0  9005",
       "2 25544  51.6416 247.4627 0006703 130.5360 325.0288 15.72125391563537")


def best_ns(run, calls: int, *args, repeat: int = 5) -> float:
    """Best CPU time per call over ``repeat`` runs of ``run(*args)`` (``calls`` calls),
    ns: the process's CPU time, not the wall clock, which on a shared machine also
    counts the time the process waits for a core."""
    best = np.inf
    for _ in range(repeat):
        start = time.process_time()
        run(*args)
        best = min(best, time.process_time() - start)
    return best / calls * 1e9


def python_calls(model, ts, q, w, body):
    for t in ts:
        model(t, q, w, body)


def kernel_calls(c, ts, q, w, out):
    # the kernel as the package's callers hold it: numba's dispatcher, put in the module
    # on the first call of a kernel (a name imported before that is a stand-in that
    # forwards to it, ~0.5 us more per call from Python)
    body_torque = compiled_torques.body_torque
    kinds, offsets, params = c.kinds, c.offsets, c.params
    for t in ts:
        body_torque(kinds, offsets, params, t, q, w, out)


def main(calls: int) -> None:
    body = RigidBody(np.array([[120.0, 4.0, -3.0], [4.0, 210.0, 6.0], [-3.0, 6.0, 260.0]]))
    orbit = KeplerOrbit(mu=EARTH_MU, a=7.0e6, e=0.01, i=np.radians(51.6), raan=0.3,
                        argp=1.1)
    tle = TLEOrbit(*ISS)
    box = Facets.box([1.0, 1.5, 2.0], center=[0.05, -0.1, 0.12], specular=0.2, diffuse=0.3)
    cases = {
        "gravity gradient, Kepler orbit": GravityGradient(orbit=orbit),
        "+ eddy currents, tilted dipole": GravityGradient(orbit=orbit) + EddyCurrentDamping(
            np.diag([1e3, 2e3, 3e3]), TiltedDipoleField(orbit)),
        "radiation + drag, TLE, 6 facets": SolarRadiationPressure(
            box, sun=SunPath(tle.epoch), orbit=tle) + AerodynamicDrag(box, tle),
    }
    rng = np.random.default_rng(0)
    ts = rng.uniform(0.0, orbit.period, calls)
    q = rng.normal(size=4)
    q /= np.linalg.norm(q)
    w = np.array([5e-4, -1e-3, 1.1e-3])
    out = np.empty(3)
    loop = None
    if NUMBA:
        import numba  # optional: only to time the kernel inside a compiled loop

        body_torque = compiled_torques.body_torque

        @numba.njit
        def loop(kinds, offsets, params, ts, q, w, out):
            for t in ts:
                body_torque(kinds, offsets, params, t, q, w, out)

    print(f"{cpu_name()}; numba: {NUMBA}; {calls} calls per run, best of 5\n")
    print(f"{'case':34s} {'Python model':>14s} {'kernel from Py':>15s} "
          f"{'kernel in loop':>15s} {'speed-up':>9s}")
    for name, model in cases.items():
        c = compile_torques(model, body, t_span=(0.0, orbit.period))
        n_py = max(calls // 20, 100)
        python = best_ns(python_calls, n_py, model, ts[:n_py], q, w, body)
        kernel_calls(c, ts[:2], q, w, out)                                # compile
        from_py = best_ns(kernel_calls, calls, c, ts, q, w, out)
        in_loop = np.nan
        if loop is not None:
            loop(c.kinds, c.offsets, c.params, ts[:2], q, w, out)         # compile
            in_loop = best_ns(loop, calls, c.kinds, c.offsets, c.params, ts, q, w, out)
        fastest = np.nanmin([from_py, in_loop])
        print(f"{name:34s} {python:11.0f} ns {from_py:12.0f} ns {in_loop:12.0f} ns "
              f"{python / fastest:8.0f}x")


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--calls", type=int, default=200_000)
    main(parser.parse_args().calls)

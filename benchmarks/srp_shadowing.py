"""What self-shadowing costs radiation pressure (issue: the Earth-orbit environment).

Two bodies: a concave 1280-face shape model (a sphere of 1 m with three radial lobes of
+-35 %, 1188 of its faces can be shaded by the rest), and a spacecraft of a few facets
(a 1 x 1.5 x 2 m bus and two 2 x 6 m solar arrays on +-y, tilted by 30 deg).  For each:
the cost of one call of the torque model (one attitude, as at each kick of the splitting
integrator) and of a batch of 1000 attitudes, without self-shadowing and with it at
``shadow_subdivision`` k = 1, 2, 4, 8 (``k^2`` rays per lit triangle) and by default
(k per triangle from its size), and the one-time cost of ``largest_torque`` (4000 Sun
directions, what the step choice reads); and how far the torque moves with k (the
sampling error, against k = 16).  Last, 30 minutes of the spacecraft tumbling in a
Keplerian orbit at 500 km (SunPath, conical shadow) by the splitting integrator at
1 s steps, with radiation pressure alone: without self-shadowing (the compiled loop)
and with it (the model called from Python at every kick).

    python benchmarks/srp_shadowing.py
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from _machine import cpu_name
from astropy.time import Time

import attitude as att
from attitude.environment import Facets, SolarRadiationPressure, SunPath

AU = 1.495978707e11
FIXED = dict(sun=[AU, 0.0, 0.0], orbit=[0.0, 0.0, 0.0], shadow=None)


def lobed_shape() -> att.Polyhedron:
    """A sphere of 1 m with three lobes about z: concave between the lobes."""
    ball = att.Polyhedron.ellipsoid(1.0, 1.0, 1.0, subdivisions=3)
    v = ball.vertices
    d = v / np.linalg.norm(v, axis=1, keepdims=True)
    r = 1.0 + 0.35 * np.cos(3.0 * np.arctan2(d[:, 1], d[:, 0])) * (1.0 - d[:, 2] ** 2)
    return att.Polyhedron(d * r[:, None], ball.faces)


def spacecraft() -> Facets:
    """A bus and two tilted solar arrays."""
    tilt = np.radians(30.0)
    n = [np.sin(tilt), 0.0, np.cos(tilt)]
    return Facets.join([
        Facets.box([1.0, 1.5, 2.0], specular=0.2, diffuse=0.4),
        Facets.plate(None, n, [0.0, 4.0, 0.0], size=(6.0, 2.0), edge=[0, 1, 0],
                     specular=0.05, diffuse=0.05, back=(0.0, 0.7)),
        Facets.plate(None, n, [0.0, -4.0, 0.0], size=(6.0, 2.0), edge=[0, 1, 0],
                     specular=0.05, diffuse=0.05, back=(0.0, 0.7))])


def cost(shape, k, q):
    """Seconds per one-attitude call, per batch of len(q), of largest_torque; torques.
    ``k``: "off", an integer, or None (the default subdivision)."""
    srp = SolarRadiationPressure(shape, **FIXED, center_of_mass=[0.05, -0.03, 0.1],
                                 self_shadowing=k != "off",
                                 shadow_subdivision=None if k == "off" else k)
    w = np.zeros(3)
    srp(0.0, q[0], w, None)
    calls = 300
    start = time.perf_counter()
    for qi in q[:calls]:
        srp(0.0, qi, w, None)
    one = (time.perf_counter() - start) / calls
    start = time.perf_counter()
    m = srp(0.0, q, w, None)
    batch = time.perf_counter() - start
    start = time.perf_counter()
    srp.largest_torque(0.0)
    largest = time.perf_counter() - start
    return one, batch, largest, m, srp


def propagation_cost():
    """Wall time of 30 min of the tumbling spacecraft with and without shadows."""
    epoch = Time("2016-10-19T00:00:00", scale="utc")
    orbit = att.KeplerOrbit.from_elements(mu=3.986004418e14, a="6878 km", e=0.001,
                                          i="51.6 deg")
    sun = SunPath(epoch)
    body = att.RigidBody.from_principal_moments([400.0, 500.0, 600.0])
    state = att.AttitudeState.from_quaternion([0, 0, 0, 1.0], epoch=epoch,
                                              omega_body=[0.01, 0.045, 0.02])
    times = np.linspace(0.0, 1800.0, 31)
    print("\n30 min of the spacecraft, splitting at 1 s, radiation pressure alone")
    print("| self-shadowing | wall time (s) | final rate (rad/s) |")
    print("| --- | ---: | --- |")
    for shade in (False, True):
        srp = SolarRadiationPressure(spacecraft(), sun=sun, orbit=orbit,
                                     center_of_mass=[0.05, -0.03, 0.1],
                                     self_shadowing=shade)
        start = time.perf_counter()
        eph = att.propagate(body, state, times, torques=[srp], step=1.0)
        wall = time.perf_counter() - start
        w = eph.dataset["angular_velocity"].values[-1]
        print(f"| {'on' if shade else 'off'} | {wall:.2f} | {np.array2string(w, precision=8)} |")


def main():
    print(f"machine: {cpu_name()}")
    rng = np.random.default_rng(1)
    q = rng.normal(size=(1000, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    for name, shape in (("lobed shape model, 1280 faces", lobed_shape()),
                        ("bus + two arrays, 10 facets", spacecraft())):
        ref = cost(shape, 16, q[:200])[3]
        print(f"\n{name}")
        print("| self-shadowing | one call (us) | 1000 attitudes (ms) | largest_torque (s) "
              "| torque vs k = 16, RMS / RMS torque |")
        print("| --- | ---: | ---: | ---: | ---: |")
        for k in ("off", 1, 2, 4, 8, None):
            one, batch, largest, m, srp = cost(shape, k, q)
            err = np.sqrt(np.mean(np.sum((m[:200] - ref) ** 2, -1)))
            rel = err / np.sqrt(np.mean(np.sum(ref**2, -1)))
            label = {"off": "off", None: "default"}.get(k, f"k = {k}")
            if k == 1:
                print(f"(facets that can be shaded: {srp.shadeable.size} of "
                      f"{len(srp.facets)})")
            print(f"| {label} | {one * 1e6:.0f} | {batch * 1e3:.0f} | {largest:.2f} "
                  f"| {rel:.3f} |")
    propagation_cost()


if __name__ == "__main__":
    argparse.ArgumentParser(description=__doc__,   # --help: what it measures, then exit
                            formatter_class=argparse.RawDescriptionHelpFormatter
                            ).parse_args()
    main()

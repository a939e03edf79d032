"""The Earth-orbit environment: how far the tilted dipole is from IGRF in low Earth orbit,
and what the tabulated models cost (issue: the Earth-orbit environment).

Orbit: the ISS element set of 2024-03-01 (51.6 deg, 420 km), one day, every 10 s.
The tilted dipole is the toolkit's fast model (attitude.torques.TiltedDipoleField, its
pole and moment rounded from IGRF-13 2020, the Earth rotation angle of the epoch);
IGRF-14 is evaluated through ppigrf to degree 13, and to degree 1 (its own dipole).

Second part: the cost of the environment torques.  One day of a tumbling box-shaped
satellite (1 x 1.5 x 2 m, 500 kg, centre of mass 12 cm off the box's centre, spinning
at 0.05 rad/s) on the same orbit, with gravity gradient alone and with gravity gradient
+ solar radiation pressure (conical shadow) + drag (exponential atmosphere) + eddy
currents in IGRF; by the default splitting integrator (its step set by the spin, the
same in both runs), or by DOP853 (``--method integrator``, rtol 1e-10).

    python benchmarks/environment.py [--hours H] [--method splitting|integrator]
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from _machine import cpu_name
from astropy import units as u

import attitude as att
from attitude.environment import (
    IGRF,
    AerodynamicDrag,
    Facets,
    SolarRadiationPressure,
    SunPath,
    TLEOrbit,
)
from attitude.model.torques import EARTH_MU, EddyCurrentDamping, GravityGradient, TiltedDipoleField

ISS = ("1 25544U 98067A   24061.50000000  .00016717  00000-0  10270-3 0  9005",
       "2 25544  51.6416 247.4627 0006703 130.5360 325.0288 15.72125391563537")


def angle(a, b):
    c = np.sum(a * b, -1) / (np.linalg.norm(a, axis=-1) * np.linalg.norm(b, axis=-1))
    return np.degrees(np.arccos(np.clip(c, -1, 1)))


def torque_cost(hours: float, method: str = "splitting"):
    """Wall time of a tumbling box with gravity gradient alone and with all torques."""
    orbit = TLEOrbit(*ISS)
    sun, igrf = SunPath(orbit.epoch), IGRF(orbit)
    size, mass = np.array([1.0, 1.5, 2.0]), 500.0
    moments = mass / 12 * np.array([size[1]**2 + size[2]**2, size[0]**2 + size[2]**2,
                                    size[0]**2 + size[1]**2])
    body = att.RigidBody.from_principal_moments(moments)
    com = np.array([0.05, -0.03, 0.10])
    box = Facets.box(size, specular=0.2, diffuse=0.4)
    state = att.AttitudeState.from_quaternion([0.0, 0.0, 0.0, 1.0], epoch=orbit.epoch,
                                              omega_body=[0.01, 0.045, 0.02])
    times = np.linspace(0.0, hours * 3600.0, int(hours * 60) + 1)
    gg = GravityGradient(EARTH_MU, orbit)
    full = [gg, SolarRadiationPressure(box, sun=sun, orbit=orbit, center_of_mass=com),
            AerodynamicDrag(box, orbit, center_of_mass=com),
            EddyCurrentDamping.spherical_shell(0.8, 2e-3, 3.5e7, igrf)]
    for model in full:                          # tabulate the paths outside the timing
        model(times, np.array([0.0, 0.0, 0.0, 1.0]), np.zeros(3), body)
    rows = []
    for name, torques in (("gravity gradient alone", [gg]),
                          ("+ SRP + drag + eddy currents (IGRF)", full)):
        options = {"rtol": 1e-10} if method == "integrator" else {}
        # warm-up: numba compiles the loop for these torques on the first call (cached)
        att.propagate(body, state, times[:3], torques=torques, method=method, **options)
        start = time.perf_counter()
        eph = att.propagate(body, state, times, torques=torques, method=method, **options)
        wall = time.perf_counter() - start
        w = eph.dataset["angular_velocity"].values
        rows.append((name, wall, np.linalg.norm(w[-1])))
    how = "DOP853 rtol 1e-10" if method == "integrator" else "splitting, default step"
    print(f"{hours:g} h of a tumbling box on the ISS orbit, {how}")
    print("| torques | wall time (s) | final rate (rad/s) |")
    print("| --- | ---: | ---: |")
    for name, wall, rate in rows:
        print(f"| {name} | {wall:.1f} | {rate:.6f} |")
    print(f"ratio: {rows[1][1] / rows[0][1]:.2f}")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--hours", type=float, default=24.0)
    parser.add_argument("--method", default="splitting", choices=["splitting", "integrator"])
    args = parser.parse_args()
    t = np.arange(0.0, 86400.0, 10.0)
    start = time.perf_counter()
    orbit = TLEOrbit(*ISS)
    orbit.position(t)
    t_orbit = time.perf_counter() - start
    start = time.perf_counter()
    igrf = IGRF(orbit)
    b = igrf(t)
    t_field = time.perf_counter() - start
    start = time.perf_counter()
    SunPath(orbit.epoch).position(t)
    t_sun = time.perf_counter() - start
    b1 = IGRF(orbit, max_degree=1)(t)
    era = float(orbit.epoch.earth_rotation_angle(0).to_value(u.rad))
    dipole = TiltedDipoleField(orbit, rotation_angle=era)(t)
    nt = 1e9
    print(f"machine: {cpu_name()}")
    print("one day of the ISS orbit, every 10 s")
    print("| model vs IGRF-14 (degree 13) | max diff (nT) | RMS diff (nT) | max angle (deg) |")
    print("| --- | ---: | ---: | ---: |")
    for name, other in (("IGRF-14, degree 1 (its dipole)", b1),
                        ("tilted dipole (attitude.torques)", dipole)):
        d = np.linalg.norm(other - b, axis=-1) * nt
        print(f"| {name} | {d.max():.0f} | {np.sqrt(np.mean(d**2)):.0f} | "
              f"{angle(other, b).max():.1f} |")
    print(f"| field strength along the orbit | {np.linalg.norm(b, axis=-1).min()*nt:.0f}"
          f" to {np.linalg.norm(b, axis=-1).max()*nt:.0f} nT | | |")
    print()
    print(f"tabulating one day (first call, then cached): SGP4 orbit {t_orbit:.2f} s, "
          f"IGRF {t_field:.2f} s, Sun {t_sun:.2f} s")
    start = time.perf_counter()
    for x in t[:2000]:
        igrf(x)
    per_call = (time.perf_counter() - start) / 2000
    print(f"one cached field evaluation (scalar t): {per_call * 1e6:.0f} us")
    print()
    torque_cost(args.hours, args.method)


if __name__ == "__main__":
    main()

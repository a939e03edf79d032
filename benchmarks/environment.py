"""The Earth-orbit environment: how far the tilted dipole is from IGRF in low Earth orbit,
and what the tabulated models cost (issue: the Earth-orbit environment).

Orbit: the ISS element set of 2024-03-01 (51.6 deg, 420 km), one day, every 10 s.
The tilted dipole is the toolkit's fast model (attitude.torques.TiltedDipoleField, its
pole and moment rounded from IGRF-13 2020, the Earth rotation angle of the epoch);
IGRF-14 is evaluated through ppigrf to degree 13, and to degree 1 (its own dipole).

    python benchmarks/environment.py
"""

from __future__ import annotations

import time

import numpy as np
from _machine import cpu_name
from astropy import units as u

from attitude.environment import IGRF, SunPath, TLEOrbit
from attitude.torques import TiltedDipoleField

ISS = ("1 25544U 98067A   24061.50000000  .00016717  00000-0  10270-3 0  9005",
       "2 25544  51.6416 247.4627 0006703 130.5360 325.0288 15.72125391563537")


def angle(a, b):
    c = np.sum(a * b, -1) / (np.linalg.norm(a, axis=-1) * np.linalg.norm(b, axis=-1))
    return np.degrees(np.arccos(np.clip(c, -1, 1)))


def main():
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


if __name__ == "__main__":
    main()

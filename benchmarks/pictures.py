"""The pictures of docs/pictures.md and the numbers quoted there.

Run from the repository root (needs the pictures extra: pip install
'attitude-dynamics[pictures]')::

    python benchmarks/pictures.py --gifs       # docs/figures/poinsot_{sam,lam,near_separatrix}.gif
                                               # and docs/figures/{apophis,hyperion}.gif
    python benchmarks/pictures.py --timings    # 30-day Apophis -> 20 s MP4, 10^4-epoch HTML

The GIFs are the Poinsot construction for the three regimes of one triaxial body (the
moments of Apophis, 0.61 : 0.965 : 1), each under 1 MB, and two real bodies from their
scenario files: Apophis's tumbling state (scenarios/apophis.toml, torque-free, its shape
the ellipsoid of its moments) and Hyperion tumbling chaotically under Saturn's gravity
gradient (scenarios/hyperion.toml: E and L change, and the construction follows them).
The timings print the wall time of ``Ephemeris.animate`` on the 30-day run of
scenarios/apophis.toml to a 20 s MP4
(20 frames/s) and the size of the HTML view of a 10^4-epoch ephemeris.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

import attitude as att

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "docs" / "figures"
MOMENTS = [0.61, 0.965, 1.0]

#: regime -> body rates (rad/s) of the Apophis-shaped body: L^2/2E > B (SAM), < B (LAM),
#: and 3 % of the way from the separatrix on the SAM side (w1/w3 = 0.402 is on it).
REGIMES = {"sam": [0.02, 0.0, 0.1], "lam": [0.1, 0.0, 0.02],
           "near_separatrix": [0.0395, 0.0, 0.1]}


def gifs(out: Path = OUT) -> None:
    body = att.RigidBody.from_principal_moments(MOMENTS)
    attitude = Rotation.from_euler("ZXZ", [250.0, 165.0, 10.0], degrees=True)
    for name, omega in REGIMES.items():
        state = att.AttitudeState("2029-04-13", attitude, omega)
        regime = att.diagnose(body, state).regime
        P = att.diagnose(body, state).periods
        span = min(2.0 * max(P.values()), 4000.0)
        eph = att.propagate(body, state, np.linspace(0.0, span, 2001))
        path = out / f"poinsot_{name}.gif"
        start = time.perf_counter()
        eph.animate(path, fps=10, duration=8.0, dpi=54, figsize=(9.0, 3.4))
        print(f"{path.relative_to(ROOT)}: {regime}, periods "
              + ", ".join(f"{k} {v:.0f} s" for k, v in P.items())
              + f"; {path.stat().st_size / 1e6:.2f} MB in {time.perf_counter() - start:.1f} s")


#: scenario -> (GIF name, days shown): a month of Apophis (its 27.4 h precession), and a
#: stretch of Hyperion's chaotic tumbling (21 d orbit).
SCENARIO_GIFS = {"apophis.toml": ("apophis", 30.0), "hyperion.toml": ("hyperion", 60.0)}


def scenario_gifs(out: Path = OUT) -> None:
    from attitude.app.cli import main

    with tempfile.TemporaryDirectory() as folder:
        for scenario, (name, days) in SCENARIO_GIFS.items():
            eph_path = Path(folder) / f"{name}.nc"
            main(["run", str(ROOT / "scenarios" / scenario), "-o", str(eph_path), "--quiet"])
            eph = att.Ephemeris.from_netcdf(eph_path)
            t = np.asarray(eph.time, dtype=float)
            keep = t <= days * 86400.0
            eph = att.Ephemeris(eph.dataset.isel(time=np.flatnonzero(keep)))
            path = out / f"{name}.gif"
            start = time.perf_counter()
            eph.animate(path, fps=10, duration=8.0, dpi=54, figsize=(9.0, 3.4))
            print(f"{path.relative_to(ROOT)}: {days:g} days of {scenario}; "
                  f"{path.stat().st_size / 1e6:.2f} MB in {time.perf_counter() - start:.1f} s")


def timings() -> None:
    with tempfile.TemporaryDirectory() as folder:
        folder = Path(folder)
        eph_path = folder / "apophis.nc"
        from attitude.app.cli import main

        main(["run", str(ROOT / "scenarios" / "apophis.toml"), "-o", str(eph_path),
              "--quiet"])
        eph = att.Ephemeris.from_netcdf(eph_path)
        start = time.perf_counter()
        movie = eph.animate(folder / "apophis.mp4", fps=20, duration=20)
        print(f"30-day Apophis ({len(eph)} epochs) -> 20 s MP4 (400 frames): "
              f"{time.perf_counter() - start:.1f} s, {movie.stat().st_size / 1e6:.2f} MB")
        body = att.RigidBody.from_principal_moments(MOMENTS)
        state = att.AttitudeState("2029-04-13", Rotation.identity(), REGIMES["sam"])
        big = att.propagate(body, state, np.linspace(0.0, 20000.0, 10_000))
        start = time.perf_counter()
        page = big.view(folder / "big.html").path
        print(f"10^4-epoch view: {page.stat().st_size / 1e6:.2f} MB in "
              f"{time.perf_counter() - start:.1f} s")


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--gifs", action="store_true", help="write the docs' GIFs")
    parser.add_argument("--timings", action="store_true", help="print the sizes and times")
    args = parser.parse_args(argv)
    if not (args.gifs or args.timings):
        parser.error("give --gifs, --timings or both")
    if args.gifs:
        gifs()
        scenario_gifs()
    if args.timings:
        timings()


if __name__ == "__main__":
    main()

"""Throughput and memory of the streaming netCDF writer (issue 14, §6).

Prints, for one process on this machine:

* epochs per second of :func:`attitude.formats.streaming.propagate_to_netcdf` for one
  torque-free body over ``--epochs`` epochs (default 1e7; the exact solution, 1e5 epochs
  per block, zlib-compressed netCDF-4), with the size of the file;
* the same for a batch of 10 bodies (1e4 epochs per block) over a tenth of the epochs;
* epochs per second of a single body under a torque (the splitting integrator, one step
  per output interval) over ``--epochs / 1000`` epochs;
* the peak of Python-allocated memory (``tracemalloc``, numpy arrays included) of the
  torque-free single-body stream at 1e5 and 1e6 epochs: bounded by the block, not the run.

Run from the repository root (about two minutes for the default 1e7 epochs; ``--epochs
1e6`` for a quick look)::

    python benchmarks/streaming.py [--epochs 10000000]
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import tempfile
import time
import tracemalloc
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

sys.path.insert(0, os.path.join(os.path.dirname(__file__), ".."))

from _machine import cpu_name  # noqa: E402  (benchmarks/_machine.py)

import attitude as att  # noqa: E402
from attitude.formats.streaming import UniformTimes, propagate_to_netcdf  # noqa: E402


def _body_and_state():
    body = att.RigidBody.from_principal_moments([0.61, 0.965, 1.0], name="tumbler")
    state = att.AttitudeState("2029-04-13", Rotation.from_euler("ZXZ", [0.3, 1.1, -0.7]),
                              [0.02, 0.003, 0.05], frame="EME2000")
    return body, state


def timed(folder: Path, name: str, body, state, n: int, **kwargs) -> tuple[float, int]:
    """Seconds and file size of one streamed run of ``n`` epochs, 1 s apart."""
    t0 = time.perf_counter()
    path = propagate_to_netcdf(body, state, UniformTimes(0.0, 1.0, n), folder / name,
                               **kwargs)
    seconds = time.perf_counter() - t0
    size = path.stat().st_size
    path.unlink()
    return seconds, size


def peak_mib(folder: Path, body, state, n: int) -> float:
    tracemalloc.start()
    try:
        propagate_to_netcdf(body, state, UniformTimes(0.0, 1.0, n), folder / "peak.nc",
                            block=100_000)
        return tracemalloc.get_traced_memory()[1] / 2**20
    finally:
        tracemalloc.stop()
        (folder / "peak.nc").unlink(missing_ok=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--epochs", type=float, default=1e7)
    n = int(parser.parse_args().epochs)
    body, state = _body_and_state()
    print(f"attitude {att.__version__}, numpy {np.__version__}, Python "
          f"{platform.python_version()}, {cpu_name()}")
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        seconds, size = timed(folder, "single.nc", body, state, n, block=100_000)
        print(f"1 body, torque-free, {n:.0e} epochs: {seconds:.1f} s, "
              f"{n / seconds:.3g} epochs/s, file {size / 2**20:.0f} MiB "
              f"({size / n:.1f} bytes/epoch)")
        nb = max(n // 10, 1)
        bodies, states = [body] * 10, [state] * 10
        seconds, size = timed(folder, "batch.nc", bodies, states, nb, block=10_000)
        print(f"10 bodies, torque-free, {nb:.0e} epochs: {seconds:.1f} s, "
              f"{10 * nb / seconds:.3g} body-epochs/s")
        nt = max(n // 1000, 1)
        torque = [att.torques.ConstantTorque([2e-4, 0.0, 1e-4], frame="inertial")]
        seconds, _ = timed(folder, "torque.nc", body, state, nt, torques=torque, step=1.0,
                           block=1_000)
        print(f"1 body, constant torque (splitting, 1 step per epoch), {nt:.0e} epochs: "
              f"{seconds:.1f} s, {nt / seconds:.3g} epochs/s")
        peak_mib(folder, body, state, 100_000)              # warm-up
        small, large = (peak_mib(folder, body, state, k) for k in (100_000, 1_000_000))
        print(f"peak Python memory, 1 body, 1e5 epochs per block: {small:.1f} MiB at 1e5 "
              f"epochs, {large:.1f} MiB at 1e6 epochs")


if __name__ == "__main__":
    main()

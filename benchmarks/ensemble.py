"""Throughput of ensemble propagation: one process versus a 2-worker dask LocalCluster,
and the memory of writing an ensemble ephemeris larger than what is ever gathered
(issue 9).

The ensemble is an Apophis-like Monte Carlo cloud (``Ensemble.sample``, the
``"tumbling"`` model, Pravec et al. 2014 means and spreads), propagated torque-free
(exact solution) to ``--epochs`` epochs over 30 days.  The full ephemeris of 1e5 bodies
x 1e3 epochs is 1e8 body-epochs x 11 float64 (quaternion, rates, L, E) = 8.8 GB, so
both modes compute the same *reduction* of the dask-backed ephemeris, the mean and the
largest angle of every body from the nominal attitude at each epoch
(:func:`attitude.ensemble.attitude_spread`), chunk by chunk:

* single process: ``propagate(ens, t, chunks=...)`` computed with dask's synchronous
  scheduler (one chunk after the other, in this process);
* cluster: ``attitude.ensemble.local_cluster(2)`` and ``propagate(ens, t,
  client=client, chunks=...)``, the same reduction computed on the workers.

Scaling efficiency = speed-up / number of workers.  ``--compare-malloc`` adds a plain
``LocalCluster`` with dask's default worker environment, whose
``MALLOC_TRIM_THRESHOLD_=65536`` turns off glibc's dynamic mmap threshold and halves the
throughput of this numpy kernel (``local_cluster`` leaves it out).  A reference row runs
the plain eager numpy path (``propagate(ens, t)``, whole arrays in memory) on a tenth of the bodies.

Bounded memory: the ephemeris of ``--bodies`` x ``--write-epochs`` is written to netCDF
(``eph.to_netcdf``, zlib-compressed) through the cluster into a temporary directory
(deleted afterwards), while a thread samples the resident memory (RSS) of this process
and of the workers; the peak of this process stays far below the output size because the
chunks are computed and written on the workers, never gathered.  The default writes the
whole 1e5 x 1e3 ephemeris (8.8 GB of float64, 5 GB compressed; about 3 minutes on two
cores); ``--write-epochs 200`` writes a fifth of it.

Run from the repository root (needs ``dask[distributed]``)::

    python benchmarks/ensemble.py                  # 1e5 bodies x 1e3 epochs (~6 min)
    python benchmarks/ensemble.py --quick          # small sizes, < 30 s
    python benchmarks/ensemble.py --compare-malloc # + a LocalCluster with dask's default
                                                   #   worker environment
    python benchmarks/ensemble.py --bodies 20000 --epochs 500 --write-epochs 200
"""

from __future__ import annotations

import argparse
import os
import platform
import shutil
import sys
import tempfile
import threading
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), ".."))

from _machine import cpu_name  # noqa: E402  (benchmarks/_machine.py)

import attitude as att  # noqa: E402
from attitude.ensemble import attitude_spread, local_cluster  # noqa: E402

DAY = 86400.0
GB = 1e9


def apophis_cloud(n: int, seed: int = 2029) -> att.Ensemble:
    """``n`` Apophis-like tumblers (body 0 the nominal), Pravec et al. 2014 spreads."""
    import astropy.units as u

    return att.Ensemble.sample(
        n, rng=seed, epoch="2029-01-01", frame="ECLIPJ2000", model="tumbling",
        mean={"angular_momentum_ra": 250 * u.deg, "angular_momentum_dec": -75 * u.deg,
              "energy_ratio": 1.024, "ratio_a": 0.61, "ratio_b": 0.965,
              "precession_period": 27.38 * u.h},
        sigma={"angular_momentum_ra": 3 * u.deg, "angular_momentum_dec": 3 * u.deg,
               "energy_ratio": 0.013 / 3, "ratio_a": 0.03, "ratio_b": 0.004,
               "precession_period": 0.07 / 3 * u.h})


def reduction(eph):
    """Mean and largest angle from the nominal per epoch: a lazy (dask) or eager
    Dataset ``(time)``."""
    import xarray as xr

    s = attitude_spread(eph)
    return xr.Dataset({"mean": s.mean("body"), "max": s.max("body")})


class PeakRSS:
    """Samples the RSS of this process and of its child processes (the dask workers
    and nannies) every ``interval`` s in a thread; ``.client`` and ``.workers`` are
    the peaks in bytes (``.workers`` is the largest sum over the children)."""

    def __init__(self, interval: float = 0.05):
        import psutil

        self._proc, self._interval = psutil.Process(), interval
        self.client = self.workers = 0
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def _run(self):
        import psutil

        while not self._stop.is_set():
            self.client = max(self.client, self._proc.memory_info().rss)
            total = 0
            for child in self._proc.children(recursive=True):
                try:
                    total += child.memory_info().rss
                except psutil.Error:
                    pass
            self.workers = max(self.workers, total)
            self._stop.wait(self._interval)

    def __enter__(self):
        self._thread.start()
        return self

    def __exit__(self, *exc):
        self._stop.set()
        self._thread.join()


def timed(fn, what=""):
    t0 = time.perf_counter()
    out = fn()
    dt = time.perf_counter() - t0
    if what:
        print(f"  [{what}: {dt:.1f} s]", file=sys.stderr, flush=True)
    return out, dt


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--bodies", type=int, default=100_000, help="ensemble size (1e5)")
    p.add_argument("--epochs", type=int, default=1000, help="epochs over 30 days (1e3)")
    p.add_argument("--write-epochs", type=int, default=None,
                   help="epochs of the netCDF write (default: --epochs; 0 skips it)")
    p.add_argument("--chunk", type=int, default=None,
                   help="bodies per dask chunk (default: about 1e6 epochs per chunk)")
    p.add_argument("--workers", type=int, default=2, help="LocalCluster workers (2)")
    p.add_argument("--compare-malloc", action="store_true",
                   help="also time a LocalCluster with dask's default worker environment "
                        "(MALLOC_TRIM_THRESHOLD_=65536, which local_cluster leaves out)")
    p.add_argument("--quick", action="store_true",
                   help="small sizes (2000 bodies x 100 epochs), finishes in seconds")
    args = p.parse_args(argv)
    if args.quick:
        args.bodies, args.epochs = 2000, 100
        args.chunk = args.chunk or 250
        args.write_epochs = 100 if args.write_epochs is None else args.write_epochs
    n, T = args.bodies, args.epochs
    write_T = T if args.write_epochs is None else args.write_epochs
    chunk = args.chunk or max(1, min(n, 1_000_000 // T))

    import warnings

    import dask
    import distributed
    import psutil

    # another cluster on this machine holds dask's default HTTP port: harmless
    warnings.filterwarnings("ignore", message="Port .* is already in use")
    # the ensemble's arrays travel in the task graph (21 MB for 1e5 bodies): expected
    warnings.filterwarnings("ignore", message="Sending large graph")

    print(f"machine: {cpu_name()}, {os.cpu_count()} cores, "
          f"{psutil.virtual_memory().total / GB:.1f} GB RAM; python "
          f"{platform.python_version()}, numpy {np.__version__}, dask {dask.__version__}, "
          f"distributed {distributed.__version__}")
    ens = apophis_cloud(n)
    t = np.linspace(0.0, 30 * DAY, T)
    work = n * T
    print(f"ensemble: {n} Apophis-like tumblers ({len(ens.invalid)} invalid draws), "
          f"{T} epochs over 30 d = {work:.2e} body-epochs, {chunk} bodies per chunk "
          f"({-(-n // chunk)} chunks); full output {work * 11 * 8 / GB:.2f} GB of float64")
    print()
    rows = []

    # --- reference: eager numpy on a tenth of the bodies (whole arrays in memory) -----
    sub = ens.subset(slice(0, max(1, n // 10)))
    _, dt = timed(lambda: reduction(att.propagate(sub, t)), "eager")
    rows.append((f"eager numpy, 1 process, {len(sub)} bodies (reference)", len(sub) * T, dt,
                 ""))

    # --- single process: the same chunks, dask's synchronous scheduler -----------------
    with dask.config.set(scheduler="synchronous"):
        single, dt1 = timed(lambda: reduction(att.propagate(ens, t, chunks=chunk)).compute(),
                        "1 process")
    rows.append(("1 process, dask chunks, synchronous scheduler", work, dt1, "1"))

    # --- the same on a LocalCluster ------------------------------------------------------
    startup = 0.0
    t0 = time.perf_counter()
    with local_cluster(args.workers) as client:
        startup = time.perf_counter() - t0
        client.run(lambda: __import__("attitude"))          # warm imports on the workers
        cluster, dt2 = timed(lambda: reduction(att.propagate(
            ens, t, client=client, chunks=chunk)).compute(), "cluster")
        speedup = dt1 / dt2
        rows.append((f"local_cluster({args.workers}): {args.workers} worker processes x 1 "
                     "thread", work, dt2,
                     f"{speedup:.2f}x, efficiency {speedup / args.workers:.0%}"))
        diff = max(float(abs(single[k] - cluster[k]).max()) for k in ("mean", "max"))
        if diff > 1e-12:
            raise SystemExit(f"the two modes disagree by {diff:.3g} rad")

        write = None
        if write_T:
            tw = np.linspace(0.0, 30 * DAY, write_T)
            eph = att.propagate(ens, tw, client=client, chunks=max(1, min(n, 10**6 // write_T)))
            tmp = Path(tempfile.mkdtemp(prefix="attitude-ensemble-bench-"))
            try:
                import resource

                before = psutil.Process().memory_info().rss
                with PeakRSS() as peak:
                    _, dtw = timed(lambda: eph.to_netcdf(tmp / "ensemble.nc"), "write")
                size = (tmp / "ensemble.nc").stat().st_size
                import xarray as xr

                with xr.open_dataset(tmp / "ensemble.nc") as back:
                    dims = dict(back["quaternion"].sizes)
                    finite = bool(np.isfinite(back["quaternion"][-1, -1].values).all())
                maxrss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
            finally:
                shutil.rmtree(tmp, ignore_errors=True)
            write = (n, write_T, dtw, size, before, peak.client, peak.workers, maxrss, dims,
                     finite)

    if args.compare_malloc:
        from distributed import Client, LocalCluster

        with LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=True,
                          dashboard_address=":0") as lc, Client(lc) as client:
            env = client.run(lambda: os.environ.get("MALLOC_TRIM_THRESHOLD_"))
            client.run(lambda: __import__("attitude"))
            _, dt3 = timed(lambda: reduction(att.propagate(
                ens, t, client=client, chunks=chunk)).compute(), "cluster, dask default env")
        speedup = dt1 / dt3
        rows.append((f"plain LocalCluster, {args.workers} workers, dask's default worker "
                     f"environment (MALLOC_TRIM_THRESHOLD_={sorted(set(env.values()))[0]})",
                     work, dt3, f"{speedup:.2f}x, efficiency {speedup / args.workers:.0%}"))

    print("| mode | body-epochs | wall time | body-epochs/s | speed-up |")
    print("|---|---:|---:|---:|---:|")
    for name, N, dt, note in rows:
        print(f"| {name} | {N:.1e} | {dt:.1f} s | {N / dt:.2e} | {note} |")
    print()
    print(f"(reduction: mean and largest angle from the nominal at each epoch, "
          f"{T} values each; the two modes agree to {diff:.1e} rad; cluster start-up "
          f"{startup:.1f} s, not included)")
    if write:
        n_w, T_w, dtw, size, before, pc, pw, maxrss, dims, finite = write
        raw = n_w * T_w * 11 * 8
        print()
        print("| netCDF write through the cluster | value |")
        print("|---|---:|")
        print(f"| ephemeris | {n_w} bodies x {T_w} epochs = {n_w * T_w:.1e} body-epochs |")
        print(f"| output, uncompressed float64 | {raw / GB:.2f} GB |")
        print(f"| file written (zlib) | {size / GB:.2f} GB |")
        print(f"| wall time | {dtw:.1f} s ({n_w * T_w / dtw:.2e} body-epochs/s) |")
        print(f"| peak RSS of this (client) process | {pc / GB:.2f} GB "
              f"(before the write {before / GB:.2f} GB; "
              f"{pc / raw:.1%} of the output) |")
        print(f"| peak RSS of the workers and nannies, summed | {pw / GB:.2f} GB |")
        print()
        print(f"(read back: quaternion dims {dims}, last sample finite: {finite}; "
              f"getrusage max RSS of this process over the whole run, the eager reference row "
              f"included, {maxrss / GB:.2f} GB)")


if __name__ == "__main__":
    main()

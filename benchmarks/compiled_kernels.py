"""Cost of one exact free-flow step of one body (issue 18): compiled against the numpy path.

Prints, for this machine and one process:

* ``compiled.free_flow_one`` called from a compiled loop (ns per step: what the compiled
  step loop of the splitting integrator pays), and called from Python (the dispatch of
  one numba call added);
* the same source run as plain Python (``ATTITUDE_NO_NUMBA=1``, the fallback when numba
  is absent);
* ``splitting._free_flow1``, the one-body path of the numpy loop (tuples of floats in
  and out of the same kernel; before the free flow had one source, a plain-float copy
  with scipy.special);
* the special functions alone (ns per call, compiled);
* numba's first-call cost: compiling every kernel into an empty cache, and loading them
  from the cache (each in a fresh interpreter).

Steps: 64 random triaxial bodies and states (SAM and LAM), each step from the same
state, a short step (``|lambda h| < pi``: ``sn, cn, dn`` and two ``R_J``) and a long one
(several polhode periods: two more ``R_F`` and one more ``R_J``).  Each figure is the
fastest of many runs of ~1 ms: on a shared machine longer runs are sliced with other
processes (measured here: 640 ns per step in 0.2 ms runs, 1900 ns in 20 ms runs at a
load average of 5 on 2 cores).

Run from the repository root::

    python benchmarks/compiled_kernels.py
"""

from __future__ import annotations

import argparse
import math
import os
import subprocess
import sys
import tempfile
import time

import numpy as np
from scipy.spatial.transform import Rotation

sys.path.insert(0, os.path.join(os.path.dirname(__file__), ".."))

from _machine import cpu_name  # noqa: E402  (benchmarks/_machine.py)

from attitude.propagation import compiled, splitting  # noqa: E402

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")


@compiled.jit
def _steps(c, q0, w0, h, n):
    """``n`` rounds of one free-flow step of each body from its state in ``q0, w0``, in a
    compiled loop (the state copied in first: 7 floats)."""
    q = q0[0].copy()
    w = w0[0].copy()
    for _ in range(n):
        for i in range(c.shape[0]):
            q[:] = q0[i]
            w[:] = w0[i]
            compiled.free_flow_one(c[i], q, w, h)


@compiled.jit
def _special(u, m, n):
    s = 0.0
    for i in range(n):
        x = u + 1e-9 * i
        sn, cn, dn = compiled.ellipj(x, m)
        s += sn + compiled.elliprf(cn * cn, dn * dn, 1.0)
        s += compiled.elliprj(cn * cn, dn * dn, 1.0, 1.0 + 3.0 * sn * sn)
    return s


@compiled.jit
def _ellipj_only(u, m, n):
    s = 0.0
    for i in range(n):
        sn, cn, dn = compiled.ellipj(u + 1e-9 * i, m)
        s += sn
    return s


def _python_calls(free_flow_one, c, quat0, omega0, h) -> float:
    """Seconds of one step of each body called from Python (fresh copies of the states
    and the row views made outside the timing)."""
    q, w = quat0.copy(), omega0.copy()
    rows = list(zip(c, q, w))
    t0 = time.perf_counter()
    for ci, qi, wi in rows:
        free_flow_one(ci, qi, wi, h)
    return time.perf_counter() - t0


def best_of(fn, repeat=100, timed=False):
    """Fastest of ``repeat`` short runs (``timed``: ``fn`` returns its own seconds).

    Runs are kept to ~1 ms and the fastest is taken: on a shared machine a longer run is
    sliced with other processes and measures them too."""
    best = math.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        own = fn()
        best = min(best, own if timed else time.perf_counter() - t0)
    return best


def states(n: int, seed: int = 5):
    rng = np.random.default_rng(seed)
    moments = np.sort(rng.uniform(1.0, 2.0, (n, 3)), axis=1)
    omega = rng.normal(size=(n, 3))
    quat = Rotation.random(n, random_state=rng).as_quat()
    consts = splitting._FreeConstants(moments)
    c = np.array([consts.row(i) for i in range(n)], dtype=float)
    return consts, c, quat, omega


def first_call_seconds(cache_dir: str, env_extra=None) -> float:
    """Seconds of the first free_flow_one call in a fresh interpreter (imports excluded)."""
    code = ("import time, numpy as np\n"
            "from attitude.propagation import compiled\n"
            "c = np.array([0.25, 0.5, 0.75, 0, 0, 3.0, 1 / 3])\n"
            "q, w = np.array([0, 0, 0, 1.0]), np.array([0.1, 0.2, 1.0])\n"
            "t = time.perf_counter(); compiled.free_flow_one(c, q, w, 30.0)\n"
            "print(time.perf_counter() - t)\n")
    env = dict(os.environ, NUMBA_CACHE_DIR=cache_dir, PYTHONPATH=ROOT)
    env.update(env_extra or {})
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                         text=True, check=True)
    return float(out.stdout.split()[-1])


def main():
    print(f"machine: {cpu_name()}, {os.cpu_count()} cores (one process used); "
          f"numba {'on' if compiled.NUMBA else 'OFF (plain Python)'}")
    n = 64
    consts, c, quat0, omega0 = states(n)
    plain = _plain_module()
    for label, h in (("short step, h = 0.37 s", 0.37), ("long step, h = 30 s", 30.0)):
        print(f"\n{label}:")
        _steps(c, quat0, omega0, h, 1)                          # compile (or load)
        reps = 5
        t = best_of(lambda: _steps(c, quat0, omega0, h, reps))  # noqa: B023
        print(f"  compiled, from a compiled loop : {t / (reps * n) * 1e9:8.0f} ns / step")
        for module, what, unit in ((compiled, "compiled, called from Python   ", 1e9),
                                   (plain, "same source as plain Python    ", 1e6)):
            t = best_of(lambda: _python_calls(module.free_flow_one, c, quat0,  # noqa: B023
                                              omega0, h), repeat=20, timed=True)  # noqa: B023
            print(f"  {what}: {t / n * unit:8.{0 if unit == 1e9 else 1}f} "
                  f"{'ns' if unit == 1e9 else 'us'} / step")
        rows = [consts.row(i) for i in range(n)]
        qs = [tuple(map(float, x)) for x in quat0]
        ws = [tuple(map(float, x)) for x in omega0]
        t = best_of(lambda: [splitting._free_flow1(rows[i], qs[i], ws[i], h)  # noqa: B023
                             for i in range(n)], repeat=20)
        print(f"  splitting._free_flow1 (tuples) : {t / n * 1e6:8.1f} us / step")
    reps = 2000
    _special(0.7, 0.6, 1)
    _ellipj_only(0.7, 0.6, 1)
    t = best_of(lambda: _ellipj_only(0.7, 0.6, reps))
    print(f"\nellipj (m = 0.6), compiled: {t / reps * 1e9:.0f} ns; with R_F and R_J: "
          f"{best_of(lambda: _special(0.7, 0.6, reps)) / reps * 1e9:.0f} ns")
    if compiled.NUMBA:
        with tempfile.TemporaryDirectory() as cache:
            cold = first_call_seconds(cache)
            warm = first_call_seconds(cache)
        print(f"first call in a fresh interpreter: {cold:.2f} s compiling into an empty "
              f"cache, {warm:.2f} s loading from the cache")


def _plain_module():
    """compiled.py loaded afresh with ATTITUDE_NO_NUMBA=1 (the plain-Python fallback)."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("attitude.propagation.compiled_plain",
                                                  compiled.__file__)
    module = importlib.util.module_from_spec(spec)
    old = os.environ.get("ATTITUDE_NO_NUMBA")
    os.environ["ATTITUDE_NO_NUMBA"] = "1"
    try:
        spec.loader.exec_module(module)
    finally:
        if old is None:
            del os.environ["ATTITUDE_NO_NUMBA"]
        else:
            os.environ["ATTITUDE_NO_NUMBA"] = old
    return module


if __name__ == "__main__":
    argparse.ArgumentParser(description=__doc__,   # --help: what it measures, then exit
                            formatter_class=argparse.RawDescriptionHelpFormatter
                            ).parse_args()
    main()

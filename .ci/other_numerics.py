"""CI's second numerics pass: the test suite again, under other rounding.

Results computed along two code paths are compared in the tests to tolerances derived
from the computation (``tests/tolerances.py``).  A tolerance that only holds for the
rounding of one CPU must fail in CI, not on a user's machine (issue 14: a batch-versus-
single test failed by 1.36e-15 on an AMD EPYC under another OpenBLAS kernel).  This
script reruns the whole suite, both tiers (the default and ``-m slow``), but for the
files listed in ``NOT_NUMERIC``,

* under another OpenBLAS kernel (``OPENBLAS_CORETYPE``), chosen from the CPU flags in
  ``/proc/cpuinfo`` so that it runs on this CPU and differs from the one OpenBLAS picks
  by itself (Haswell where AVX-512 is present, else Sandybridge, Nehalem or Prescott);
* with numba switched off (``ATTITUDE_NO_NUMBA=1``), so that every propagation takes
  the numpy path the first pass took compiled (issue 18: both paths agree to round-off);
* with numpy's dispatched SIMD targets switched off (``NPY_DISABLE_CPU_FEATURES``), so
  that its loops (``sin``, ``exp``, ``sqrt``, sums) take the baseline code.  Only the
  targets numpy dispatches to *and* finds on this CPU can be disabled (numpy refuses to
  import otherwise); the choice is checked by importing numpy under it first.

Usage: ``python .ci/other_numerics.py [pytest arguments]`` from the repository root, in
the environment that has the package and its test extra installed.  It prints what it
chose and exits with pytest's status.
"""

from __future__ import annotations

import os
import platform
import subprocess
import sys
from pathlib import Path

#: The test files whose outcome cannot depend on the rounding of the floating-point
#: operations, left out of this pass (every other file of tests/, the doctests of
#: attitude/ and the pages of docs/ run, slow tier included):
NOT_NUMERIC = [
    "tests/test_architecture.py",    # the import graph, module sizes, docs tables: source
    "tests/test_docstrings.py",      # that doctests exist (they themselves run here)
    "tests/test_packaging.py",       # distribution name, licence, install hints: text
    "tests/test_startup.py",         # which modules an import loads (sys.modules)
    "tests/test_compile_notice.py",  # numba's compile message (numba is off here)
    "tests/test_inputs.py",          # bad input: exit 2 and the message naming the key
    "tests/test_readme.py",          # the examples' exit status (their numbers: doctests)
    "tests/benchmarks",              # smoke runs of the benchmark scripts: timings
]


def cpu_flags() -> set[str]:
    """The CPU flags of the first processor in ``/proc/cpuinfo`` (empty elsewhere)."""
    try:
        text = Path("/proc/cpuinfo").read_text()
    except OSError:
        return set()
    for line in text.splitlines():
        if line.split(":")[0].strip() in ("flags", "Features"):
            return set(line.split(":", 1)[1].split())
    return set()


def openblas_coretype(flags: set[str]) -> str | None:
    """An OpenBLAS kernel this CPU runs that is not the one OpenBLAS picks for it: one
    step below the widest vector extension it has (None off x86-64)."""
    if platform.machine().lower() not in ("x86_64", "amd64"):
        return None
    if "avx512f" in flags:
        return "Haswell"        # AVX2 kernels instead of SkylakeX / Cooperlake / Zen
    if "avx2" in flags:
        return "Sandybridge"    # AVX kernels instead of Haswell / Zen
    if "avx" in flags:
        return "Nehalem"        # SSE4 kernels instead of Sandybridge
    return "Prescott"           # SSE3: any x86-64


def numpy_features(python: str) -> list[str]:
    """numpy's dispatched SIMD targets that this CPU has (the ones that can be disabled)."""
    code = (
        "try:\n"
        "    from numpy._core import _multiarray_umath as m\n"
        "except ImportError:\n"
        "    from numpy.core import _multiarray_umath as m\n"
        "print(' '.join(f for f in m.__cpu_dispatch__ if m.__cpu_features__.get(f)))\n")
    out = subprocess.run([python, "-c", code], capture_output=True, text=True, check=True)
    return out.stdout.split()


def imports_numpy(python: str, env: dict) -> bool:
    """Whether numpy imports and multiplies matrices under ``env``."""
    code = "import numpy as np; np.ones((3, 3)) @ np.ones(3); import scipy.linalg"
    return subprocess.run([python, "-c", code], env=env, capture_output=True).returncode == 0


def environment(python: str = sys.executable) -> dict:
    """The environment of the second pass (checked to import numpy)."""
    env = dict(os.environ)
    env["CI"] = env.get("CI") or "1"                 # the derandomised hypothesis profile
    env["HYPOTHESIS_PROFILE"] = "ci"
    # numba off: this pass runs the numpy fallback of the splitting integrator (and the
    # compiled kernels as plain Python), the first pass ran the compiled loop
    env["ATTITUDE_NO_NUMBA"] = "1"
    kernel = openblas_coretype(cpu_flags())
    if kernel:
        env["OPENBLAS_CORETYPE"] = kernel
    features = numpy_features(python)
    if features:
        env["NPY_DISABLE_CPU_FEATURES"] = " ".join(features)
        if not imports_numpy(python, env):           # e.g. a target numpy cannot drop
            print(f"numpy does not import with NPY_DISABLE_CPU_FEATURES={features}; "
                  "running with its SIMD targets on", file=sys.stderr)
            del env["NPY_DISABLE_CPU_FEATURES"]
    if not imports_numpy(python, env):
        raise SystemExit(f"numpy does not import under OPENBLAS_CORETYPE={kernel}")
    return env


def main(argv: list[str]) -> int:
    root = Path(__file__).resolve().parent.parent
    env = environment()
    print("second numerics pass: OPENBLAS_CORETYPE="
          f"{env.get('OPENBLAS_CORETYPE', '(default)')} NPY_DISABLE_CPU_FEATURES="
          f"{env.get('NPY_DISABLE_CPU_FEATURES', '(none)')}", flush=True)
    # both tiers (no -m), on every core (pytest-xdist, as the first pass)
    cmd = [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider",
           "-o", "addopts=--doctest-modules --doctest-glob=*.md -ra",
           "-n", "auto", "--maxprocesses=4",
           *(f"--ignore={path}" for path in NOT_NUMERIC), *argv]
    return subprocess.run(cmd, env=env, cwd=root).returncode


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

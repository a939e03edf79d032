"""Tests of the inversion wing; :func:`inversion_benchmark` is the benchmark script
(``benchmarks/inversion.py``: its synthetic cases and geometry), loaded once."""

import functools
import importlib.util
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


@functools.cache
def inversion_benchmark():
    """``benchmarks/inversion.py`` as a module (benchmarks/ is not a package)."""
    spec = importlib.util.spec_from_file_location("inversion_benchmark",
                                                  ROOT / "benchmarks" / "inversion.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module

"""What starting costs (issue 25): ``attitude --help`` loads none of the numerical stack,
and ``import attitude`` loads the costly packages only when they are used.  Each check runs
in a fresh interpreter and looks at ``sys.modules`` (import times vary with the machine)."""

import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

HEAVY = ("numpy", "scipy", "astropy", "xarray", "numba", "matplotlib", "rich", "dask")


def loaded_after(code: str, *argv: str) -> tuple[set[str], subprocess.CompletedProcess]:
    """The top-level packages of ``HEAVY`` imported by ``code`` (run with ``argv``)."""
    script = (f"import sys\nsys.argv = ['attitude', *{list(argv)!r}]\n"
              "try:\n" + "".join(f"    {line}\n" for line in code.splitlines())
              + "except SystemExit:\n    pass\n"
              f"print('\\n' + __import__('json').dumps(sorted({{m.split('.')[0] for m in "
              f"sys.modules}} & set({list(HEAVY)!r}))))\n")
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                          cwd=ROOT)
    assert proc.returncode == 0, proc.stderr
    return set(json.loads(proc.stdout.splitlines()[-1])), proc


@pytest.mark.parametrize("argv", [["--help"], ["--version"], ["run", "--help"],
                                  ["check", "--help"], ["convert", "--help"],
                                  ["fit", "--help"], ["lightcurve", "--help"]])
def test_help_imports_no_numerical_package(argv):
    code = "import runpy\nrunpy.run_module('attitude', run_name='__main__')"
    loaded, proc = loaded_after(code, *argv)
    assert loaded == set()
    assert "attitude" in proc.stdout


def test_import_attitude_loads_only_the_exceptions():
    loaded, _ = loaded_after("import attitude")
    assert loaded == set()



def test_a_torque_free_propagation_loads_no_numba_plotting_or_wing():
    """The core dependencies only (xarray itself imports dask where it is installed);
    the modules of earlier releases' paths are stand-ins without a file until used."""
    code = """\
import numpy as np
import attitude as att
from astropy.time import Time
from scipy.spatial.transform import Rotation
body = att.RigidBody.from_principal_moments([0.61, 0.965, 1.0])
state = att.AttitudeState(Time("2029-04-13", scale="tdb"), Rotation.identity(),
                          np.array([0.01, 0.002, 0.03]))
eph = att.propagate(body, state, np.linspace(0.0, 1000.0, 11))
att.diagnose(body, state)
wings = [m for m, module in sys.modules.items() if getattr(module, "__file__", None)
         and m.split(".")[:2] in (["attitude", w] for w in (
             "formats", "photometry", "fitting", "environment", "spinorbit", "app"))]
assert not wings, wings
"""
    loaded, _ = loaded_after(code)
    assert loaded >= {"numpy", "scipy", "astropy", "xarray"}
    assert not loaded & {"numba", "matplotlib", "rich"}


def test_numba_loads_on_the_first_kernel_call():
    code = """\
from attitude.propagation import compiled
assert "numba" not in sys.modules
if compiled.NUMBA:
    assert compiled.ellipj(0.3, 0.5)[0] == compiled.ellipj.py_func(0.3, 0.5)[0]
    assert "numba" in sys.modules
    from attitude.propagation import compiled_loop
    assert type(compiled_loop.free_flow_one).__name__ == "CPUDispatcher"
"""
    loaded_after(code)


def test_kernels_called_first_from_several_threads():
    """The first calls may come at once from the threads of ``each_on_cores``: each waits
    for the dispatchers and the rebinding of all kernels."""
    code = """\
from concurrent.futures import ThreadPoolExecutor
from attitude.propagation import compiled, compiled_loop
import numpy as np
kernels = [compiled.ellipj, compiled.elliprf, compiled.ellipj, compiled.elliprf] * 2
args = [(0.3, 0.5), (1.0, 2.0, 3.0)] * 4
with ThreadPoolExecutor(8) as pool:
    got = list(pool.map(lambda ka: ka[0](*ka[1]), zip(kernels, args)))
want = [k.py_func(*a) for k, a in zip(kernels, args)]
assert np.allclose(np.array(got[0::2]), np.array(want[0::2]), rtol=1e-15, atol=0)
assert np.allclose(got[1::2], want[1::2], rtol=1e-15, atol=0)
if compiled.NUMBA:
    assert "numba" in sys.modules and compiled.ellipj.signatures
    assert type(compiled_loop.free_flow_one).__name__ == "CPUDispatcher"
"""
    loaded_after(code)


def test_a_missing_dependency_is_named_at_import():
    """``import attitude`` loads none of its dependencies, but says at once which is
    missing (here xarray, hidden from the import system) instead of failing at first use."""
    script = ("import importlib.util as iu\n"
              "real = iu.find_spec\n"
              "iu.find_spec = lambda name, *a: None if name == 'xarray' else real(name, *a)\n"
              "import attitude\n")
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                          cwd=ROOT, timeout=120)
    assert proc.returncode == 1
    assert proc.stderr.strip().splitlines()[-1] == (
        "ImportError: attitude needs xarray: pip install attitude-dynamics "
        "(or pip install xarray)")

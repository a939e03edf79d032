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


"""The kernels say once on stderr when numba compiles them (issue 25: the first run
compiled for ~10 s without a word), never when numba loads them from its cache; the
``--quiet`` of ``attitude``, ``ATTITUDE_QUIET=1`` and ``set_compile_notice(False)``
silence it.  Each case compiles a small kernel of its own, in a fresh interpreter, with
numba's cache in a folder of its own."""

import argparse
import os
import subprocess
import sys
from pathlib import Path

import pytest

from attitude.propagation import compiled

ROOT = Path(__file__).resolve().parents[1]

needs_numba = pytest.mark.skipif(not compiled.NUMBA, reason="numba absent or disabled")

KERNEL = """\
import numba
from attitude.propagation.compiled import jit

@jit
def twice(x):
    return 2.0 * x

@numba.njit(cache=True)
def thrice(x):          # not one of attitude's kernels: compiles in silence
    return 3.0 * x
"""


def run(tmp_path, code, **env):
    (tmp_path / "kernel.py").write_text(KERNEL)
    environ = {**os.environ, "PYTHONPATH": os.pathsep.join([str(tmp_path), str(ROOT)]),
               "NUMBA_CACHE_DIR": str(tmp_path / "cache"), **env}
    if "ATTITUDE_QUIET" not in env:
        environ.pop("ATTITUDE_QUIET", None)
    proc = subprocess.run([sys.executable, "-c", "import kernel\n" + code], env=environ,
                          capture_output=True, text=True, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    return proc.stderr


@needs_numba
def test_a_compile_says_so_once_and_a_cache_load_says_nothing(tmp_path):
    code = "kernel.twice(1.0); kernel.twice(2.0); kernel.twice(3)"     # 2 signatures
    assert run(tmp_path, code) == compiled.COMPILE_NOTICE + "\n"
    assert run(tmp_path, code) == ""                                  # from the cache


@needs_numba
def test_other_numba_functions_compile_in_silence(tmp_path):
    assert run(tmp_path, "kernel.thrice(1.0)") == ""


@needs_numba
@pytest.mark.parametrize("code, env", [
    ("kernel.twice(1.0)", {"ATTITUDE_QUIET": "1"}),
    ("from attitude.propagation.compiled import set_compile_notice\n"
     "set_compile_notice(False)\nkernel.twice(1.0)", {}),
    ("from attitude.propagation.compiled import quiet_compiles\n"
     "with quiet_compiles():\n    kernel.twice(1.0)", {}),
])
def test_silenced(tmp_path, code, env):
    assert run(tmp_path, code, **env) == ""


def test_quiet_compiles_restores_the_setting():
    before = compiled.set_compile_notice(True)
    try:
        with compiled.quiet_compiles():
            assert compiled.set_compile_notice(False) is False
        with compiled.quiet_compiles(False):
            assert compiled.set_compile_notice(True) is True
        assert compiled.set_compile_notice(True) is True
    finally:
        compiled.set_compile_notice(before)


@pytest.mark.parametrize("name", ["run", "section", "fit", "lightcurve"])
@pytest.mark.parametrize("quiet", [True, False])
def test_cli_quiet_silences_the_notice_while_the_command_runs(name, quiet, monkeypatch):
    import importlib

    module = importlib.import_module(f"attitude.app.commands.{name}")
    seen = []

    def body(args):
        seen.append(compiled.set_compile_notice(True))      # the setting while it runs
        return 0

    monkeypatch.setattr(module, f"_{name}", body)
    before = compiled.set_compile_notice(True)
    try:
        assert module.command(argparse.Namespace(quiet=quiet)) == 0
        assert seen == [not quiet]
        assert compiled.set_compile_notice(before) is True            # restored
    finally:
        compiled.set_compile_notice(before)

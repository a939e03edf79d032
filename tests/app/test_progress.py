"""Progress of long work (issue 26): shown on stderr by the ``attitude`` command, as
plain lines when stderr is not a terminal (here: pytest's capture), as a rich bar on a
terminal (a pseudo-terminal in a subprocess), nothing under ``--quiet``; the output
(stdout, the files) is the same either way."""

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from attitude.app.cli import main
from attitude.foundations import progress
from attitude.propagation.compiled import COMPILE_NOTICE
from tests.app.test_scenario import GOOD, write

ROOT = Path(__file__).resolve().parents[2]

#: A run that reports its progress: the splitting integrator (a torque), 3 h of 10 s.
TORQUED = GOOD.replace('duration = "2 min"', 'duration = "3 h"') + """
[[torques]]
type = "constant"
torque = { value = [0.0, 1e-3, 0.0], unit = "N m" }
frame = "body"
"""


@pytest.fixture
def immediate(monkeypatch):
    """Every report shown at once and every update written (the defaults wait 1 s, then
    write every 10 s: a short test run would show nothing)."""
    monkeypatch.setattr(progress, "DELAY", 0.0)
    monkeypatch.setattr(progress, "INTERVAL", 0.0)


def _run(tmp_path, capsys, *extra):
    path = write(tmp_path, TORQUED)
    out = tmp_path / "out.nc"
    code = main(["run", str(path), "-o", str(out), *extra])
    std = capsys.readouterr()
    with xr.open_dataset(out) as ds:
        data = ds.load()
    return code, std, data


def test_run_shows_plain_progress_lines_and_the_same_output(tmp_path, capsys, monkeypatch,
                                                           immediate):
    code, shown, with_progress = _run(tmp_path, capsys)
    assert code == 0
    # the kernels' compile notice, on a first run with numba (tests/test_compile_notice.py)
    lines = [ln for ln in shown.err.splitlines() if ln != COMPILE_NOTICE]
    assert lines and all(ln.startswith("attitude: propagation: ") for ln in lines), lines
    assert lines[-1].startswith("attitude: propagation: done, 3 h of 3 h simulated in ")
    assert "\r" not in shown.err                    # lines, not a rewritten line
    monkeypatch.setattr(progress, "DELAY", float("inf"))      # the same run, no report
    code, silent, without = _run(tmp_path, capsys)
    assert code == 0 and silent.err == ""
    assert shown.out == silent.out
    for name in ("quaternion", "angular_velocity"):
        np.testing.assert_array_equal(with_progress[name].values, without[name].values)


def test_quiet_keeps_stderr_empty(tmp_path, capsys, immediate):
    code, std, _ = _run(tmp_path, capsys, "--quiet")
    assert code == 0 and std.out == "" and std.err == ""


def test_section_reports_its_orbits(tmp_path, capsys, immediate):
    out = tmp_path / "sec.nc"
    assert main(["section", "scenarios/hyperion_section.toml", "-o", str(out),
                 "--orbits", "3"]) == 0
    err = capsys.readouterr().err.splitlines()
    assert err[-1].startswith("attitude: surface of section: done, 3 of 3 orbits in ")
    assert main(["section", "scenarios/hyperion_section.toml", "-o", str(out),
                 "--orbits", "3", "--quiet"]) == 0
    assert capsys.readouterr() == ("", "")


def test_the_library_is_silent_unless_asked(capsys, immediate):
    with progress.Progress(3, "work") as bar:          # show=None outside the command
        bar.update(3)
    assert not bar.shown and capsys.readouterr().err == ""
    with progress.showing(), progress.Progress(3, "outer", unit="steps") as outer:
        with progress.Progress(2, "inner") as inner:   # nested: only the outermost
            inner.update(2)
        outer.update(3)
        assert outer.shown and not inner.shown
    err = capsys.readouterr().err.splitlines()
    assert err == [err[0], err[1]] and "inner" not in "".join(err)
    assert err[0].startswith("attitude: outer: 100 % (3 of 3 steps), ")


#: A driver that runs the child's lines (CHILD) with stdout and stderr on a
#: pseudo-terminal, then prints OUTPUT there, and writes what the terminal received.
ON_A_TERMINAL = """
import os, pty, sys
pid, fd = pty.fork()
if pid == 0:          # the child: stderr is a terminal
CHILD
    print("OUTPUT", flush=True)
    os._exit(0)
chunks = []
while True:
    try:
        data = os.read(fd, 4096)
    except OSError:
        break
    if not data:
        break
    chunks.append(data)
os.waitpid(pid, 0)
sys.stdout.write(b"".join(chunks).decode(errors="replace"))
"""


def _screen(child: str, env: dict, timeout: float) -> str:
    """What a terminal shows of the Python lines ``child`` run on it, then OUTPUT."""
    script = ON_A_TERMINAL.replace("CHILD", textwrap.indent(textwrap.dedent(child), "    "))
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                          timeout=timeout, env=env)
    assert proc.returncode == 0, proc.stderr
    return proc.stdout


BAR = """
from attitude.foundations import progress
progress.DELAY = 0.0
with progress.showing():
    for _ in progress.track(range(5), 5, "demo", unit="steps"):
        pass
"""


def test_a_terminal_gets_a_bar_that_goes_away():
    pytest.importorskip("rich")
    screen = _screen(BAR, {**os.environ, "PYTHONPATH": str(ROOT)}, 120)
    assert "demo" in screen and "5 of 5 steps" in screen      # rich's bar
    assert "\x1b[" in screen                                    # drawn with escapes
    assert "attitude: demo:" not in screen                      # not the plain lines
    assert screen.rstrip().endswith("OUTPUT")                   # removed before the output


def test_run_workers_reports_the_chunks_the_scheduler_finished(tmp_path, capsys, immediate):
    """The chunks of an ensemble counted on the dask scheduler as they finish (a cluster
    of threads here: the scheduler's counts are the same as with processes)."""
    pytest.importorskip("distributed")
    import attitude as att
    from attitude.app.commands.run import _task_progress
    from attitude.propagation.cluster import local_cluster

    cloud = att.Ensemble.from_arrays(principal_moments=np.tile([1.0, 1.5, 2.0], (50, 1)),
                                     quaternion=np.tile([0.0, 0.0, 0.0, 1.0], (50, 1)),
                                     omega_body=np.tile([0.01, 0.0, 0.1], (50, 1)),
                                     epoch="2030-01-01")
    with local_cluster(1, processes=False) as client:
        with progress.showing(), _task_progress(client, interval=0.05):
            eph = att.propagate(cloud, np.linspace(0.0, 600.0, 5), client=client, chunks=10)
            eph.to_netcdf(tmp_path / "cloud.nc")
        first = capsys.readouterr().err.splitlines()
        with progress.showing(), _task_progress(client, interval=0.05):   # a second run:
            eph = att.propagate(cloud, np.linspace(0.0, 900.0, 5), client=client, chunks=25)
            eph.to_netcdf(tmp_path / "cloud2.nc")                       # its chunks only
        second = capsys.readouterr().err.splitlines()
    assert first[-1].startswith("attitude: ensemble: done, 5 of 5 chunks in "), first
    assert second[-1].startswith("attitude: ensemble: done, 2 of 2 chunks in "), second


#: numba's cache empty (a folder of its own): the kernel is compiled
COMPILE = """
from attitude.foundations import progress
from attitude.propagation.compiled import jit
progress.DELAY = 0.0          # shown at once, however fast this machine compiles

@jit
def twice(x):
    return 2.0 * x

twice(1.0)
"""


def test_the_first_compile_on_a_terminal_is_a_report_that_goes_away(tmp_path):
    """On a terminal the compile notice is a report with the time going, removed when
    the kernel is compiled (in a log it stays the one line of tests/test_compile_notice.py).
    The kernel is compiled in a fresh interpreter with numba's cache in a folder of its
    own."""
    pytest.importorskip("rich")
    from attitude.propagation import compiled
    if not compiled.NUMBA:
        pytest.skip("numba absent or disabled")
    env = {**os.environ, "PYTHONPATH": str(ROOT), "NUMBA_CACHE_DIR": str(tmp_path)}
    env.pop("ATTITUDE_QUIET", None)
    screen = _screen(COMPILE, env, 300)
    words = COMPILE_NOTICE.removeprefix("attitude: ").rstrip(".")
    assert words in screen and "\x1b[" in screen                   # drawn by rich
    assert COMPILE_NOTICE not in screen                             # not the plain line
    assert screen.rstrip().endswith("OUTPUT")                       # removed before it

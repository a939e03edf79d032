"""The Python examples of README.md and docs/*.md run as pasted (issue 26).

Every ```python block of README.md, and every ```python block of docs/*.md that is not a
doctest (those run under ``--doctest-glob=*.md``), is written to a script and run in a
fresh interpreter from the repository root, where a user who cloned the repository
stands: a block must hold its own imports and read only files shipped in the repository,
by paths relative to the root.  The script runs in a scratch directory that mirrors the
root (a symbolic link to each of its top-level entries), so that the files a block
writes (``apophis.nc``, ``cloud.nc``) land there and not in the checkout.

An HTML comment on the line before a block marks an exception, with its reason:
``<!-- slow: ... -->`` runs it in the slow tier only, ``<!-- not run: ... -->`` skips it
(the skip names the reason).  Keep them few.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
#: Seconds a block may take (a LocalCluster starts in a few seconds; the machine is shared).
TIMEOUT = 240
_BLOCK = re.compile(r"^```python[ \t]*\n(.*?)^```", re.S | re.M)
_MARK = re.compile(r"<!--\s*(slow|not run)\s*:\s*(.*?)\s*-->\s*$", re.S)


def python_blocks(path: Path) -> list[tuple[int, str, str | None, str]]:
    """The non-doctest ```python blocks of a Markdown file: (line, code, marker, reason),
    the marker ("slow", "not run" or None) from an HTML comment on the line before."""
    text = path.read_text(encoding="utf-8")
    blocks = []
    for match in _BLOCK.finditer(text):
        code = match.group(1)
        if any(line.lstrip().startswith(">>>") for line in code.splitlines()):
            continue                                  # a doctest: run by --doctest-glob
        before = text[:match.start()].rstrip("\n").rsplit("\n", 1)[-1]
        mark = _MARK.search(before)
        line = text.count("\n", 0, match.start()) + 1
        blocks.append((line, code, mark and mark.group(1), mark and mark.group(2)))
    return blocks


def _cases():
    files = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
    for path in files:
        for line, code, marker, reason in python_blocks(path):
            name = f"{path.relative_to(ROOT)}:{line}"
            marks = []
            if marker == "slow":
                marks.append(pytest.mark.slow)
            elif marker == "not run":
                marks.append(pytest.mark.skip(reason=f"{name} not run: {reason}"))
            yield pytest.param(code, id=name, marks=marks)


def _mirror_of_root(tmp_path: Path) -> Path:
    """A directory whose top-level entries are links to the repository root's."""
    mirror = tmp_path / "root"
    mirror.mkdir()
    for entry in ROOT.iterdir():
        if entry.name not in (".git",) and not entry.name.endswith(".nc"):
            (mirror / entry.name).symlink_to(entry, target_is_directory=entry.is_dir())
    return mirror


def run_script(code: str, cwd: Path, timeout: float = TIMEOUT):
    """Run ``code`` as a script ``example.py`` in ``cwd`` with this interpreter, the
    repository's package first on the path."""
    script = cwd / "example.py"
    script.write_text(code, encoding="utf-8")
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(
        p for p in (str(ROOT), os.environ.get("PYTHONPATH", "")) if p))
    return subprocess.run([sys.executable, script.name], cwd=cwd, env=env, timeout=timeout,
                          capture_output=True, text=True)


def test_the_readme_has_its_python_examples():
    """The extraction finds the README's three examples (a test that finds no block
    would pass on a README whose fences were renamed)."""
    assert len(python_blocks(ROOT / "README.md")) >= 3


@pytest.mark.parametrize("code", list(_cases()))
def test_python_block_runs_as_pasted(code, tmp_path):
    done = run_script(code, _mirror_of_root(tmp_path))
    assert done.returncode == 0, (
        f"exit {done.returncode}\n--- code\n{code}\n--- stderr\n{done.stderr[-4000:]}")


@pytest.mark.slow      # starts a LocalCluster whose worker dies: ~50 s on a busy machine
def test_worker_death_is_reported_with_its_causes(tmp_path):
    """A script that reads a missing file outside its ``__main__`` guard kills dask's
    workers (each re-imports the script); the error names that cause, not only the
    guard, and the worker's own error is on stderr."""
    pytest.importorskip("distributed")
    code = textwrap.dedent("""\
        import attitude as att
        from attitude.ensemble import local_cluster

        if __name__ != "__main__":
            open("no_such_catalogue.csv")           # what a worker runs on re-import
        if __name__ == "__main__":
            with local_cluster(1):
                pass
        """)
    done = run_script(code, tmp_path, timeout=120)
    assert done.returncode == 1
    assert "FileNotFoundError" in done.stderr and "no_such_catalogue.csv" in done.stderr
    message = done.stderr.strip().splitlines()[-1]
    assert message.startswith("attitude.foundations.errors.AttitudeError: the dask "
                              "LocalCluster did not start")
    assert "outside that guard fails" in message and "move it under the guard" in message

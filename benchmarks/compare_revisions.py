"""The benchmarks on two revisions of the package, side by side (issue 25: a
reorganisation must leave every benchmark as fast as it was, within 5 %).

Each revision is checked out in a temporary git worktree; each benchmark command runs
there with that tree first on ``sys.path`` (``PYTHONPATH``), once to warm numba's cache,
then ``--repeat`` times alternating between the two revisions, and the best wall time
of each is kept (the machine's other load only ever adds time).  What each benchmark
prints is kept beside the table (``--keep DIR``) for comparing the numbers themselves.

Run from the repository root::

    python benchmarks/compare_revisions.py 7127c23 HEAD          # the default set
    python benchmarks/compare_revisions.py A B --repeat 3 --only benchmarks/torquefree.py
"""

from __future__ import annotations

import argparse
import os
import shlex
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: Benchmark commands (relative to the repository root) that run in about a minute or
#: less on the 2-core machine; the longer ones take their own options.
DEFAULT = [
    "benchmarks/torquefree.py",
    "benchmarks/freebody.py",
    "benchmarks/compiled_torques.py --calls 100000",
    "benchmarks/photometry.py --epochs 5000 --shadow-epochs 100",
    "benchmarks/streaming.py --epochs 1000000",
]


def worktree(rev: str, parent: Path) -> Path:
    """A detached worktree of ``rev`` under ``parent``."""
    path = parent / rev.replace("/", "_")
    subprocess.run(["git", "worktree", "add", "--detach", "-q", str(path), rev], cwd=ROOT,
                   check=True)
    return path


def timed(tree: Path, command: str, log: Path | None) -> float:
    """Wall time of one run of ``command`` in ``tree`` (seconds); its output to ``log``."""
    env = dict(os.environ, PYTHONPATH=str(tree), ATTITUDE_QUIET="1")
    t0 = time.perf_counter()
    proc = subprocess.run([sys.executable, *shlex.split(command)], cwd=tree, env=env,
                          capture_output=True, text=True)
    elapsed = time.perf_counter() - t0
    if log is not None:
        log.write_text(proc.stdout + proc.stderr)
    if proc.returncode != 0:
        raise RuntimeError(f"{command} failed in {tree}:\n{proc.stderr[-2000:]}")
    return elapsed


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("old", help="the earlier revision (a commit, tag or branch)")
    parser.add_argument("new", help="the later revision")
    parser.add_argument("--repeat", type=int, default=1, help="timed runs of each (default 1)")
    parser.add_argument("--only", nargs="*", help="benchmark commands instead of the default set")
    parser.add_argument("--keep", type=Path, help="folder for each benchmark's output")
    args = parser.parse_args(argv)
    commands = args.only or DEFAULT
    if args.keep:
        args.keep.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        trees = {rev: worktree(rev, Path(tmp)) for rev in (args.old, args.new)}
        try:
            print(f"| benchmark | {args.old} (s) | {args.new} (s) | change |")
            print("| --- | ---: | ---: | ---: |")
            for command in commands:
                best = {}
                for tree in trees.values():          # warm numba's cache
                    timed(tree, command, None)
                for k in range(args.repeat):
                    for rev, tree in trees.items():
                        name = f"{Path(command.split()[0]).stem}_{rev}_{k}.txt"
                        log = args.keep / name if args.keep else None
                        best[rev] = min(best.get(rev, float("inf")),
                                        timed(tree, command, log))
                old, new = best[args.old], best[args.new]
                print(f"| `{command}` | {old:.2f} | {new:.2f} | {100 * (new / old - 1):+.1f} % |",
                      flush=True)
        finally:
            for tree in trees.values():
                subprocess.run(["git", "worktree", "remove", "--force", str(tree)], cwd=ROOT,
                               check=False)
    return 0


if __name__ == "__main__":
    sys.exit(main())

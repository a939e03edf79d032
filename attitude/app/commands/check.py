"""``attitude check``: run scenarios and compare them with their ``[expect]`` tables."""

from __future__ import annotations

import os
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

from ...binary.config import is_binary, load_binary, run_binary
from ...foundations.errors import AttitudeError, PropagationError
from ...inversion.config import is_inversion, load_inversion, run_inversion
from ...photometry.config import run_lightcurve  # photometry (issue 15)
from ..scenario import load_scenario, read_scenario_toml, run_scenario
from .common import (
    EXIT_EXPECTATION,
    EXIT_INPUT,
    EXIT_OK,
    EXIT_PROPAGATION,
    expectation_line,
    one_line,
)
from .invert import start_from_scenario

#: Nothing public: :func:`attitude.app.cli.main` runs ``command(args)`` (the command line
#: is the interface, tested in tests/app/test_cli.py).
__all__ = []


def _check_targets(paths) -> tuple[list[Path], list[str]]:
    """Scenario files named by ``paths`` (files, or folders searched for ``*.toml``).

    Everything a folder holds under a ``*.toml`` name is a target, not only regular files:
    a folder or a pipe named ``x.toml`` is then reported as an error of its own."""
    files, errors = [], []
    for p in map(Path, paths):
        if p.is_dir():
            found = sorted(p.rglob("*.toml"))
            if not found:
                errors.append(f"{p}: no *.toml scenario files in this folder")
            files.extend(found)
        elif p.exists():
            files.append(p)
        else:
            errors.append(f"{p}: no such file or folder")
    return list(dict.fromkeys(files)), errors


def _check_one(path: str) -> dict:
    """Run one scenario for ``attitude check`` (in a worker process): a plain dict whose
    ``status`` is ``ok``, ``skipped`` (no ``[expect]``), ``input`` or ``propagation``.
    Never raises: a bad file must not stop the others."""
    start = time.perf_counter()
    out = {"path": path, "status": "ok", "expect": [], "message": ""}
    try:
        _run_one(path, out)
    except PropagationError as exc:
        out.update(status="propagation", message=one_line(exc))
    except (AttitudeError, OSError) as exc:
        out.update(status="input", message=one_line(exc))
    except Exception as exc:  # noqa: BLE001 - a bug: report it, keep checking the others
        out.update(status="propagation",
                   message=f"internal error: {type(exc).__name__}: {one_line(exc)}")
    if out["status"] != "ok":
        out["expect"] = []
    if out["message"] and not out["message"].startswith(path):
        out["message"] = f"{path}: {out['message']}"
    out["seconds"] = time.perf_counter() - start
    return out


def _run_one(path: str, out: dict) -> None:
    """Fill ``out`` with the expectations of the scenario at ``path`` (raises on bad
    input or a failed propagation)."""
    document = read_scenario_toml(path)
    if not isinstance(document.get("expect"), dict):
        out["status"] = "skipped"
        return
    if is_inversion(document):           # issue 27: lightcurves in, shape and pole out
        run = run_inversion(load_inversion(path), write_outputs=False,
                            load_start=start_from_scenario)
        out["name"], out["expect"] = run.name, [dict(e) for e in run.expect]
        return
    if is_binary(document):              # issue 28: the full two-body problem
        run = run_binary(load_binary(path), write_outputs=False)
        out["name"], out["expect"] = run.name, [dict(e) for e in run.expect]
        return
    result = run_scenario(load_scenario(path), write_outputs=False)
    out["name"] = result.scenario.name
    out["expect"] = [dict(e) for e in result.expectations]
    # --- photometry (issue 15): the lightcurve expectations ---
    photometry = result.scenario.photometry
    if photometry is not None and photometry.expect:
        out["expect"].extend(run_lightcurve(result.scenario, photometry, write=False).expect)
    # --- end photometry ---


def _check_line(path: str, e: dict) -> str:
    """``pass  scenarios/apophis.toml  precession: expected 27.38 +/- 0.0821 h, got ...``"""
    status = "pass" if e["ok"] else "FAIL"
    return f"{status}  {path}  " + expectation_line(e).split(" ", 1)[1].lstrip()


def _default_jobs() -> int:
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not on Linux
        return max(1, os.cpu_count() or 1)


def command(args) -> int:
    files, errors = _check_targets(args.paths)
    for message in errors:
        print(f"attitude: error: {message}", file=sys.stderr)
    jobs = args.jobs or _default_jobs()
    if jobs < 1:
        print("attitude: error: --jobs: must be at least 1", file=sys.stderr)
        return EXIT_INPUT
    start = time.perf_counter()
    names = [str(f) for f in files]
    if jobs == 1 or len(names) <= 1:
        results = map(_check_one, names)
        pool = None
    else:
        pool = ProcessPoolExecutor(max_workers=min(jobs, len(names)))
        results = pool.map(_check_one, names)
    passed = failed = checked = 0
    bad = len(errors)
    worst = EXIT_INPUT if errors else EXIT_OK
    try:
        for res in results:     # in the order given, each as soon as it is done
            if res["status"] == "skipped":
                continue
            checked += 1
            if res["status"] != "ok":      # one line, on stderr, naming the file
                print(f"attitude: error: {res['message']}", file=sys.stderr)
                bad += 1
                code = EXIT_INPUT if res["status"] == "input" else EXIT_PROPAGATION
                worst = EXIT_INPUT if EXIT_INPUT in (worst, code) else max(worst, code)
                continue
            for e in res["expect"]:
                print(_check_line(res["path"], e))
                passed += e["ok"]
                failed += not e["ok"]
            if args.times:
                print(f"time  {res['path']}  {res['seconds']:.2f} s")
            sys.stdout.flush()
    finally:
        if pool is not None:
            pool.shutdown()
    if checked == 0 and not errors:
        print("attitude: error: no scenario with an [expect] table in "
              + ", ".join(args.paths), file=sys.stderr)
        return EXIT_INPUT
    errored = f", {bad} error{'s' if bad > 1 else ''}" if bad else ""
    print(f"{passed} passed, {failed} failed{errored} ({checked} scenarios in "
          f"{time.perf_counter() - start:.1f} s)")
    if worst != EXIT_OK:
        return worst
    return EXIT_EXPECTATION if failed else EXIT_OK

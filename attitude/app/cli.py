"""The ``attitude`` command.

Exit codes: 0 success, 1 an expectation failed, 2 bad input (malformed or non-physical
scenario, unreadable file: one line ``attitude: error: FILE: KEY: message``, never a
traceback), 3 the propagation itself failed (or an internal error: one line, the traceback
with ``ATTITUDE_DEBUG=1``).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import os
import sys
import time
import tomllib
import traceback
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

from ..analysis.classification import classification_json, classify, format_classification
from ..analysis.statistics import classify_ensemble, regime_fractions
from ..fitting import fit, sample_posterior
from ..fitting.config import fitted_scenario
from ..fitting.plot import corner_figure, residual_figure
from ..formats.aem import convert
from ..formats.spice import convert_to_ck
from ..foundations.errors import AttitudeError, PropagationError
from ..model.ephemeris import Ephemeris, write_atomically
from ..photometry.config import run_lightcurve  # photometry (issue 15)
from ..photometry.plot import save_lightcurve_figures  # photometry (issue 15)
from ..propagation.cluster import local_cluster
from ..propagation.events import event_table
from ..spinorbit import section as spinorbit_section  # attitude section (spin-orbit wing)
from ..version import __version__
from .plot import save_figures
from .scenario import load_scenario, run_scenario

__all__ = ["main"]

EXIT_OK, EXIT_EXPECTATION, EXIT_INPUT, EXIT_PROPAGATION = 0, 1, 2, 3

_RUN_HELP = """\
Propagate the scenario, print a summary and write its outputs.

The scenario file (TOML) names a body, an initial state, a duration and an output step;
see docs/scenarios.md.  For example:

  attitude run scenarios/apophis.toml
  attitude run scenarios/apophis.toml -o /tmp/apophis.nc --report /tmp/apophis.json

The netCDF ephemeris goes to [output].netcdf (relative to the scenario file), or to -o.
With --plot the figures (polhode, herpolhode, body axes, Euler angles, and the regime
over time for runs with torques) are written as PNG next to it, e.g.
scenarios/apophis_polhode.png (needs matplotlib: pip install 'attitude-dynamics[plot]'):

  attitude run scenarios/apophis.toml --plot

A scenario with an [ensemble] table propagates a population (a Monte Carlo cloud of
states, or a table of bodies); --workers N runs it on a dask LocalCluster of N worker
processes (pip install 'attitude-dynamics[dask]'), writing the ephemeris chunk by chunk:

  attitude run scenarios/apophis_ensemble.toml --workers 2
"""

_MAIN_HELP = """\
Rotation-state analysis of spacecraft and small bodies.

  attitude run scenarios/apophis.toml      propagate a scenario, print a summary,
                                           write the netCDF ephemeris
  attitude run FILE.toml --report R.json   also write a JSON report
  attitude check scenarios/                run every scenario with an [expect] table
                                           and compare (what CI runs)
  attitude classify scenarios/apophis.nc   regime, periods, margin, confidence
  attitude convert eph.nc eph.aem          netCDF -> CCSDS AEM (KVN); .xml for XML,
                                           .bc for a SPICE C-kernel

Exit codes: 0 success, 1 an expectation failed, 2 bad input, 3 propagation failed.
"""


def _format_seconds(s: float, digits: int = 10) -> str:
    for unit, size in (("d", 86400.0), ("h", 3600.0), ("min", 60.0)):
        if abs(s) >= 2 * size:
            return f"{s / size:.{digits}g} {unit}"
    return f"{s:.{digits}g} s"


def _number(x) -> str:
    return f"{x:.10g}" if isinstance(x, float) else str(x)


def _expectation_cells(e: dict) -> tuple[str, str, str, str]:
    """``(key, expected, tolerance, got)`` of one expectation, as text (units included)."""
    unit = f" {e['unit']}" if "unit" in e else ""
    if "tolerance" in e:
        expected, tolerance = f"{_number(e['expected'])}{unit}", f"+/- {e['tolerance']:.3g}{unit}"
    elif e["key"] in ("regime", "resonance"):        # resonance: the spin-orbit wing
        expected, tolerance = e["expected"], "exact"
    else:
        expected, tolerance = f"<= {e['expected']:.3g}", "upper bound"
    got = "absent" if e["got"] is None else _number(e["got"]) + unit
    key = e["key"] + (f" (at {e['at']})" if "at" in e else "")      # spin_period
    return key, expected, tolerance, got


def _expectation_line(e: dict) -> str:
    """``ok   precession: expected 27.38 +/- 0.0821 h, got 27.38``."""
    key, expected, tolerance, got = _expectation_cells(e)
    if "tolerance" in e:
        expected = f"{_number(e['expected'])} {tolerance}"
    return f"{'ok  ' if e['ok'] else 'FAIL'} {key}: expected {expected}, got {got}"


def _summary_rows(result) -> list[tuple[str, str]]:
    """The summary of ``attitude run`` as ``(quantity, value)`` rows, without the
    expectations (one table, plain or rich, is made from them)."""
    sc, eph, d = result.scenario, result.ephemeris, result.diagnosis
    method = sc.method or ("splitting" if sc.torques else "exact")
    scenario = ("Scenario", f"{sc.name}  ({sc.path})")
    run = ("Run", f"{len(eph)} epochs over {_format_seconds(sc.duration)}, step "
                  f"{_format_seconds(sc.step)}, method {method}")
    if result.ensemble is not None:
        return [scenario] + _ensemble_rows(result, run)
    body, state = sc.body, sc.state
    A, B, C = body.principal_moments
    w = state.omega_body
    wn = math.degrees(float((w @ w) ** 0.5))
    rows = [
        scenario,
        ("Body", f"A = {A:.6g}, B = {B:.6g}, C = {C:.6g} kg m^2 ({body.symmetry})"
         + (f", mass {body.mass:.6g} kg" if body.mass is not None else "")),
        ("State", f"epoch {state.epoch.isot} {state.epoch.scale.upper()}, frame {state.frame},"
                  f" |omega| = {wn:.6g} deg/s"),
        run,
    ]
    periods = ", ".join(f"{k} {_format_seconds(v)}" for k, v in result.periods.items())
    if sc.torques:
        rows.append(("Motion", f"initial state (torque-free): {d.regime}"))
        c = result.classification
        if c is None:
            rows.append(("Classified", result.note))
        else:
            extra = ""
            ly = c.lyapunov
            if ly is not None and ly.chaotic:
                extra = f"; Lyapunov time {_format_seconds(ly.lyapunov_time)}"
            elif ly is not None:
                extra = "; regular (Lyapunov exponent not above the torque-free control)"
            rows.append(("Classified", f"regime {c.regime} (confidence {c.confidence:.2f})"
                         + (f"; periods: {periods}" if periods else "") + extra))
            if len(c.segments) > 1:
                rows.append(("Segments", " -> ".join(
                    f"{reg} from {_format_seconds(start)}" for start, _, reg in c.segments)))
    else:
        rows.append(("Motion", f"regime {d.regime}" + (f"; periods: {periods}" if periods
                                                        else "")))
    c = result.conservation
    rows.append(("Changed" if sc.torques else "Conserved",
                 f"L (inertial vector): |L0| = {d.angular_momentum:.10g} kg m^2/s, "
                 f"max |L - L0|/|L0| = {c['angular_momentum_rel_drift']:.2g}; "
                 f"E0 = {d.kinetic_energy:.10g} J, max |E - E0|/E0 = "
                 f"{c['energy_rel_drift']:.2g}"))
    spin = result.spin                   # the spin period and its trend (issue 17)
    if spin is not None:
        rows.append(("Spin", _spin_text(spin, bool(sc.torques))))
    if sc.events:
        found = event_table(eph)
        rows.append(("Events", f"{len(found)} found" + (": " + ", ".join(
            f"{name} at {_format_seconds(t)}" for t, name in found[:5]) if found else "")
            + (f", ... ({len(found) - 5} more in the ephemeris)" if len(found) > 5 else "")))
    return rows


def _spin_text(spin, torques: bool) -> str:
    """``period 134.74 s -> 134.89 s; trend +75.0 +/- 0.4 ms/day, e-folding 4.92 yr``."""
    text = f"period 2 pi |L|/2E: {_format_seconds(spin.period_start, 7)}"
    if not torques:
        return text + " (constant without torques)"
    text += (f" at start, {_format_seconds(spin.period_end, 7)} at end; trend "
             f"{spin.trend_ms_per_day:+.4g} +/- {spin.trend_stderr * 86.4e6:.2g} ms/day "
             f"(least squares over the run)")
    if math.isfinite(spin.efolding):
        years = abs(spin.efolding) / 31557600.0
        size = f"{years:.4g} yr" if years >= 2 else _format_seconds(abs(spin.efolding), 4)
        text += (f", {'e-folding' if spin.efolding > 0 else 'spin-up e-folding'} "
                 f"{size}")
    return text


def _ensemble_rows(result, run: tuple[str, str]) -> list[tuple[str, str]]:
    """Summary rows of an ensemble run (population, regimes, period quantiles, spread)."""
    e, sc = result.ensemble, result.scenario
    bad = len(e["invalid"]) + len(e["failed"])
    rows = [("Ensemble", f"{e['size']} bodies, {e['valid']} propagated"
             + (f", {len(e['invalid'])} invalid input, {len(e['failed'])} failed"
                if bad else "") + f"; epoch {sc.state.epoch.isot} "
             f"{sc.state.epoch.scale.upper()}, frame {sc.state.frame}"),
            run,
            ("Regimes", ", ".join(f"{k} {100 * v:.1f} %" for k, v in
                                  e["regime_fractions"].items()) or "none")]
    for i, why in list(e["invalid"].items())[:5]:
        name = sc.ensemble.names[int(i)]
        rows.append(("Invalid", f"body {i}" + (f" ({name})" if name else "") + f": {why}"))
    if len(e["invalid"]) > 5:
        rows.append(("Invalid", f"... and {len(e['invalid']) - 5} more (--report lists all)"))
    if e["failed"]:
        rows.append(("Failed", "bodies " + ", ".join(map(str, e["failed"][:20]))))
    for key, q in e["period_quantiles"].items():
        rows.append(("Period", f"{key}: median {_format_seconds(q['0.5'])} (5-95 %: "
                               f"{_format_seconds(q['0.05'])} .. {_format_seconds(q['0.95'])})"))
    spread = e["spread_at_end_deg"]
    if spread:
        rows.append(("Spread", "angle from the nominal attitude at the end: "
                     + ", ".join(f"{100 * float(q):g} % within {v:.3g} deg"
                                 for q, v in spread.items())))
    c = result.conservation
    rows.append(("Conserved" if not sc.torques else "Changed",
                 f"worst body: max |L - L0|/|L0| = {c['angular_momentum_rel_drift']:.2g}, "
                 f"max |E - E0|/E0 = {c['energy_rel_drift']:.2g}"))
    return rows


def _summary(result) -> str:
    """The plain-text summary: one ``Label      value`` line per row, then one line per
    expectation and per output file."""
    rows = _summary_rows(result)
    rows += [("Expect", _expectation_line(e)) for e in result.expectations]
    rows += [("Wrote", str(p)) for p in result.outputs]
    return "\n".join(f"{label:<10} {value}" for label, value in rows)


def _rich_summary(result, console) -> None:
    """The summary as rich tables on ``console`` (a ``rich.console.Console``): the run
    (quantity, value), then the expectations (expected, tolerance, got, ok)."""
    from rich.table import Table  # optional ('attitude-dynamics[cli]')
    from rich.text import Text

    table = Table(title=Text(f"attitude run: {result.scenario.name}"), title_justify="left")
    table.add_column("quantity", style="bold", no_wrap=True)
    table.add_column("value", overflow="fold")
    for label, value in _summary_rows(result):
        table.add_row(label, Text(value))
    for p in result.outputs:
        table.add_row("Wrote", Text(str(p)))
    console.print(table)
    if result.expectations:
        exp = Table(title="expectations", title_justify="left")
        for name in ("key", "expected", "tolerance", "got"):
            exp.add_column(name, overflow="fold")
        exp.add_column("ok", no_wrap=True)
        for e in result.expectations:
            ok = Text("ok", style="bold green") if e["ok"] else Text("FAIL", style="bold red")
            exp.add_row(*map(Text, _expectation_cells(e)), ok)
        console.print(exp)


def _print_summary(result) -> None:
    """Rich tables on a terminal when ``rich`` is installed (pip install
    'attitude-dynamics[cli]'), else the plain-text summary (pipes, files, no rich)."""
    if sys.stdout.isatty():
        try:
            from rich.console import Console  # optional ('attitude-dynamics[cli]')
        except ImportError:
            pass
        else:
            _rich_summary(result, Console())
            return
    print(_summary(result))


def _plot_stem(args, result) -> Path:
    """Where ``--plot`` writes: next to the netCDF output, else next to the scenario."""
    target = result.outputs[0] if result.outputs else result.scenario.path
    return Path(target).with_suffix("")


def _cmd_run(args) -> int:
    if args.plot:
        try:
            import matplotlib  # noqa: F401  (optional: 'attitude-dynamics[plot]')
        except ImportError:
            print(f"attitude: error: {args.scenario}: --plot needs matplotlib; install it "
                  "with pip install 'attitude-dynamics[plot]'", file=sys.stderr)
            return EXIT_INPUT
    scenario = load_scenario(args.scenario)
    if args.workers is not None:
        if args.workers < 1:
            print("attitude: error: --workers: must be at least 1", file=sys.stderr)
            return EXIT_INPUT
        if scenario.ensemble is None:
            print(f"attitude: error: {args.scenario}: --workers: the scenario has no "
                  "[ensemble] table (a single body runs in one process)", file=sys.stderr)
            return EXIT_INPUT
        with local_cluster(args.workers) as client:
            result = run_scenario(scenario, netcdf=args.output, client=client)
    else:
        result = run_scenario(scenario, netcdf=args.output,
                              progress=not args.quiet and sys.stderr.isatty())
    if args.plot:
        result.outputs.extend(save_figures(result.ephemeris, _plot_stem(args, result),
                                           result.classification,
                                           regime=result.classification is not None))
    if args.report:
        report = json.dumps(result.report(), indent=2, default=float)
        write_atomically(Path(args.report), lambda tmp: Path(tmp).write_text(report + "\n"))
    if not args.quiet:
        _print_summary(result)
    return EXIT_OK if result.ok else EXIT_EXPECTATION


_CHECK_HELP = """\
Run every scenario that has an [expect] table and compare what it gives with what it
expects: one line per expectation (scenario, key, expected, tolerance, got, pass/FAIL),
then 'N passed, M failed'.  PATH is a scenario file or a folder (searched recursively for
*.toml; files without [expect] are skipped).  Scenarios run in parallel, one per core.
No output files are written.  Put it in your CI:

  attitude check scenarios/
  attitude check scenarios/apophis.toml my_study/ --jobs 2

In a scenario file:

  [expect]
  regime = "SAM"
  precession = { value = 27.38, unit = "h", rel_tol = 0.003 }
  energy_rel_drift = { max = 1e-13 }

Exit codes: 0 all passed, 1 an expectation failed, 2 a file is malformed or missing (the
other files are still checked and reported), 3 a propagation failed.
"""


def _check_targets(paths) -> tuple[list[Path], list[str]]:
    """Scenario files named by ``paths`` (files, or folders searched for ``*.toml``)."""
    files, errors = [], []
    for p in map(Path, paths):
        if p.is_dir():
            found = sorted(f for f in p.rglob("*.toml") if f.is_file())
            if not found:
                errors.append(f"{p}: no *.toml scenario files in this folder")
            files.extend(found)
        elif p.is_file():
            files.append(p)
        else:
            errors.append(f"{p}: no such file or folder")
    return list(dict.fromkeys(files)), errors


def _check_one(path: str) -> dict:
    """Run one scenario for ``attitude check`` (in a worker process): a plain dict."""
    start = time.perf_counter()
    out = {"path": path, "status": "ok", "expect": [], "message": ""}
    try:
        with open(path, "rb") as fh:
            has_expect = isinstance(tomllib.load(fh).get("expect"), dict)
    except (OSError, tomllib.TOMLDecodeError):
        has_expect = True          # let load_scenario report it in its own words
    if not has_expect:
        out["status"] = "skipped"
        return out
    try:
        result = run_scenario(load_scenario(path), write_outputs=False)
    except PropagationError as exc:
        out.update(status="propagation", message=str(exc))
    except (AttitudeError, OSError) as exc:
        out.update(status="input", message=_one_line(exc))
    except Exception as exc:  # noqa: BLE001 - a bug: report it, keep checking the others
        out.update(status="propagation",
                   message=f"{path}: internal error: {type(exc).__name__}: "
                           f"{_one_line(exc)}")
    else:
        out["name"] = result.scenario.name
        out["expect"] = [{k: v for k, v in e.items()} for e in result.expectations]
        # --- photometry (issue 15): the lightcurve expectations ---
        if result.scenario.photometry is not None and result.scenario.photometry.expect:
            try:
                lc_run = run_lightcurve(result.scenario, result.scenario.photometry,
                                        write=False)
                out["expect"].extend(lc_run.expect)
            except AttitudeError as exc:
                out.update(status="input", message=str(exc))
        # --- end photometry ---
    if out["message"] and path not in out["message"]:
        out["message"] = f"{path}: {out['message']}"
    out["seconds"] = time.perf_counter() - start
    return out


def _check_line(path: str, e: dict) -> str:
    """``pass  scenarios/apophis.toml  precession: expected 27.38 +/- 0.0821 h, got ...``"""
    status = "pass" if e["ok"] else "FAIL"
    return f"{status}  {path}  " + _expectation_line(e).split(" ", 1)[1].lstrip()


def _default_jobs() -> int:
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not on Linux
        return max(1, os.cpu_count() or 1)


def _cmd_check(args) -> int:
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
    worst = EXIT_INPUT if errors else EXIT_OK
    try:
        for res in results:     # in the order given, each as soon as it is done
            if res["status"] == "skipped":
                continue
            checked += 1
            if res["status"] != "ok":
                print(f"attitude: error: {res['message']}", file=sys.stderr)
                print(f"ERROR {res['path']}: {res['message']}")
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
    print(f"{passed} passed, {failed} failed ({checked} scenarios in "
          f"{time.perf_counter() - start:.1f} s)")
    if worst != EXIT_OK:
        return worst
    return EXIT_EXPECTATION if failed else EXIT_OK


_CONVERT_HELP = """\
Convert an ephemeris between netCDF (.nc) and CCSDS Attitude Ephemeris Messages
(.aem: KVN text, .xml: XML), by file suffix, or write a SPICE C-kernel (.bc, type 3 with
angular velocity, plus the SCLK, LSK, frame kernel and a meta-kernel beside it; needs
pip install 'attitude-dynamics[spice]').  AEM files are written in version 2.0 with
ATTITUDE_TYPE = QUATERNION/ANGVEL unless --attitude-type says otherwise; AEM versions 1.0
and 2.0 are read.  See docs/formats.md.

  attitude convert scenarios/apophis.nc apophis.aem --object-name APOPHIS --object-id 99942
  attitude convert apophis.aem apophis.xml
  attitude convert mission.aem mission.nc
  attitude convert scenarios/apophis.nc apophis.bc --object-id -99942 --frame ECLIPJ2000
"""


def _cmd_convert(args) -> int:
    if Path(args.output).suffix.lower() == ".bc":
        out = convert_to_ck(args.input, args.output, object_id=args.object_id,
                            object_name=args.object_name, body_frame=args.body_frame,
                            frame=args.frame, attitude_type=args.attitude_type)
    else:
        options = {k: v for k, v in (("object_name", args.object_name),
                                     ("object_id", args.object_id),
                                     ("ref_frame_a", args.frame),
                                     ("ref_frame_b", args.body_frame),
                                     ("attitude_type", args.attitude_type)) if v is not None}
        out = convert(args.input, args.output, **options)
    print(f"Wrote      {out}")
    return EXIT_OK


_CLASSIFY_HELP = """\
Classify the rotation in an ephemeris file (netCDF, as written by 'attitude run'): the
regime (PA-short, PA-long, SAM, LAM, separatrix, axisymmetric, spherical, at-rest), the
measured periods, the margin to the nearest regime boundary, a confidence, and the
regime over time in sliding windows for perturbed runs.  See docs/diagnostics.md.

  attitude run scenarios/apophis.toml
  attitude classify scenarios/apophis.nc
  attitude classify scenarios/apophis.nc --json

An ensemble file (dims body, time) gets one line per body and the regime fractions.
"""


def _cmd_classify(args) -> int:
    eph = Ephemeris.from_netcdf(args.ephemeris)
    if eph.is_batch:
        return _classify_batch(eph, args)
    result = classify(eph)
    results = result if isinstance(result, list) else [result]
    if args.json:
        docs = [classification_json(c) for c in results]
        print(json.dumps(docs if isinstance(result, list) else docs[0], indent=2,
                         default=float))
    else:
        print("\n\n".join(format_classification(c) for c in results))
    return EXIT_OK


def _classify_batch(eph, args) -> int:
    """An ensemble file: each body classified (``attitude.ensemble.classify_ensemble``),
    one line per body and the regime fractions; bodies that cannot be classified are
    listed with the reason and do not stop the others."""
    table = classify_ensemble(eph)
    names = (eph.dataset["body_name"].values if "body_name" in eph.dataset.coords
             else [""] * table.sizes["body"])
    fractions = regime_fractions(table)
    if args.json:
        rows = [{"body": int(i), "name": str(n), "regime": str(r),
                 "confidence": None if c != c else float(c), "reason": str(why)}
                for i, n, r, c, why in zip(table.body.values, names, table.regime.values,
                                            table.confidence.values, table.reason.values)]
        print(json.dumps({"regime_fractions": fractions, "bodies": rows}, indent=2))
        return EXIT_OK
    for i, n, r, c, why in zip(table.body.values, names, table.regime.values,
                               table.confidence.values, table.reason.values):
        label = f"body {i}" + (f" ({n})" if n else "")
        print(f"{label:<24} {r}" + (f" (confidence {c:.2f})" if c == c else f": {why}"))
    print("Regimes    " + (", ".join(f"{k} {100 * v:.1f} %" for k, v in fractions.items())
                           or "none classified"))
    return EXIT_OK


# --- attitude section (spin-orbit wing, issue 19) -------------------------------------

_SECTION_HELP = """\
Compute the surface of section of a spin-orbit scenario: the stroboscopic map at
periapsis (angle of the long axis from periapsis, spin rate / mean motion) of the grid of
initial conditions in its [section] table, for the body and the Keplerian orbit of its
gravity_gradient torque, each trajectory classified regular or chaotic by the
finite-time Lyapunov test.  Writes netCDF (dims initial, orbit) and, with --plot, a PNG.

  attitude section scenarios/hyperion_section.toml -o section.nc --plot

Exit codes: 0 written, 2 a malformed scenario or a missing [section] table.
"""


def _cmd_section(args) -> int:
    scenario = load_scenario(args.scenario)
    if scenario.section is None:
        print(f"attitude: error: {args.scenario}: section: the scenario has no [section] "
              "table (angles, rates, n_orbits)", file=sys.stderr)
        return EXIT_INPUT
    cfg = scenario.section
    if args.orbits is not None:
        if args.orbits < 1:
            print("attitude: error: --orbits: must be at least 1", file=sys.stderr)
            return EXIT_INPUT
        cfg = dataclasses.replace(cfg, n_orbits=args.orbits)
    target = Path(args.output) if args.output else (
        cfg.netcdf or Path(args.scenario).with_suffix(".section.nc"))
    so = spinorbit_section.spin_orbit_of(scenario.body, scenario.torques)
    start = time.perf_counter()
    sec = spinorbit_section.run_section(so, cfg)
    elapsed = time.perf_counter() - start
    written = [spinorbit_section.write_section(sec, target)]
    if args.plot:
        fig = spinorbit_section.section_figure(
            sec, centres=spinorbit_section.island_centres(so))
        png = target.with_suffix(".png")
        written.append(write_atomically(png, lambda tmp: fig.savefig(tmp, format="png",
                                                                      dpi=150)))
    if not args.quiet:
        chaotic = int(sec["chaotic"].sum()) if "chaotic" in sec else 0
        print(f"{scenario.name}: {sec.sizes['initial']} initial conditions x "
              f"{sec.sizes['orbit'] - 1} orbits in {elapsed:.1f} s; omega0 = "
              f"{so.omega0:.4g}, e = {so.e:.4g}; chaotic: {chaotic}")
        for path in written:
            print(f"wrote {path}")
    return EXIT_OK
_FIT_HELP = """\
Fit the rotation state (and moment ratios) of a scenario to its [observations]: the
[body] and [state] are the first guess; attitude samples, body rates, periods and
lightcurves (with their 1-sigma; one magnitude offset per lightcurve session) are
fitted by least squares with the exact torque-free solution, from the guess and its
discrete alternatives (SAM/LAM mirror, psi0 + pi). Prints the parameters
with their 1-sigma, the regime and its margin; writes the best state as a scenario you
can run ([observations].output or -o), and with --posterior the MCMC samples (emcee) as
netCDF.

  attitude fit scenarios/tumbler_fit.toml
  attitude run scenarios/tumbler_fit_fit.toml
  attitude fit scenarios/nea_lightcurve_fit.toml

Exit codes: 0 a converged fit, 1 the fit did not converge (the reason is printed),
2 bad input.
"""


def _cmd_fit(args) -> int:
    scenario = load_scenario(args.scenario)
    cfg = scenario.observations
    if cfg is None:
        print(f"attitude: error: {args.scenario}: observations: the scenario has no "
              "[observations] table (attitude, rates, periods or lightcurve)", file=sys.stderr)
        return EXIT_INPUT
    result = fit(list(cfg.observations), scenario.body, scenario.state, free=cfg.free,
                 multistart=cfg.multistart)
    target = Path(args.output) if args.output else cfg.output
    text = fitted_scenario(result, name=scenario.name, duration=scenario.duration,
                           step=scenario.step, source=Path(args.scenario).name)
    written = [write_atomically(target, lambda tmp: Path(tmp).write_text(text))]
    post = None
    if args.posterior or cfg.posterior is not None:
        opts = cfg.posterior or {}
        post = sample_posterior(result, n_walkers=opts.get("walkers", 32),
                                n_steps=opts.get("steps", 1000), rng=opts.get("seed"))
        nc = cfg.posterior_netcdf or Path(args.scenario).with_suffix(".posterior.nc")
        written.append(write_atomically(nc, lambda tmp: post.samples.to_netcdf(tmp)))
    if args.plot:
        stem = target.with_suffix("")
        figures = [("residuals", residual_figure(result))]
        if post is not None:
            figures.append(("corner", corner_figure(post)))
        for name, fig in figures:
            png = Path(f"{stem}_{name}.png")
            written.append(write_atomically(
                png, lambda tmp, fig=fig: fig.savefig(tmp, format="png", dpi=120)))
    if not args.quiet:
        print(f"{scenario.name}: {'converged' if result.success else 'NOT CONVERGED'} "
              f"({result.message})")
        print(result.summary())
        if len(result.alternatives) > 1:
            alts = ", ".join(f"{r} chi2 {c:.4g}" for c, r in result.alternatives)
            print(f"  optima from the {len(result.alternatives)} starts: {alts}")
        for k, lc in enumerate(result.lightcurve_offsets()):
            print(f"  lightcurve {k} offsets (mag, one per session):")
            for label, b, s in zip(lc["session"], lc["offset"], lc["sigma"]):
                print(f"    session {label}  {b:.5f} +- {s:.2g}")
        if post is not None:
            print(f"  posterior: regime fractions {post.regime_fractions}, acceptance "
                  f"{post.acceptance_fraction:.2f}")
        for path in written:
            print(f"wrote {path}")
    return EXIT_OK if result.success else EXIT_EXPECTATION


# --- photometry (issue 15): attitude lightcurve ------------------------------------------
_LIGHTCURVE_HELP = """\
Propagate a scenario, render its lightcurve from the [photometry] table (shape, law,
Sun/observer geometry, cadence, noise), write it as netCDF ([photometry].output or -o),
fit its periods and print them: the fundamental periods P1, P2 of the Fourier series
(every lightcurve frequency is n1/P1 + n2/P2) and the double-peaked lightcurve period.
The lightcurve keys of [expect] (lightcurve_period, lightcurve_amplitude,
lightcurve_lattice) are checked.

  attitude lightcurve scenarios/apophis_lightcurve.toml --plot

Exit codes: 0 success, 1 an expectation failed, 2 bad input, 3 the propagation failed.
"""


def _cmd_lightcurve(args) -> int:
    scenario = load_scenario(args.scenario)
    if scenario.photometry is None:
        print(f"attitude: error: {args.scenario}: photometry: the scenario has no "
              "[photometry] table", file=sys.stderr)
        return EXIT_INPUT
    result = run_lightcurve(scenario, scenario.photometry, output=args.output)
    if args.plot:
        stem = Path(result.outputs[0] if result.outputs else scenario.path).with_suffix("")
        result.outputs.extend(save_lightcurve_figures(result.lightcurve, result.fit, stem))
    report = result.report()
    if args.report:
        text = json.dumps({"scenario": scenario.name, **report}, indent=2, default=float)
        write_atomically(Path(args.report), lambda tmp: Path(tmp).write_text(text + "\n"))
    if not args.quiet:
        fit = result.fit
        periods = ", ".join(f"P{k + 1} = {p / 3600:.6g} +/- {s / 3600:.2g} h" for k, (p, s)
                            in enumerate(zip(fit.periods, fit.uncertainties)))
        print(f"{scenario.name}: {len(result.lightcurve)} epochs, amplitude "
              f"{report['amplitude_mag']:.3f} mag, rms of the fit {fit.rms:.2g} mag")
        print(f"  periods: {periods}")
        print(f"  lightcurve period (double-peaked, 2/f of the strongest term "
              f"{fit.strongest}): {fit.lightcurve_period / 3600:.6g} h")
        for e in result.expect:
            print(f"  expect {e['key']}: expected {e['expected']} {e['unit']}, got "
                  f"{e['got']}: {'pass' if e['ok'] else 'FAIL'}")
        for path in result.outputs:
            print(f"  wrote {path}")
    return EXIT_OK if result.ok else EXIT_EXPECTATION
# --- end photometry ----------------------------------------------------------------------


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="attitude", description=_MAIN_HELP,
        formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--version", action="version", version=f"attitude {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    run = sub.add_parser("run", help="propagate a scenario file", description=_RUN_HELP,
                         formatter_class=argparse.RawDescriptionHelpFormatter)
    run.add_argument("scenario", metavar="SCENARIO.toml", help="scenario file")
    run.add_argument("-o", "--output", metavar="OUT.nc",
                     help="netCDF ephemeris path (overrides [output].netcdf)")
    run.add_argument("--report", metavar="REPORT.json", help="write a JSON report")
    run.add_argument("--quiet", action="store_true", help="print nothing on success")
    run.add_argument("--plot", action="store_true",
                     help="write the figures as PNG next to the output (needs matplotlib)")
    run.add_argument("--workers", type=int, default=None, metavar="N",
                     help="[ensemble] scenarios: run on a dask LocalCluster of N worker "
                          "processes (needs pip install 'attitude-dynamics[dask]')")
    run.set_defaults(func=_cmd_run)

    chk = sub.add_parser("check", help="run scenarios and compare with their [expect] tables",
                         description=_CHECK_HELP,
                         formatter_class=argparse.RawDescriptionHelpFormatter)
    chk.add_argument("paths", nargs="+", metavar="PATH",
                     help="scenario file or folder of *.toml files")
    chk.add_argument("-j", "--jobs", type=int, default=None, metavar="N",
                     help="scenarios run at once (default: the number of available cores)")
    chk.add_argument("--times", action="store_true",
                     help="also print the run time of each scenario")
    chk.set_defaults(func=_cmd_check)

    cls = sub.add_parser("classify", help="classify the rotation in an ephemeris file",
                         description=_CLASSIFY_HELP,
                         formatter_class=argparse.RawDescriptionHelpFormatter)
    cls.add_argument("ephemeris", metavar="EPHEMERIS.nc", help="netCDF ephemeris")
    cls.add_argument("--json", action="store_true", help="print JSON instead of a table")
    cls.set_defaults(func=_cmd_classify)

    conv = sub.add_parser("convert",
                          help="convert .nc <-> .aem (CCSDS AEM KVN) / .xml, or to .bc (SPICE)",
                          description=_CONVERT_HELP,
                          formatter_class=argparse.RawDescriptionHelpFormatter)
    conv.add_argument("input", metavar="IN", help="ephemeris file (.nc, .aem or .xml)")
    conv.add_argument("output", metavar="OUT", help="output file (.nc, .aem or .xml)")
    conv.add_argument("--object-name", help="AEM OBJECT_NAME (default: the body name)")
    conv.add_argument("--object-id", help="AEM OBJECT_ID; for .bc the NAIF ID (negative "
                      "integer, default -999)")
    conv.add_argument("--frame", help="inertial frame name written to the file (AEM "
                      "REF_FRAME_A, SPICE reference frame; default: the ephemeris frame)")
    conv.add_argument("--body-frame", help="AEM REF_FRAME_B / SPICE body frame (default "
                      "SC_BODY_1)")
    conv.add_argument("--attitude-type", help="AEM ATTITUDE_TYPE (default QUATERNION/ANGVEL;"
                      " also QUATERNION, EULER_ANGLE, ...)")
    conv.set_defaults(func=_cmd_convert)

    sec = sub.add_parser("section", help="spin-orbit surface of section of a scenario "
                         "(netCDF, --plot for a PNG)", description=_SECTION_HELP,
                         formatter_class=argparse.RawDescriptionHelpFormatter)
    sec.add_argument("scenario", metavar="SCENARIO.toml", help="scenario with a [section] table")
    sec.add_argument("-o", "--output", metavar="OUT.nc",
                     help="netCDF path (default [section].netcdf or SCENARIO.section.nc)")
    sec.add_argument("--orbits", type=int, default=None, metavar="N",
                     help="override [section].n_orbits")
    sec.add_argument("--plot", action="store_true", help="also write OUT.png (matplotlib)")
    sec.add_argument("--quiet", action="store_true", help="print nothing on success")
    sec.set_defaults(func=_cmd_section)
    fitp = sub.add_parser("fit", help="fit the rotation state to a scenario's "
                          "[observations]", description=_FIT_HELP,
                          formatter_class=argparse.RawDescriptionHelpFormatter)
    fitp.add_argument("scenario", metavar="SCENARIO.toml",
                      help="scenario with [observations]; [body] and [state] are the guess")
    fitp.add_argument("-o", "--output", metavar="FITTED.toml",
                      help="the best state as a scenario (default [observations].output or "
                           "SCENARIO_fit.toml)")
    fitp.add_argument("--posterior", action="store_true",
                      help="also sample the posterior (emcee; [observations.posterior])")
    fitp.add_argument("--plot", action="store_true", help="write the residuals (and, with "
                      "--posterior, the corner plot) as PNG next to the fitted scenario")
    fitp.add_argument("--quiet", action="store_true", help="print nothing on success")
    fitp.set_defaults(func=_cmd_fit)
    # --- photometry (issue 15) ---
    lcp = sub.add_parser("lightcurve", help="synthesise a scenario's lightcurve and fit its "
                         "periods", description=_LIGHTCURVE_HELP,
                         formatter_class=argparse.RawDescriptionHelpFormatter)
    lcp.add_argument("scenario", metavar="SCENARIO.toml", help="scenario with [photometry]")
    lcp.add_argument("-o", "--output", metavar="OUT.nc",
                     help="netCDF lightcurve path (overrides [photometry].output)")
    lcp.add_argument("--report", metavar="REPORT.json", help="write a JSON report")
    lcp.add_argument("--quiet", action="store_true", help="print nothing on success")
    lcp.add_argument("--plot", action="store_true", help="write the lightcurve, periodogram, "
                     "folded and frequency-map figures as PNG (needs matplotlib)")
    lcp.set_defaults(func=_cmd_lightcurve)
    return parser


def _one_line(text: str) -> str:
    """``text`` on one line (messages quoting other tools may hold newlines)."""
    return " ".join(str(text).split())


def _file_of(args) -> str | None:
    """The input file of the command, to name it in errors that do not."""
    for name in ("scenario", "ephemeris", "input"):
        value = getattr(args, name, None)
        if value:
            return str(value)
    return None


def _error_line(exc: Exception, file: str | None) -> str:
    """``attitude: error: FILE: KEY: message`` for an :class:`AttitudeError`."""
    text = _one_line(exc)
    if isinstance(exc, AttitudeError) and exc.path is None and file and not text.startswith(
            file):
        text = f"{file}: {text}"
    return f"attitude: error: {text}"


def main(argv: list[str] | None = None) -> int:
    """The ``attitude`` command: parse ``argv`` (default ``sys.argv[1:]``), run the
    subcommand and return its exit code.

    Exit codes (docs/scenarios.md): 0 success, 1 an expectation failed, 2 bad input (one
    line ``attitude: error: FILE: KEY: message`` on stderr, never a traceback), 3 the
    propagation failed, or an internal error (one line; the traceback with
    ``ATTITUDE_DEBUG=1``).

    Examples
    --------
    >>> main(["check", "scenarios/apophis.toml", "--jobs", "1"])  # doctest: +ELLIPSIS
    pass  scenarios/apophis.toml  regime: expected SAM, got SAM
    ...
    0
    """
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.command is None:
        parser.print_help()
        return EXIT_INPUT
    file = _file_of(args)
    try:
        return args.func(args)
    except PropagationError as exc:
        print(_error_line(exc, file), file=sys.stderr)
        return EXIT_PROPAGATION
    except AttitudeError as exc:
        print(_error_line(exc, file), file=sys.stderr)
        return EXIT_INPUT
    except OSError as exc:
        where = exc.filename or file or ""
        print(f"attitude: error: {where}: {_one_line(exc.strerror or exc)}", file=sys.stderr)
        return EXIT_INPUT
    except Exception as exc:  # noqa: BLE001 - a bug: one line, the traceback on request
        if os.environ.get("ATTITUDE_DEBUG", "") not in ("", "0"):
            traceback.print_exc()
        print(f"attitude: error: {file or 'attitude'}: internal error: "
              f"{type(exc).__name__}: {_one_line(exc)} (please report it; ATTITUDE_DEBUG=1 "
              "shows the traceback)", file=sys.stderr)
        return EXIT_PROPAGATION


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())

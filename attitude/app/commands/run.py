"""``attitude run``: propagate a scenario, print its summary, write its outputs."""

from __future__ import annotations

import contextlib
import json
import logging
import math
import sys
import threading
from pathlib import Path

from ...binary.config import is_binary
from ...foundations.progress import Progress
from ...model.ephemeris import write_atomically
from ...propagation.cluster import local_cluster
from ...propagation.compiled import quiet_compiles
from ...propagation.events import event_table
from ..plot import save_figures
from ..scenario import load_scenario, read_scenario_toml, run_scenario
from .common import (
    EXIT_EXPECTATION,
    EXIT_INPUT,
    EXIT_OK,
    expectation_cells,
    expectation_line,
    format_seconds,
)
from .run_binary import run_binary_command

#: Nothing public: :func:`attitude.app.cli.main` runs ``command(args)`` (the command line
#: is the interface, tested in tests/app/test_cli.py).
__all__ = []


def _summary_rows(result) -> list[tuple[str, str]]:
    """The summary of ``attitude run`` as ``(quantity, value)`` rows, without the
    expectations (one table, plain or rich, is made from them)."""
    sc, eph, d = result.scenario, result.ephemeris, result.diagnosis
    method = (eph.dataset.attrs.get("method") or sc.method
              or ("splitting" if sc.torques else "exact"))
    scenario = ("Scenario", f"{sc.name}  ({sc.path})")
    run = ("Run", f"{len(eph)} epochs over {format_seconds(sc.duration)}, step "
                  f"{format_seconds(sc.step)}, method {method}")
    reason = eph.dataset.attrs.get("method_reason")
    why = [("Method", f"{method}: {reason}")] if reason else []   # which ran and why
    if result.ensemble is not None:
        return [scenario] + _ensemble_rows(result, run) + why
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
    ] + why
    periods = ", ".join(f"{k} {format_seconds(v)}" for k, v in result.periods.items())
    if sc.torques:
        rows.append(("Motion", f"initial state (torque-free): {d.regime}"))
        c = result.classification
        if c is None:
            rows.append(("Classified", result.note))
        else:
            extra = ""
            ly = c.lyapunov
            if ly is not None and ly.chaotic:
                extra = f"; Lyapunov time {format_seconds(ly.lyapunov_time)}"
            elif ly is not None:
                extra = "; regular (Lyapunov exponent not above the torque-free control)"
            rows.append(("Classified", f"regime {c.regime} (confidence {c.confidence:.2f})"
                         + (f"; periods: {periods}" if periods else "") + extra))
            if len(c.segments) > 1:
                rows.append(("Segments", " -> ".join(
                    f"{reg} from {format_seconds(start)}" for start, _, reg in c.segments)))
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
            f"{name} at {format_seconds(t)}" for t, name in found[:5]) if found else "")
            + (f", ... ({len(found) - 5} more in the ephemeris)" if len(found) > 5 else "")))
    return rows


def _spin_text(spin, torques: bool) -> str:
    """``period 134.74 s -> 134.89 s; trend +75.0 +/- 0.4 ms/day, e-folding 4.92 yr``."""
    text = f"period 2 pi |L|/2E: {format_seconds(spin.period_start, 7)}"
    if not torques:
        return text + " (constant without torques)"
    text += (f" at start, {format_seconds(spin.period_end, 7)} at end; trend "
             f"{spin.trend_ms_per_day:+.4g} +/- {spin.trend_stderr * 86.4e6:.2g} ms/day "
             f"(least squares over the run)")
    if math.isfinite(spin.efolding):
        years = abs(spin.efolding) / 31557600.0
        size = f"{years:.4g} yr" if years >= 2 else format_seconds(abs(spin.efolding), 4)
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
        rows.append(("Period", f"{key}: median {format_seconds(q['0.5'])} (5-95 %: "
                               f"{format_seconds(q['0.05'])} .. {format_seconds(q['0.95'])})"))
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
    rows += [("Expect", expectation_line(e)) for e in result.expectations]
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
            exp.add_row(*map(Text, expectation_cells(e)), ok)
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


@contextlib.contextmanager
def _dask_warnings_hidden():
    """distributed's own log below errors kept off stderr (its nanny's "Worker process
    still alive after 4.0 seconds, killing" when the cluster closes is no news to the
    user: the results are written by then)."""
    try:      # its import sets its loggers' levels: ours must come after
        import distributed  # noqa: F401  (optional: 'attitude-dynamics[dask]')
    except ImportError:
        pass              # local_cluster says what to install
    logger = logging.getLogger("distributed")
    level = logger.level
    logger.setLevel(logging.ERROR)
    try:
        yield
    finally:
        logger.setLevel(level)


#: The dask tasks of an ensemble's chunks (attitude.propagation.batch), by the prefix the
#: scheduler counts them under: the name of the function each runs (``_propagate_chunk``)
#: without dask's leading underscore (``dask.utils.key_split``).
CHUNK_TASK = "propagate_chunk"


def _chunk_counts(dask_scheduler, prefix: str = CHUNK_TASK) -> tuple[int, int]:
    """``(finished, waiting)`` chunk tasks, on the scheduler: the times a task of the
    prefix reached memory (a running count), and those still to run."""
    tasks = dask_scheduler.task_prefixes.get(prefix)
    if tasks is None:
        return 0, 0
    waiting = sum(tasks.states.get(s, 0) for s in ("waiting", "queued", "processing",
                                                   "no-worker"))
    return int(tasks.state_counts.get("memory", 0)), int(waiting)


@contextlib.contextmanager
def _task_progress(client, interval: float = 0.5):
    """The chunks of ``attitude run --workers`` as they finish on the cluster (asked of
    the scheduler every ``interval`` s), as :mod:`attitude.foundations.progress` shows."""
    bar = Progress(None, "ensemble", unit="chunks")
    if not bar.shown:
        yield
        return
    stop = threading.Event()
    start = client.run_on_scheduler(_chunk_counts)[0]      # chunks of earlier runs

    done = [0]

    def poll() -> bool:
        try:
            finished, waiting = client.run_on_scheduler(_chunk_counts)
        except Exception:  # noqa: BLE001 - the cluster closing: the report stops
            return False
        now = finished - start
        bar.update(now - done[0], total=now + waiting or None)
        done[0] = now
        return True

    def watch():
        while not stop.wait(interval) and poll():
            pass

    thread = threading.Thread(target=watch, name="ensemble progress", daemon=True)
    thread.start()
    try:
        yield
    finally:
        stop.set()
        thread.join()
        poll()                  # the chunks that finished since the last look
        bar.close()


def command(args) -> int:
    """``attitude run``; its ``--quiet`` also silences the kernels' compile notice."""
    with quiet_compiles(args.quiet):
        return _run(args)


def _run(args) -> int:
    if args.plot:
        try:
            import matplotlib  # noqa: F401  (optional: 'attitude-dynamics[plot]')
        except ImportError:
            print(f"attitude: error: {args.scenario}: --plot needs matplotlib; install it "
                  "with pip install 'attitude-dynamics[plot]'", file=sys.stderr)
            return EXIT_INPUT
    if is_binary(read_scenario_toml(args.scenario)):      # issue 28: two rigid bodies
        return run_binary_command(args)
    scenario = load_scenario(args.scenario)
    if args.workers is not None:
        if args.workers < 1:
            print("attitude: error: --workers: must be at least 1", file=sys.stderr)
            return EXIT_INPUT
        if scenario.ensemble is None:
            print(f"attitude: error: {args.scenario}: --workers: the scenario has no "
                  "[ensemble] table (a single body runs in one process)", file=sys.stderr)
            return EXIT_INPUT
        with _dask_warnings_hidden(), local_cluster(args.workers) as client, \
                _task_progress(client):
            result = run_scenario(scenario, netcdf=args.output, client=client)
    else:
        result = run_scenario(scenario, netcdf=args.output, progress=not args.quiet)
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

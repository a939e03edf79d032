"""The ``[observations]`` table of a scenario file and the ``attitude fit`` run.

The scenario's ``[body]`` and ``[state]`` are the first guess; ``[observations]`` says
what was measured::

    [observations]
    free = ["energy_ratio", "ratio_a", "ratio_b", "precession_period", "phi0", "psi0"]
    attitude = { file = "tracker.csv", sigma = "0.05 deg" }   # t (s) or time (ISO, UTC),
                                                               # qx, qy, qz, qw
    rates = { file = "gyro.csv", sigma = "1e-4 rad/s" }        # t or time, wx, wy, wz
    periods = { precession = { value = 27.38, sigma = 0.07, unit = "h" } }
    multistart = true                       # also from the guess's mirror and psi0 + pi
    output = "fitted.toml"                  # the best state as a scenario (default
                                            # <scenario>_fit.toml)
    posterior = { walkers = 32, steps = 2000, seed = 1, netcdf = "posterior.nc" }

    [[observations.lightcurve]]             # any number of them
    file = "night1-3.csv"      # ALCDEF or CSV (attitude.read_lightcurve: jd / mjd / time,
                               # mag, optional mag_err and session columns)
    sigma = "0.02 mag"         # 1-sigma where the file gives none
    sessions = true            # one magnitude offset per session of the file (default)
    shape = "ellipsoid"        # from the body's moments (or axes = [...]), or an OBJ file
    subdivisions = 2           # ellipsoid mesh: 20 * 4**n faces
    law = "ls-lambert"         # or { name = "hapke", w = 0.3, ... }
    sun = [1.0, 0.0, 0.0]      # fixed directions body -> Sun and body -> observer in
    observer = [0.9, 0.4, 0.1] # the [state] frame; or, per epoch from the target's orbit:
    # orbit = { mu = "1.32712440018e20 m3/s2", a = "1.1 AU", e = 0.2, ... }
    # observer = "earth"       # (default with an orbit); light_time = true

Times in the attitude and rate files are seconds since the ``[state]`` epoch (column
``t``) or ISO 8601 dates in UTC (column ``time``); lightcurve files carry their own
dates (UTC JD, MJD or ISO).  The lightcurve keys ``shape``, ``axes``, ``length_unit``,
``subdivisions``, ``law``, ``sun``, ``observer``, ``orbit`` and ``light_time`` mean what
they mean in ``[photometry]`` (:mod:`attitude.photometry.config`).  Light time: with an
orbit and ``light_time = true`` the attitude is modelled at the emission times (the
file's times minus the light time) -- except for ALCDEF files, whose reader already
moves the times to the asteroid (``LTCAPP``/``LTCDAYS``), so their times are used as
they are.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
from astropy import units as u
from astropy.time import Time, TimeDelta

from ..foundations.errors import AttitudeError, ScenarioError
from ..foundations.spec import Key, Table
from ..model.regimes import PERIOD_KEYS
from ..model.state import format_epoch
from ..photometry.config import PHOTOMETRY as _PHOTOMETRY
from ..photometry.config import parse_photometry
from ..photometry.geometry import Geometry
from ..photometry.readers import read_lightcurve
from .leastsq import FitResult
from .observations import (
    AngularVelocityObservations,
    AttitudeObservations,
    LightcurveObservations,
    PeriodObservations,
)
from .parameters import PARAMETERS

__all__ = ["OBSERVATIONS", "LIGHTCURVE", "ObservationsConfig", "parse_observations",
           "fitted_scenario"]

_FILE = (Key("file", "string", required=True, doc="CSV, path relative to the scenario"),)
#: The keys of a lightcurve that mean what they mean in ``[photometry]``.
_PHOTOMETRY_KEYS = ("shape", "axes", "length_unit", "subdivisions", "law", "sun",
                    "observer", "orbit", "light_time")

#: One ``[[observations.lightcurve]]`` table.
LIGHTCURVE = Table("lightcurve", (
    Key("file", "string", required=True,
        doc="ALCDEF or CSV (attitude.read_lightcurve), path relative to the scenario"),
    Key("format", "string", choices=("alcdef", "csv"), doc="default: from the file"),
    Key("sigma", "quantity", unit="mag", positive=True,
        doc="magnitude 1-sigma where the file gives none"),
    Key("sessions", "boolean", default=True,
        doc="one magnitude offset per session of the file (false: one for all)"),
    # the shape, law and geometry keys of [photometry], as it declares them
    replace(_PHOTOMETRY["shape"], required=False, default="ellipsoid"),
    _PHOTOMETRY["axes"],
    replace(_PHOTOMETRY["subdivisions"], default=2),
    _PHOTOMETRY["length_unit"],
    replace(_PHOTOMETRY["law"], default="ls-lambert"),
    replace(_PHOTOMETRY["sun"], doc="fixed direction body -> Sun, [state] frame"),
    _PHOTOMETRY["observer"],
    _PHOTOMETRY["orbit"],
    replace(_PHOTOMETRY["light_time"],
            doc="with an orbit: model the attitude at the emission times"),
), exactly_one=(("sun", "orbit"),), needs=(("sun", ("observer",)),
                                          ("light_time", ("orbit",))),
    doc="A lightcurve: the magnitudes, the shape and scattering law that make them, and the "
        "Sun/observer geometry (fixed vectors, or from the target's orbit).")

#: The ``[observations]`` table (declared in :data:`attitude.app.scenario_spec.SCENARIO`).
OBSERVATIONS = Table("observations", (
    Key("free", "any", schema={"type": "array", "items": {"enum": list(PARAMETERS)},
                               "minItems": 1, "uniqueItems": True},
        doc="parameters to fit (attitude.fitting.PARAMETERS); default all"),
    Key("attitude", "table", table=Table("attitude", _FILE + (
        Key("sigma", "quantity", unit="rad", required=True, positive=True,
            doc="angular 1-sigma per axis"),)),
        doc="quaternions (body -> inertial): columns t or time, qx, qy, qz, qw"),
    Key("rates", "table", table=Table("rates", _FILE + (
        Key("sigma", "quantity", unit="rad/s", required=True, positive=True),)),
        doc="body rates: columns t or time, wx, wy, wz (rad/s)"),
    Key("lightcurve", "tables", table=LIGHTCURVE,
        doc="lightcurves [[observations.lightcurve]]: one offset per session"),
    Key("periods", "table", table=Table("periods", tuple(
        Key(k, "table", table=Table(k, (
            Key("value", "number", required=True, positive=True),
            Key("sigma", "number", required=True, positive=True),
            Key("unit", "unit", unit="s", default="s"))), doc=f"the {k} period")
        for k in PERIOD_KEYS)), doc="measured periods with their 1-sigma"),
    Key("multistart", "boolean", default=True,
        doc="also start from the guess's discrete alternatives (SAM/LAM mirror, psi0 + "
            "pi); false: from the guess only, when it is known to be close"),
    Key("output", "string", doc="the best state as a scenario file; default "
                                "<scenario>_fit.toml"),
    Key("posterior", "table", table=Table("posterior", (
        Key("walkers", "integer", positive=True, default=32),
        Key("steps", "integer", positive=True, default=1000),
        Key("seed", "integer", nonnegative=True),
        Key("netcdf", "string", doc="samples; default <scenario>_posterior.nc"),
    )), doc="MCMC (emcee) after the fit"),
), doc="What was measured; the [body] and [state] are the first guess (attitude fit).")


@dataclass(frozen=True)
class ObservationsConfig:
    """The parsed ``[observations]`` table.

    Examples
    --------
    >>> from attitude.app.scenario import load_scenario
    >>> cfg = load_scenario("scenarios/tumbler_fit.toml").observations
    >>> [type(o).__name__ for o in cfg.observations], cfg.output.name
    (['AttitudeObservations'], 'tumbler_fit_fit.toml')
    >>> round(float(np.degrees(cfg.observations[0].sigma)), 6)     # sigma = "0.05 deg"
    0.05
    """

    observations: tuple
    free: tuple | None
    output: Path
    posterior: dict | None
    posterior_netcdf: Path | None
    multistart: bool = True


def _csv(folder: Path, spec: dict, where: str, columns: tuple, path):
    """``(times, values)`` of a samples file (attitude quaternions, body rates): a header
    row naming ``t`` (s since the [state] epoch) or ``time`` (ISO, UTC) and ``columns``,
    then one row of numbers per sample; ``#`` lines are comments.  Every problem is a
    :class:`ScenarioError` keyed ``{where}.file`` naming the file and its line."""
    file = folder / spec["file"]
    need = f"{', '.join(columns)} and t (s since the [state] epoch) or time (ISO, UTC)"

    def fail(message, lineno=None):
        line = f"line {lineno}: " if lineno else ""
        return ScenarioError(f"{file.name}: {line}{message}", key=f"{where}.file",
                             path=path)

    try:
        text = file.read_bytes().decode("utf-8", errors="replace")
    except OSError as exc:
        raise fail(f"cannot read the file ({exc.strerror or exc})") from None
    rows = [(k, [f.strip() for f in line.split(",")])
            for k, line in enumerate(text.splitlines(), start=1)
            if line.strip() and not line.lstrip().startswith("#")]
    if not rows:
        raise fail(f"empty file: give a header row naming the columns {need}, then one row "
                   "per sample")
    (header_line, names), rows = rows[0], rows[1:]
    missing = [c for c in columns if c not in names]
    if missing or not ({"t", "time"} & set(names)):
        raise fail(f"needs the columns {need}; line {header_line} names "
                   f"{', '.join(names)[:200]}")
    if not rows:
        raise fail("no samples after the header row")
    clock = "t" if "t" in names else "time"
    i_time, i_values = names.index(clock), [names.index(c) for c in columns]
    times, values = [], []
    for lineno, fields in rows:
        if len(fields) != len(names):
            raise fail(f"expected {len(names)} fields ({', '.join(names)}), got "
                       f"{len(fields)}", lineno)
        try:
            row = [float(fields[i]) for i in i_values]
            times.append(fields[i_time] if clock == "time" else float(fields[i_time]))
        except ValueError:
            raise fail(f"not a number in {','.join(fields)[:80]!r}", lineno) from None
        if not np.all(np.isfinite(row + ([] if clock == "time" else times[-1:]))):
            raise fail(f"a value is not finite in {','.join(fields)[:80]!r}", lineno)
        if "qw" in columns and not any(row):
            raise fail("the quaternion is zero: give unit quaternions qx, qy, qz, qw "
                       "(scalar last)", lineno)
        values.append(row)
    if clock == "t":
        return np.array(times), np.array(values)
    try:
        return Time(times, format="isot", scale="utc"), np.array(values)
    except ValueError:
        bad = next((k for (k, _), t in zip(rows, times) if not _is_isot(t)), None)
        raise fail("the time column must hold ISO 8601 dates such as "
                   "2026-11-25T00:00:00", bad) from None


def _is_isot(text: str) -> bool:
    try:
        Time(text, format="isot", scale="utc")
    except ValueError:
        return False
    return True


def _lightcurve(spec: dict, where: str, folder: Path, path: str, body, frame: str):
    """One ``[[observations.lightcurve]]`` table -> LightcurveObservations."""
    file = folder / spec["file"]
    try:
        lc = read_lightcurve(file, format=spec.get("format"))
    except AttitudeError as exc:            # LightcurveFormatError: the file and the line
        line = f"{exc.key}: " if exc.key else ""
        raise ScenarioError(f"{file.name}: {line}{exc.reason}", key=f"{where}.file",
                            path=path) from None
    alcdef = lc.dataset.attrs.get("format") == "ALCDEF"
    # shape, law and geometry: the [photometry] reader, its errors re-keyed
    sub = {k: spec[k] for k in _PHOTOMETRY_KEYS if k in spec}
    sub.setdefault("shape", "ellipsoid")
    sub.setdefault("subdivisions", 2)
    sub.setdefault("law", "ls-lambert")
    if "sun" in sub:
        sub["sun"] = [float(x) for x in sub["sun"]]
    if sub["shape"] == "ellipsoid" and "axes" not in sub and body is None:
        raise ScenarioError("shape = \"ellipsoid\" takes the body's moments: give [body] "
                            "or axes", key=f"{where}.shape", path=path)
    try:
        cfg = parse_photometry(sub, None, Path(path), body)
    except ScenarioError as exc:
        key = (exc.key or "").replace("photometry", where, 1)
        raise ScenarioError(exc.reason, key=key, path=path) from None
    times = lc.epoch + TimeDelta(lc.time, format="sec")
    g = cfg.geometry
    if "orbit" in g:
        try:
            geom = Geometry.from_orbit(g["orbit"], times, g["observer"], frame=frame,
                                       light_time=g["light_time"])
        except AttitudeError as exc:
            raise ScenarioError(exc.reason, key=f"{where}.orbit", path=path) from None
        if alcdef:                          # the reader moved the times to the asteroid
            geom = Geometry(sun=geom.sun, observer=geom.observer,
                            sun_distance=geom.sun_distance,
                            observer_distance=geom.observer_distance, frame=frame)
    else:
        geom = Geometry(sun=g["sun"], observer=g["observer"], frame=frame)
    err = np.asarray(lc.dataset["magnitude_error"].values, dtype=float)
    missing = ~(np.isfinite(err) & (err > 0))
    if np.any(missing):
        if "sigma" not in spec:
            raise ScenarioError(f"{file.name} gives no magnitude uncertainty for "
                                f"{int(missing.sum())} of {err.size} points: give sigma "
                                f"(e.g. \"0.02 mag\")", key=f"{where}.sigma", path=path)
        err = np.where(missing, spec["sigma"], err)
    sessions = np.asarray(lc.dataset["session"].values) if spec.get("sessions", True) \
        else None
    return LightcurveObservations(times, lc.magnitude, err, geom, cfg.shape, cfg.law,
                                  sessions=sessions)


def parse_observations(table: dict, folder: Path, scenario_path: Path, *, body=None,
                       frame: str = "ICRF") -> ObservationsConfig:
    """Observation objects from a validated ``[observations]`` table.

    ``body`` (the first guess) makes the shape ``"ellipsoid"`` of a lightcurve; ``frame``
    is the inertial frame of the ``[state]`` (the Sun and observer directions are in it).

    Raises
    ------
    ScenarioError
        Naming the key: unreadable or malformed files, no observations, unknown
        parameter names in ``free``.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> folder = pathlib.Path(tempfile.mkdtemp())
    >>> _ = (folder / "q.csv").write_text("t,qx,qy,qz,qw" + chr(10) + "0,0,0,0,1" + chr(10)
    ...                                   + "1,0,0,0.0998,0.9950" + chr(10))
    >>> table = {"attitude": {"file": "q.csv", "sigma": 1e-3},
    ...          "periods": {"polhode": {"value": 27.38, "sigma": 0.07, "unit": "h"}}}
    >>> cfg = parse_observations(table, folder, folder / "fit.toml")
    >>> [type(o).__name__ for o in cfg.observations]
    ['AttitudeObservations', 'PeriodObservations']
    >>> cfg.observations[0].times.tolist(), cfg.output.name
    ([0.0, 1.0], 'fit_fit.toml')
    """
    path = str(scenario_path)
    obs = []
    try:
        if "attitude" in table:
            t, q = _csv(folder, table["attitude"], "observations.attitude",
                        ("qx", "qy", "qz", "qw"), path)
            obs.append(AttitudeObservations(t, q, table["attitude"]["sigma"]))
        if "rates" in table:
            t, w = _csv(folder, table["rates"], "observations.rates", ("wx", "wy", "wz"),
                        path)
            obs.append(AngularVelocityObservations(t, w, table["rates"]["sigma"]))
        if table.get("periods"):
            pairs = {k: (v["value"] * u.Unit(v.get("unit", "s")),
                         v["sigma"] * u.Unit(v.get("unit", "s")))
                     for k, v in table["periods"].items()}
            obs.append(PeriodObservations(**pairs))
        for k, spec in enumerate(table.get("lightcurve") or ()):
            obs.append(_lightcurve(spec, f"observations.lightcurve[{k}]", folder, path,
                                   body, frame))
    except ScenarioError:
        raise
    except AttitudeError as exc:  # the observation objects' keyed errors, under the table
        raise ScenarioError(exc.reason, key=f"observations.{exc.key}" if exc.key
                            else "observations", path=path) from None
    if not obs:
        raise ScenarioError("give attitude, rates, periods or [[observations.lightcurve]]",
                            key="observations", path=path)
    free = table.get("free")
    if free is not None:
        if not (isinstance(free, list) and free and all(isinstance(f, str) for f in free)):
            raise ScenarioError("expected a non-empty list of parameter names",
                                key="observations.free", path=path)
        bad = [f for f in free if f not in PARAMETERS]
        if bad:
            raise ScenarioError(f"unknown parameter(s) {bad}; use {', '.join(PARAMETERS)}",
                                key="observations.free", path=path)
        free = tuple(free)
    stem = scenario_path.with_suffix("")
    output = folder / table["output"] if "output" in table else \
        Path(f"{stem}_fit.toml")
    post = table.get("posterior")
    netcdf = None
    if post is not None:
        netcdf = folder / post["netcdf"] if "netcdf" in post else \
            Path(f"{stem}_posterior.nc")
    return ObservationsConfig(tuple(obs), free, output, post, netcdf,
                              bool(table.get("multistart", True)))


def _vector(v) -> str:
    return "[" + ", ".join(f"{float(x):.17g}" for x in v) + "]"


#: The unit (or the ratio) of each parameter in the fitted scenario's comments; the
#: angles in degrees, as ``attitude fit`` prints them.
_COMMENT_UNITS = {"angular_momentum_ra": "deg", "angular_momentum_dec": "deg",
                  "phi0": "deg", "psi0": "deg", "precession_period": "s",
                  "energy_ratio": "(E/E0)", "ratio_a": "(A/C)", "ratio_b": "(B/C)"}


def _labelled(name: str, value: float, sigma: float) -> str:
    """``30.23289012 +- 0.00803 deg``: a parameter and its 1-sigma with the unit."""
    unit = _COMMENT_UNITS.get(name, "")
    scale = np.degrees(1.0) if unit == "deg" else 1.0
    return f"{value * scale:.10g} +- {sigma * scale:.3g} {unit}".rstrip()


def fitted_scenario(result: FitResult, *, name: str, duration: float, step: float,
                    source: str) -> str:
    """The fitted body and state as the text of a scenario file one can propagate.

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> body = att.RigidBody.from_principal_moments([0.6, 0.9, 1.0])
    >>> truth = att.AttitudeState("2029-04-13", Rotation.identity(), [0.05, 0.1, 1.0])
    >>> t = np.linspace(0.0, 10.0, 20)
    >>> q = att.propagate(body, truth, t).dataset["quaternion"].values
    >>> res = att.fit(att.AttitudeObservations(t, q, "0.01 deg"), body, truth,
    ...               free=["energy_ratio"], multistart=False)
    >>> text = fitted_scenario(res, name="demo", duration=60.0, step=1.0, source="demo.toml")
    >>> import tomllib; sorted(tomllib.loads(text))
    ['body', 'propagation', 'scenario', 'state']
    """
    state, body = result.state, result.body
    rows = ",\n  ".join(_vector(r) for r in body.inertia)
    lines = [
        f"# Fitted by `attitude fit {source}`: regime {result.regime}, chi2 = "
        f"{result.chi2:.6g} for {result.dof} degrees of freedom.",
        "# Parameters (1-sigma):",
        *(f"#   {k} = {_labelled(k, result.parameters[k], result.uncertainties[k])}"
          for k in PARAMETERS),
        *(f"#   lightcurve {n} session {label}: offset = {b:.6f} +- {sb:.2g} mag"
          for n, lc in enumerate(result.lightcurve_offsets())
          for label, b, sb in zip(lc["session"], lc["offset"], lc["sigma"])),
        "",
        "[scenario]",
        f'name = "{name} (fitted)"',
        "",
        "[body]",
        f"inertia = [\n  {rows},\n]   # kg m2, body frame",
        "",
        "[state]",
        f'epoch = "{format_epoch(state.epoch)}"',
        f'time_scale = "{state.epoch.scale}"',
        f'frame = "{state.frame}"',
        f"attitude = {{ quaternion_scalar_last = {_vector(state.attitude.as_quat())} }}",
        f'omega_body = {{ value = {_vector(state.omega_body)}, unit = "rad/s" }}',
        "",
        "[propagation]",
        f'duration = "{duration:.17g} s"',
        f'step = "{step:.17g} s"',
        "",
    ]
    return "\n".join(lines)

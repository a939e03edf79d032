"""Scenario files (TOML): a body, an initial state, a propagation, outputs and
expectations, validated before any work is done.

Every problem is reported as a :class:`~attitude.foundations.errors.ScenarioError` whose message is
one line naming the file and the key (``scenarios/x.toml: state.omega_body: ...``).
See the scenario section of the docs for the full format.
"""

from __future__ import annotations

import argparse
import difflib
import json
import sys
import tomllib
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr
from astropy.time import Time
from scipy.spatial.transform import Rotation

from ..analysis import statistics
from ..analysis.classification import classify
from ..analysis.diagnostics import add_diagnostics
from ..analysis.spindown import spin_trend
from ..binary.config import is_binary
from ..fitting.config import parse_observations
from ..foundations.errors import (
    AttitudeError,
    DiagnosticsError,
    InvalidBodiesWarning,
    ScenarioError,
)
from ..foundations.expectation import Expectation
from ..foundations.quantities import read_unit
from ..foundations.spec import Key, Table, json_schema, markdown, validate
from ..inversion.config import is_inversion
from ..model.body import MassProperties, RigidBody
from ..model.ephemeris import Ephemeris, relative_drifts
from ..model.freebody import diagnose
from ..model.population import Ensemble
from ..model.regimes import PERIOD_KEYS
from ..model.sampling import DEFAULTS as _ENSEMBLE_DEFAULTS
from ..model.sampling import DIRECTION_SIGMA as _ENSEMBLE_DIRECTION
from ..model.sampling import MODELS
from ..model.state import AttitudeState, check_frame, rotation_from_table, spin_axis_quaternion
from ..model.tables import COLUMNS
from ..model.torques import BuildContext, from_config
from ..photometry.config import EXPECT_KEYS as LIGHTCURVE_EXPECT_KEYS
from ..photometry.config import parse_photometry
from ..propagation.batch import STATUS_FAILED, STATUS_OK
from ..propagation.events import nutation_crossing
from ..propagation.propagator import propagate
from ..spinorbit import section as spinorbit_section  # [section], spin-orbit [expect]
from .expectations import check_expectations, known_variables, needs_dataset
from .scenario_spec import (
    CONSERVATION_KEYS,
    EXPECT_KEYS,
    REDUCTIONS,
    SCENARIO,
    SPIN_EXPECT_KEYS,
    SPIN_EXPECT_UNITS,
)

__all__ = ["Scenario", "RunResult", "load_scenario", "run_scenario", "check_expectations",
           "spin_axis_state", "known_variables", "SCHEMA", "EXPECT_KEYS", "SCENARIO",
           "scenario_schema", "scenario_reference"]

_BODY_KINDS = ("principal_moments", "inertia", "shape", "parts")
_PART_PLACEMENT = ("primitive", "offset", "orientation")

#: Allowed keys of each table (derived from :data:`attitude.app.scenario_spec.SCENARIO`, the one
#: declaration of the format).
SCHEMA: dict[str, Any] = {
    k.name: (k.table.names() if k.kind == "table" and k.name != "expect" else
             list if k.kind == "tables" else dict)
    for k in SCENARIO.keys}


@dataclass(frozen=True, eq=False)
class Scenario:
    """A parsed, validated scenario file.

    Examples
    --------
    >>> sc = load_scenario("scenarios/apophis.toml")
    >>> sc.name, sc.duration, sc.step
    ('Apophis tumbling state', 2592000.0, 600.0)
    """

    path: Path
    name: str
    description: str
    body: RigidBody
    state: AttitudeState
    duration: float
    step: float
    method: str | None = None
    rtol: float | None = None
    integrator_step: float | None = None
    order: int | None = None
    torques: tuple = ()
    netcdf: Path | None = None
    expect: tuple = ()
    """The ``[expect]`` entries (:class:`attitude.foundations.expectation.Expectation`;
    the lightcurve keys are in :attr:`photometry`)."""
    ensemble: Any = None
    """An :class:`attitude.Ensemble` when the file has an ``[ensemble]`` table (``body``
    and ``state`` are then its nominal member: body 0, or the first valid one)."""
    chunk: int | None = None
    events: tuple = ()
    """The ``[[events]]`` as :class:`attitude.Event` objects (passed to ``propagate``)."""
    section: Any = None
    """The ``[section]`` table (:class:`attitude.spinorbit.section.SectionConfig`)."""
    observations: Any = None
    """The parsed ``[observations]`` table (:class:`attitude.fitting.config.ObservationsConfig`),
    used by ``attitude fit``."""
    photometry: Any = None
    """The parsed ``[photometry]`` table (:class:`attitude.photometry.config.PhotometryConfig`),
    used by ``attitude lightcurve``."""
    shape_model: tuple | None = None
    """``(absolute path of the body's OBJ file, its length unit)`` when ``[body]`` names a
    shape: written into the ephemeris (attributes ``shape_model``, ``shape_length_unit``)
    so that ``attitude animate`` and ``attitude view`` draw the shape."""

    @property
    def times(self) -> np.ndarray:
        """Output times, s since the epoch: ``0, step, 2 step, ...`` up to ``duration``."""
        n = int(np.floor(self.duration / self.step * (1 + 1e-12))) + 1
        t = np.arange(n) * self.step
        if t[-1] < self.duration * (1 - 1e-12):
            t = np.append(t, self.duration)
        return t


class _Reader:
    """Raises ScenarioError naming the file and the key."""

    def __init__(self, path: Path):
        self.path = path

    def fail(self, key: str | None, message: str) -> ScenarioError:
        return ScenarioError(message, path=str(self.path), key=key)

    def wrap(self, key: str, exc: AttitudeError) -> ScenarioError:
        """An error of a model constructor, re-raised under the scenario key (its own key,
        if any, appended)."""
        if isinstance(exc, ScenarioError):
            return exc
        inner = getattr(exc, "key", None)
        return self.fail(f"{key}.{inner}" if inner else key,
                         getattr(exc, "reason", str(exc)))


def read_scenario_toml(path: str | Path) -> dict:
    """The TOML document of a scenario file, not yet validated (``run`` and ``check`` read
    files through it); a ScenarioError naming the file unless it is readable UTF-8 TOML."""
    path = Path(path)
    try:
        if path.exists() and not path.is_file():     # a folder, a pipe: never opened
            kind = "a folder" if path.is_dir() else "a pipe or a device"
            raise ScenarioError(f"is {kind}, not a scenario file", path=str(path))
        with open(path, "rb") as fh:
            return tomllib.load(fh)
    except FileNotFoundError:
        raise ScenarioError("no such file", path=str(path)) from None
    except OSError as exc:
        raise ScenarioError(f"cannot read the file ({exc.strerror or exc})",
                            path=str(path)) from None
    except UnicodeDecodeError as exc:
        raise ScenarioError(f"not UTF-8 text (byte {exc.object[exc.start]:#04x} at offset "
                            f"{exc.start}); save the scenario as UTF-8", path=str(path)) from None
    except tomllib.TOMLDecodeError as exc:
        raise ScenarioError(f"not valid TOML ({exc})", path=str(path)) from None


def load_scenario(path: str | Path) -> Scenario:
    """Read and validate a scenario file.

    The file is checked against :data:`attitude.app.scenario_spec.SCENARIO` (keys, types,
    lengths, units, signs, dates), then the physics (mass properties, states, torques) is
    built; nothing is propagated.

    Parameters
    ----------
    path : str or path-like

    Returns
    -------
    Scenario

    Raises
    ------
    ScenarioError
        For any problem: unreadable file, TOML syntax, unknown or missing keys, wrong
        types or lengths, unparseable units or dates, non-physical bodies or states;
        ``str(err)`` is one line ``FILE: KEY: message``.

    Examples
    --------
    >>> sc = load_scenario("scenarios/apophis.toml")
    >>> sc.body.name, sc.state.frame, len(sc.times)
    ('Apophis', 'ECLIPJ2000', 4321)
    """
    path = Path(path)
    r = _Reader(path)
    raw = read_scenario_toml(path)
    if is_inversion(raw):
        raise ScenarioError("an inversion scenario ([inversion]: lightcurves in, shape and "
                            f"pole out): run it with `attitude invert {path}`", path=path)
    if is_binary(raw):
        raise ScenarioError("a binary scenario ([binary]: two bodies and their mutual "
                            f"orbit): run it with `attitude run {path}` (in Python: "
                            "attitude.binary.config.load_binary)", path=path)
    doc = validate(raw, SCENARIO, path=str(path), error=ScenarioError)
    meta = doc.get("scenario", {})
    name = meta.get("name", path.stem)
    description = meta.get("description", "")
    ensemble, chunk = None, None
    if "ensemble" in doc:
        ensemble, chunk = _ensemble(r, doc, path.parent)
        body, state = _nominal(r, ensemble)
    else:
        body = _body(r, doc["body"], path.parent)
        state = _state(r, doc["state"], body)

    prop = doc["propagation"]
    duration, step = prop["duration"], prop["step"]
    if step > duration:
        raise r.fail("propagation.step", f"the step ({step:.6g} s) is longer than "
                                         f"propagation.duration ({duration:.6g} s): the run "
                                         "would hold the first epoch alone; use a step no "
                                         "longer than the duration")
    if duration / step > 5e7:
        raise r.fail("propagation.step", f"{duration / step:.3g} epochs is too many for one "
                                         "run; use a longer step")
    method, rtol = prop.get("method"), prop.get("rtol")
    if rtol is not None and not rtol < 1:
        raise r.fail("propagation.rtol", f"expected a tolerance between 0 and 1, got {rtol!r}")
    integrator_step, order = prop.get("integrator_step"), prop.get("order")
    if (integrator_step is not None or order is not None) and (
            method not in (None, "splitting") or (rtol is not None and method is None)):
        raise r.fail("propagation.integrator_step" if integrator_step is not None
                     else "propagation.order",
                     "only used by the splitting integrator (method = \"splitting\"; with "
                     "rtol give method = \"splitting\" too)")

    body_table = doc.get("body", {})
    torques = _torques(r, doc.get("torques", []), BuildContext(
        epoch=state.epoch, frame=state.frame, folder=path.parent, body=body,
        shape=body_table.get("shape"), length_unit=body_table.get("length_unit", "m")))
    if torques and method == "exact":
        raise r.fail("propagation.method", "'exact' is the torque-free solution; remove it "
                                           "(or use 'integrator') with [[torques]]")
    events = _events(r, doc.get("events", []))
    if events and ensemble is not None:
        raise r.fail("events", "not with [ensemble]: events are located on single runs")

    netcdf = doc.get("output", {}).get("netcdf")
    expect = _parse_expect(r, doc.get("expect", {}))
    if ensemble is None and any(e.key.startswith("regime_fractions") for e in expect):
        raise r.fail("expect.regime_fractions", "only for scenarios with an [ensemble] table")
    section = spinorbit_section.load_tables(   # spin-orbit wing: [section], its [expect]
        doc, body=body, torques=torques, expect=expect, ensemble=ensemble,
        folder=path.parent, fail=r.fail)
    observations = None                        # fitting wing: [observations]
    if "observations" in doc:
        observations = parse_observations(doc["observations"], path.parent, path,
                                          body=body, frame=state.frame)
    photometry = None                          # photometry wing: [photometry], its [expect]
    if "photometry" in doc:
        photometry = parse_photometry(doc["photometry"], doc.get("expect"), path, body)
    elif any(k in LIGHTCURVE_EXPECT_KEYS for k in doc.get("expect", {})):
        raise r.fail("expect", "lightcurve expectations need a [photometry] table")
    return Scenario(path=path, name=name, description=description, body=body, state=state,
                    duration=duration, step=step, method=method, rtol=rtol,
                    integrator_step=integrator_step, order=order, torques=tuple(torques),
                    netcdf=(path.parent / netcdf) if netcdf else None, expect=expect,
                    ensemble=ensemble, chunk=chunk, events=events, section=section,
                    photometry=photometry, observations=observations,
                    shape_model=((str((path.parent / body_table["shape"]).resolve()),
                                  str(body_table.get("length_unit", "m")))
                                 if ensemble is None and "shape" in body_table else None))


def _ensemble(r: _Reader, doc: dict, folder: Path):
    """The ``[ensemble]`` table: a sampled population (``model``, ``size``, ``seed``,
    ``[ensemble.mean]``, ``[ensemble.sigma]``) or a table of bodies (``table``); the
    epoch and frame come from ``[state]``, which then holds nothing else."""
    table, state = doc["ensemble"], doc["state"]
    for key in state:
        if key not in ("epoch", "time_scale", "frame"):
            raise r.fail(f"state.{key}", "not with [ensemble]: [state] gives only epoch, "
                                         "time_scale and frame; the ensemble the states")
    epoch, frame = _epoch_frame(r, state)
    chunk = table.get("chunk")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", InvalidBodiesWarning)  # reported by the run
        if "table" in table:
            try:
                return Ensemble.from_table(folder / table["table"], epoch=epoch,
                                           frame=frame), chunk
            except AttitudeError as exc:
                raise r.wrap("ensemble.table", exc) from None
        model = table.get("model", "tumbling")
        spec = MODELS[model]
        direction = _ENSEMBLE_DIRECTION[model]
        mean, sigma = table["mean"], table.get("sigma", {})
        for part, values, allowed in (("mean", mean, spec),
                                      ("sigma", sigma, {**spec, direction: "rad"})):
            for k in values:
                if k not in allowed:
                    raise r.fail(f"ensemble.{part}.{k}", f"not a parameter of the {model!r} "
                                                         f"model ({', '.join(allowed)})")
        for k in spec:
            if k not in mean and k not in _ENSEMBLE_DEFAULTS:
                raise r.fail(f"ensemble.mean.{k}", f"missing key (a parameter of the "
                                                   f"{model!r} model)")
        for k in sigma:
            if k not in mean and k != direction:
                raise r.fail(f"ensemble.sigma.{k}", "no ensemble.mean value for it")
        try:
            ens = Ensemble.sample(table["size"], rng=table["seed"], model=model,
                                  mean=mean, sigma=sigma or None, epoch=epoch, frame=frame,
                                  include_nominal=table.get("include_nominal", True))
        except AttitudeError as exc:
            raise r.wrap("ensemble.mean", exc) from None
    return ens, chunk


def _nominal(r: _Reader, ensemble) -> tuple[RigidBody, AttitudeState]:
    valid = np.nonzero(ensemble.valid)[0]
    if valid.size == 0:
        first = next(iter(ensemble.invalid.items()), (0, "no bodies"))
        raise r.fail("ensemble", f"no valid body (body {first[0]}: {first[1]})")
    i = int(valid[0])
    return ensemble.body_at(i), ensemble.state_at(i)


def _torques(r: _Reader, tables, context: BuildContext) -> tuple:
    """Each ``[[torques]]`` table becomes a torque model (see docs/torques.md), built in
    the scenario's context (epoch, frame, folder, body)."""
    models = []
    for i, table in enumerate(tables):
        try:
            models.append(from_config(table, context=context))
        except AttitudeError as exc:
            raise r.wrap(f"torques[{i}]", exc) from None
    return tuple(models)


def _events(r: _Reader, tables) -> tuple:
    """Each ``[[events]]`` table becomes an :class:`attitude.Event`."""
    events = []
    for i, table in enumerate(tables):
        try:
            events.append(nutation_crossing(table["angle"], table.get("axis", "C"),
                                            terminal=table.get("terminal", False),
                                            direction=table.get("direction", 0)))
        except AttitudeError as exc:
            raise r.wrap(f"events[{i}]", exc) from None
    return tuple(events)


def _body(r: _Reader, table: dict, folder: Path) -> RigidBody:
    kind = next(k for k in _BODY_KINDS if k in table)
    name = table.get("name", "")
    mass = table.get("mass")
    try:
        if kind == "principal_moments":
            return RigidBody.from_principal_moments(table[kind], mass=mass, name=name)
        if kind == "inertia":
            return RigidBody(table[kind], mass=mass, name=name)
        if kind == "shape":
            return RigidBody.from_obj(folder / table["shape"], density=table["density"],
                                      length_unit=table.get("length_unit", "m"), name=name)
        return RigidBody.from_parts(_parts(r, table["parts"]), name=name)
    except AttitudeError as exc:
        raise r.wrap(f"body.{kind}", exc) from None


def _parts(r: _Reader, parts) -> list[MassProperties]:
    if not parts:
        raise r.fail("body.parts", "expected a non-empty array of tables")
    out = []
    for i, part in enumerate(parts):
        key = f"body.parts[{i}]"
        params = {k: v for k, v in part.items() if k not in _PART_PLACEMENT}
        try:
            props = MassProperties.from_primitive(part["primitive"], **params)
        except AttitudeError as exc:
            raise r.wrap(key, exc) from None
        orientation = None
        if "orientation" in part:
            orientation = _rotation(r, part["orientation"], f"{key}.orientation")
        out.append(props.placed(part.get("offset", np.zeros(3)), orientation))
    return out


def _rotation(r: _Reader, table: dict, key: str) -> Rotation:
    """A validated :data:`~attitude.app.scenario_spec.ROTATION` table -> scipy Rotation."""
    return rotation_from_table(table, key, r.fail)


_SPIN_KEYS = ("spin_axis", "spin_rate", "spin_period", "spin_about")


def spin_axis_state(body: RigidBody, ra: float, dec: float, rate: float,
                    about: str = "C") -> tuple[Rotation, np.ndarray]:
    """Attitude (body -> inertial) and body-frame rates of a principal-axis spin at
    ``rate`` (rad/s) about the principal axis ``about`` pointing to right ascension
    ``ra``, declination ``dec`` (rad): :meth:`attitude.AttitudeState.from_spin_axis`
    without the epoch.

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> body = att.RigidBody.from_principal_moments([1.0, 2.0, 3.0])
    >>> rot, w = spin_axis_state(body, 0.0, np.pi / 2, 1e-3)
    >>> np.round(rot.apply([0.0, 0.0, 1.0]), 12) + 0.0, w
    (array([0., 0., 1.]), array([0.   , 0.   , 0.001]))
    """
    q = spin_axis_quaternion(ra, dec, about=about)
    axis_body = body.principal_axes[:, "ABC".index(about)]
    return Rotation.from_quat(q) * body.body_to_principal, rate * axis_body




def _spin_state(r: _Reader, table: dict, body: RigidBody) -> tuple[Rotation, np.ndarray]:
    ra, dec = table["spin_axis"]["ra"], table["spin_axis"]["dec"]
    if not abs(dec) <= np.pi / 2 * (1 + 1e-12):
        raise r.fail("state.spin_axis.dec", f"must be within +-90 deg, got "
                                            f"{np.degrees(dec):.6g} deg")
    if "spin_rate" in table:
        rate = table["spin_rate"]
    elif "spin_period" in table:
        rate = 2 * np.pi / table["spin_period"]
    else:
        raise r.fail("state.spin_rate", "missing key: give exactly one of spin_rate, "
                                        "spin_period with spin_axis")
    return spin_axis_state(body, ra, dec, rate, table.get("spin_about", "C"))


def _epoch_frame(r: _Reader, table: dict) -> tuple[Time, str]:
    """``state.epoch`` (read in ``state.time_scale``, default TDB) and ``state.frame``."""
    try:
        frame = check_frame(table.get("frame", "ICRF"))
    except AttitudeError as exc:
        raise r.wrap("state.frame", exc) from None
    return table["epoch"], frame


def _state(r: _Reader, table: dict, body: RigidBody) -> AttitudeState:
    spin = "spin_axis" in table
    if not spin and "omega_body" not in table:
        raise r.fail("state.omega_body", "missing key (or give spin_axis with "
                                         "spin_rate/spin_period)")
    epoch, frame = _epoch_frame(r, table)
    if spin:
        attitude, omega = _spin_state(r, table, body)
    else:
        attitude = (_rotation(r, table["attitude"], "state.attitude") if "attitude" in table
                    else Rotation.identity())
        omega = table["omega_body"]
    try:
        return AttitudeState(epoch=epoch, attitude=attitude, omega_body=omega, frame=frame)
    except AttitudeError as exc:  # physical validation by AttitudeState
        raise r.wrap("state", exc) from None


# --- running ------------------------------------------------------------------------



@dataclass(frozen=True, eq=False)
class RunResult:
    """What a scenario run produced: the ephemeris, the analytic diagnosis of the initial
    state, the classification of the ephemeris (runs with torques), the conservation
    figures, the expectation outcomes and the files written.

    Examples
    --------
    >>> result = run_scenario(load_scenario("scenarios/dzhanibekov.toml"),
    ...                       write_outputs=False)
    >>> result.regime, result.ok, result.outputs
    ('SAM', True, [])
    >>> round(result.periods["polhode"], 4)         # the T-handle flips back every 3.31 s
    3.3108
    >>> sorted(result.report())
    ['conservation', 'expect', 'outputs', 'periods', 'regime', 'scenario', 'spin']
    >>> round(result.spin.period_start, 4)         # 2 pi |L| / 2E, s
    0.5
    """

    scenario: Scenario
    ephemeris: Any
    diagnosis: Any
    classification: Any
    conservation: dict
    expectations: list
    outputs: list
    note: str = ""
    dataset: Any = None
    """The dataset the ``[expect]`` variables were read from (the ephemeris dataset, with
    the :func:`~attitude.analysis.diagnostics.add_diagnostics` variables when needed), or None."""
    ensemble: dict | None = None
    """Summary of an ensemble run (:func:`ensemble_summary`), or None."""
    spin: Any = None
    """The spin period at the ends of the run and its trend
    (:class:`attitude.analysis.spindown.SpinTrend`), or None (an ensemble, a body at rest)."""

    @property
    def ok(self) -> bool:
        return all(e["ok"] for e in self.expectations)

    @property
    def regime(self) -> str | None:
        """The analytic regime of a torque-free run; the classified regime (including
        ``chaotic``) of a run with torques; the most common regime of an ensemble."""
        if self.ensemble is not None:
            fractions = self.ensemble["regime_fractions"]
            return next(iter(fractions)) if fractions else None
        if not self.scenario.torques:
            return self.diagnosis.regime
        return self.classification.regime if self.classification is not None else None

    @property
    def periods(self) -> dict:
        """Analytic periods of a torque-free run; measured periods of a run with torques;
        the median periods over the bodies of an ensemble."""
        if self.ensemble is not None:
            return {k: q["0.5"] for k, q in self.ensemble["period_quantiles"].items()}
        if not self.scenario.torques:
            return dict(self.diagnosis.periods)
        return dict(self.classification.periods) if self.classification is not None else {}

    def report(self) -> dict:
        """The ``--report`` JSON document (docs/scenarios.md), with an ``ensemble`` entry for an
        ensemble run."""
        doc = {
            "scenario": self.scenario.name,
            "regime": self.regime,
            "periods": self.periods,
            "conservation": self.conservation,
            "expect": self.expectations,
            "outputs": [str(p) for p in self.outputs],
        }
        if self.ensemble is not None:
            doc["ensemble"] = self.ensemble
        if self.spin is not None:
            doc["spin"] = self.spin.as_dict()
        return doc


def run_scenario(scenario: Scenario, *, netcdf: str | Path | None = None,
                 write_outputs: bool = True, progress: bool = False,
                 client=None) -> RunResult:
    """Propagate a scenario, classify it, check its ``[expect]`` table, write outputs.

    A torque-free run is described by the analytic :func:`attitude.diagnose` of its
    initial state.  A run with torques is classified from its ephemeris by
    :func:`attitude.analysis.classification` with the finite-time Lyapunov test (``chaotic``), so
    its
    regime and periods are measured ones.  ``write_outputs=False`` writes no file (what
    ``attitude check`` does).  An ensemble scenario runs on ``client`` (a dask client)
    when one is given, else in this process (:func:`ensemble_summary`).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> sc = load_scenario("scenarios/dzhanibekov.toml")
    >>> out = pathlib.Path(tempfile.mkdtemp()) / "dzhanibekov.nc"
    >>> result = run_scenario(sc, netcdf=out)
    >>> [e["key"] for e in result.expectations if e["ok"]]
    ['regime', 'polhode', 'angular_momentum_rel_drift', 'energy_rel_drift']
    >>> result.outputs == [out], out.is_file()
    (True, True)
    >>> bool(result.conservation["energy_rel_drift"] < 1e-12)
    True
    """
    if scenario.ensemble is not None:
        return _run_ensemble(scenario, netcdf=netcdf, write_outputs=write_outputs,
                             client=client)
    torques = list(scenario.torques)
    eph = propagate(scenario.body, scenario.state, scenario.times, method=scenario.method,
                    rtol=scenario.rtol, torques=torques, step=scenario.integrator_step,
                    order=scenario.order, progress=progress,
                    events=list(scenario.events) or None)
    if scenario.shape_model is not None:          # the pictures draw the shape (issue 29)
        eph = Ephemeris(eph.dataset.assign_attrs(shape_model=scenario.shape_model[0],
                                                 shape_length_unit=scenario.shape_model[1]))
    diagnosis = diagnose(scenario.body, scenario.state)
    classification, note = None, ""
    if torques:
        try:
            # the Lyapunov test re-propagates with the run's own splitting step
            options = ({"step": scenario.integrator_step}
                       if scenario.integrator_step is not None else None)
            classification = classify(eph, chaos=True, torques=torques,
                                      require_periods=False, lyapunov_options=options)
        except (DiagnosticsError, AttitudeError) as exc:
            note = f"not classified: {exc}"
    conservation = eph.conservation()
    need = needs_dataset(scenario)
    dataset = None
    if need == "base":
        dataset = eph.dataset
    elif need is not None:
        try:
            dataset = add_diagnostics(eph, periods=need == "periods").dataset
        except (DiagnosticsError, AttitudeError) as exc:
            note = (note + "; " if note else "") + f"no diagnostics: {exc}"
    try:                                   # the spin period and its trend (issue 17)
        spin = spin_trend(eph)
    except (DiagnosticsError, AttitudeError) as exc:
        spin = None
        note = (note + "; " if note else "") + f"no spin trend: {exc}"
    result = RunResult(scenario, eph, diagnosis, classification, conservation, [], [], note,
                       dataset, spin=spin)
    result.expectations.extend(check_expectations(
        scenario, result.regime, result.periods, conservation, diagnosis=diagnosis,
        dataset=dataset, spin=spin,
        spinorbit=spinorbit_section.expectation_values(scenario, eph)))  # spin-orbit wing
    target = Path(netcdf) if netcdf is not None else scenario.netcdf
    if target is not None and write_outputs:
        result.outputs.append(eph.to_netcdf(target))
    return result


def _run_ensemble(scenario: Scenario, *, netcdf, write_outputs: bool, client) -> RunResult:
    chunks = scenario.chunk if (client is not None or scenario.chunk) else None
    eph = propagate(scenario.ensemble, scenario.times, method=scenario.method,
                    rtol=scenario.rtol, torques=list(scenario.torques),
                    step=scenario.integrator_step, order=scenario.order, client=client,
                    chunks=chunks)
    eph.dataset.attrs["title"] = f"attitude ensemble ephemeris: {scenario.name}"
    outputs = []
    target = Path(netcdf) if netcdf is not None else scenario.netcdf
    if target is not None and write_outputs:
        outputs.append(eph.to_netcdf(target))
        if client is not None or chunks is not None:   # statistics from the file, lazily
            eph = Ephemeris(xr.open_dataset(outputs[-1], engine="netcdf4",
                                            decode_times=False, chunks={}))
    summary = ensemble_summary(scenario, eph)
    diagnosis = diagnose(scenario.body, scenario.state)
    result = RunResult(scenario, eph, diagnosis, None, summary.pop("conservation"), [],
                       outputs, "", None, summary)
    result.expectations.extend(check_expectations(
        scenario, result.regime, result.periods, result.conservation, diagnosis=None,
        dataset=None, fractions=summary["regime_fractions"]))
    return result


def ensemble_summary(scenario: Scenario, eph) -> dict:
    """Regime fractions, period quantiles (analytic for torque-free runs, else regimes
    classified per body), the attitude spread from the nominal at the end (sampled
    ensembles; empty for a catalogue), the worst conservation over the valid bodies,
    and the invalid bodies: plain JSON types."""
    ens = scenario.ensemble
    if scenario.torques:
        fractions = statistics.regime_fractions(eph)
        quantiles = {}
    else:
        diag = statistics.diagnose_ensemble(ens)
        fractions = statistics.regime_fractions(diag)
        pq = statistics.period_quantiles(diag, q=[0.05, 0.5, 0.95])
        quantiles = {str(k): {f"{q:g}": float(v) for q, v in zip(pq["quantile"].values,
                                                                  pq.sel(period=k).values)}
                     for k in pq["period"].values}
    ds = eph.dataset
    ok = ds["status"] == STATUS_OK
    dL, dE = relative_drifts(ds)
    reductions = [dL.where(ok).max(), dE.where(ok).max()]
    if ens.nominal is not None and ens.valid[ens.nominal]:   # a sampled cloud
        spread = statistics.attitude_spread(eph, ens.nominal).isel(time=-1).where(ok)
        reductions.append(spread.quantile([0.5, 0.9, 0.99], skipna=True))
    dL, dE, *spread_q = _compute(*reductions)
    spread_deg = {f"{q:g}": float(np.degrees(v)) for q, v in zip(
        spread_q[0]["quantile"].values, spread_q[0].values)} if spread_q else {}
    status = np.asarray(ds["status"].values)
    return {
        "size": int(status.size),
        "valid": int(np.sum(status == STATUS_OK)),
        "invalid": {str(i): why for i, why in ens.invalid.items()},
        "failed": [int(i) for i in np.nonzero(status == STATUS_FAILED)[0]],
        "regime_fractions": fractions,
        "period_quantiles": quantiles,
        "spread_at_end_deg": spread_deg,
        "conservation": {"angular_momentum_rel_drift": float(np.nan_to_num(dL)),
                         "energy_rel_drift": float(np.nan_to_num(dE))},
    }


def _compute(*objects):
    """Evaluate xarray objects in one pass (one dask graph when they are lazy)."""
    try:
        import dask  # optional ('attitude-dynamics[dask]')
    except ImportError:
        return objects
    return dask.compute(*objects)


def _parse_nutation_range(r: _Reader, spec: dict, where: str) -> list[Expectation]:
    """``{ min = .., max = .., unit = "deg", abs_tol = .. }`` -> two expectations
    ``nutation_range.min`` and ``nutation_range.max`` (in ``unit``, default rad)."""
    unit = spec.get("unit", "rad")
    if not spec["min"] <= spec["max"]:
        raise r.fail(where, f"min ({spec['min']}) is larger than max ({spec['max']})")
    return [Expectation(f"nutation_range.{k}", spec[k], unit, abs_tol=spec["abs_tol"])
            for k in ("min", "max")]


def _parse_variables(r: _Reader, table: dict, where: str) -> list[Expectation]:
    """``[expect.variables]``: ``name = { at = "end", component = 2, value = .., unit = "..",
    rel_tol = .. }`` for any variable of :func:`known_variables`."""
    known = known_variables()
    out = []
    for label, spec in table.items():
        key = f"{where}.{label}"
        name = spec.get("variable", label)
        if name not in known:
            near = difflib.get_close_matches(name, list(known), n=1)
            hint = f"; did you mean '{near[0]}'?" if near else \
                f"; known: {', '.join(known)}"
            raise r.fail(f"{key}.variable" if "variable" in spec else key,
                         f"unknown variable {name!r}{hint}")
        var_units, series = known[name]
        at = spec.get("at")
        if series and at is None:
            raise r.fail(f"{key}.at", f"{name} is a time series: give at = one of "
                                      f"{', '.join(REDUCTIONS)}")
        if not series and at is not None:
            raise r.fail(f"{key}.at", f"{name} is a single number; remove 'at'")
        component = spec.get("component")
        vector = name in ("quaternion", "angular_velocity", "angular_momentum",
                          "momentum_axis_angle")
        if component is not None:
            size = 4 if name == "quaternion" else 3
            if not vector:
                raise r.fail(f"{key}.component", f"{name} is not a vector; remove 'component'")
            if component != "norm" and (isinstance(component, bool) or
                                        not isinstance(component, int) or
                                        not 0 <= component < size):
                raise r.fail(f"{key}.component", f"expected an index 0..{size - 1} or "
                                                 f"\"norm\", got {component!r}")
        elif vector:
            raise r.fail(f"{key}.component", f"{name} is a vector: give component = an index "
                                             "or \"norm\"")
        unit_text = spec.get("unit", var_units)
        try:
            read_unit(unit_text, like=var_units)
        except AttitudeError as exc:
            raise r.fail(f"{key}.unit", exc.reason) from None
        out.append(Expectation.from_table(
            f"variables.{label}", {**spec, "unit": unit_text},
            source=(("variable", name), ("at", at), ("component", component))))
    return out


def _parse_expect(r: _Reader, table: dict) -> tuple[Expectation, ...]:
    """The ``[expect]`` table (already checked against the spec) as a tuple of
    :class:`~attitude.foundations.expectation.Expectation`.

    ``regime = "SAM"``; a period key (``polhode``, ``precession``, ``rotation``, ``spin``)
    as ``{ value = 27.38, unit = "h", rel_tol = 0.01 }`` (or ``abs_tol`` in the same
    unit); a conservation key as ``{ max = 1e-12 }``; ``nutation_range = { min = ..,
    max = .., unit = "deg", abs_tol = .. }``; a ``[expect.variables]`` table of dataset
    variables reduced over the run (:func:`_parse_variables`); ``[expect.regime_fractions]``;
    the spin period and its trend; the spin-orbit wing's keys.  The lightcurve keys are
    read with ``[photometry]`` (:func:`attitude.photometry.config.parse_photometry`).
    """
    parsed = []
    for key, spec in table.items():
        where = f"expect.{key}"
        if key == "regime":
            parsed.append(Expectation.exact(key, spec))
        elif key in PERIOD_KEYS:
            parsed.append(Expectation.from_table(key, spec, default_unit="s"))
        elif key in CONSERVATION_KEYS:
            parsed.append(Expectation.at_most(key, spec["max"]))
        elif key == "nutation_range":
            parsed.extend(_parse_nutation_range(r, spec, where))
        elif key == "variables":
            parsed.extend(_parse_variables(r, spec, where))
        elif key in LIGHTCURVE_EXPECT_KEYS:
            continue           # photometry wing: parsed by attitude.photometry.config
        elif key in spinorbit_section.EXPECT_KEYS:          # spin-orbit wing
            parsed.append(spinorbit_section.parse_expect(key, spec, r.fail))
        elif key in SPIN_EXPECT_KEYS:                      # issue 17: attitude.spindown
            at = (("at", spec.get("at", "end")),) if key == "spin_period" else ()
            parsed.append(Expectation.from_table(key, spec,
                                                 default_unit=SPIN_EXPECT_UNITS[key],
                                                 reported=at))
        elif key == "regime_fractions":
            parsed.extend(Expectation.from_table(f"regime_fractions.{regime}", frac)
                          for regime, frac in spec.items())
    return tuple(parsed)


# --- the format, generated from the spec ------------------------------------------------

_SCHEMA_DESCRIPTION = (
    "Scenario files (TOML) of the attitude toolkit: a body, an initial state, a propagation, "
    "torques, events, outputs and expectations (docs/scenarios.md). TOML maps to JSON one to "
    "one; editors with a TOML language server (e.g. Taplo, Even Better TOML) validate against "
    "this schema with a first-line comment '#:schema ./docs/scenario.schema.json'. Generated "
    "by 'python -m attitude.app.scenario --schema' from attitude.app.scenario_spec, the "
    "declaration "
    "the loader validates with; the loader also checks what a schema cannot (units, "
    "physical mass properties, quaternion norms, dates).")


def scenario_schema() -> dict:
    """The JSON Schema (draft 2020-12) of scenario files, from
    :data:`attitude.app.scenario_spec.SCENARIO` (what ``docs/scenario.schema.json`` holds).

    Examples
    --------
    >>> schema = scenario_schema()
    >>> schema["required"], schema["properties"]["propagation"]["required"]
    (['state', 'propagation'], ['duration', 'step'])
    """
    return json_schema(SCENARIO, title="attitude scenario file",
                       description=_SCHEMA_DESCRIPTION)


def scenario_reference() -> str:
    """The key reference of scenario files as markdown (the generated section of
    docs/scenarios.md), from :data:`attitude.app.scenario_spec.SCENARIO`.

    Examples
    --------
    >>> print(scenario_reference().splitlines()[0])
    ### `[scenario]`
    """
    columns = Table("", (Key("columns", "table", table=COLUMNS),))
    return markdown(SCENARIO) + "\n" + markdown(columns)


def _main(argv=None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m attitude.app.scenario",
        description="Print the scenario format generated from attitude.app.scenario_spec.")
    group = parser.add_mutually_exclusive_group(required=True)
    group.add_argument("--schema", action="store_true", help="the JSON Schema")
    group.add_argument("--reference", action="store_true", help="the markdown key reference")
    args = parser.parse_args(argv)
    text = (json.dumps(scenario_schema(), indent=2) + "\n" if args.schema
            else scenario_reference())
    sys.stdout.write(text)
    return 0


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(_main())

"""Scenario files (TOML): a body, an initial state, a propagation, outputs and
expectations, validated before any work is done.

Every problem is reported as a :class:`~attitude.errors.ScenarioError` whose message is
one line naming the file and the key (``scenarios/x.toml: state.omega_body: ...``).
See the scenario section of the docs for the full format.
"""

from __future__ import annotations

import difflib
import tomllib
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr
from astropy import units as u
from astropy.time import Time
from scipy.spatial.transform import Rotation

from . import statistics
from .body import MassProperties, RigidBody
from .classify import classify
from .diagnostics import DIAGNOSTIC_VARIABLES, SCALAR_DIAGNOSTICS, add_diagnostics
from .ephemeris import Ephemeris, relative_drifts
from .errors import (
    AttitudeError,
    DiagnosticsError,
    InvalidBodiesWarning,
    ScenarioError,
    TorqueConfigError,
)
from .freebody import diagnose
from .photometry.config import EXPECT_KEYS as LIGHTCURVE_EXPECT_KEYS
from .photometry.config import parse_photometry
from .population import Ensemble
from .propagation.batch import STATUS_FAILED, STATUS_OK
from .propagation.propagator import METHODS, propagate
from .quantities import parse_quantity
from .regimes import PERIOD_KEYS, REGIMES
from .sampling import DEFAULTS as _ENSEMBLE_DEFAULTS
from .sampling import DIRECTION_SIGMA as _ENSEMBLE_DIRECTION
from .sampling import MODELS
from .spinorbit import section as spinorbit_section  # [section], spin-orbit [expect]
from .state import AttitudeState, check_frame, spin_axis_quaternion
from .torques import from_config

__all__ = ["Scenario", "RunResult", "load_scenario", "run_scenario", "check_expectations",
           "spin_axis_state", "known_variables", "SCHEMA", "EXPECT_KEYS"]

#: Allowed keys of each table (``None``: free-form sub-table checked by its parser).
SCHEMA: dict[str, dict[str, Any]] = {
    "scenario": {"name": str, "description": str},
    "body": {"principal_moments": None, "inertia": None, "shape": str, "density": None,
             "length_unit": str, "parts": list, "mass": None, "name": str},
    "state": {"epoch": str, "time_scale": str, "frame": str, "attitude": dict,
              "omega_body": None, "spin_axis": dict, "spin_rate": None, "spin_period": None,
              "spin_about": str},
    "propagation": {"duration": None, "step": None, "method": str, "rtol": float,
                    "integrator_step": None, "order": int},
    "torques": list,
    "output": {"netcdf": str},
    "expect": dict,
    "ensemble": {"size": int, "seed": int, "model": str, "mean": dict, "sigma": dict,
                 "table": str, "chunk": int, "include_nominal": bool},
    "section": dict,            # spin-orbit wing: checked by spinorbit.section.parse_section
    # --- photometry (issue 15): parsed by attitude.photometry.config ---
    "photometry": dict,
}
_BODY_KINDS = ("principal_moments", "inertia", "shape", "parts")
_PART_PLACEMENT = ("primitive", "offset", "orientation")


@dataclass(frozen=True, eq=False)
class Scenario:
    """A parsed, validated scenario file."""

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
    ensemble: Any = None
    """An :class:`attitude.Ensemble` when the file has an ``[ensemble]`` table (``body``
    and ``state`` are then its nominal member: body 0, or the first valid one)."""
    chunk: int | None = None
    section: Any = None
    """The ``[section]`` table (:class:`attitude.spinorbit.section.SectionConfig`)."""
    photometry: Any = None
    """The parsed ``[photometry]`` table (:class:`attitude.photometry.config.PhotometryConfig`),
    used by ``attitude lightcurve``."""

    @property
    def times(self) -> np.ndarray:
        """Output times, s since the epoch: ``0, step, 2 step, ...`` up to ``duration``."""
        n = int(np.floor(self.duration / self.step * (1 + 1e-12))) + 1
        t = np.arange(n) * self.step
        if t[-1] < self.duration * (1 - 1e-12):
            t = np.append(t, self.duration)
        return t


class _Reader:
    """Reads values out of the TOML tree, raising ScenarioError naming file and key."""

    def __init__(self, path: Path):
        self.path = path

    def fail(self, key: str, message: str) -> ScenarioError:
        return ScenarioError(message, path=str(self.path), key=key)

    def check_keys(self, table: dict, allowed, where: str) -> None:
        for key in table:
            if key not in allowed:
                near = difflib.get_close_matches(key, list(allowed), n=1)
                hint = f"; did you mean '{near[0]}'?" if near else \
                    f"; allowed keys: {', '.join(allowed)}"
                raise self.fail(f"{where}.{key}" if where else key, f"unknown key{hint}")

    def table(self, doc: dict, key: str, *, required: bool = True) -> dict:
        if key not in doc:
            if required:
                raise self.fail(key, f"missing table [{key}]")
            return {}
        value = doc[key]
        if not isinstance(value, dict):
            raise self.fail(key, f"expected a table [{key}], got {type(value).__name__}")
        return value

    def string(self, table: dict, key: str, where: str, default=None, required=False) -> str:
        if key not in table:
            if required:
                raise self.fail(f"{where}.{key}", "missing key")
            return default
        value = table[key]
        if not isinstance(value, str):
            raise self.fail(f"{where}.{key}", f"expected a string, got {value!r}")
        return value

    def quantity(self, value, unit: str, key: str, *, shape=None):
        """A number (SI), an astropy string, or ``{value = ..., unit = "..."}``."""
        if isinstance(value, dict):
            self.check_keys(value, ("value", "unit"), key)
            if "value" not in value or "unit" not in value:
                raise self.fail(key, "a quantity table needs both 'value' and 'unit'")
            try:
                q = u.Quantity(value["value"], u.Unit(value["unit"]))
            except (ValueError, TypeError) as exc:
                raise self.fail(key, f"cannot read {value!r} as a quantity ({exc})") from None
        elif isinstance(value, str):
            try:
                q = parse_quantity(value)
            except (ValueError, TypeError):
                raise self.fail(key, f"cannot parse {value!r} as a quantity; write a number "
                                     f"and a unit such as '1.5 {unit}'") from None
        elif isinstance(value, bool) or not isinstance(value, (int, float, list)):
            raise self.fail(key, f"expected a number, a string with a unit or a "
                                 f"{{value, unit}} table, got {value!r}")
        else:
            try:
                q = np.asarray(value, dtype=float) * u.Unit(unit)
            except (ValueError, TypeError):
                raise self.fail(key, f"expected numbers, got {value!r}") from None
        try:
            out = q.to_value(unit)
        except u.UnitConversionError:
            raise self.fail(key, f"unit '{q.unit}' cannot be converted to '{unit}'") from None
        out = np.asarray(out, dtype=float)
        if shape is not None and out.shape != shape:
            raise self.fail(key, f"expected shape {shape}, got {out.shape}")
        if not np.all(np.isfinite(out)):
            raise self.fail(key, f"every value must be finite, got {out.tolist()}")
        return float(out) if out.ndim == 0 else out


def load_scenario(path: str | Path) -> Scenario:
    """Read and validate a scenario file.

    Raises
    ------
    ScenarioError
        For any problem: unreadable file, TOML syntax, unknown or missing keys, wrong
        types, unparseable units, non-physical bodies or states.
    """
    path = Path(path)
    r = _Reader(path)
    try:
        with open(path, "rb") as fh:
            doc = tomllib.load(fh)
    except FileNotFoundError:
        raise ScenarioError("no such file", path=str(path)) from None
    except OSError as exc:
        raise ScenarioError(f"cannot read the file ({exc.strerror})", path=str(path)) from None
    except tomllib.TOMLDecodeError as exc:
        raise ScenarioError(f"not valid TOML ({exc})", path=str(path)) from None
    r.check_keys(doc, SCHEMA, "")
    for name in ("scenario", "body", "state", "propagation", "output", "ensemble"):
        if name in doc:
            r.check_keys(r.table(doc, name), SCHEMA[name], name)

    meta = r.table(doc, "scenario", required=False)
    name = r.string(meta, "name", "scenario", default=path.stem)
    description = r.string(meta, "description", "scenario", default="")
    ensemble, chunk = None, None
    if "ensemble" in doc:
        ensemble, chunk = _ensemble(r, doc, path.parent)
        body, state = _nominal(r, ensemble)
    else:
        body = _body(r, r.table(doc, "body"), path.parent)
        try:
            state = _state(r, r.table(doc, "state"), body)
        except ScenarioError:
            raise
        except AttitudeError as exc:  # physical validation by AttitudeState
            raise r.fail("state", str(exc)) from None

    prop = r.table(doc, "propagation")
    for key in ("duration", "step"):
        if key not in prop:
            raise r.fail(f"propagation.{key}", "missing key")
    duration = r.quantity(prop["duration"], "s", "propagation.duration")
    step = r.quantity(prop["step"], "s", "propagation.step")
    if not duration > 0:
        raise r.fail("propagation.duration", f"must be positive, got {duration} s")
    if not step > 0:
        raise r.fail("propagation.step", f"must be positive, got {step} s")
    if duration / step > 5e7:
        raise r.fail("propagation.step", f"{duration / step:.3g} epochs is too many for one "
                                         "run; use a longer step")
    method = r.string(prop, "method", "propagation")
    if method is not None and method not in METHODS:
        raise r.fail("propagation.method", f"{method!r} is unknown; choose one of {METHODS}")
    rtol = prop.get("rtol")
    if rtol is not None and (not isinstance(rtol, float) or not 0 < rtol < 1):
        raise r.fail("propagation.rtol", f"expected a float between 0 and 1, got {rtol!r}")
    integrator_step = None
    if "integrator_step" in prop:
        integrator_step = r.quantity(prop["integrator_step"], "s", "propagation.integrator_step")
        if not integrator_step > 0:
            raise r.fail("propagation.integrator_step", f"must be positive, got "
                                                        f"{integrator_step} s")
    order = prop.get("order")
    if order is not None and (isinstance(order, bool) or order not in (2, 4, 6)):
        raise r.fail("propagation.order", f"expected 2, 4 or 6, got {order!r}")
    if (integrator_step is not None or order is not None) and (
            method not in (None, "splitting") or rtol is not None):
        raise r.fail("propagation.integrator_step" if integrator_step is not None
                     else "propagation.order",
                     "only used by the splitting integrator (method = \"splitting\", no rtol)")

    torques = _torques(r, doc.get("torques", []), state.epoch)
    if torques and method == "exact":
        raise r.fail("propagation.method", "'exact' is the torque-free solution; remove it "
                                           "(or use 'integrator') with [[torques]]")

    out = r.table(doc, "output", required=False)
    netcdf = r.string(out, "netcdf", "output")
    expect = _parse_expect(r, r.table(doc, "expect", required=False))
    if ensemble is None and any(e["key"].startswith("regime_fractions") for e in expect):
        raise r.fail("expect.regime_fractions", "only for scenarios with an [ensemble] table")
    section = spinorbit_section.load_tables(   # spin-orbit wing: [section], its [expect]
        doc, body=body, torques=torques, expect=expect, ensemble=ensemble,
        folder=path.parent, fail=r.fail)
    # --- photometry (issue 15): the [photometry] table and the lightcurve [expect] keys ---
    photometry = None
    if "photometry" in doc:
        photometry = parse_photometry(doc["photometry"], doc.get("expect"), path, body)
    elif any(k in LIGHTCURVE_EXPECT_KEYS for k in doc.get("expect", {})):
        raise r.fail("expect", "lightcurve expectations need a [photometry] table")
    # --- end photometry ---
    return Scenario(path=path, name=name, description=description, body=body, state=state,
                    duration=duration, step=step, method=method, rtol=rtol,
                    integrator_step=integrator_step, order=order, torques=tuple(torques),
                    netcdf=(path.parent / netcdf) if netcdf else None, expect=expect,
                    ensemble=ensemble, chunk=chunk, section=section,
                    photometry=photometry)


def _ensemble(r: _Reader, doc: dict, folder: Path):
    """The ``[ensemble]`` table: a sampled population (``model``, ``size``, ``seed``,
    ``[ensemble.mean]``, ``[ensemble.sigma]``) or a table of bodies (``table``); the
    epoch and frame come from ``[state]``, which then holds nothing else."""
    if "body" in doc:
        raise r.fail("body", "not with [ensemble]: the ensemble defines the bodies")
    table = r.table(doc, "ensemble")
    state = r.table(doc, "state")
    for key in state:
        if key not in ("epoch", "time_scale", "frame"):
            raise r.fail(f"state.{key}", "not with [ensemble]: [state] gives only epoch, "
                                         "time_scale and frame; the ensemble the states")
    epoch, frame = _epoch_frame(r, state)
    chunk = table.get("chunk")
    if chunk is not None and (isinstance(chunk, bool) or not isinstance(chunk, int)
                              or chunk < 1):
        raise r.fail("ensemble.chunk", f"expected a positive integer, got {chunk!r}")
    if ("table" in table) == ("mean" in table):
        raise r.fail("ensemble", "give exactly one of table (a CSV/Parquet file of bodies) "
                                 "and [ensemble.mean] (a sampled population)")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", InvalidBodiesWarning)  # reported by the run
        if "table" in table:
            for key in ("size", "seed", "model", "sigma", "include_nominal"):
                if key in table:
                    raise r.fail(f"ensemble.{key}", "only with [ensemble.mean] (sampling)")
            try:
                return Ensemble.from_table(folder / r.string(table, "table", "ensemble"),
                                           epoch=epoch, frame=frame), chunk
            except AttitudeError as exc:
                raise r.fail("ensemble.table", str(exc)) from None
        model = r.string(table, "model", "ensemble", default="tumbling")
        if model not in MODELS:
            raise r.fail("ensemble.model", f"{model!r} is unknown; choose one of "
                                           f"{', '.join(MODELS)}")
        spec = MODELS[model]
        for key in ("size", "seed"):
            value = table.get(key)
            if value is None:
                raise r.fail(f"ensemble.{key}", "missing key" + (
                    " (a fixed seed makes the run reproducible)" if key == "seed" else ""))
            if isinstance(value, bool) or not isinstance(value, int) or value < (
                    1 if key == "size" else 0):
                kind = "positive" if key == "size" else "non-negative"
                raise r.fail(f"ensemble.{key}", f"expected a {kind} integer, got {value!r}")
        parsed = {}
        direction = _ENSEMBLE_DIRECTION[model]
        for part in ("mean", "sigma"):
            sub = table.get(part, {})
            if not isinstance(sub, dict):
                raise r.fail(f"ensemble.{part}", "expected a table")
            keys = {**spec, direction: "rad"} if part == "sigma" else spec
            r.check_keys(sub, keys, f"ensemble.{part}")
            parsed[part] = {k: r.quantity(v, keys[k], f"ensemble.{part}.{k}")
                            for k, v in sub.items()}
        for k in spec:
            if k not in parsed["mean"] and k not in _ENSEMBLE_DEFAULTS:
                raise r.fail(f"ensemble.mean.{k}", f"missing key (a parameter of the "
                                                   f"{model!r} model)")
        for k in parsed["sigma"]:
            if k not in parsed["mean"] and k != direction:
                raise r.fail(f"ensemble.sigma.{k}", "no ensemble.mean value for it")
        nominal = table.get("include_nominal", True)
        if not isinstance(nominal, bool):
            raise r.fail("ensemble.include_nominal", f"expected true or false, got {nominal!r}")
        try:
            ens = Ensemble.sample(table["size"], rng=table["seed"], model=model,
                                  mean=parsed["mean"], sigma=parsed["sigma"] or None,
                                  epoch=epoch, frame=frame, include_nominal=nominal)
        except AttitudeError as exc:
            raise r.fail("ensemble.mean", str(exc)) from None
    return ens, chunk


def _nominal(r: _Reader, ensemble) -> tuple[RigidBody, AttitudeState]:
    valid = np.nonzero(ensemble.valid)[0]
    if valid.size == 0:
        first = next(iter(ensemble.invalid.items()))
        raise r.fail("ensemble", f"no valid body (body {first[0]}: {first[1]})")
    i = int(valid[0])
    return ensemble.body_at(i), ensemble.state_at(i)


def _torques(r: _Reader, tables, epoch) -> tuple:
    """Each ``[[torques]]`` table becomes a torque model (see docs/torques.md)."""
    if not isinstance(tables, list) or not all(isinstance(t, dict) for t in tables):
        raise r.fail("torques", "expected an array of tables [[torques]]")
    models = []
    for i, table in enumerate(tables):
        try:
            models.append(from_config(table, base_epoch=epoch))
        except TorqueConfigError as exc:
            raise r.fail(f"torques[{i}].{exc.key}", exc.reason) from None
        except AttitudeError as exc:
            raise r.fail(f"torques[{i}]", str(exc)) from None
    return tuple(models)


def _body(r: _Reader, table: dict, folder: Path) -> RigidBody:
    kinds = [k for k in _BODY_KINDS if k in table]
    if len(kinds) != 1:
        raise r.fail("body", f"give exactly one of {', '.join(_BODY_KINDS)} (got "
                             f"{', '.join(kinds) or 'none'})")
    kind = kinds[0]
    name = r.string(table, "name", "body", default="")
    mass = r.quantity(table["mass"], "kg", "body.mass") if "mass" in table else None
    for key in ("density", "length_unit"):
        if key in table and kind != "shape":
            raise r.fail(f"body.{key}", "only used with body.shape")
    try:
        if kind == "principal_moments":
            moments = r.quantity(table[kind], "kg m2", "body.principal_moments", shape=(3,))
            return RigidBody.from_principal_moments(moments, mass=mass, name=name)
        if kind == "inertia":
            inertia = r.quantity(table[kind], "kg m2", "body.inertia", shape=(3, 3))
            return RigidBody(inertia, mass=mass, name=name)
        if kind == "shape":
            shape = folder / r.string(table, "shape", "body")
            if "density" not in table:
                raise r.fail("body.density", "missing key (needed with body.shape)")
            density = r.quantity(table["density"], "kg/m3", "body.density")
            unit = r.string(table, "length_unit", "body", default="m")
            try:
                u.Unit(unit)
            except ValueError:
                raise r.fail("body.length_unit", f"unknown unit {unit!r}") from None
            if mass is not None:
                raise r.fail("body.mass", "the mass of a shape model follows from its density")
            return RigidBody.from_obj(shape, density=density, length_unit=unit, name=name)
        return RigidBody.from_parts(_parts(r, table["parts"]), name=name)
    except ScenarioError:
        raise
    except AttitudeError as exc:
        raise r.fail(f"body.{kind}", str(exc)) from None


def _parts(r: _Reader, parts) -> list[MassProperties]:
    if not isinstance(parts, list) or not parts:
        raise r.fail("body.parts", "expected a non-empty array of tables")
    out = []
    for i, part in enumerate(parts):
        key = f"body.parts[{i}]"
        if not isinstance(part, dict):
            raise r.fail(key, f"expected a table, got {part!r}")
        if "primitive" not in part:
            raise r.fail(f"{key}.primitive", "missing key")
        params = {}
        units = {"mass": "kg", "masses": "kg", "size": "m", "radius": "m", "length": "m",
                 "inner_radius": "m", "outer_radius": "m", "semi_axes": "m", "positions": "m"}
        for k, v in part.items():
            if k in _PART_PLACEMENT:
                continue
            if k not in units:
                near = difflib.get_close_matches(k, list(units), n=1)
                hint = f"; did you mean '{near[0]}'?" if near else ""
                raise r.fail(f"{key}.{k}", f"unknown key{hint}")
            params[k] = r.quantity(v, units[k], f"{key}.{k}")
        try:
            props = MassProperties.from_primitive(part["primitive"], **params)
        except AttitudeError as exc:
            raise r.fail(key, str(exc)) from None
        offset = r.quantity(part.get("offset", [0.0, 0.0, 0.0]), "m", f"{key}.offset",
                            shape=(3,))
        orientation = None
        if "orientation" in part:
            orientation = _rotation(r, part["orientation"], f"{key}.orientation")
        out.append(props.placed(offset, orientation))
    return out


def _rotation(r: _Reader, table, key: str) -> Rotation:
    if not isinstance(table, dict):
        raise r.fail(key, "expected a table such as { quaternion_scalar_last = [0, 0, 0, 1] } "
                          "or { euler = \"ZXZ\", angles = { value = [..], unit = \"deg\" } }")
    forms = [k for k in ("quaternion_scalar_last", "quaternion_scalar_first", "euler")
             if k in table]
    r.check_keys(table, ("quaternion_scalar_last", "quaternion_scalar_first", "euler",
                         "angles"), key)
    if len(forms) != 1:
        raise r.fail(key, "give exactly one of quaternion_scalar_last, quaternion_scalar_first, "
                          "euler")
    form = forms[0]
    if form == "euler":
        seq = table["euler"]
        if "angles" not in table:
            raise r.fail(f"{key}.angles", "missing key (needed with euler)")
        angles = r.quantity(table["angles"], "rad", f"{key}.angles")
        try:
            return Rotation.from_euler(seq, angles)
        except (ValueError, TypeError) as exc:
            raise r.fail(f"{key}.euler", str(exc)) from None
    if "angles" in table:
        raise r.fail(f"{key}.angles", "only used with euler")
    q = np.asarray(r.quantity(table[form], "", f"{key}.{form}", shape=(4,)))
    norm = np.linalg.norm(q)
    if abs(norm - 1) > 1e-6:
        raise r.fail(f"{key}.{form}", f"quaternion {q.tolist()} has norm {norm:.9g}, not 1; "
                                      "normalise it and check the component order")
    return Rotation.from_quat(q, scalar_first=(form == "quaternion_scalar_first"))


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
    if "spin_axis" not in table:
        other = next(k for k in _SPIN_KEYS if k in table)
        raise r.fail("state.spin_axis", f"missing key (needed with state.{other})")
    for key in ("attitude", "omega_body"):
        if key in table:
            raise r.fail(f"state.{key}", "not with state.spin_axis (the spin axis and rate "
                                         "give both the attitude and omega_body)")
    axis = table["spin_axis"]
    r.check_keys(axis, ("ra", "dec"), "state.spin_axis")
    for key in ("ra", "dec"):
        if key not in axis:
            raise r.fail(f"state.spin_axis.{key}", "missing key")
    ra = r.quantity(axis["ra"], "rad", "state.spin_axis.ra")
    dec = r.quantity(axis["dec"], "rad", "state.spin_axis.dec")
    if not abs(dec) <= np.pi / 2 * (1 + 1e-12):
        raise r.fail("state.spin_axis.dec", f"must be within +-90 deg, got "
                                            f"{np.degrees(dec):.6g} deg")
    if ("spin_rate" in table) == ("spin_period" in table):
        raise r.fail("state.spin_rate", "give exactly one of spin_rate, spin_period")
    if "spin_rate" in table:
        rate = r.quantity(table["spin_rate"], "rad/s", "state.spin_rate")
        if not rate >= 0:
            raise r.fail("state.spin_rate", f"must be non-negative, got {rate} rad/s")
    else:
        period = r.quantity(table["spin_period"], "s", "state.spin_period")
        if not period > 0:
            raise r.fail("state.spin_period", f"must be positive, got {period} s")
        rate = 2 * np.pi / period
    about = r.string(table, "spin_about", "state", default="C")
    if about not in ("A", "B", "C"):
        raise r.fail("state.spin_about", f"expected \"A\", \"B\" or \"C\" (principal "
                                         f"axes, A <= B <= C), got {about!r}")
    return spin_axis_state(body, ra, dec, rate, about)


def _epoch_frame(r: _Reader, table: dict) -> tuple[Time, str]:
    """``state.epoch`` (in ``state.time_scale``, default TDB) and ``state.frame``."""
    scale = r.string(table, "time_scale", "state", default="tdb").lower()
    if scale not in Time.SCALES:
        raise r.fail("state.time_scale", f"{scale!r} is not a time scale; use one of "
                                         f"{', '.join(Time.SCALES)}")
    epoch_text = r.string(table, "epoch", "state", required=True)
    try:
        epoch = Time(epoch_text, scale=scale, precision=9)
    except ValueError:
        raise r.fail("state.epoch", f"cannot parse {epoch_text!r} as a time; use ISO 8601 "
                                    "such as '2029-04-13T00:00:00'") from None
    frame = r.string(table, "frame", "state", default="ICRF")
    try:
        frame = check_frame(frame)
    except AttitudeError as exc:
        raise r.fail("state.frame", str(exc)) from None
    return epoch, frame


def _state(r: _Reader, table: dict, body: RigidBody) -> AttitudeState:
    spin = any(k in table for k in _SPIN_KEYS)
    for key in ("epoch",) if spin else ("epoch", "omega_body"):
        if key not in table:
            raise r.fail(f"state.{key}", "missing key" + (
                "" if key == "epoch" else " (or give spin_axis with spin_rate/spin_period)"))
    epoch, frame = _epoch_frame(r, table)
    if spin:
        attitude, omega = _spin_state(r, table, body)
    else:
        attitude = (_rotation(r, table["attitude"], "state.attitude") if "attitude" in table
                    else Rotation.identity())
        omega = r.quantity(table["omega_body"], "rad/s", "state.omega_body", shape=(3,))
    return AttitudeState(epoch=epoch, attitude=attitude, omega_body=omega, frame=frame)


# --- running ------------------------------------------------------------------------

CONSERVATION_KEYS = ("angular_momentum_rel_drift", "energy_rel_drift")


@dataclass(frozen=True, eq=False)
class RunResult:
    """What a scenario run produced: the ephemeris, the analytic diagnosis of the initial
    state, the classification of the ephemeris (runs with torques), the conservation
    figures, the expectation outcomes and the files written."""

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
    the :func:`~attitude.diagnostics.add_diagnostics` variables when needed), or None."""
    ensemble: dict | None = None
    """Summary of an ensemble run (:func:`ensemble_summary`), or None."""

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
        return doc


def run_scenario(scenario: Scenario, *, netcdf: str | Path | None = None,
                 write_outputs: bool = True, progress: bool = False,
                 client=None) -> RunResult:
    """Propagate a scenario, classify it, check its ``[expect]`` table, write outputs.

    A torque-free run is described by the analytic :func:`attitude.diagnose` of its
    initial state.  A run with torques is classified from its ephemeris by
    :func:`attitude.classify` with the finite-time Lyapunov test (``chaotic``), so its
    regime and periods are measured ones.  ``write_outputs=False`` writes no file (what
    ``attitude check`` does).  An ensemble scenario runs on ``client`` (a dask client)
    when one is given, else in this process (:func:`ensemble_summary`).
    """
    if scenario.ensemble is not None:
        return _run_ensemble(scenario, netcdf=netcdf, write_outputs=write_outputs,
                             client=client)
    torques = list(scenario.torques)
    eph = propagate(scenario.body, scenario.state, scenario.times, method=scenario.method,
                    rtol=scenario.rtol, torques=torques, step=scenario.integrator_step,
                    order=scenario.order, progress=progress)
    diagnosis = diagnose(scenario.body, scenario.state)
    classification, note = None, ""
    if torques:
        try:
            classification = classify(eph, chaos=True, torques=torques,
                                      require_periods=False)
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
    result = RunResult(scenario, eph, diagnosis, classification, conservation, [], [], note,
                       dataset)
    result.expectations.extend(check_expectations(
        scenario, result.regime, result.periods, conservation, diagnosis=diagnosis,
        dataset=dataset,
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


#: Reductions of a time series for ``[expect.variables]``.
REDUCTIONS = ("start", "end", "max", "min", "mean")
#: Variables of the base ephemeris dataset (docs/states_and_ephemerides.md) and their units.
BASE_VARIABLES = {"quaternion": "1", "angular_velocity": "rad s-1",
                  "angular_momentum": "kg m2 s-1", "kinetic_energy": "J"}
_VARIABLE_KEYS = ("variable", "at", "component", "value", "unit", "rel_tol", "abs_tol")
_TOLERANCE_KEYS = ("rel_tol", "abs_tol")


def known_variables() -> dict[str, tuple[str, bool]]:
    """Variables ``[expect.variables]`` may name: ``{name: (units, is_time_series)}``.

    The base dataset (``quaternion``, ``angular_velocity``, ``angular_momentum``,
    ``kinetic_energy``), the time series of :func:`attitude.diagnostics.add_diagnostics`
    (:data:`~attitude.diagnostics.DIAGNOSTIC_VARIABLES`) and its scalars (conservation
    figures, ``attitude_noise``, measured periods ``period_<key>`` and their
    ``period_<key>_uncertainty``).
    """
    out = {k: (v, True) for k, v in BASE_VARIABLES.items()}
    out.update({k: (v[0], True) for k, v in DIAGNOSTIC_VARIABLES.items()})
    out.update({name: (units, False) for name, units, _ in SCALAR_DIAGNOSTICS.values()})
    for key in PERIOD_KEYS:
        out[f"period_{key}"] = ("s", False)
        out[f"period_{key}_uncertainty"] = ("s", False)
    return out


def _tolerance(r: _Reader, spec: dict, where: str, value: float, scale: float = 1.0) -> float:
    """Exactly one of ``rel_tol`` / ``abs_tol`` (in the expectation's unit) -> absolute."""
    if ("rel_tol" in spec) == ("abs_tol" in spec):
        raise r.fail(where, "give exactly one of rel_tol, abs_tol")
    tol_key = "rel_tol" if "rel_tol" in spec else "abs_tol"
    tol = r.quantity(spec[tol_key], "", f"{where}.{tol_key}")
    if not tol >= 0:
        raise r.fail(f"{where}.{tol_key}", "must be non-negative")
    return tol * abs(value) if tol_key == "rel_tol" else tol * scale


def _unit(r: _Reader, text, where: str, target: str) -> u.UnitBase:
    if not isinstance(text, str):
        raise r.fail(where, f"expected a unit string, got {text!r}")
    try:
        unit = u.Unit(text)
    except ValueError:
        raise r.fail(where, f"unknown unit {text!r}") from None
    if not unit.is_equivalent(u.Unit(target)):
        raise r.fail(where, f"unit '{text}' cannot be converted to '{target}'")
    return unit


def _parse_nutation_range(r: _Reader, spec, where: str) -> list[dict]:
    """``{ min = .., max = .., unit = "deg", abs_tol = .. }`` -> two entries
    ``nutation_range.min`` and ``nutation_range.max`` (in ``unit``, default rad)."""
    if not isinstance(spec, dict):
        raise r.fail(where, "expected { min = ..., max = ..., unit = \"deg\", abs_tol = ... }")
    r.check_keys(spec, ("min", "max", "unit", "abs_tol"), where)
    for key in ("min", "max", "abs_tol"):
        if key not in spec:
            raise r.fail(f"{where}.{key}", "missing key")
    unit = spec.get("unit", "rad")
    _unit(r, unit, f"{where}.unit", "rad")
    out = {}
    for key in ("min", "max", "abs_tol"):
        value = spec[key]
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise r.fail(f"{where}.{key}", f"expected a number (in {unit}), got {value!r}")
        out[key] = float(value)
    if not out["abs_tol"] >= 0:
        raise r.fail(f"{where}.abs_tol", "must be non-negative")
    if not out["min"] <= out["max"]:
        raise r.fail(where, f"min ({out['min']}) is larger than max ({out['max']})")
    return [{"key": f"nutation_range.{k}", "expected": out[k], "unit": unit,
             "tolerance": out["abs_tol"]} for k in ("min", "max")]


def _parse_variables(r: _Reader, table, where: str) -> list[dict]:
    """``[expect.variables]``: ``name = { at = "end", component = 2, value = .., unit = "..",
    rel_tol = .. }`` for any variable of :func:`known_variables`."""
    if not isinstance(table, dict):
        raise r.fail(where, "expected a table [expect.variables]")
    known = known_variables()
    out = []
    for label, spec in table.items():
        key = f"{where}.{label}"
        if not isinstance(spec, dict):
            raise r.fail(key, "expected { at = \"end\", value = ..., unit = \"...\", "
                              "rel_tol = ... }")
        r.check_keys(spec, _VARIABLE_KEYS, key)
        name = spec.get("variable", label)
        if not isinstance(name, str):
            raise r.fail(f"{key}.variable", f"expected a string, got {name!r}")
        if name not in known:
            near = difflib.get_close_matches(name, list(known), n=1)
            hint = f"; did you mean '{near[0]}'?" if near else \
                f"; known: {', '.join(known)}"
            raise r.fail(f"{key}.variable" if "variable" in spec else key,
                         f"unknown variable {name!r}{hint}")
        var_units, series = known[name]
        at = spec.get("at")
        if series and at not in REDUCTIONS:
            raise r.fail(f"{key}.at", f"{name} is a time series: give at = one of "
                                      f"{', '.join(REDUCTIONS)}" +
                         ("" if at is None else f", got {at!r}"))
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
        if "value" not in spec:
            raise r.fail(f"{key}.value", "missing key")
        value = spec["value"]
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise r.fail(f"{key}.value", f"expected a number, got {value!r}")
        unit_text = spec.get("unit", var_units)
        _unit(r, unit_text, f"{key}.unit", var_units)
        entry = {"key": f"variables.{label}", "expected": float(value), "unit": unit_text,
                 "tolerance": _tolerance(r, spec, key, float(value)),
                 "variable": name, "at": at, "component": component}
        out.append(entry)
    return out


def _parse_expect(r: _Reader, table: dict) -> tuple[dict, ...]:
    """Validate the ``[expect]`` table at load time (before any work is done).

    ``regime = "SAM"``; a period key (``polhode``, ``precession``, ``rotation``, ``spin``)
    as ``{ value = 27.38, unit = "h", rel_tol = 0.01 }`` (or ``abs_tol`` in the same
    unit); a conservation key as ``{ max = 1e-12 }``; ``nutation_range = { min = ..,
    max = .., unit = "deg", abs_tol = .. }``; a ``[expect.variables]`` table of dataset
    variables reduced over the run (:func:`_parse_variables`).
    """
    parsed = []
    for key, spec in table.items():
        where = f"expect.{key}"
        if key == "regime":
            if spec not in REGIMES:
                raise r.fail(where, f"expected one of {', '.join(REGIMES)}, got {spec!r}")
            parsed.append({"key": key, "expected": spec})
        elif key in PERIOD_KEYS:
            if not isinstance(spec, dict):
                raise r.fail(where, "expected { value = ..., unit = \"h\", rel_tol = ... }")
            r.check_keys(spec, ("value", "unit", "rel_tol", "abs_tol"), where)
            if ("rel_tol" in spec) == ("abs_tol" in spec):
                raise r.fail(where, "give exactly one of rel_tol, abs_tol")
            unit = spec.get("unit", "s")
            value = r.quantity({"value": spec.get("value"), "unit": unit}, "s", where)
            scale = u.Unit(unit).to(u.s)
            parsed.append({"key": key, "expected": value / scale, "unit": unit,
                           "tolerance": _tolerance(r, spec, where, value / scale)})
        elif key in CONSERVATION_KEYS:
            if not isinstance(spec, dict) or set(spec) != {"max"}:
                raise r.fail(where, "expected { max = ... }")
            parsed.append({"key": key, "expected": r.quantity(spec["max"], "",
                                                              f"{where}.max")})
        elif key in LIGHTCURVE_EXPECT_KEYS:
            continue           # photometry (issue 15): parsed by attitude.photometry.config
        elif key == "nutation_range":
            parsed.extend(_parse_nutation_range(r, spec, where))
        elif key == "variables":
            parsed.extend(_parse_variables(r, spec, where))
        elif key in spinorbit_section.EXPECT_KEYS:          # spin-orbit wing (issue 19)
            parsed.append(spinorbit_section.parse_expect(key, spec, r.fail))
        elif key == "regime_fractions":
            if not isinstance(spec, dict) or not spec:
                raise r.fail(where, "expected a table such as { SAM = { value = 0.95, "
                                    "abs_tol = 0.05 } }")
            r.check_keys(spec, REGIMES, where)
            for regime, frac in spec.items():
                w = f"{where}.{regime}"
                if not isinstance(frac, dict):
                    raise r.fail(w, "expected { value = ..., abs_tol = ... }")
                r.check_keys(frac, ("value", "rel_tol", "abs_tol"), w)
                value = r.quantity(frac.get("value"), "", f"{w}.value")
                if not 0 <= value <= 1:
                    raise r.fail(f"{w}.value", f"a fraction is between 0 and 1, got {value}")
                parsed.append({"key": f"regime_fractions.{regime}", "expected": value,
                               "tolerance": _tolerance(r, frac, w, value)})
        else:
            allowed = EXPECT_KEYS
            near = difflib.get_close_matches(key, allowed, n=1)
            hint = f"; did you mean '{near[0]}'?" if near else f"; allowed: {', '.join(allowed)}"
            raise r.fail(where, f"unknown expectation{hint}")
    return tuple(parsed)


#: Keys of the ``[expect]`` table.
EXPECT_KEYS = ("regime",) + PERIOD_KEYS + CONSERVATION_KEYS + (
    "nutation_range", "variables", "regime_fractions") + spinorbit_section.EXPECT_KEYS \
    + LIGHTCURVE_EXPECT_KEYS


def needs_dataset(scenario: Scenario) -> str | None:
    """Whether checking the expectations needs :func:`add_diagnostics` of the run:
    ``None`` (no), ``"base"`` (base variables only), ``"diagnostics"`` or ``"periods"``."""
    need = None
    base = set(BASE_VARIABLES)
    for spec in scenario.expect:
        if spec["key"].startswith("nutation_range.") and scenario.torques:
            need = need or "diagnostics"
        elif "variable" in spec:
            if spec["variable"].startswith("period_"):
                return "periods"
            if spec["variable"] not in base:
                need = "diagnostics"
            elif need is None:
                need = "base"
    return need


def _reduce(data: np.ndarray, at: str | None) -> float:
    if at is None:
        return float(data)
    if at == "start":
        return float(data[0])
    if at == "end":
        return float(data[-1])
    return float(getattr(np, {"max": "nanmax", "min": "nanmin", "mean": "nanmean"}[at])(data))


def _variable_value(dataset, spec: dict) -> float | None:
    """The reduced value of one ``[expect.variables]`` entry in its expected unit."""
    if dataset is None or spec["variable"] not in dataset:
        return None
    var = dataset[spec["variable"]]
    data = np.asarray(var.values, dtype=float)
    comp = spec["component"]
    if comp == "norm":
        data = np.linalg.norm(data, axis=-1)
    elif comp is not None:
        data = data[..., comp]
    got = _reduce(data, spec["at"])
    units = var.attrs.get("units", "1")
    return float((got * u.Unit(units)).to_value(spec["unit"]))


def check_expectations(scenario: Scenario, regime: str | None, periods: dict,
                       conservation: dict, *, diagnosis=None, dataset=None,
                       fractions: dict | None = None,
                       spinorbit: dict | None = None) -> list[dict]:
    """Compare the parsed ``[expect]`` entries with what the run gave.

    ``diagnosis`` (:func:`attitude.diagnose` of the initial state) gives the nutation range
    of a torque-free run; ``dataset`` (the run's ephemeris dataset, with the variables of
    :func:`attitude.diagnostics.add_diagnostics` when :func:`needs_dataset` says so) the
    nutation range of a run with torques (extremes of ``nutation_angle`` over the run) and
    the ``[expect.variables]`` values.  Without them those entries get ``got = None``
    (a failure).
    """
    results = []
    for spec in scenario.expect:
        key = spec["key"]
        out = {k: v for k, v in spec.items() if k not in ("variable", "at", "component")}
        if key == "resonance":                        # spin-orbit wing: a "p:q" string
            out["got"] = (spinorbit or {}).get(key)
            out["ok"] = out["got"] == spec["expected"]
            results.append(out)
            continue
        if key == "regime":
            out["got"] = regime
            out["ok"] = regime == spec["expected"]
            results.append(out)
            continue
        if key in PERIOD_KEYS:
            got = periods.get(key)
            got = None if got is None else got / u.Unit(spec["unit"]).to(u.s)
        elif key.startswith("nutation_range."):
            got = _nutation_bound(scenario, key.rsplit(".", 1)[1], diagnosis, dataset)
            got = None if got is None else float((got * u.rad).to_value(spec["unit"]))
        elif key.startswith("variables."):
            got = _variable_value(dataset, spec)
        elif key.startswith("regime_fractions."):
            got = None if fractions is None else fractions.get(key.split(".", 1)[1], 0.0)
        elif key == "libration_amplitude":            # spin-orbit wing
            got = (spinorbit or {}).get(key)
        else:
            out["got"] = conservation[key]
            out["ok"] = bool(out["got"] <= spec["expected"])
            results.append(out)
            continue
        out["got"] = got
        out["ok"] = bool(got is not None and np.isfinite(got) and
                         abs(got - spec["expected"]) <= spec["tolerance"])
        results.append(out)
    return results


def _nutation_bound(scenario: Scenario, which: str, diagnosis, dataset) -> float | None:
    """theta_min / theta_max, rad: analytic (torque-free) or over the run (torques)."""
    if not scenario.torques:
        if diagnosis is None or diagnosis.nutation_range is None:
            return None
        return float(diagnosis.nutation_range[0 if which == "min" else 1])
    if dataset is None or "nutation_angle" not in dataset:
        return None
    return _reduce(np.asarray(dataset["nutation_angle"].values, dtype=float), which)

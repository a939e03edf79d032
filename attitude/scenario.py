"""Scenario files (TOML): a body, an initial state, a propagation, outputs and
expectations, validated before any work is done.

Every problem is reported as a :class:`~attitude.errors.ScenarioError` whose message is
one line naming the file and the key (``scenarios/x.toml: state.omega_body: ...``).
See the scenario section of the docs for the full format.
"""

from __future__ import annotations

import difflib
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from astropy import units as u
from astropy.time import Time
from scipy.spatial.transform import Rotation

from ._units import parse_quantity
from .body import MassProperties, RigidBody
from .errors import AttitudeError, ScenarioError
from .regimes import PERIOD_KEYS, REGIMES
from .state import AttitudeState, check_frame

__all__ = ["Scenario", "RunResult", "load_scenario", "run_scenario", "check_expectations", "SCHEMA"]

#: Allowed keys of each table (``None``: free-form sub-table checked by its parser).
SCHEMA: dict[str, dict[str, Any]] = {
    "scenario": {"name": str, "description": str},
    "body": {"principal_moments": None, "inertia": None, "shape": str, "density": None,
             "length_unit": str, "parts": list, "mass": None, "name": str},
    "state": {"epoch": str, "time_scale": str, "frame": str, "attitude": dict,
              "omega_body": None},
    "propagation": {"duration": None, "step": None, "method": str, "rtol": float},
    "torques": list,
    "output": {"netcdf": str},
    "expect": dict,
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
    torques: tuple = ()
    netcdf: Path | None = None
    expect: tuple = ()

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
    for name in ("scenario", "body", "state", "propagation", "output"):
        if name in doc:
            r.check_keys(r.table(doc, name), SCHEMA[name], name)

    meta = r.table(doc, "scenario", required=False)
    name = r.string(meta, "name", "scenario", default=path.stem)
    description = r.string(meta, "description", "scenario", default="")
    body = _body(r, r.table(doc, "body"), path.parent)
    try:
        state = _state(r, r.table(doc, "state"))
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
    from .propagate import METHODS

    if method is not None and method not in METHODS:
        raise r.fail("propagation.method", f"{method!r} is unknown; choose one of {METHODS}")
    rtol = prop.get("rtol")
    if rtol is not None and (not isinstance(rtol, float) or not 0 < rtol < 1):
        raise r.fail("propagation.rtol", f"expected a float between 0 and 1, got {rtol!r}")

    torques = _torques(r, doc.get("torques", []), state.epoch)
    if torques and method == "exact":
        raise r.fail("propagation.method", "'exact' is the torque-free solution; remove it "
                                           "(or use 'integrator') with [[torques]]")

    out = r.table(doc, "output", required=False)
    netcdf = r.string(out, "netcdf", "output")
    expect = _parse_expect(r, r.table(doc, "expect", required=False))
    return Scenario(path=path, name=name, description=description, body=body, state=state,
                    duration=duration, step=step, method=method, rtol=rtol,
                    torques=tuple(torques),
                    netcdf=(path.parent / netcdf) if netcdf else None, expect=expect)


def _torques(r: _Reader, tables, epoch) -> tuple:
    """Each ``[[torques]]`` table becomes a torque model (see docs/torques.md)."""
    from .torques import TorqueConfigError, from_config

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


def _state(r: _Reader, table: dict) -> AttitudeState:
    for key in ("epoch", "omega_body"):
        if key not in table:
            raise r.fail(f"state.{key}", "missing key")
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

    @property
    def ok(self) -> bool:
        return all(e["ok"] for e in self.expectations)

    @property
    def regime(self) -> str | None:
        """The analytic regime of a torque-free run; the classified regime (including
        ``chaotic``) of a run with torques."""
        if not self.scenario.torques:
            return self.diagnosis.regime
        return self.classification.regime if self.classification is not None else None

    @property
    def periods(self) -> dict:
        """Analytic periods of a torque-free run; measured periods of a run with torques."""
        if not self.scenario.torques:
            return dict(self.diagnosis.periods)
        return dict(self.classification.periods) if self.classification is not None else {}

    def report(self) -> dict:
        """The ``--report`` JSON document (API.md)."""
        return {
            "scenario": self.scenario.name,
            "regime": self.regime,
            "periods": self.periods,
            "conservation": self.conservation,
            "expect": self.expectations,
            "outputs": [str(p) for p in self.outputs],
        }


def run_scenario(scenario: Scenario, *, netcdf: str | Path | None = None,
                 write_outputs: bool = True) -> RunResult:
    """Propagate a scenario, classify it, check its ``[expect]`` table, write outputs.

    A torque-free run is described by the analytic :func:`attitude.diagnose` of its
    initial state.  A run with torques is classified from its ephemeris by
    :func:`attitude.classify` with the finite-time Lyapunov test (``chaotic``), so its
    regime and periods are measured ones.  ``write_outputs=False`` writes no file (what
    ``attitude check`` does).
    """
    from .classify import classify
    from .diagnostics import DiagnosticsError
    from .propagate import propagate
    from .torquefree import diagnose

    torques = list(scenario.torques)
    eph = propagate(scenario.body, scenario.state, scenario.times, method=scenario.method,
                    rtol=scenario.rtol, torques=torques)
    diagnosis = diagnose(scenario.body, scenario.state)
    classification, note = None, ""
    if torques:
        try:
            classification = classify(eph, chaos=True, torques=torques,
                                      require_periods=False)
        except (DiagnosticsError, AttitudeError) as exc:
            note = f"not classified: {exc}"
    conservation = eph.conservation()
    result = RunResult(scenario, eph, diagnosis, classification, conservation, [], [], note)
    result.expectations.extend(check_expectations(scenario, result.regime, result.periods,
                                                  conservation))
    target = Path(netcdf) if netcdf is not None else scenario.netcdf
    if target is not None and write_outputs:
        result.outputs.append(eph.to_netcdf(target))
    return result


def _parse_expect(r: _Reader, table: dict) -> tuple[dict, ...]:
    """Validate the ``[expect]`` table at load time (before any work is done).

    ``regime = "SAM"``; a period key (``polhode``, ``precession``, ``rotation``, ``spin``)
    as ``{ value = 27.38, unit = "h", rel_tol = 0.01 }`` (or ``abs_tol`` in the same
    unit); a conservation key as ``{ max = 1e-12 }``.
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
            tol_key = "rel_tol" if "rel_tol" in spec else "abs_tol"
            tol = r.quantity(spec[tol_key], "", f"{where}.{tol_key}")
            if not tol >= 0:
                raise r.fail(f"{where}.{tol_key}", "must be non-negative")
            scale = u.Unit(unit).to(u.s)
            parsed.append({"key": key, "expected": value / scale, "unit": unit,
                           "tolerance": tol * abs(value) / scale if tol_key == "rel_tol"
                           else tol})
        elif key in CONSERVATION_KEYS:
            if not isinstance(spec, dict) or set(spec) != {"max"}:
                raise r.fail(where, "expected { max = ... }")
            parsed.append({"key": key, "expected": r.quantity(spec["max"], "",
                                                              f"{where}.max")})
        else:
            allowed = ("regime",) + PERIOD_KEYS + CONSERVATION_KEYS
            near = difflib.get_close_matches(key, allowed, n=1)
            hint = f"; did you mean '{near[0]}'?" if near else f"; allowed: {', '.join(allowed)}"
            raise r.fail(where, f"unknown expectation{hint}")
    return tuple(parsed)


def check_expectations(scenario: Scenario, regime: str | None, periods: dict,
                       conservation: dict) -> list[dict]:
    """Compare the parsed ``[expect]`` entries with what the run gave."""
    results = []
    for spec in scenario.expect:
        key = spec["key"]
        out = dict(spec)
        if key == "regime":
            out["got"] = regime
            out["ok"] = regime == spec["expected"]
        elif key in PERIOD_KEYS:
            got = periods.get(key)
            out["got"] = None if got is None else got / u.Unit(spec["unit"]).to(u.s)
            out["ok"] = bool(got is not None and
                             abs(out["got"] - spec["expected"]) <= spec["tolerance"])
        else:
            out["got"] = conservation[key]
            out["ok"] = bool(out["got"] <= spec["expected"])
        results.append(out)
    return results

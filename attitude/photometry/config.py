"""The ``[photometry]`` table of scenario files and the lightcurve run.

``attitude lightcurve SCENARIO.toml`` propagates the scenario's rotation state, renders
the lightcurve, fits its periods and checks the lightcurve keys of ``[expect]``.  The
table (all keys optional except the shape)::

    [photometry]
    shape = "ellipsoid"        # the homogeneous ellipsoid with the body's moments, or an
                               # OBJ file (path relative to the scenario) in the body frame
    # axes = ["1.1 km", "0.7 km", "0.6 km"]   # shape = "ellipsoid": explicit semi-axes
    length_unit = "m"          # of the OBJ coordinates
    subdivisions = 3           # ellipsoid mesh: 20 * 4**n faces
    law = "ls-lambert"         # or { name = "hapke", w = 0.3, xi = -0.3, B0 = 1, h = 0.05 }
    materials = [ { faces = [0, 64], law = { name = "phong", specular = 0.6 } } ]
    sun = [1.0, 0.0, 0.0]      # body -> Sun, inertial frame of the state; or
    observer = [0.8, 0.6, 0.0] # ... and body -> observer
    # orbit = { mu = "1.32712440018e20 m3/s2", a = "0.9224 AU", e = 0.19, ... }
    # observer = "earth"       # with orbit: astropy's built-in Earth, light time corrected
    cadence = "30 min"         # sampling (default: [propagation].step)
    noise = "0.01 mag"         # Gaussian noise added to the magnitudes (default none)
    seed = 1
    shadows = false
    periods = 2                # 1: Lomb-Scargle with harmonics; 2: Pravec et al. 2005
    order = 4
    output = "apophis_lightcurve.nc"

``[expect]`` keys of the lightcurve: ``lightcurve_period`` (the double-peaked period;
``{ value, unit, rel_tol | abs_tol }``), ``lightcurve_amplitude`` (peak to peak, mag),
and ``lightcurve_lattice = { value = [27.38, 131.5], unit = "h", rel_tol = 0.01 }``:
each listed period's frequency must lie on the fitted lattice ``n1/P1 + n2/P2``
(``|n| <= order``) within ``rel_tol``.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import astropy.units as u
import numpy as np

from attitude.foundations.errors import AttitudeError, ScenarioError
from attitude.foundations.quantities import to_si
from attitude.model.orbit import KeplerOrbit
from attitude.model.shape import Polyhedron
from attitude.photometry.brightness import lightcurve
from attitude.photometry.dataset import Lightcurve
from attitude.photometry.geometry import Geometry
from attitude.photometry.periods import PeriodFit, fit_periods, lattice_combination
from attitude.photometry.scattering import FacetMaterials, scattering_law
from attitude.propagation.propagator import propagate

#: JSON Schema of the ``[photometry]`` table (declared in
#: :data:`attitude.app.scenario_spec.SCENARIO`; :func:`parse_photometry` checks the same keys).
PHOTOMETRY_SCHEMA = {
    "type": "object",
    "additionalProperties": False,
    "required": [
        "shape"
    ],
    "description": "photometry (attitude lightcurve): shape, scattering law, geometry, cadence; see docs/photometry.md",  # noqa: E501
    "properties": {
        "shape": {
            "type": "string",
            "description": "\"ellipsoid\" (from the body's moments, or axes) or an OBJ file"
        },
        "axes": {
            "type": "array",
            "minItems": 3,
            "maxItems": 3
        },
        "length_unit": {
            "type": "string"
        },
        "subdivisions": {
            "type": "integer",
            "minimum": 0,
            "maximum": 8
        },
        "law": {
            "oneOf": [
                {
                    "type": "string"
                },
                {
                    "type": "object",
                    "required": [
                        "name"
                    ]
                }
            ]
        },
        "materials": {
            "type": "array",
            "items": {
                "type": "object",
                "required": [
                    "faces",
                    "law"
                ],
                "additionalProperties": False,
                "properties": {
                    "faces": {
                        "type": "array",
                        "items": {
                            "type": "integer"
                        },
                        "minItems": 2,
                        "maxItems": 2
                    },
                    "law": {
                        "oneOf": [
                            {
                                "type": "string"
                            },
                            {
                                "type": "object",
                                "required": [
                                    "name"
                                ]
                            }
                        ]
                    }
                }
            }
        },
        "sun": {
            "type": "array",
            "items": {
                "type": "number"
            },
            "minItems": 3,
            "maxItems": 3
        },
        "observer": {
            "oneOf": [
                {
                    "type": "array",
                    "items": {
                        "type": "number"
                    },
                    "minItems": 3,
                    "maxItems": 3
                },
                {
                    "enum": [
                        "earth",
                        "sun"
                    ]
                }
            ]
        },
        "orbit": {
            "type": "object"
        },
        "light_time": {
            "type": "boolean"
        },
        "cadence": {
            "type": [
                "number",
                "string"
            ]
        },
        "noise": {
            "type": [
                "number",
                "string"
            ]
        },
        "seed": {
            "type": "integer"
        },
        "shadows": {
            "type": "boolean"
        },
        "periods": {
            "enum": [
                1,
                2
            ]
        },
        "order": {
            "type": "integer",
            "minimum": 1,
            "maximum": 8
        },
        "output": {
            "type": "string"
        }
    }
}
def _tolerance_schema(value: dict, description: str) -> dict:
    """JSON Schema of a lightcurve expectation: ``value`` and one of the tolerances."""
    return {"type": "object",
            "properties": {"value": value, "unit": {"type": "string"},
                           "rel_tol": {"type": "number", "minimum": 0},
                           "abs_tol": {"type": "number", "minimum": 0}},
            "additionalProperties": False, "required": ["value"],
            "oneOf": [{"required": ["rel_tol"]}, {"required": ["abs_tol"]}],
            "description": description}


#: JSON Schemas of the lightcurve ``[expect]`` keys.
EXPECT_SCHEMAS = {
    "lightcurve_period": _tolerance_schema(
        {"type": "number"}, "photometry: the double-peaked lightcurve period (default unit s)"),
    "lightcurve_amplitude": _tolerance_schema(
        {"type": "number"}, "photometry: peak-to-peak amplitude (default unit mag)"),
    "lightcurve_lattice": _tolerance_schema(
        {"type": "array", "items": {"type": "number"}, "minItems": 1},
        "photometry: periods whose frequencies lie on the fitted lattice n1/P1 + n2/P2 "
        "within rel_tol"),
}

__all__ = ["PhotometryConfig", "LightcurveRun", "parse_photometry", "run_lightcurve",
           "check_lightcurve", "EXPECT_KEYS"]

#: The lightcurve keys of ``[expect]``.
EXPECT_KEYS = ("lightcurve_period", "lightcurve_amplitude", "lightcurve_lattice")
_KEYS = ("shape", "axes", "length_unit", "subdivisions", "law", "materials", "sun",
         "observer", "orbit", "light_time", "cadence", "noise", "seed", "shadows", "periods",
         "order", "output")


@dataclass(frozen=True, eq=False)
class PhotometryConfig:
    """A parsed ``[photometry]`` table with the lightcurve expectations.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from attitude.app.scenario import load_scenario
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "spin.toml"
    >>> _ = path.write_text('''
    ... [body]
    ... principal_moments = [1.0, 2.0, 2.5]
    ... [state]
    ... epoch = "2024-01-01"
    ... omega_body = { value = [0, 0, 1], unit = "cycle/h" }
    ... [propagation]
    ... duration = "3 h"
    ... step = "2 min"
    ... [photometry]
    ... shape = "ellipsoid"
    ... subdivisions = 1
    ... law = "lambert"
    ... sun = [1.0, 0.0, 0.3]
    ... observer = [1.0, 0.2, 0.3]
    ... periods = 1
    ... order = 2
    ... [expect]
    ... lightcurve_period = { value = 1.0, unit = "h", rel_tol = 1e-3 }
    ... ''')
    >>> sc = load_scenario(path)          # a triaxial ellipsoid spinning once an hour
    >>> cfg = sc.photometry
    >>> len(cfg.shape.faces), cfg.law.name, cfg.periods, cfg.order
    (80, 'lambert', 1, 2)
    >>> cfg.expect[0]["key"], cfg.expect[0]["scale"]        # hours -> seconds
    ('lightcurve_period', 3600.0)
    """

    shape: Any
    law: Any
    geometry: dict
    cadence: float | None = None
    noise: float = 0.0
    seed: int | None = None
    shadows: bool = False
    periods: int = 2
    order: int = 4
    output: Path | None = None
    expect: tuple = ()


def _fail(path, key, message):
    return ScenarioError(message, key=key, path=str(path))


def parse_photometry(table: dict, expect: dict | None, path, body) -> PhotometryConfig:
    """Read a ``[photometry]`` table (and the lightcurve keys of ``[expect]``).

    Parameters
    ----------
    table : dict
        The TOML table.
    expect : dict or None
        The whole ``[expect]`` table; only :data:`EXPECT_KEYS` are read.
    path : Path
        The scenario file (relative paths start from its folder; errors name it).
    body : RigidBody
        The scenario's body (for ``shape = "ellipsoid"``).

    Raises
    ------
    ScenarioError
        Naming ``photometry.<key>`` (or ``expect.<key>``) and the fix.

    Examples
    --------
    >>> import attitude as att
    >>> from attitude.photometry.config import parse_photometry
    >>> body = att.RigidBody.from_principal_moments([0.61, 0.965, 1.0])
    >>> cfg = parse_photometry({"shape": "ellipsoid", "law": "lambert",
    ...                         "sun": [1, 0, 0], "observer": [0, 1, 0]}, None,
    ...                        "x.toml", body)
    >>> len(cfg.shape.faces), cfg.law
    (1280, Lambert(albedo=1.0))
    """
    path = Path(path)
    if not isinstance(table, dict):
        raise _fail(path, "photometry", "expected a table [photometry]")
    unknown = sorted(set(table) - set(_KEYS))
    if unknown:
        raise _fail(path, f"photometry.{unknown[0]}", f"unknown key; allowed: {', '.join(_KEYS)}")

    def key(k):
        return f"photometry.{k}"

    def quantity(value, unit, k):
        try:
            return to_si(value, unit, name=key(k), error=ValueError)
        except ValueError as exc:
            raise _fail(path, key(k), str(exc).split(": ", 1)[-1]) from None

    def step(name, fn, *args):
        # ShapeModelError, PhotometryError, OrbitError -> ScenarioError naming the key
        try:
            return fn(*args)
        except ScenarioError:
            raise
        except AttitudeError as exc:
            inner = exc.key if exc.key in ("sun", "observer") else name
            raise _fail(path, key(inner), exc.reason) from None

    shape = step("shape", _shape, table, path, body, quantity)
    law = step("law", _law, table, path, len(shape.faces))
    geometry = step("sun", _geometry, table, path, quantity)
    cadence = quantity(table["cadence"], "s", "cadence") if "cadence" in table else None
    if cadence is not None and not cadence > 0:
        raise _fail(path, key("cadence"), f"must be positive, got {cadence} s")
    noise = quantity(table.get("noise", 0.0), "mag", "noise")
    if noise < 0:
        raise _fail(path, key("noise"), f"must be >= 0, got {noise} mag")
    periods = table.get("periods", 2)
    if periods not in (1, 2) or isinstance(periods, bool):
        raise _fail(path, key("periods"), f"expected 1 or 2, got {periods!r}")
    order = table.get("order", 4)
    if isinstance(order, bool) or not isinstance(order, int) or not 1 <= order <= 8:
        raise _fail(path, key("order"), f"expected an integer in 1..8, got {order!r}")
    shadows = table.get("shadows", False)
    if not isinstance(shadows, bool):
        raise _fail(path, key("shadows"), f"expected true or false, got {shadows!r}")
    seed = table.get("seed")
    if seed is not None and (isinstance(seed, bool) or not isinstance(seed, int)):
        raise _fail(path, key("seed"), f"expected an integer, got {seed!r}")
    output = table.get("output")
    if output is not None and not isinstance(output, str):
        raise _fail(path, key("output"), "expected a file name")
    return PhotometryConfig(shape=shape, law=law, geometry=geometry, cadence=cadence,
                            noise=noise, seed=seed, shadows=shadows, periods=periods,
                            order=order, output=path.parent / output if output else None,
                            expect=_expect(expect or {}, path))


def _shape(table, path, body, quantity):
    spec = table.get("shape")
    if spec is None:
        raise _fail(path, "photometry.shape", "missing key: \"ellipsoid\" (from the body's "
                                              "moments) or an OBJ file")
    subdivisions = table.get("subdivisions", 3)
    if spec == "ellipsoid":
        if "axes" in table:
            axes = quantity(table["axes"], "m", "axes")
            if np.shape(axes) != (3,):
                raise _fail(path, "photometry.axes", "expected three semi-axes")
            return Polyhedron.ellipsoid(*axes, subdivisions=subdivisions)
        shape = Polyhedron.ellipsoid_from_moments(body.principal_moments,
                                                  subdivisions=subdivisions)
        # principal frame -> body frame (the identity for bodies given by their moments)
        to_body = body.body_to_principal.inv()
        return Polyhedron(to_body.apply(np.array(shape.vertices)), shape.faces)
    if not isinstance(spec, str):
        raise _fail(path, "photometry.shape", "expected \"ellipsoid\" or an OBJ file name")
    return Polyhedron.from_obj(path.parent / spec, length_unit=table.get("length_unit", "m"))


def _law_from(spec, path, where):
    if isinstance(spec, str):
        return scattering_law(spec)
    if isinstance(spec, dict) and "name" in spec:
        params = {k: v for k, v in spec.items() if k != "name"}
        return scattering_law(spec["name"], **params)
    raise _fail(path, where, "expected a law name or { name = \"...\", parameters }")


def _law(table, path, n_faces):
    law = _law_from(table.get("law", "lommel-seeliger"), path, "photometry.law")
    materials = table.get("materials")
    if materials is None:
        return law
    if not isinstance(materials, list):
        raise _fail(path, "photometry.materials", "expected a list of { faces = [start, "
                                                  "stop], law = ... }")
    laws, index = [law], np.zeros(n_faces, dtype=int)
    for k, item in enumerate(materials):
        where = f"photometry.materials[{k}]"
        if not isinstance(item, dict) or set(item) != {"faces", "law"}:
            raise _fail(path, where, "expected { faces = [start, stop], law = ... }")
        faces = item["faces"]
        if not (isinstance(faces, list) and len(faces) == 2
                and all(isinstance(x, int) for x in faces)
                and 0 <= faces[0] < faces[1] <= n_faces):
            raise _fail(path, f"{where}.faces", f"expected [start, stop] with 0 <= start < "
                                                f"stop <= {n_faces} (face indices)")
        laws.append(_law_from(item["law"], path, f"{where}.law"))
        index[faces[0]:faces[1]] = len(laws) - 1
    return FacetMaterials(laws, index)


def _geometry(table, path, quantity):
    if "orbit" in table:
        orbit = table["orbit"]
        if not isinstance(orbit, dict):
            raise _fail(path, "photometry.orbit", "expected { mu = ..., a = ..., e = ... }")
        try:
            kepler = KeplerOrbit.from_elements(**orbit)
        except TypeError:
            raise _fail(path, "photometry.orbit", "allowed keys: mu, a, e, i, raan, argp, "
                                                  "mean_anomaly") from None
        except AttitudeError as exc:
            raise _fail(path, f"photometry.orbit.{exc.key}", exc.reason) from None
        observer = table.get("observer", "earth")
        if not isinstance(observer, str):
            raise _fail(path, "photometry.observer", "with an orbit the observer is "
                                                     "\"earth\" or \"sun\"")
        return {"orbit": kepler, "observer": observer,
                "light_time": bool(table.get("light_time", True))}
    for k in ("sun", "observer"):
        if k not in table:
            raise _fail(path, f"photometry.{k}", "missing key: give sun and observer "
                                                 "vectors, or an orbit")
    Geometry(sun=table["sun"], observer=table["observer"])        # validates
    return {"sun": table["sun"], "observer": table["observer"]}


def _expect(expect, path):
    parsed = []
    for name in EXPECT_KEYS:
        if name not in expect:
            continue
        spec = expect[name]
        where = f"expect.{name}"
        if not isinstance(spec, dict) or "value" not in spec \
                or ("rel_tol" in spec) == ("abs_tol" in spec) \
                or set(spec) - {"value", "unit", "rel_tol", "abs_tol"}:
            raise _fail(path, where, "expected { value = ..., unit = ..., rel_tol = ... } "
                                     "(or abs_tol)")
        unit = spec.get("unit", "mag" if name == "lightcurve_amplitude" else "s")
        try:
            value = np.asarray(spec["value"], dtype=float)
            scale = u.Unit(unit).to(u.mag if name == "lightcurve_amplitude" else u.s)
        except (TypeError, ValueError, u.UnitsError) as exc:
            raise _fail(path, where, f"bad value or unit ({exc})") from None
        if (name == "lightcurve_lattice") != (value.ndim == 1):
            raise _fail(path, f"{where}.value", "a list of periods for lightcurve_lattice, "
                                                "a number otherwise")
        parsed.append({"key": name, "expected": value.tolist(), "unit": unit,
                       "scale": scale, "rel_tol": spec.get("rel_tol"),
                       "abs_tol": spec.get("abs_tol")})
    return tuple(parsed)


@dataclass(frozen=True, eq=False)
class LightcurveRun:
    """What ``attitude lightcurve`` computed.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from attitude.app.scenario import load_scenario
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "spin.toml"
    >>> _ = path.write_text('''
    ... [body]
    ... principal_moments = [1.0, 2.0, 2.5]
    ... [state]
    ... epoch = "2024-01-01"
    ... omega_body = { value = [0, 0, 1], unit = "cycle/h" }
    ... [propagation]
    ... duration = "3 h"
    ... step = "2 min"
    ... [photometry]
    ... shape = "ellipsoid"
    ... subdivisions = 1
    ... law = "lambert"
    ... sun = [1.0, 0.0, 0.3]
    ... observer = [1.0, 0.2, 0.3]
    ... periods = 1
    ... order = 2
    ... [expect]
    ... lightcurve_period = { value = 1.0, unit = "h", rel_tol = 1e-3 }
    ... ''')
    >>> sc = load_scenario(path)          # a triaxial ellipsoid spinning once an hour
    >>> run = run_lightcurve(sc, sc.photometry)
    >>> run.ok, run.outputs
    (True, [])
    >>> report = run.report()
    >>> round(report["lightcurve_period_h"], 3), bool(report["amplitude_mag"] > 0.1)
    (1.0, True)
    """

    lightcurve: Lightcurve
    fit: PeriodFit
    expect: list = field(default_factory=list)
    outputs: list = field(default_factory=list)
    diagnosis: Any = None

    @property
    def ok(self) -> bool:
        return all(e["ok"] for e in self.expect)

    def report(self) -> dict:
        """JSON-ready summary."""
        out = {"periods_h": [float(p) / 3600 for p in self.fit.periods],
               "uncertainties_h": [float(p) / 3600 for p in self.fit.uncertainties],
               "lightcurve_period_h": self.fit.lightcurve_period / 3600,
               "amplitude_mag": self.lightcurve.amplitude(),
               "strongest_term": list(self.fit.strongest), "note": self.fit.note,
               "expect": self.expect, "outputs": [str(p) for p in self.outputs]}
        return json.loads(json.dumps(out, default=float))


def run_lightcurve(scenario, config: PhotometryConfig, *, output=None,
                   write: bool = True) -> LightcurveRun:
    """Propagate, render, fit and check a scenario's lightcurve.

    Parameters
    ----------
    scenario : Scenario
    config : PhotometryConfig
    output : path, optional
        Overrides ``[photometry].output``.
    write : bool
        Write the netCDF file (when an output is set).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from attitude.app.scenario import load_scenario
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "spin.toml"
    >>> _ = path.write_text('''
    ... [body]
    ... principal_moments = [1.0, 2.0, 2.5]
    ... [state]
    ... epoch = "2024-01-01"
    ... omega_body = { value = [0, 0, 1], unit = "cycle/h" }
    ... [propagation]
    ... duration = "3 h"
    ... step = "2 min"
    ... [photometry]
    ... shape = "ellipsoid"
    ... subdivisions = 1
    ... law = "lambert"
    ... sun = [1.0, 0.0, 0.3]
    ... observer = [1.0, 0.2, 0.3]
    ... periods = 1
    ... order = 2
    ... [expect]
    ... lightcurve_period = { value = 1.0, unit = "h", rel_tol = 1e-3 }
    ... ''')
    >>> sc = load_scenario(path)          # a triaxial ellipsoid spinning once an hour
    >>> run = run_lightcurve(sc, sc.photometry, output=path.with_suffix(".nc"))
    >>> bool(abs(run.fit.lightcurve_period / 3600.0 - 1.0) < 1e-3)  # the rotation period
    True
    >>> run.outputs[0].name, len(run.lightcurve.magnitude)
    ('spin.nc', 91)
    """
    step = config.cadence or scenario.step
    times = np.arange(0.0, scenario.duration + 0.5 * step, step)
    times = times[times <= scenario.duration * (1 + 1e-12)]
    eph = propagate(scenario.body, scenario.state, times,
                    torques=list(scenario.torques) or None)
    g = config.geometry
    if "orbit" in g:
        geom = Geometry.from_orbit(g["orbit"], times, g["observer"], epoch=scenario.state.epoch,
                                   frame=eph.frame, light_time=g["light_time"])
    else:
        geom = Geometry(sun=g["sun"], observer=g["observer"])
    lc = lightcurve(eph, config.shape, geom, config.law, shadows=config.shadows)
    if config.noise > 0:
        rng = np.random.default_rng(config.seed)
        ds = lc.dataset.copy()
        ds["magnitude"] = ds.magnitude + rng.normal(0.0, config.noise, ds.sizes["time"])
        ds["magnitude_error"] = ("time", np.full(ds.sizes["time"], config.noise),
                                 {"units": "mag", "long_name": "1-sigma magnitude noise"})
        lc = Lightcurve(ds)
    fit = fit_periods(times, lc.magnitude, sigma=config.noise or None,
                      n_periods=config.periods, order=config.order)
    expect = check_lightcurve(config.expect, fit, lc)
    outputs = []
    target = Path(output) if output else config.output
    if write and target is not None:
        outputs.append(lc.to_netcdf(target))
    return LightcurveRun(lightcurve=lc, fit=fit, expect=expect, outputs=outputs)


def check_lightcurve(specs, fit: PeriodFit, lc: Lightcurve) -> list[dict]:
    """Compare the lightcurve expectations with the fit.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from attitude.app.scenario import load_scenario
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "spin.toml"
    >>> _ = path.write_text('''
    ... [body]
    ... principal_moments = [1.0, 2.0, 2.5]
    ... [state]
    ... epoch = "2024-01-01"
    ... omega_body = { value = [0, 0, 1], unit = "cycle/h" }
    ... [propagation]
    ... duration = "3 h"
    ... step = "2 min"
    ... [photometry]
    ... shape = "ellipsoid"
    ... subdivisions = 1
    ... law = "lambert"
    ... sun = [1.0, 0.0, 0.3]
    ... observer = [1.0, 0.2, 0.3]
    ... periods = 1
    ... order = 2
    ... [expect]
    ... lightcurve_period = { value = 1.0, unit = "h", rel_tol = 1e-3 }
    ... ''')
    >>> sc = load_scenario(path)          # a triaxial ellipsoid spinning once an hour
    >>> run = run_lightcurve(sc, sc.photometry, write=False)
    >>> spec = dict(sc.photometry.expect[0], expected=1.1)   # a wrong period: 1.1 h
    >>> [(r["key"], r["ok"]) for r in check_lightcurve([spec], run.fit, run.lightcurve)]
    [('lightcurve_period', False)]
    """
    results = []
    for spec in specs:
        name, scale = spec["key"], spec["scale"]
        expected = spec["expected"]
        out = {"key": name, "expected": expected, "unit": spec["unit"]}
        if name == "lightcurve_lattice":
            # the largest relative distance of the listed frequencies from the lattice
            errors = [lattice_combination(1.0 / (p * scale), *fit.frequencies,
                                          max_order=fit.order)[2]
                      for p in expected] if fit.n_periods == 2 else [np.inf]
            tol = spec["rel_tol"] if spec["rel_tol"] is not None else np.inf
            out.update(expected=0.0, unit="(relative distance from the lattice)",
                       periods=expected, period_unit=spec["unit"], got=float(max(errors)),
                       tolerance=float(tol), ok=bool(max(errors) <= tol))
        else:
            got = fit.lightcurve_period / scale if name == "lightcurve_period" \
                else lc.amplitude() / scale
            tol = spec["abs_tol"] if spec["abs_tol"] is not None \
                else spec["rel_tol"] * abs(expected)
            out.update(got=float(got), tolerance=float(tol),
                       ok=bool(abs(got - expected) <= tol))
        results.append(out)
    return results

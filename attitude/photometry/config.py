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
from attitude.foundations.expectation import Expectation
from attitude.foundations.spec import Key, Table, validate
from attitude.model.orbit import KeplerOrbit
from attitude.model.shape import Polyhedron
from attitude.photometry.brightness import lightcurve
from attitude.photometry.dataset import Lightcurve
from attitude.photometry.geometry import Geometry
from attitude.photometry.periods import PeriodFit, fit_periods, lattice_combination
from attitude.photometry.scattering import FacetMaterials, scattering_law
from attitude.propagation.propagator import propagate

#: A scattering law: a name, or ``{ name = "hapke", parameters... }`` (checked by
#: :func:`attitude.photometry.scattering.scattering_law`).
_LAW_SCHEMA = {"oneOf": [{"type": "string"},
                         {"type": "object", "required": ["name"]}]}

#: One of ``[photometry] materials``: a range of faces with its own law.
MATERIAL = Table("material", (
    Key("faces", "any", required=True,
        schema={"type": "array", "items": {"type": "integer"}, "minItems": 2, "maxItems": 2},
        doc="[start, stop): face indices"),
    Key("law", "any", required=True, schema=_LAW_SCHEMA, doc="the faces' scattering law"),
))

#: The target's heliocentric orbit, ``orbit = { mu = ..., a = ..., e = ..., ... }``
#: (:meth:`attitude.model.orbit.KeplerOrbit.from_elements`).
ORBIT = Table("orbit", (
    Key("mu", "quantity", unit="m3/s2", required=True, positive=True,
        doc="gravitational parameter of the Sun (1.32712440018e20 m3/s2)"),
    Key("a", "quantity", unit="m", required=True, positive=True, doc="semi-major axis"),
    Key("e", "quantity", unit="", bounds=(0.0, None), default=0, doc="eccentricity, < 1"),
    Key("i", "quantity", unit="rad", default=0, doc="inclination"),
    Key("raan", "quantity", unit="rad", default=0, doc="longitude of the ascending node"),
    Key("argp", "quantity", unit="rad", default=0, doc="argument of periapsis"),
    Key("mean_anomaly", "quantity", unit="rad", default=0, doc="at the [state] epoch"),
), doc="Keplerian elements in the inertial frame of the state")

#: The ``[photometry]`` table (in :data:`attitude.app.scenario_spec.SCENARIO`; read by
#: :func:`parse_photometry`, which also checks what a table cannot say: files, laws,
#: directions).
PHOTOMETRY = Table("photometry", (
    Key("shape", "string", required=True,
        doc="\"ellipsoid\" (from the body's moments, or axes) or an OBJ file"),
    Key("axes", "quantity", unit="m", shape=(3,), positive=True,
        doc="shape = \"ellipsoid\": explicit semi-axes"),
    Key("length_unit", "unit", unit="m", default="m", doc="of the OBJ coordinates"),
    Key("subdivisions", "integer", bounds=(0, 8), default=3,
        doc="ellipsoid mesh: 20 * 4**n faces"),
    Key("law", "any", schema=_LAW_SCHEMA, default="lommel-seeliger",
        doc="scattering law: a name or { name = ..., parameters } (docs/photometry.md)"),
    Key("materials", "tables", table=MATERIAL,
        doc="face ranges with their own law (spacecraft)"),
    Key("sun", "quantity", unit="", shape=(3,),
        doc="fixed direction body -> Sun, inertial frame of the state"),
    Key("observer", "any", schema={"oneOf": [
        {"type": "array", "items": {"type": "number"}, "minItems": 3, "maxItems": 3},
        {"enum": ["earth", "sun"]}]},
        doc="fixed direction body -> observer; with an orbit \"earth\" (default) or "
            "\"sun\""),
    Key("orbit", "table", table=ORBIT,
        doc="the target's heliocentric orbit (geometry per epoch)"),
    Key("light_time", "boolean", default=True, doc="with an orbit: light-time corrected"),
    Key("cadence", "quantity", unit="s", positive=True,
        doc="sampling; default [propagation].step"),
    Key("noise", "quantity", unit="mag", nonnegative=True,
        doc="Gaussian noise added to the magnitudes; default none"),
    Key("seed", "integer", doc="of the noise"),
    Key("shadows", "boolean", default=False),
    Key("periods", "integer", choices=(1, 2), default=2,
        doc="1: Lomb-Scargle with harmonics; 2: Pravec et al. 2005"),
    Key("order", "integer", bounds=(1, 8), default=4, doc="Fourier order of the fit"),
    Key("output", "string", doc="netCDF of the lightcurve, relative to the scenario file"),
), doc="photometry (attitude lightcurve): shape, scattering law, geometry, cadence; see "
       "docs/photometry.md")

#: The lightcurve ``[expect]`` keys (in :data:`attitude.app.scenario_spec.SCENARIO`; read by
#: :func:`parse_photometry`).
EXPECT = (
    Key("lightcurve_period", "table", table=Expectation.table(
        "lightcurve_period", unit="s", default_unit="s"),
        doc="photometry: the double-peaked lightcurve period"),
    Key("lightcurve_amplitude", "table", table=Expectation.table(
        "lightcurve_amplitude", unit="mag", default_unit="mag"),
        doc="photometry: peak-to-peak amplitude"),
    Key("lightcurve_lattice", "table", table=Table("lightcurve_lattice", (
        Key("value", "any", required=True, schema={
            "type": "array", "items": {"type": "number"}, "minItems": 1},
            doc="periods"),
        Key("unit", "unit", unit="s", default="s"),
        Key("rel_tol", "number", required=True, nonnegative=True,
            doc="largest relative distance of a frequency from the lattice"))),
        doc="photometry: periods whose frequencies lie on the fitted lattice n1/P1 + n2/P2 "
            "within rel_tol"),
)

__all__ = ["PhotometryConfig", "LightcurveRun", "parse_photometry", "run_lightcurve",
           "check_lightcurve", "EXPECT", "EXPECT_KEYS", "PHOTOMETRY", "MATERIAL",
           "ORBIT"]

#: The lightcurve keys of ``[expect]``.
EXPECT_KEYS = tuple(k.name for k in EXPECT)
#: The unit the run's value of each lightcurve key is computed in.
_SI = {"lightcurve_period": u.s, "lightcurve_amplitude": u.mag, "lightcurve_lattice": u.s}


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
    >>> cfg.expect[0].key, cfg.expect[0].value, cfg.expect[0].unit
    ('lightcurve_period', 1.0, 'h')
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
    table = validate(table, PHOTOMETRY, where="photometry", path=str(path),
                     error=ScenarioError)

    def key(k):
        return f"photometry.{k}"

    def step(name, fn, *args):
        # ShapeModelError, PhotometryError, OrbitError -> ScenarioError naming the key
        try:
            return fn(*args)
        except ScenarioError:
            raise
        except AttitudeError as exc:
            inner = exc.key if exc.key in ("sun", "observer") else name
            raise _fail(path, key(inner), exc.reason) from None

    shape = step("shape", _shape, table, path, body)
    law = step("law", _law, table, path, len(shape.faces))
    geometry = step("sun", _geometry, table, path)
    output = table.get("output")
    return PhotometryConfig(shape=shape, law=law, geometry=geometry,
                            cadence=table.get("cadence"), noise=table.get("noise", 0.0),
                            seed=table.get("seed"), shadows=table.get("shadows", False),
                            periods=table.get("periods", 2), order=table.get("order", 4),
                            output=path.parent / output if output else None,
                            expect=_expect(expect or {}, path))


def _shape(table, path, body):
    spec = table["shape"]
    subdivisions = table.get("subdivisions", 3)
    if spec == "ellipsoid":
        if "axes" in table:
            return Polyhedron.ellipsoid(*table["axes"], subdivisions=subdivisions)
        shape = Polyhedron.ellipsoid_from_moments(body.principal_moments,
                                                  subdivisions=subdivisions)
        # principal frame -> body frame (the identity for bodies given by their moments)
        to_body = body.body_to_principal.inv()
        return Polyhedron(to_body.apply(np.array(shape.vertices)), shape.faces)
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
    laws, index = [law], np.zeros(n_faces, dtype=int)
    for k, item in enumerate(materials):
        where = f"photometry.materials[{k}]"
        faces = item["faces"]
        if not (isinstance(faces, list) and len(faces) == 2
                and all(isinstance(x, int) for x in faces)
                and 0 <= faces[0] < faces[1] <= n_faces):
            raise _fail(path, f"{where}.faces", f"expected [start, stop] with 0 <= start < "
                                                f"stop <= {n_faces} (face indices)")
        laws.append(_law_from(item["law"], path, f"{where}.law"))
        index[faces[0]:faces[1]] = len(laws) - 1
    return FacetMaterials(laws, index)


def _geometry(table, path):
    if "orbit" in table:
        try:
            kepler = KeplerOrbit.from_elements(**table["orbit"])
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


def _expect(expect, path) -> tuple[Expectation, ...]:
    """The lightcurve keys of an ``[expect]`` table as expectations."""
    mine = {k: v for k, v in expect.items() if k in EXPECT_KEYS}
    checked = validate(mine, Table("expect", EXPECT), where="expect", path=str(path),
                       error=ScenarioError)
    lattice = checked.get("lightcurve_lattice", {}).get("value", [1.0])
    if not (isinstance(lattice, list) and lattice and all(
            isinstance(p, (int, float)) and not isinstance(p, bool) and np.isfinite(p)
            and p > 0 for p in lattice)):
        raise _fail(path, "expect.lightcurve_lattice.value",
                    f"expected a list of periods (positive numbers), got {lattice!r}"[:200])
    default = {"lightcurve_amplitude": "mag"}
    return tuple(Expectation.from_table(k, checked[k], default_unit=default.get(k, "s"))
                 for k in EXPECT_KEYS if k in checked)


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
    >>> import dataclasses
    >>> wrong = dataclasses.replace(sc.photometry.expect[0], value=1.1)   # 1.1 h
    >>> [(r["key"], r["ok"]) for r in check_lightcurve([wrong], run.fit, run.lightcurve)]
    [('lightcurve_period', False)]
    """
    results = []
    for e in specs:
        scale = u.Unit(e.unit).to(_SI[e.key])
        if e.key == "lightcurve_lattice":
            # the largest relative distance of the listed frequencies from the lattice
            errors = [lattice_combination(1.0 / (p * scale), *fit.frequencies,
                                          max_order=fit.order)[2]
                      for p in e.value] if fit.n_periods == 2 else [np.inf]
            distance = Expectation(e.key, 0.0, "(relative distance from the lattice)",
                                   abs_tol=float(e.rel_tol),
                                   reported=(("periods", list(e.value)),
                                             ("period_unit", e.unit)))
            results.append(distance.check(float(max(errors))))
        else:
            got = fit.lightcurve_period if e.key == "lightcurve_period" else lc.amplitude()
            results.append(e.check(float(got / scale)))
    return results

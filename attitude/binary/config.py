"""The binary scenario file: ``[binary]``, its bodies, orbit and impulses, and ``[expect]``.

A binary starts from two bodies and their mutual orbit, so its scenario file holds a
``[scenario]`` table, a ``[binary]`` table (with ``[binary.primary]``,
``[binary.secondary]``, ``[binary.orbit]`` and any number of ``[[binary.impulse]]``) and
optionally ``[expect]``::

    [scenario]
    name = "Didymos-Dimorphos"

    [binary]
    epoch = "2022-09-26T23:14:00"
    time_scale = "utc"
    duration = "2 d"
    output_step = "10 min"
    order = 2
    method = "lgvi"               # at `step` (default: 1/200 of the shortest period); or
                                  # "integrator" (DOP853 at `rtol`, default 1e-10)
    synchronous = true            # the secondary locked: long axis to the primary

    [binary.primary]
    primitive = "ellipsoid"       # or "sphere" with radius, or shape = "x.obj" + density
    mass = "5.3e11 kg"
    semi_axes = [394.0, 394.0, 290.0]
    spin_period = "2.26 h"        # about the axis of largest moment; or omega (body frame)

    [binary.secondary]
    primitive = "ellipsoid"
    mass = "4.3e9 kg"
    semi_axes = [89.5, 84.5, 57.5]

    [binary.orbit]
    semi_major_axis = "1.19 km"   # and eccentricity, inclination, raan, argp,
                                  # mean_anomaly; or position and velocity

    [[binary.impulse]]
    time = "1 d"                  # since the epoch; or epoch = "2022-09-27T23:14:00"
    body = "secondary"
    beta = 3.61                   # the DART form; or delta_v = [...]
    impactor_mass = "580 kg"
    impactor_velocity = { value = [0.0, -6145.0, 0.0], unit = "m/s" }

    [expect]
    period_change = { value = -33.0, unit = "min", abs_tol = 2.0 }
    secondary_regime = "librating"

The bodies' frames are their shapes' or primitives' own axes (a primitive's x, y, z are
its semi-axes' directions); positions are centre of mass to centre of mass, the
secondary's relative to the primary's, in the inertial frame ``frame``.

**Impulses.**  ``delta_v`` is the body's velocity change.  The DART form gives it from
the impactor's momentum (Cheng et al. 2023, Nature 616, 457, their eq. 1):
``M dv = m U + m (beta - 1) (E . U) E`` with ``M`` the body's mass, ``m``, ``U`` the
impactor's mass and velocity relative to the body, ``E`` the unit direction of the net
ejecta momentum (``ejecta_direction``).  Without ``ejecta_direction`` the ejecta are taken
to leave along the impactor's direction, the common simplification
``dv = beta m U / M``.

**Synchronous start.**  ``synchronous = true`` turns the secondary so that its long axis
(smallest moment) points to the primary and its axis of largest moment along the orbit
normal, spinning at the orbit's angular rate ``|R x V| / |R|^2`` about it.
``circular = true`` in ``[binary.orbit]`` sets the initial speed to that of a circular
orbit in the mutual force of the two bodies (not the point masses'), along the velocity's
direction: a Keplerian circular speed about an oblate primary starts a slightly eccentric
orbit, and with it a forced libration.

**Ensembles.**  ``[binary.ensemble]`` runs ``n`` variants of the system
(:func:`attitude.binary.ensemble`): each is the file's values with the keys of ``sigma``
(``"table.key"``: :data:`SAMPLED`) drawn from normals about them (``seed``; each
semi-axis its own draw; ``impulse.*`` for every impulse in the DART form), a draw that
makes no valid system counts as bad input (status 1).  ``[expect.regime_fractions]``
(only with it, and the only expectation it takes) checks each regime's share::

    [binary.ensemble]
    n = 100
    seed = 1
    sigma = { "impulse.beta" = 0.2, "primary.mass" = "1e10 kg" }
    client = "local"              # optional: a dask LocalCluster, or a scheduler address

    [expect.regime_fractions]
    librating = { value = 1.0, abs_tol = 0.05 }

:func:`run_binary` propagates it (:func:`attitude.propagate`), diagnoses it
(:func:`attitude.binary.diagnostics.diagnose`), checks ``[expect]`` and writes the netCDF
ephemeris.
"""

from __future__ import annotations

import copy
import dataclasses
import json
import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import astropy.units as u
import numpy as np
from scipy.spatial.transform import Rotation

from attitude.binary.diagnostics import REGIMES, diagnose, period_change
from attitude.binary.dynamics import mutual_forces
from attitude.binary.ensembles import ensemble as run_ensemble
from attitude.binary.propagate import METHODS as AVAILABLE_METHODS
from attitude.binary.propagate import propagate_binary
from attitude.binary.system import BinaryState, BinarySystem, Impulse, impact_delta_v
from attitude.foundations.errors import AttitudeError, ScenarioError
from attitude.foundations.expectation import Expectation
from attitude.foundations.quantities import TIME_SCALES
from attitude.foundations.spec import Key, Table, markdown, validate
from attitude.model.body import MassProperties, RigidBody
from attitude.model.ephemeris import write_atomically
from attitude.model.orbit import KeplerOrbit
from attitude.model.state import ATTITUDE_TABLE, rotation_from_table

__all__ = ["BINARY", "EXPECT", "BinaryScenario", "BinaryRun", "is_binary", "load_binary",
           "binary_reference",
           "run_binary", "impact_delta_v"]

#: Longest run, in Keplerian orbits (about a day of DOP853 here).
MAX_ORBITS = 1e5

#: Methods a ``[binary]`` table may name (:func:`attitude.binary.propagate_binary`'s).
METHODS = AVAILABLE_METHODS
#: DOP853's tolerance when ``method = "integrator"`` gives none.
DEFAULT_RTOL = 1e-10

#: An attitude (body -> inertial): a quaternion or Euler angles (the single-body
#: scenario's form, declared once in the model layer).
ROTATION = ATTITUDE_TABLE


def _body_table(name: str) -> Table:
    return Table(name, (
        Key("name", "string", doc="label"),
        Key("shape", "string", doc="OBJ shape model, relative to the scenario file"),
        Key("density", "quantity", unit="kg/m3", positive=True, doc="bulk density of `shape`"),
        Key("length_unit", "unit", unit="m", default="m",
            doc="unit of the vertex coordinates of `shape`"),
        Key("primitive", "string", choices=("ellipsoid", "sphere"),
            doc="a homogeneous solid ellipsoid (semi_axes) or sphere (radius)"),
        Key("mass", "quantity", unit="kg", positive=True, doc="of the primitive"),
        Key("semi_axes", "quantity", unit="m", shape=(3,), positive=True,
            doc="ellipsoid: along the body's x, y, z"),
        Key("radius", "quantity", unit="m", positive=True, doc="sphere"),
        Key("principal_moments", "quantity", unit="kg m2", shape=(3,), positive=True,
            doc="a body known by its moments and mass (order 2 only); body frame = "
                "principal frame"),
        Key("attitude", "table", table=ROTATION, doc="body -> inertial; default identity"),
        Key("spin_period", "quantity", unit="s", positive=True,
            doc="spin about the axis of largest moment"),
        Key("omega", "quantity", unit="rad/s", shape=(3,), doc="body-frame angular velocity"),
    ), exactly_one=(("shape", "primitive", "principal_moments"),),
        at_most_one=(("spin_period", "omega"),),
        needs=(("shape", ("density",)), ("primitive", ("mass",)),
               ("principal_moments", ("mass",)),
               ("density", ("shape",)), ("length_unit", ("shape",))),
        excludes=(("shape", ("mass", "semi_axes", "radius")),),
        doc="A homogeneous body: a shape model and its density, or a primitive and its "
            "mass; or (order 2) principal moments and a mass.")


ORBIT = Table("orbit", (
    Key("semi_major_axis", "quantity", unit="m", positive=True),
    Key("eccentricity", "number", default=0.0, bounds=(0.0, None)),
    Key("inclination", "quantity", unit="rad", default=0.0),
    Key("raan", "quantity", unit="rad", default=0.0, doc="longitude of the ascending node"),
    Key("argp", "quantity", unit="rad", default=0.0, doc="argument of periapsis"),
    Key("mean_anomaly", "quantity", unit="rad", default=0.0, doc="at the epoch"),
    Key("position", "quantity", unit="m", shape=(3,),
        doc="the secondary relative to the primary, inertial"),
    Key("velocity", "quantity", unit="m/s", shape=(3,)),
    Key("circular", "boolean", default=False,
        doc="the speed of a circular orbit in the mutual force, along the velocity"),
), exactly_one=(("semi_major_axis", "position"),),
    needs=(("position", ("velocity",)), ("velocity", ("position",))),
    excludes=(("position", ("eccentricity", "inclination", "raan", "argp",
                            "mean_anomaly")),),
    doc="The mutual orbit at the epoch: Keplerian elements with mu = G (m1 + m2), or the "
        "relative position and velocity.")

IMPULSE = Table("impulse", (
    Key("time", "quantity", unit="s", nonnegative=True, doc="since the epoch"),
    Key("epoch", "time", doc="ISO 8601, in `time_scale` (default: [binary]'s)"),
    Key("time_scale", "string", choices=TIME_SCALES + tuple(s.upper() for s in TIME_SCALES)),
    Key("body", "string", choices=("primary", "secondary"), default="secondary"),
    Key("delta_v", "quantity", unit="m/s", shape=(3,), doc="the body's velocity change"),
    Key("beta", "number", positive=True, default=1.0, doc="momentum enhancement factor"),
    Key("impactor_mass", "quantity", unit="kg", positive=True),
    Key("impactor_velocity", "quantity", unit="m/s", shape=(3,),
        doc="relative to the body, inertial"),
    Key("ejecta_direction", "quantity", unit="", shape=(3,),
        doc="net ejecta momentum direction (default: the impactor's)"),
    Key("angular_impulse", "quantity", unit="kg m2/s", shape=(3,),
        doc="added to the body's angular momentum, inertial"),
), exactly_one=(("time", "epoch"), ("delta_v", "impactor_velocity")),
    needs=(("impactor_velocity", ("impactor_mass",)), ("impactor_mass", ("impactor_velocity",)),
           ("beta", ("impactor_velocity",)), ("ejecta_direction", ("impactor_velocity",))),
    doc="A sudden change: delta_v, or the DART form M dv = m U + m (beta - 1) (E.U) E.")

#: The keys ``[binary.ensemble] sigma`` may draw (as ``"table.key"``) and their units.
SAMPLED = {"primary.mass": "kg", "secondary.mass": "kg", "primary.semi_axes": "m",
           "secondary.semi_axes": "m", "primary.spin_period": "s",
           "orbit.semi_major_axis": "m", "orbit.eccentricity": "", "impulse.beta": "",
           "impulse.impactor_mass": "kg"}
ENSEMBLE = Table("ensemble", (
    Key("n", "integer", required=True, bounds=(1, 1_000_000), doc="members"),
    Key("seed", "integer", default=0, doc="of the normal draws"),
    Key("chaos", "boolean", default=False, doc="each member's Lyapunov exponent"),
    Key("chunk_size", "integer", bounds=(1, None), doc="members per dask task"),
    Key("client", "string", doc='"local" or a dask scheduler address; default: in process'),
    Key("sigma", "table", required=True, table=Table("sigma", tuple(
        Key(k, "quantity", unit=u, nonnegative=True, shape=((), (3,)) if "axes" in k
            else ()) for k, u in SAMPLED.items())),
        doc='standard deviations of the drawn keys, e.g. { "impulse.beta" = 0.2 }; each '
            "member is the file's values plus sigma times a normal draw (each semi-axis "
            "its own)"),
))

BINARY = Table("binary", (
    Key("epoch", "time", required=True, doc="ISO 8601, in `time_scale`"),
    Key("time_scale", "string", choices=TIME_SCALES + tuple(s.upper() for s in TIME_SCALES),
        default="tdb"),
    Key("frame", "string", default="ICRF", doc="inertial frame label"),
    Key("duration", "quantity", unit="s", required=True, positive=True),
    Key("output_step", "quantity", unit="s", required=True, positive=True),
    Key("order", "integer", default=2, bounds=(2, 12), doc="of the mutual potential"),
    Key("method", "string", choices=METHODS, default="lgvi",
        doc="lgvi: the Lie-group variational integrator at fixed steps; integrator: "
            "DOP853 at rtol"),
    Key("step", "quantity", unit="s", positive=True,
        doc="lgvi: the longest step (default 1/200 of the shortest of the orbit and spin "
            "periods)"),
    Key("rtol", "number", positive=True, bounds=(None, 1.0),
        doc="integrator: DOP853's tolerance (default 1e-10)"),
    Key("synchronous", "boolean", default=False,
        doc="start the secondary locked: long axis to the primary, spin = orbital rate"),
    Key("output", "string", doc="netCDF ephemeris, relative to the scenario file"),
    Key("primary", "table", table=_body_table("primary"), required=True),
    Key("secondary", "table", table=_body_table("secondary"), required=True),
    Key("orbit", "table", table=ORBIT, required=True),
    Key("impulse", "tables", table=IMPULSE, doc="any number of [[binary.impulse]]"),
    Key("ensemble", "table", table=ENSEMBLE,
        doc="run n variants of the system, the keys of `sigma` drawn from normals"),
))

SCENARIO = Table("scenario", (
    Key("name", "string"),
    Key("description", "string"),
))

_BOUND = Table("bound", (Key("max", "number", required=True, nonnegative=True),))
#: ``[expect]`` of a binary scenario: periods, the libration, the regime, the period
#: change across the first impulse, and the conservation bounds.
EXPECT = Table("expect", (
    *(Key(k, "table", table=Expectation.table(k, unit="s", default_unit="s"), doc=d)
      for k, d in (("orbit_period", "sidereal, from the separation"),
                   ("osculating_period", "Kepler's, at the first sample"),
                   ("libration_period", "of the secondary's libration angle"),
                   ("primary_spin_period", "2 pi / mean |w1|"),
                   ("secondary_spin_period", "2 pi / mean |w2|"),
                   ("period_change", "orbit period after the first impulse minus before"))),
    Key("libration_amplitude", "table", table=Expectation.table(
        "libration_amplitude", unit="rad", default_unit="rad")),
    Key("apsidal_rate", "table", table=Expectation.table(
        "apsidal_rate", unit="rad/s", default_unit="rad/s")),
    Key("lyapunov_exponent", "table", table=Expectation.table(
        "lyapunov_exponent", unit="1/s", default_unit="1/s"),
        doc="finite-time, of the whole run (it and secondary_regime = 'chaotic' make the "
            "run measure it: attitude.binary.chaos)"),
    Key("secondary_regime", "string", choices=REGIMES),
    Key("regime_fractions", "table", table=Table("regime_fractions", tuple(
        Key(r, "table", table=Expectation.table(r, unit="", with_unit=False))
        for r in REGIMES)), doc="[binary.ensemble]: each regime's share of the members"),
    *(Key(k, "table", table=_BOUND, doc="largest relative change between impulses")
      for k in ("energy_rel_drift", "angular_momentum_rel_drift")),
))

#: ``[expect]`` keys measured in time, and their default units.
_TIME_KEYS = ("orbit_period", "osculating_period", "libration_period",
              "primary_spin_period", "secondary_spin_period", "period_change")


def is_binary(document: dict) -> bool:
    """Whether a parsed scenario file is a binary (it has a ``[binary]`` table).

    Examples
    --------
    >>> is_binary({"binary": {}}), is_binary({"body": {}})
    (True, False)
    """
    return isinstance(document.get("binary"), dict)


@dataclass(frozen=True, eq=False)
class BinaryScenario:
    """A binary scenario file, validated and built: the system, its initial state, the
    impulses, the output times, the expectations (:func:`load_binary` makes one).

    Examples
    --------
    >>> BinaryScenario.__dataclass_fields__["impulses"].type
    'tuple'
    """

    path: Path
    name: str
    system: BinarySystem
    state: BinaryState
    impulses: tuple
    times: np.ndarray
    method: str
    rtol: float | None
    step: float | None
    expect: tuple
    output: Path | None
    note: str = ""
    ensemble: dict | None = None


def _fail(path, key, message) -> ScenarioError:
    return ScenarioError(message, path=str(path), key=key)


def load_binary(path) -> BinaryScenario:
    """Read, validate and build a binary scenario file (nothing is propagated).

    Raises
    ------
    ScenarioError
        On a file that cannot be read or parsed, a key that is missing, unknown or of the
        wrong type, bodies that overlap, an orbit that is not bound where one is needed,
        an impulse outside the run (the message names the file and the key).

    Examples
    --------
    >>> import pathlib, tempfile
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "b.toml"
    >>> _ = path.write_text('''
    ... [binary]
    ... epoch = "2026-12-01"
    ... duration = "1 d"
    ... output_step = "1 h"
    ... synchronous = true
    ... [binary.primary]
    ... primitive = "sphere"
    ... mass = 5.2e11
    ... radius = 390.0
    ... [binary.secondary]
    ... primitive = "ellipsoid"
    ... mass = 4.3e9
    ... semi_axes = [103.16, 79.35, 66.13]
    ... [binary.orbit]
    ... semi_major_axis = "1.19 km"
    ... ''')
    >>> sc = load_binary(path)
    >>> len(sc.times), sc.system.order, sc.state.secondary_omega.round(9).tolist()
    (25, 2, [0.0, 0.0, 0.000144103])
    """
    path = Path(path)
    try:
        document = tomllib.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError) as err:
        raise ScenarioError(f"cannot read the file: {getattr(err, 'strerror', None) or err}",
                            path=str(path)) from None
    except tomllib.TOMLDecodeError as err:
        raise ScenarioError(f"not valid TOML: {err}", path=str(path)) from None
    if not is_binary(document):
        raise ScenarioError("has no [binary] table", path=str(path))
    unknown = sorted(set(document) - {"scenario", "binary", "expect"})
    if unknown:
        raise ScenarioError(f"unknown table(s) {', '.join(unknown)} in a binary scenario "
                            "(it has [scenario], [binary] and [expect])", path=str(path),
                            key=unknown[0])
    raw = document["binary"]
    scale = raw.get("time_scale", "tdb") if isinstance(raw.get("time_scale"), str) else "tdb"
    for item in raw.get("impulse", []) if isinstance(raw.get("impulse"), list) else []:
        if isinstance(item, dict) and "epoch" in item and "time_scale" not in item:
            item["time_scale"] = scale      # an impulse's epoch: in [binary]'s scale
    meta = validate(document.get("scenario", {}), SCENARIO, where="scenario", path=str(path),
                    error=ScenarioError)
    cfg = validate(raw, BINARY, where="binary", path=str(path), error=ScenarioError)
    cfg = {k.name: k.default for k in BINARY.keys if k.default is not None} | cfg
    expect_doc = document.get("expect", {})
    if not isinstance(expect_doc, dict):
        raise _fail(path, "expect", "must be a table")
    expect = validate(expect_doc, EXPECT, where="expect", path=str(path), error=ScenarioError)

    ensemble = cfg.pop("ensemble", None)
    if ensemble is not None:
        ensemble = {"seed": 0, "chaos": False} | ensemble
    if ensemble is not None and set(expect) - {"regime_fractions"}:
        raise _fail(path, f"expect.{sorted(set(expect) - {'regime_fractions'})[0]}",
                    "a [binary.ensemble] scenario expects only regime_fractions")
    if ensemble is None and "regime_fractions" in expect:
        raise _fail(path, "expect.regime_fractions", "needs a [binary.ensemble]")
    scenario = _build(path, meta, cfg, expect)
    if ensemble is not None:
        _members(path, cfg, expect, ensemble, 1)          # each drawn key is in the file
        scenario = dataclasses.replace(scenario, ensemble={**ensemble, "cfg": cfg,
                                                            "expect": expect})
    return scenario


def _build(path: Path, meta: dict, cfg: dict, expect: dict) -> BinaryScenario:
    """The scenario of a validated ``[binary]`` table (``cfg``, with defaults)."""
    primary = _body(path, cfg["primary"], "primary")
    secondary = _body(path, cfg["secondary"], "secondary")
    try:
        system = BinarySystem(primary, secondary, order=cfg["order"])
    except AttitudeError as err:
        raise _fail(path, "binary.order", getattr(err, "reason", str(err))) from None
    position, velocity = _orbit(path, cfg["orbit"], system)
    _check_apart(path, system, position)
    needs_bound = cfg["synchronous"] or any(k in expect for k in (
        "orbit_period", "osculating_period", "period_change"))
    if needs_bound and 0.5 * velocity @ velocity - system.mu / np.linalg.norm(position) >= 0:
        raise _fail(path, "binary.orbit", "the mutual orbit is not bound (its Keplerian "
                                          "energy is >= 0), and the synchronous start or "
                                          "the orbit expectations need a bound orbit; lower "
                                          "the speed or raise the masses")
    attitudes, omegas = [], []
    for name, body in (("primary", primary), ("secondary", secondary)):
        attitude, omega = _spin(path, cfg[name], body, name)
        attitudes.append(attitude)
        omegas.append(omega)
    if cfg["synchronous"]:
        for key in ("attitude", "spin_period", "omega"):
            if key in cfg["secondary"]:
                raise _fail(path, f"binary.secondary.{key}", "not with synchronous = true "
                                                             "(which sets the secondary's "
                                                             "attitude and spin)")
        attitudes[1], omegas[1] = _synchronous(secondary, position, velocity)
    try:
        state = BinaryState(cfg["epoch"], position, velocity, attitudes[0], omegas[0],
                            attitudes[1], omegas[1], frame=cfg["frame"])
    except AttitudeError as err:
        raise _fail(path, "binary.frame" if "frame" in str(err) else "binary",
                    getattr(err, "reason", str(err))) from None
    duration, step = cfg["duration"], cfg["output_step"]
    energy = 0.5 * velocity @ velocity - system.mu / np.linalg.norm(position)
    if energy < 0:
        orbits = duration / (2 * math.pi * math.sqrt((-system.mu / (2 * energy)) ** 3
                                                     / system.mu))
        if orbits > MAX_ORBITS:
            raise _fail(path, "binary.duration", f"{orbits:.3g} orbits is too long for one "
                                                 f"run (at most {MAX_ORBITS:.0e}); shorten "
                                                 "it")
    if step > duration:
        raise _fail(path, "binary.output_step", f"the output step ({step:.6g} s) is longer "
                                                f"than the duration ({duration:.6g} s)")
    if duration / step > 1e7:
        raise _fail(path, "binary.output_step", f"{duration / step:.3g} samples is too many "
                                                "for one run; use a longer output step")
    times = np.arange(0.0, duration * (1 + 1e-12), step)
    if times[-1] < duration * (1 - 1e-12):
        times = np.append(times, duration)
    impulses = tuple(_impulse(path, item, i, state, system, duration)
                     for i, item in enumerate(cfg.get("impulse", [])))
    if "period_change" in expect and not impulses:
        raise _fail(path, "expect.period_change", "needs a [[binary.impulse]]: the change "
                                                  "is measured across the first one")
    if "period_change" in expect and not 0 < min(i.time for i in impulses) < duration:
        raise _fail(path, "expect.period_change", "the first impulse is at an end of the "
                                                  "run: the change needs orbits before and "
                                                  "after it")
    method = cfg["method"]
    for key, owner in (("rtol", "integrator"), ("step", "lgvi")):
        if key in cfg and method != owner:
            raise _fail(path, f"binary.{key}", f"only with method = \"{owner}\" (the "
                                               f"method is {method!r})")
    rtol = cfg.get("rtol", DEFAULT_RTOL) if method == "integrator" else None
    output = path.parent / cfg["output"] if "output" in cfg else None
    return BinaryScenario(path, meta.get("name", path.stem), system, state, impulses, times,
                          method, rtol, cfg.get("step"), _expectations(expect), output)


def _body(path, table: dict, name: str) -> RigidBody:
    label = table.get("name", name)
    try:
        if "shape" in table:
            return RigidBody.from_obj(path.parent / table["shape"], density=table["density"],
                                      length_unit=table.get("length_unit", "m"), name=label)
        if "principal_moments" in table:
            return RigidBody.from_principal_moments(table["principal_moments"],
                                                    mass=table["mass"], name=label)
        if table["primitive"] == "sphere":
            if "radius" not in table or "semi_axes" in table:
                raise _fail(path, f"binary.{name}.radius", "a sphere takes radius (not "
                                                            "semi_axes)")
            props = MassProperties.solid_sphere(table["mass"], table["radius"])
        else:
            if "semi_axes" not in table or "radius" in table:
                raise _fail(path, f"binary.{name}.semi_axes", "an ellipsoid takes semi_axes "
                                                               "(not radius)")
            props = MassProperties.solid_ellipsoid(table["mass"], table["semi_axes"])
        return RigidBody.from_mass_properties(props, name=label)
    except ScenarioError:
        raise
    except AttitudeError as err:
        key = next(k for k in ("shape", "principal_moments", "primitive") if k in table)
        raise _fail(getattr(err, "path", None) or path, f"binary.{name}.{key}",
                    getattr(err, "reason", str(err))) from None


def _rotation(path, table: dict, key: str) -> Rotation:
    return rotation_from_table(table, key, lambda k, message: _fail(path, k, message))


def _spin(path, table: dict, body: RigidBody, name: str) -> tuple[Rotation, np.ndarray]:
    attitude = (_rotation(path, table["attitude"], f"binary.{name}.attitude")
                if "attitude" in table else Rotation.identity())
    if "omega" in table:
        return attitude, np.asarray(table["omega"], dtype=float)
    if "spin_period" in table:
        return attitude, 2 * math.pi / table["spin_period"] * body.principal_axes[:, 2]
    return attitude, np.zeros(3)


def _orbit(path, table: dict, system: BinarySystem) -> tuple[np.ndarray, np.ndarray]:
    if "position" in table:
        position = np.asarray(table["position"], dtype=float)
        velocity = np.asarray(table["velocity"], dtype=float)
        if not np.any(position):
            raise _fail(path, "binary.orbit.position", "the two centres coincide")
    else:
        try:
            orbit = KeplerOrbit(system.mu, table["semi_major_axis"],
                                e=table.get("eccentricity", 0.0),
                                i=table.get("inclination", 0.0),
                                raan=table.get("raan", 0.0), argp=table.get("argp", 0.0),
                                mean_anomaly=table.get("mean_anomaly", 0.0))
        except AttitudeError as err:
            key = {"a": "semi_major_axis", "e": "eccentricity", "i": "inclination"}.get(
                getattr(err, "key", None) or "", getattr(err, "key", None) or "")
            raise _fail(path, f"binary.orbit.{key}".rstrip("."),
                        getattr(err, "reason", str(err))) from None
        position, velocity = orbit.position(0.0), orbit.velocity(0.0)
    if table.get("circular", False):
        if "eccentricity" in table and table["eccentricity"] != 0:
            raise _fail(path, "binary.orbit.circular", "not with an eccentricity")
        speed = float(np.linalg.norm(velocity))
        if not speed > 0:
            raise _fail(path, "binary.orbit.circular", "needs a velocity direction")
        force = mutual_forces(system, position, np.eye(3), np.eye(3)).force
        pull = -float(force @ position) / np.linalg.norm(position)
        if not pull > 0:
            raise _fail(path, "binary.orbit.circular", "the mutual force does not pull the "
                                                       "bodies together here")
        radial = position / np.linalg.norm(position)
        along = velocity - (velocity @ radial) * radial
        along = along / np.linalg.norm(along)
        velocity = along * math.sqrt(pull * np.linalg.norm(position) / system.reduced_mass)
    return position, velocity


def _extent(body: RigidBody) -> float:
    """Largest distance of the body's surface from its centre of mass, m."""
    dist = body.distribution
    if dist is None:
        return 0.0
    if dist.shape is not None:
        return float(np.linalg.norm(dist.shape.vertices - body.center_of_mass, axis=1).max())
    return float(np.max(dist.semi_axes))


def _check_apart(path, system: BinarySystem, position: np.ndarray) -> None:
    reach = _extent(system.primary) + _extent(system.secondary)
    distance = float(np.linalg.norm(position))
    if distance <= reach:
        raise _fail(path, "binary.orbit", f"the bodies overlap: their centres are "
                                          f"{distance:.6g} m apart, their extents add up to "
                                          f"{reach:.6g} m; place the secondary farther out")


def _synchronous(secondary: RigidBody, position, velocity) -> tuple[Rotation, np.ndarray]:
    """Long axis to the primary, largest-moment axis along the orbit normal, spinning at
    the orbital rate about it."""
    h = np.cross(position, velocity)
    rate = np.linalg.norm(h) / (position @ position)
    z = h / np.linalg.norm(h)
    x = -position / np.linalg.norm(position)
    principal_to_inertial = np.column_stack([x, np.cross(z, x), z])
    axes = secondary.principal_axes              # body-frame columns A, B, C
    if np.linalg.det(axes) < 0:
        axes = axes * np.array([1.0, 1.0, -1.0])
    attitude = Rotation.from_matrix(principal_to_inertial @ axes.T)
    return attitude, rate * axes[:, 2]


def _impulse(path, item: dict, i: int, state: BinaryState, system: BinarySystem,
             duration: float) -> Impulse:
    key = f"binary.impulse[{i}]"
    if "epoch" in item:
        t = float((item["epoch"].tdb - state.epoch.tdb).to_value("s"))
        where = f"{key}.epoch"
    else:
        t, where = item["time"], f"{key}.time"
    if not 0 <= t <= duration:
        raise _fail(path, where, f"{t:.6g} s after the epoch is outside the run "
                                 f"(0 .. {duration:.6g} s)")
    body = item.get("body", "secondary")
    if "delta_v" in item:
        dv = np.asarray(item["delta_v"], dtype=float)
    else:
        mass = getattr(system, body).mass
        dv = impact_delta_v(item["impactor_mass"], item["impactor_velocity"],
                            item.get("beta", 1.0), mass, item.get("ejecta_direction"))
    return Impulse(t, body=body, delta_v=dv,
                   angular_impulse=item.get("angular_impulse", np.zeros(3)))


def _expectations(expect: dict) -> tuple:
    out = []
    for key, spec in expect.items():
        if key == "secondary_regime":
            out.append(Expectation.exact(key, spec))
        elif key == "regime_fractions":
            out += [Expectation.from_table(f"regime_fractions.{r}", v, default_unit="")
                    for r, v in spec.items()]
        elif key in ("energy_rel_drift", "angular_momentum_rel_drift"):
            out.append(Expectation.at_most(key, spec["max"]))
        else:
            default = "s" if key in _TIME_KEYS else {
                "libration_amplitude": "rad", "lyapunov_exponent": "1/s"}.get(key, "rad/s")
            out.append(Expectation.from_table(key, spec, default_unit=default))
    return tuple(out)


@dataclass(frozen=True, eq=False)
class BinaryRun:
    """The outcome of :func:`run_binary`: the ephemeris, its diagnosis, the period change
    across the first impulse (or None), the ``[expect]`` checks and the files written.

    Examples
    --------
    >>> BinaryRun("x", None, None, None, [{"ok": True}], []).ok
    True
    """

    name: str
    ephemeris: object
    diagnosis: object
    change: object
    expect: list
    outputs: list
    note: str = ""
    method: str = "integrator"
    extra: dict = field(default_factory=dict)
    ensemble: object = None

    @property
    def ok(self) -> bool:
        """Every expectation met."""
        return all(check["ok"] for check in self.expect)

    def report(self) -> dict:
        """The ``--report`` JSON document: scenario, regime (the secondary's), periods
        (s), the period change, conservation, expect, outputs; for an ensemble: the
        members' status counts, the regime fractions and the period changes' quantiles."""
        if self.ensemble is not None:
            return _ensemble_report(self)
        d = self.diagnosis
        doc = {"scenario": self.name, "regime": d.secondary_regime,
               "periods": {"orbit": d.orbit_period, "osculating": d.osculating_period,
                           "libration": d.libration_period,
                           "primary_spin": d.primary_spin_period,
                           "secondary_spin": d.secondary_spin_period},
               "libration_amplitude": d.libration_amplitude,
               "apsidal_rate": d.apsidal_rate, "eccentricity": d.eccentricity,
               "conservation": d.conservation, "method": self.method,
               "expect": self.expect, "outputs": [str(p) for p in self.outputs]}
        if d.lyapunov is not None:
            doc["lyapunov_exponent"] = d.lyapunov_exponent
        if self.change is not None:
            c = self.change
            doc["period_change"] = {"time": c.time, "before": c.before, "after": c.after,
                                    "change": c.change,
                                    "osculating_before": c.osculating_before,
                                    "osculating_after": c.osculating_after}
        if self.note:
            doc["note"] = self.note
        return _finite(doc)


def _finite(value):
    """``value`` with every non-finite float (a period not measured) as None (JSON)."""
    if isinstance(value, dict):
        return {k: _finite(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_finite(v) for v in value]
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def _draws(path, cfg: dict, sigma: dict, rng) -> tuple[dict, dict]:
    """One member's ``[binary]`` table (a copy with the drawn keys) and its inputs."""
    member = copy.deepcopy(cfg)
    inputs = {}
    for key, sig in sigma.items():
        table, name = key.split(".")
        where = f"binary.ensemble.sigma.{key}"
        if table == "impulse":
            items = [i for i in member.get("impulse", []) if "impactor_mass" in i]
            if not items:
                raise _fail(path, where, "no [[binary.impulse]] in the DART form "
                                         "(impactor_mass) to draw it for")
            value = float(items[0].get(name, 1.0) + sig * rng.normal())
            for item in items:
                item[name] = value
        else:
            holder = member[table]
            if name not in holder and name != "eccentricity":
                raise _fail(path, where, f"[binary.{table}] has no {name} to draw about")
            base = np.asarray(holder.get(name, 0.0), dtype=float)
            value = base + np.asarray(sig, dtype=float) * rng.normal(size=base.shape)
            holder[name] = value if base.shape else float(value)
        label = key.replace(".", "_")
        if np.ndim(value):
            inputs.update({f"{label}_{j}": float(v) for j, v in enumerate(value)})
        else:
            inputs[label] = float(value)
    return member, inputs


def _members(path, cfg: dict, expect: dict, spec: dict, n: int | None = None) -> list:
    """The members of ``[binary.ensemble]``: ``(system, state, impulses, inputs)``, or
    ``(error, None, [], inputs)`` for a draw that makes no valid system (status 1)."""
    rng = np.random.default_rng(spec["seed"])
    members = []
    for _ in range(spec["n"] if n is None else n):
        member, inputs = _draws(path, cfg, spec["sigma"], rng)
        try:
            built = _build(path, {}, member, expect)
            members.append((built.system, built.state, list(built.impulses), inputs))
        except (AttitudeError, ValueError) as err:
            members.append((err, None, [], inputs))
    return members


def _run_ensemble(scenario: BinaryScenario, output, write_outputs: bool) -> BinaryRun:
    spec = scenario.ensemble
    members = _members(scenario.path, spec["cfg"], spec["expect"], spec)
    ds = run_ensemble(members, scenario.times, method=scenario.method, rtol=scenario.rtol,
                      step=scenario.step, chaos=spec["chaos"], client=spec.get("client"),
                      chunk_size=spec.get("chunk_size"))
    fractions = ds.attrs["regime_fractions"]
    checks = [e.check(fractions.get(e.key.split(".", 1)[1], 0.0)) for e in scenario.expect]
    outputs = []
    target = Path(output) if output is not None else scenario.output
    if write_outputs and target is not None:
        out = ds.assign_attrs(regime_fractions=json.dumps(fractions))
        for key in ("message", "secondary_regime"):
            out[key] = out[key].astype(str)
        outputs.append(write_atomically(target, lambda tmp: out.to_netcdf(
            tmp, engine="netcdf4", format="NETCDF4")))
    return BinaryRun(scenario.name, None, None, None, checks, outputs, scenario.note,
                     scenario.method, ensemble=ds)


def _ensemble_report(run: BinaryRun) -> dict:
    ds = run.ensemble
    status = ds["status"].values
    change = ds["period_change"].values[status == 0]
    change = change[np.isfinite(change)]
    doc = {"scenario": run.name, "members": int(status.size),
           "status": {"ok": int(np.sum(status == 0)), "invalid_input": int(np.sum(status == 1)),
                      "failed": int(np.sum(status == 2))},
           "regime_fractions": ds.attrs["regime_fractions"], "method": run.method,
           "expect": run.expect, "outputs": [str(p) for p in run.outputs]}
    if change.size:
        doc["period_change_quantiles"] = dict(zip(
            ("p05", "p50", "p95"), np.quantile(change, [0.05, 0.5, 0.95]).tolist()))
    return doc


def run_binary(scenario: BinaryScenario, *, output=None, write_outputs: bool = True
               ) -> BinaryRun:
    """Propagate a binary scenario, diagnose it, check ``[expect]``, write the ephemeris.

    Parameters
    ----------
    scenario : BinaryScenario
        From :func:`load_binary`.
    output : path, optional
        The netCDF ephemeris (default: ``[binary] output``; none if neither).
    write_outputs : bool
        False for a check that writes nothing.

    Raises
    ------
    PropagationError
        The integrator failed.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> folder = pathlib.Path(tempfile.mkdtemp())
    >>> _ = (folder / "b.toml").write_text('''
    ... [binary]
    ... epoch = "2026-12-01"
    ... duration = "30 h"
    ... output_step = "20 min"
    ... method = "integrator"
    ... [binary.primary]
    ... primitive = "sphere"
    ... mass = 5.2e11
    ... radius = 390.0
    ... [binary.secondary]
    ... primitive = "sphere"
    ... mass = 4.3e9
    ... radius = 80.0
    ... [binary.orbit]
    ... semi_major_axis = "1.19 km"
    ... [expect]
    ... orbit_period = { value = 12.112, unit = "h", abs_tol = 0.001 }   # Kepler
    ... ''')
    >>> run = run_binary(load_binary(folder / "b.toml"), output=folder / "b.nc")
    >>> run.ok, [p.name for p in run.outputs]
    (True, ['b.nc'])
    """
    if scenario.ensemble is not None:
        return _run_ensemble(scenario, output, write_outputs)
    eph = propagate_binary(scenario.system, scenario.state, scenario.times,
                           method=scenario.method, rtol=scenario.rtol, step=scenario.step,
                           events=list(scenario.impulses))
    eph.dataset.attrs["title"] = f"attitude ephemeris: binary system, {scenario.name}"
    times = [imp.seconds_after(scenario.state.epoch) for imp in scenario.impulses]
    chaos = any(e.key == "lyapunov_exponent" or (e.key == "secondary_regime"
                                                 and e.value == "chaotic")
                for e in scenario.expect)
    d = diagnose(eph, impulses=times, chaos=chaos, system=scenario.system)
    change = None
    if times and scenario.times[0] < min(times) <= scenario.times[-1]:
        change = period_change(eph, min(times))
    checks = [_check(e, d, change) for e in scenario.expect]
    outputs = []
    target = Path(output) if output is not None else scenario.output
    if write_outputs and target is not None:
        outputs.append(eph.to_netcdf(target))
    return BinaryRun(scenario.name, eph, d, change, checks, outputs, scenario.note,
                     scenario.method)


def _check(e: Expectation, d, change) -> dict:
    key = e.key
    if key == "secondary_regime":
        return e.check(d.secondary_regime)
    if key in ("energy_rel_drift", "angular_momentum_rel_drift"):
        return e.check(d.conservation[key])
    if key == "period_change":
        got = change.change if change is not None else None
    else:
        got = getattr(d, key)
    if got is None or not math.isfinite(got):
        return e.check(None)
    si = {"libration_amplitude": u.rad, "apsidal_rate": u.rad / u.s,
          "lyapunov_exponent": 1 / u.s}.get(key, u.s)
    return e.check(float((got * si).to_value(e.unit)))


def binary_reference() -> str:
    """The key reference of binary scenario files as markdown (the generated section of
    docs/binary.md): ``[binary]`` and its ``[expect]`` keys.

    Examples
    --------
    >>> print(binary_reference().splitlines()[0])
    ### `[binary]`
    """
    return markdown(Table("", (Key("binary", "table", table=BINARY),
                               Key("expect", "table", table=EXPECT))))


if __name__ == "__main__":        # python -m attitude.binary.config: the key reference
    print(binary_reference(), end="")

"""The scenario registry: the ``[[torques]]`` tables of a scenario file, their builders,
and :func:`from_config`, which turns one table into a model; wings add their own types
(:func:`register_torque_type`)."""

from __future__ import annotations

import dataclasses
import difflib
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

from astropy import units as u

from ...foundations.constants import EARTH_MU
from ...foundations.earth_rotation import earth_rotation_angle
from ...foundations.errors import OrbitError, TorqueConfigError
from ...foundations.spec import Key, Table, json_schema, validate
from ..body import RigidBody
from ..orbit import KeplerOrbit
from .base import TorqueModel
from .common import check_keys
from .constant import ConstantTorque
from .dissipation import EnergyDissipation
from .eddy_current import EddyCurrentDamping
from .fields import TiltedDipoleField, UniformField
from .gravity_gradient import GravityGradient
from .heavy_top import HeavyTopPivot
from .magnetic_dipole import MagneticDipole

__all__ = ["ORBIT_TABLE", "ORBIT_SOURCES", "FIELD_SOURCES", "TORQUE_TABLES", "TORQUE_TYPES",
           "BuildContext", "register_torque_type", "from_config"]


#: An inline orbit table ``orbit = { a = "7000 km", e = 0.0, ... }``.
ORBIT_TABLE = Table("orbit", (
    Key("a", "quantity", unit="m", positive=True, doc="semi-major axis"),
    Key("e", "quantity", unit="", bounds=(0.0, None), default=0,
        doc="eccentricity, 0 <= e < 1"),
    Key("i", "quantity", unit="rad", default=0, doc="inclination"),
    Key("raan", "quantity", unit="rad", default=0,
        doc="right ascension of the ascending node"),
    Key("argp", "quantity", unit="rad", default=0, doc="argument of periapsis"),
    Key("mean_anomaly", "quantity", unit="rad", default=0, doc="mean anomaly at `epoch`"),
    Key("epoch", "time", doc="when `mean_anomaly` holds; default the scenario epoch"),
    Key("tle", "any", schema={"type": "array", "items": {"type": "string"}, "minItems": 2,
                              "maxItems": 2},
        doc="a two-line element set instead of the elements: SGP4 in GCRF (in the [state] "
            "frame for solar_radiation and drag; attitude.environment.TLEOrbit; t = 0 at "
            "the scenario epoch)"),
), exactly_one=(("a", "tle"),),
    excludes=(("tle", ("e", "i", "raan", "argp", "mean_anomaly", "epoch")),),
    doc="The body's orbit about the primary, inertial frame: Keplerian elements, or a "
        "two-line element set")

#: Builders of the orbit and field sources that live in a wing
#: (:mod:`attitude.environment` registers ``"tle"`` and ``"igrf"`` when imported):
#: ``ORBIT_SOURCES["tle"](lines, base_epoch)`` and
#: ``FIELD_SOURCES["igrf"](orbit, base_epoch, max_degree)``.
ORBIT_SOURCES: dict[str, Callable] = {}
FIELD_SOURCES: dict[str, Callable] = {}

_FIELD_TABLE = Table("field", (
    Key("model", "string", choices=("dipole", "uniform", "igrf"), default="dipole",
        doc="the Earth's tilted dipole along `orbit`, a uniform field, or IGRF-14 along "
            "`orbit` (attitude.environment.IGRF; `field = \"igrf\"` for short)"),
    Key("max_degree", "integer", bounds=(1, 13), default=13, doc="IGRF: highest degree"),
    Key("moment", "quantity", unit="A m2", positive=True, doc="dipole moment"),
    Key("tilt", "quantity", unit="rad", doc="dipole tilt from the inertial z axis"),
    Key("pole_longitude", "quantity", unit="rad", doc="longitude of the dipole pole"),
    Key("rotation_angle", "quantity", unit="rad",
        doc="Earth rotation angle at t = 0; default from the scenario epoch"),
    Key("rotation_rate", "quantity", unit="rad/s", doc="Earth rotation rate"),
    Key("vector", "quantity", unit="T", shape=(3,), doc="uniform field, inertial frame"),
), excludes=(("vector", ("moment", "tilt", "pole_longitude", "rotation_angle",
                          "rotation_rate", "max_degree")),))

#: The keys of each ``[[torques]]`` type (``type`` selects the table).
TORQUE_TABLES: dict[str, Table] = {t.name: t for t in (
    Table("gravity_gradient", (
        Key("mu", "quantity", unit="m3/s2", required=True, positive=True,
            doc="gravitational parameter of the primary"),
        Key("orbit", "table", required=True, table=ORBIT_TABLE, doc=ORBIT_TABLE.doc),
    ), doc="Point-mass primary: `3 mu / r^5 (r x I r)`."),
    Table("constant", (
        Key("torque", "quantity", unit="N m", shape=(3,), required=True, doc="the torque"),
        Key("frame", "string", choices=("body", "inertial"), default="body",
            doc="axes of `torque`"),
    ), doc="A fixed torque in body or inertial axes."),
    Table("dissipation", (
        Key("time_constant", "quantity", unit="s", required=True, positive=True,
            doc="e-folding time of the excess energy"),
    ), doc="Internal energy dissipation (damper, fuel slosh); the inertial L is kept."),
    Table("eddy_current", (
        Key("magnetic_tensor", "quantity", unit="S m4", shape=((), (3, 3)),
            doc="magnetic tensor, body frame (scalar: isotropic)"),
        Key("shell", "table", table=Table("shell", (
            Key("radius", "quantity", unit="m", required=True, positive=True),
            Key("thickness", "quantity", unit="m", required=True, positive=True),
            Key("conductivity", "quantity", unit="S/m", required=True, positive=True))),
            doc="thin conducting spherical shell"),
        Key("sphere", "table", table=Table("sphere", (
            Key("radius", "quantity", unit="m", required=True, positive=True),
            Key("conductivity", "quantity", unit="S/m", required=True, positive=True))),
            doc="solid conducting sphere"),
        Key("field", "any",
            schema={"oneOf": [{"type": "string", "enum": ["dipole", "igrf", "uniform"]},
                              json_schema(_FIELD_TABLE, root=False)]},
            doc="the magnetic field: a table, or the model name (\"igrf\"); default the "
                "Earth's tilted dipole"),
        Key("mu", "quantity", unit="m3/s2", positive=True,
            doc="gravitational parameter of the primary (dipole field); default the Earth's"),
        Key("orbit", "table", table=ORBIT_TABLE, doc=ORBIT_TABLE.doc + " (dipole field)"),
    ), exactly_one=(("magnetic_tensor", "shell", "sphere"),),
        doc="Eddy currents induced by a magnetic field: `(M (w x B)) x B`."),
    Table("heavy_top", (
        Key("pivot_to_com", "quantity", unit="m", shape=(3,), required=True,
            doc="pivot -> centre of mass, body frame"),
        Key("mass", "quantity", unit="kg", positive=True, doc="default the body's mass"),
        Key("g", "quantity", unit="m/s2", positive=True, doc="gravity; default 9.80665"),
        Key("up", "quantity", unit="", shape=(3,), doc="inertial unit vector, up"),
    ), doc="Uniform gravity about a fixed pivot."),
)}
# a residual magnetic dipole: the field keys are eddy_current's (one field reader)
TORQUE_TABLES["magnetic_dipole"] = Table("magnetic_dipole", (
    Key("moment", "quantity", unit="A m2", shape=(3,), required=True,
        doc="magnetic moment, body frame"),
    *(TORQUE_TABLES["eddy_current"][name] for name in ("field", "mu", "orbit")),
), doc="A body-fixed (residual) magnetic dipole in a magnetic field: `m x B`.")

def _orbit_from_table(table, mu: float, key: str, base_epoch) -> KeplerOrbit:
    """A validated :data:`ORBIT_TABLE` (SI values; ``epoch`` an astropy Time) -> orbit."""
    if "tle" in table:
        if "tle" not in ORBIT_SOURCES:
            raise TorqueConfigError("a TLE orbit needs attitude.environment (import "
                                    "attitude)", key=f"{key}.tle")
        try:
            return ORBIT_SOURCES["tle"](table["tle"], base_epoch)
        except OrbitError as err:
            raise TorqueConfigError(err.reason, key=f"{key}.{err.key}") from None
    elements = {k: table[k] for k in ORBIT_TABLE.names() if k in table and k != "epoch"}
    try:
        orbit = KeplerOrbit(mu=mu, **elements)
    except OrbitError as err:
        raise TorqueConfigError(err.reason, key=f"{key}.{err.key}") from None
    if "epoch" in table:
        if base_epoch is None:
            raise TorqueConfigError("an orbit epoch needs the scenario epoch "
                                    "(from_config(..., base_epoch=...))", key=f"{key}.epoch")
        dt = float((base_epoch - table["epoch"]).to_value(u.s))
        orbit = KeplerOrbit(orbit.mu, orbit.a, orbit.e, orbit.i, orbit.raan, orbit.argp,
                            orbit.mean_anomaly + orbit.mean_motion * dt)
    return orbit


def _gravity_gradient(table, base_epoch):
    mu = table["mu"]
    return GravityGradient(mu, _orbit_from_table(table["orbit"], mu, "orbit", base_epoch))


def _constant(table, base_epoch):
    return ConstantTorque(table["torque"], frame=table.get("frame", "body"))


def _dissipation(table, base_epoch):
    check_keys(table, ("type", "time_constant"), "")
    if "time_constant" not in table:
        raise TorqueConfigError("missing: give the e-folding time of the "
                                "excess energy, e.g. \"30 min\"", key="time_constant")
    return EnergyDissipation(table["time_constant"])


_FIELD_KEYS = {"dipole": ("model", "moment", "tilt", "pole_longitude", "rotation_angle",
                          "rotation_rate"),
               "uniform": ("model", "vector"),
               "igrf": ("model", "max_degree")}


def _prefixed(prefix: str, build: Callable, *args, **kwargs):
    """Call ``build``; re-raise its :class:`TorqueConfigError` under ``prefix.key``."""
    try:
        return build(*args, **kwargs)
    except TorqueConfigError as err:
        raise TorqueConfigError(err.reason, key=f"{prefix}.{err.key}") from None


def _field_from_table(table, base_epoch):
    field_table = table.get("field", {"model": "dipole"})
    if isinstance(field_table, str):                 # field = "igrf": the model by name
        field_table = {"model": field_table}
    field_table = validate(field_table, _FIELD_TABLE, where="field", error=TorqueConfigError)
    model = field_table.get("model", "dipole")
    check_keys(field_table, _FIELD_KEYS[model], "field")
    if model == "uniform":
        for key in ("orbit", "mu"):
            if key in table:
                raise TorqueConfigError("not used by a uniform field; remove it", key=key)
        if "vector" not in field_table:
            raise TorqueConfigError("missing: give { value = [x, y, z], "
                                    "unit = \"nT\" }", key="field.vector")
        return UniformField(field_table["vector"])
    if "orbit" not in table:
        raise TorqueConfigError("missing: the dipole field is evaluated along the "
                                "body's orbit (or use field.model = \"uniform\")", key="orbit")
    mu = table.get("mu", EARTH_MU)
    orbit = _orbit_from_table(table["orbit"], mu, "orbit", base_epoch)
    if model == "igrf":
        if base_epoch is None:
            raise TorqueConfigError("the IGRF field needs the scenario epoch", key="field")
        try:
            return FIELD_SOURCES["igrf"](orbit, base_epoch, field_table.get("max_degree", 13))
        except OrbitError as err:
            raise TorqueConfigError(err.reason, key=f"field.{err.key}") from None
    kwargs = {k: field_table[k] for k in _FIELD_KEYS["dipole"][1:] if k in field_table}
    if "rotation_angle" not in kwargs and base_epoch is not None:
        kwargs["rotation_angle"] = earth_rotation_angle(base_epoch)
    return _prefixed("field", TiltedDipoleField, orbit, **kwargs)


def _eddy_current(table, base_epoch):
    field = _field_from_table(table, base_epoch)
    if "magnetic_tensor" in table:
        return EddyCurrentDamping(table["magnetic_tensor"], field)
    if "shell" in table:
        spec = table["shell"]
        return _prefixed("shell", EddyCurrentDamping.spherical_shell, spec["radius"],
                         spec["thickness"], spec["conductivity"], field)
    spec = table["sphere"]
    return _prefixed("sphere", EddyCurrentDamping.solid_sphere, spec["radius"],
                     spec["conductivity"], field)


def _magnetic_dipole(table, base_epoch):
    return MagneticDipole(table["moment"], _field_from_table(table, base_epoch))


def _heavy_top(table, base_epoch):
    kwargs = {k: table[k] for k in ("mass", "g", "up") if k in table}
    return HeavyTopPivot(pivot_to_com=table["pivot_to_com"], **kwargs)


#: ``type`` values of scenario ``[[torques]]`` tables and their builders
#: ``build(values, base_epoch)``.
TORQUE_TYPES: dict[str, Callable] = {
    "gravity_gradient": _gravity_gradient,
    "constant": _constant,
    "dissipation": _dissipation,
    "eddy_current": _eddy_current,
    "heavy_top": _heavy_top,
    "magnetic_dipole": _magnetic_dipole,
}


@dataclasses.dataclass(frozen=True, eq=False)
class BuildContext:
    """What a ``[[torques]]`` builder may need beyond its own table.

    A scenario builds one context and passes it to every torque table it reads
    (:func:`from_config`); builders registered with :func:`register_torque_type` receive
    it whole, the built-in ones its ``epoch``.

    Parameters
    ----------
    epoch : astropy Time, optional
        The scenario epoch, ``t = 0``.
    frame : str
        Inertial frame of the states (the ``[state]`` frame).
    folder : path-like, optional
        Folder of the scenario file: file names in torque tables are relative to it.
    body : RigidBody, optional
        The scenario's body (its centre of mass: torques are taken about it).
    shape : str, optional
        The ``[body] shape`` file name (relative to ``folder``), when the body was given
        by a shape model.
    length_unit : str
        Unit of the vertex coordinates of ``shape``.

    Examples
    --------
    >>> from astropy.time import Time
    >>> ctx = BuildContext(epoch=Time("2024-03-01T00:00:00", scale="utc"), frame="GCRF")
    >>> orbit_table = {"a": 7.0e6, "e": 0.001}
    >>> ctx.orbit(orbit_table) is ctx.orbit(dict(orbit_table))   # built once, shared
    True
    """

    epoch: Any = None
    frame: str = "ICRF"
    folder: Path | None = None
    body: RigidBody | None = None
    shape: str | None = None
    length_unit: str = "m"
    _shared: dict = dataclasses.field(default_factory=dict, init=False, repr=False)

    def shared(self, key, build: Callable):
        """``build()`` the first time ``key`` is asked for, the same object after: the
        torques of one scenario share their orbit tables and the Sun's path, so each is
        tabulated once and interpolated once per integrator stage."""
        if key not in self._shared:
            self._shared[key] = build()
        return self._shared[key]

    def orbit(self, table: Mapping, *, mu: float = EARTH_MU, key: str = "orbit"):
        """The orbit of a validated ``orbit`` table (:data:`ORBIT_TABLE`): Keplerian
        elements about ``mu``, or an element set through SGP4 in :attr:`frame` (needs
        :mod:`attitude.environment`); equal tables give the same object."""
        def build():
            if "tle" in table and "tle" in ORBIT_SOURCES:
                try:
                    return ORBIT_SOURCES["tle"](table["tle"], self.epoch, self.frame)
                except OrbitError as err:
                    raise TorqueConfigError(err.reason, key=f"{key}.{err.key}") from None
            return _orbit_from_table(table, mu, key, self.epoch)
        memo = ("orbit", float(mu), tuple(sorted((k, repr(v)) for k, v in table.items())))
        return self.shared(memo, build)


#: Builders ``build(values, context)`` of the torque types a wing registers
#: (:func:`register_torque_type`); they get the whole :class:`BuildContext`.
_CONTEXT_BUILDERS: dict[str, Callable] = {}


def register_torque_type(table: Table, build: Callable) -> None:
    """Add a ``[[torques]]`` type declared outside this module (the environment wing's
    ``"solar_radiation"`` and ``"drag"``): ``table`` (its keys, named ``table.name``) is
    checked by :func:`from_config`, and ``build(values, context)`` gets the validated
    values (SI) and the :class:`BuildContext`.

    Examples
    --------
    >>> import attitude.environment              # registers "solar_radiation" and "drag"
    >>> from attitude.model.torques import TORQUE_TABLES
    >>> "solar_radiation" in TORQUE_TABLES
    True
    """
    TORQUE_TABLES[table.name] = table
    _CONTEXT_BUILDERS[table.name] = build


def from_config(table: Mapping, *, base_epoch=None,
                context: BuildContext | None = None) -> TorqueModel:
    """Build a torque model from a scenario ``[[torques]]`` table.

    Quantities are numbers (SI), strings parsed by astropy (``"7000 km"``) or
    ``{ value = ..., unit = "..." }`` tables.

    ==================  ====================================================================
    ``type``            keys
    ==================  ====================================================================
    gravity_gradient    ``mu`` (m3/s2); ``orbit = { a, e = 0, i = 0, raan = 0, argp = 0,
                        mean_anomaly = 0, epoch }`` (``epoch``: when ``mean_anomaly``
                        holds; default the scenario epoch)
    constant            ``torque`` (N m, 3-vector); ``frame = "body" | "inertial"``
    dissipation         ``time_constant`` (s)
    eddy_current        one of ``magnetic_tensor`` (S m4, scalar or 3x3, body frame),
                        ``shell = { radius, thickness, conductivity }``,
                        ``sphere = { radius, conductivity }``; ``field = { model =
                        "dipole", moment, tilt, pole_longitude, rotation_angle,
                        rotation_rate }`` (default: the Earth's tilted dipole, with the
                        rotation angle from ``base_epoch``) with ``orbit`` and ``mu``
                        (default the Earth's), or ``field = { model = "uniform",
                        vector = {value, unit} }``
    magnetic_dipole     ``moment`` (A m2, 3-vector, body frame); ``field``, ``orbit``,
                        ``mu`` as ``eddy_current`` (``field = "igrf"`` for IGRF-14)
    heavy_top           ``pivot_to_com`` (m, body frame); ``mass`` (kg, default the
                        body's); ``g`` (m/s2); ``up`` (inertial unit vector)
    solar_radiation,    ``orbit``; ``facets`` (boxes, plates, facets) or the ``[body]``
    drag                shape, named ``materials``; registered by
                        :mod:`attitude.environment.config` (docs/environment.md)
    ==================  ====================================================================

    Parameters
    ----------
    table : mapping
        One ``[[torques]]`` table (``type`` plus the keys above).
    base_epoch : astropy Time, optional
        The scenario epoch (``t = 0``): used for ``orbit.epoch`` and the Earth rotation
        angle of the dipole field.
    context : BuildContext, optional
        What the scenario knows beyond the table (epoch, frame, folder, body); its
        ``epoch`` is used when ``base_epoch`` is not given.  The environment's types
        (``solar_radiation``, ``drag``; docs/environment.md) need it.

    Returns
    -------
    TorqueModel

    Raises
    ------
    TorqueConfigError
        (a ``ValueError``) whose message starts with the key path inside the table, e.g.
        ``"orbit.e: must be in [0, 1), got 1.2"``; unknown keys and types come with a
        did-you-mean suggestion.

    Examples
    --------
    >>> from attitude.model.torques import from_config
    >>> gg = from_config({"type": "gravity_gradient", "mu": "3.986004418e14 m3/s2",
    ...                   "orbit": {"a": "7000 km", "e": 0.0, "i": "0 deg"}})
    >>> gg
    GravityGradient(mu=3.986004418e+14, orbit=KeplerOrbit(mu=398600441800000.0, a=7000000.0, ...))
    >>> from_config({"type": "gravity_gradient", "mu": 3.986e14, "orbit": {"a": 7e6, "e": 1.2}})
    Traceback (most recent call last):
    ...
    attitude.foundations.errors.TorqueConfigError: orbit.e: must be in [0, 1), got 1.2; ...
    >>> from_config({"type": "disipation", "time_constant": "30 min"})
    Traceback (most recent call last):
    ...
    attitude.foundations.errors.TorqueConfigError: type: unknown torque type 'disipation'; ...
    """
    if not isinstance(table, Mapping):
        raise TorqueConfigError(f"expected a table with a 'type' key, got "
                                f"{type(table).__name__}", key="type")
    kinds = [*TORQUE_TYPES, *_CONTEXT_BUILDERS]
    if "type" not in table:
        raise TorqueConfigError(f"missing; choose one of {', '.join(kinds)}", key="type")
    kind = table["type"]
    if not isinstance(kind, str) or kind not in kinds:
        near = difflib.get_close_matches(kind, kinds, n=1) if isinstance(kind, str) else []
        did = f"did you mean {near[0]!r}? " if near else ""
        raise TorqueConfigError(f"unknown torque type {kind!r}; {did}choose one of "
                                f"{', '.join(kinds)}", key="type")
    if context is None:
        context = BuildContext(epoch=base_epoch)
    elif base_epoch is None:
        base_epoch = context.epoch
    orbit = table.get("orbit")
    if base_epoch is not None and isinstance(orbit, Mapping) and isinstance(
            orbit.get("epoch"), str):     # an orbit epoch is read in the scenario's scale
        table = {**table, "orbit": {**orbit, "epoch": {"value": orbit["epoch"],
                                                       "scale": base_epoch.scale}}}
    values = validate(table, TORQUE_TABLES[kind].with_keys(Key("type", "string")),
                      error=TorqueConfigError)
    if kind in _CONTEXT_BUILDERS:
        return _CONTEXT_BUILDERS[kind](values, context)
    return TORQUE_TYPES[kind](values, base_epoch)

"""The environment's ``[[torques]]`` types in scenario files: ``"solar_radiation"`` and
``"drag"``.

Both act on the spacecraft's outer surface, given in the torque table in one of two ways
(the same description photometry uses, :mod:`attitude.model.surface`):

- ``facets = [ { type = "box", size = [...] }, { type = "plate", area = ..., normal =
  [...], center = [...] }, { type = "facet", ... } ]``: boxes, thin plates (two faces
  back to back: a solar array) and one-sided facets, body frame;
- without ``facets``, the faces of the ``[body] shape`` model, with ``surface = [ {
  faces = [start, stop], material = "..." } ]`` giving face ranges their material (the
  ``[photometry] materials`` convention).

Optical properties are named once, ``materials = { mli = { specular = 0.0, diffuse =
0.2 } }``, and referred to by name (``material = "mli"`` on a facet, or as the default of
the whole table); ``specular`` and ``diffuse`` can also be given on a facet directly.
Torques are taken about ``center_of_mass`` (default: the body's centre of mass, in the
coordinates of the facets).  The builders get a :class:`attitude.model.torques.BuildContext`
(epoch, frame, scenario folder, body): the orbit tables and the Sun's path are shared
between the torques of one scenario.

The tables are declared here (:data:`TORQUE_TABLES`) and registered with
:func:`attitude.model.torques.register_torque_type`; :mod:`attitude.app.scenario_spec` adds them
to the scenario format.

Examples
--------
>>> from astropy.time import Time
>>> from attitude.model.torques import BuildContext, from_config
>>> ctx = BuildContext(epoch=Time("2016-10-01T00:00:00", scale="utc"), frame="GCRF")
>>> srp = from_config({"type": "solar_radiation", "orbit": {"a": "7714 km", "i": "66 deg"},
...                    "facets": [{"type": "box", "size": [1.0, 2.0, 3.0]}]}, context=ctx)
>>> len(srp.facets), srp.shadow
(6, 'conical')
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..foundations.constants import EARTH_MU
from ..foundations.errors import AttitudeError, TorqueConfigError
from ..foundations.spec import Key, Table
from ..model.shape import Polyhedron
from ..model.surface import OpticalProperties, Surface
from ..model.torques import ORBIT_TABLE, BuildContext, register_torque_type
from .drag import AerodynamicDrag, ExponentialAtmosphere
from .facets import Facets
from .frames import check_frame
from .msis import MSISAtmosphere
from .radiation import SOLAR_PRESSURE_1AU, SolarRadiationPressure
from .sun import SunPath

__all__ = ["TORQUE_TABLES", "FACET_TABLES", "MATERIAL_TABLE", "build_facets",
           "build_solar_radiation", "build_drag"]

_OPTICS = (
    Key("material", "string", doc="a name from `materials`; default the table's `material`"),
    Key("specular", "number", bounds=(0.0, 1.0), doc="rho_s, instead of a material"),
    Key("diffuse", "number", bounds=(0.0, 1.0), doc="rho_d, instead of a material"),
)
_OPTICS_RULE = (("material", ("specular", "diffuse")),)
_CENTER = Key("center", "quantity", unit="m", shape=(3,), default="[0, 0, 0]",
              doc="centre, body frame")
_NORMAL = Key("normal", "quantity", unit="", shape=(3,), required=True,
              doc="outward normal, body frame (normalised)")
# The outline of a plate or facet: read by self-shadowing only.
_OUTLINE = (
    Key("size", "quantity", unit="m", shape=(2,), positive=True,
        doc="a rectangle's edges [a, b], instead of `area` (its outline for "
            "self_shadowing; by area alone it is a square)"),
    Key("edge", "quantity", unit="", shape=(3,),
        doc="direction of the rectangle's edge a, body frame (projected into the plane); "
            "default the body axis least aligned with the normal"),
)

#: The entries of ``facets = [...]``, chosen by ``type``.
FACET_TABLES = (
    Table("box", (
        Key("size", "quantity", unit="m", shape=(3,), required=True, positive=True,
            doc="edges along the body axes"),
        _CENTER, *_OPTICS,
    ), excludes=_OPTICS_RULE, doc="a rectangular box: six facets"),
    Table("plate", (
        Key("area", "quantity", unit="m2", positive=True, doc="area of one face"),
        *_OUTLINE, _NORMAL, _CENTER, *_OPTICS,
        Key("back_material", "string", doc="material of the rear face; default as the front"),
    ), excludes=_OPTICS_RULE, exactly_one=(("area", "size"),),
        doc="a thin plate (a solar array): two facets back to back, normals +n and -n"),
    Table("facet", (
        Key("area", "quantity", unit="m2", positive=True),
        *_OUTLINE, _NORMAL, _CENTER, *_OPTICS,
    ), excludes=_OPTICS_RULE, exactly_one=(("area", "size"),),
        doc="one flat facet, lit or hit on its outward side only"),
)

#: A named material: ``materials = { name = { specular, diffuse } }``.
MATERIAL_TABLE = Table("material", (
    Key("specular", "number", bounds=(0.0, 1.0), default=0,
        doc="fraction reflected specularly, rho_s"),
    Key("diffuse", "number", bounds=(0.0, 1.0), default=0,
        doc="fraction reflected diffusely (Lambert), rho_d; rho_s + rho_d <= 1"),
), doc="optical properties (attitude.surface.OpticalProperties); the rest is absorbed")

_FACE_RANGE = Table("surface", (
    Key("faces", "any", schema={"type": "array", "items": {"type": "integer"},
                                "minItems": 2, "maxItems": 2},
        doc="[start, stop): face indices of the [body] shape"),
    Key("material", "string", required=True, doc="a name from `materials`"),
))

_SURFACE_KEYS = (
    Key("orbit", "table", required=True, table=ORBIT_TABLE, doc=ORBIT_TABLE.doc),
    Key("mu", "quantity", unit="m3/s2", positive=True,
        doc="gravitational parameter (Keplerian orbit); default the Earth's"),
    Key("facets", "tables", variants=FACET_TABLES,
        doc="the outer surface as boxes, plates and facets, body frame; default the faces "
            "of the [body] shape"),
    Key("materials", "map", table=MATERIAL_TABLE, doc="named optical properties"),
    Key("material", "string",
        doc="material of every face or facet that names none; default black (absorbing)"),
    Key("surface", "tables", table=_FACE_RANGE,
        doc="[body] shape: the material of face ranges, as [photometry] materials"),
    Key("center_of_mass", "quantity", unit="m", shape=(3,),
        doc="in the coordinates of the facets; default the body's centre of mass"),
)

#: The ``[[torques]]`` tables of the environment's types.
TORQUE_TABLES = (
    Table("solar_radiation", (
        *_SURFACE_KEYS,
        Key("shadow", "string", choices=("conical", "cylindrical", "none"),
            default="conical", doc="Earth shadow model (penumbra with conical)"),
        Key("pressure", "quantity", unit="N/m2", nonnegative=True, default=SOLAR_PRESSURE_1AU,
            doc="radiation pressure at 1 au"),
        Key("self_shadowing", "boolean", default=False,
            doc="a facet feels only its part the rest of the body does not shade (ray "
                "casting with embree, the shadows extra; the outlines of plates and "
                "facets: size and edge)"),
        Key("shadow_subdivision", "integer", positive=True,
            doc="self_shadowing: each triangle of a facet cut into k^2 parts, one ray each; "
                "default k per triangle from its size (parts at most 1/24 of the body, "
                "k <= 16)"),
    ), excludes=(("facets", ("surface",)),),
        doc="Solar radiation pressure on facets (absorbed, specular, diffuse), zero in the "
            "Earth's umbra (attitude.environment.SolarRadiationPressure; "
            "docs/environment.md)."),
    Table("drag", (
        *_SURFACE_KEYS,
        Key("cd", "number", nonnegative=True, default=2.2, doc="drag coefficient"),
        Key("atmosphere", "string", choices=("exponential", "msis"), default="exponential",
            doc="density model: Vallado's exponential table, or NRLMSIS 2.1 (pymsis, the "
                "msis extra) with f107, f107a, ap"),
        Key("f107", "number", positive=True,
            doc="msis: F10.7 of the previous day, sfu (held constant)"),
        Key("f107a", "number", positive=True,
            doc="msis: 81-day mean F10.7, sfu (held constant)"),
        Key("ap", "number", nonnegative=True, doc="msis: daily Ap (held constant)"),
        Key("corotation", "boolean", default=True,
            doc="the air turns with the Earth"),
    ), excludes=(("facets", ("surface",)),),
        doc="Aerodynamic drag in free-molecular flow on facets "
            "(attitude.environment.AerodynamicDrag; docs/environment.md); the optical "
            "properties are not used."),
)

_MSIS_KEYS = ("f107", "f107a", "ap")


def _material(name: str, materials: dict, key: str) -> OpticalProperties:
    if name not in materials:
        known = ", ".join(materials) or "none given"
        raise TorqueConfigError(f"unknown material {name!r}; name one of the table's "
                                f"materials ({known})", key=key)
    return materials[name]


def _materials(values: dict) -> dict:
    out = {}
    for name, spec in values.get("materials", {}).items():
        try:
            out[name] = OpticalProperties(spec.get("specular", 0.0), spec.get("diffuse", 0.0),
                                          name=name)
        except AttitudeError as err:
            raise TorqueConfigError(err.reason, key=f"materials.{name}.{err.key}") from None
    return out


def _optics(entry: dict, materials: dict, default: OpticalProperties, key: str
            ) -> OpticalProperties:
    if "material" in entry:
        return _material(entry["material"], materials, f"{key}.material")
    if "specular" in entry or "diffuse" in entry:
        try:
            return OpticalProperties(entry.get("specular", 0.0), entry.get("diffuse", 0.0))
        except AttitudeError as err:
            raise TorqueConfigError(err.reason, key=f"{key}.{err.key}") from None
    return default


def _one_facet(entry: dict, materials: dict, default: OpticalProperties, key: str
               ) -> Facets:
    optics = _optics(entry, materials, default, key)
    center = entry.get("center", np.zeros(3))
    kind = entry["type"]
    if kind == "box":
        return Facets.box(entry["size"], center, specular=optics.specular,
                          diffuse=optics.diffuse)
    normal = np.asarray(entry["normal"], dtype=float)
    if not np.linalg.norm(normal) > 0:
        raise TorqueConfigError("the normal is zero; give the outward direction of the "
                                "facet", key=f"{key}.normal")
    back = optics
    if "back_material" in entry:
        back = _material(entry["back_material"], materials, f"{key}.back_material")
    try:
        plate = Facets.plate(entry.get("area"), normal, center, specular=optics.specular,
                             diffuse=optics.diffuse, back=(back.specular, back.diffuse),
                             size=entry.get("size"), edge=entry.get("edge"))
    except TorqueConfigError as err:
        raise TorqueConfigError(err.reason, key=f"{key}.{err.key}") from None
    if kind == "facet":                    # the front face of a plate
        return Facets(plate.areas[:1], plate.normals[:1], plate.centroids[:1],
                      plate.specular[:1], plate.diffuse[:1], plate.triangles[:2], [0, 0])
    return plate


def _shape_facets(values: dict, context: BuildContext, materials: dict,
                  default: OpticalProperties) -> Facets:
    if context.shape is None:
        raise TorqueConfigError("missing: give facets = [ { type = \"box\", size = [...] }, "
                                "... ] or a [body] shape model", key="facets")
    path = Path(context.folder if context.folder is not None else ".") / context.shape
    shape = context.shared(("shape", path, context.length_unit), lambda: Polyhedron.from_obj(
        path, length_unit=context.length_unit))
    n = len(shape.faces)
    props, index = [default], np.zeros(n, dtype=int)
    for i, item in enumerate(values.get("surface", [])):
        key = f"surface[{i}]"
        faces = item.get("faces")
        if not (isinstance(faces, list) and len(faces) == 2
                and all(isinstance(x, int) and not isinstance(x, bool) for x in faces)
                and 0 <= faces[0] < faces[1] <= n):
            raise TorqueConfigError(f"expected [start, stop] with 0 <= start < stop <= {n} "
                                    f"(face indices of the [body] shape), got {faces!r}",
                                    key=f"{key}.faces")
        props.append(_material(item["material"], materials, f"{key}.material"))
        index[faces[0]:faces[1]] = len(props) - 1
    try:
        return Facets.from_surface(Surface(shape, tuple(props), index))
    except TorqueConfigError as err:
        raise TorqueConfigError(f"the [body] shape: {err.reason}", key="facets") from None


def build_facets(values: dict, context: BuildContext) -> Facets:
    """The :class:`Facets` of a validated ``solar_radiation`` or ``drag`` table: its
    ``facets`` entries, or the faces of the ``[body] shape`` with their materials.

    Examples
    --------
    >>> from attitude.model.torques import BuildContext
    >>> f = build_facets({"facets": [{"type": "plate", "area": 2.0, "normal": [0, 0, 1],
    ...                               "material": "cells"}],
    ...                   "materials": {"cells": {"specular": 0.1, "diffuse": 0.05}}},
    ...                  BuildContext())
    >>> f.areas, f.specular
    (array([2., 2.]), array([0.1, 0.1]))
    """
    materials = _materials(values)
    default = OpticalProperties()
    if "material" in values:
        default = _material(values["material"], materials, "material")
    if "facets" not in values:
        return _shape_facets(values, context, materials, default)
    if not values["facets"]:
        raise TorqueConfigError("expected at least one box, plate or facet", key="facets")
    return Facets.join([_one_facet(entry, materials, default, f"facets[{i}]")
                    for i, entry in enumerate(values["facets"])])


def _center_of_mass(values: dict, context: BuildContext) -> np.ndarray:
    if "center_of_mass" in values:
        return values["center_of_mass"]
    if context.body is not None:
        return np.asarray(context.body.center_of_mass, dtype=float)
    return np.zeros(3)


def _orbit(values: dict, context: BuildContext):
    try:
        check_frame(context.frame)
    except AttitudeError as err:
        raise TorqueConfigError(f"the [state] frame: {err.reason} (the orbit, the Sun and "
                                "the air are Earth-centred)", key="orbit") from None
    return context.orbit(values["orbit"], mu=values.get("mu", EARTH_MU))


def build_solar_radiation(values: dict, context: BuildContext) -> SolarRadiationPressure:
    """A :class:`SolarRadiationPressure` from a validated ``solar_radiation`` table.

    Examples
    --------
    >>> from astropy.time import Time
    >>> from attitude.model.torques import BuildContext
    >>> ctx = BuildContext(epoch=Time("2016-10-01T00:00:00", scale="utc"), frame="GCRF")
    >>> srp = build_solar_radiation({"orbit": {"a": 7.7e6}, "shadow": "none",
    ...     "facets": [{"type": "facet", "area": 1.0, "normal": [1, 0, 0]}]}, ctx)
    >>> srp.shadow is None
    True
    """
    if context.epoch is None:
        raise TorqueConfigError("radiation pressure needs the scenario epoch (the Sun's "
                                "position)", key="orbit")
    facets = build_facets(values, context)
    orbit = _orbit(values, context)
    sun = context.shared(("sun", context.frame), lambda: SunPath(context.epoch,
                                                                 frame=context.frame))
    shadow = values.get("shadow", "conical")
    return SolarRadiationPressure(facets, sun=sun, orbit=orbit,
                                  shadow=None if shadow == "none" else shadow,
                                  center_of_mass=_center_of_mass(values, context),
                                  pressure=values.get("pressure", SOLAR_PRESSURE_1AU),
                                  self_shadowing=values.get("self_shadowing", False),
                                  shadow_subdivision=values.get("shadow_subdivision"))


def build_drag(values: dict, context: BuildContext) -> AerodynamicDrag:
    """An :class:`AerodynamicDrag` from a validated ``drag`` table.

    Examples
    --------
    >>> from attitude.model.torques import BuildContext
    >>> drag = build_drag({"orbit": {"a": 6.8e6}, "cd": 2.0,
    ...     "facets": [{"type": "box", "size": [1.0, 1.0, 1.0]}]}, BuildContext())
    >>> drag.cd, type(drag.density).__name__
    (2.0, 'ExponentialAtmosphere')
    """
    atmosphere = values.get("atmosphere", "exponential")
    if atmosphere == "msis":
        for key in _MSIS_KEYS:
            if key not in values:
                raise TorqueConfigError("missing: the NRLMSIS density needs the solar and "
                                        "geomagnetic indices f107, f107a and ap (held "
                                        "constant over the run)", key=key)
        if context.epoch is None:
            raise TorqueConfigError("NRLMSIS needs the scenario epoch", key="atmosphere")
        density = MSISAtmosphere(values["f107"], values["f107a"], values["ap"],
                                 epoch=context.epoch)
    else:
        for key in _MSIS_KEYS:
            if key in values:
                raise TorqueConfigError("only with atmosphere = \"msis\"", key=key)
        density = ExponentialAtmosphere()
    facets = build_facets(values, context)
    orbit = _orbit(values, context)
    return AerodynamicDrag(facets, orbit, density=density, cd=values.get("cd", 2.2),
                           center_of_mass=_center_of_mass(values, context),
                           corotation=values.get("corotation", True),
                           epoch=context.epoch, frame=context.frame)


for _table, _build in zip(TORQUE_TABLES, (build_solar_radiation, build_drag), strict=True):
    register_torque_type(_table, _build)

"""The scenario file format, declared: one :class:`~attitude.foundations.spec.Table` per TOML table.

:data:`SCENARIO` is the one source of the loader's checks
(:func:`attitude.app.scenario.load_scenario`
runs :func:`attitude.foundations.spec.validate` on it before any work), of
``docs/scenario.schema.json``
(``python -m attitude.app.scenario --schema``) and of the key reference in docs/scenarios.md
(``python -m attitude.app.scenario --reference``).  A new table is a
:class:`~attitude.foundations.spec.Table`
declared here and added to :data:`SCENARIO` (its reader goes into :mod:`attitude.app.scenario`).

Examples
--------
>>> from attitude.app.scenario_spec import SCENARIO
>>> SCENARIO["propagation"].table["duration"].describe()
'quantity (s), > 0'
"""

from __future__ import annotations

from ..environment.config import TORQUE_TABLES as ENVIRONMENT_TORQUE_TABLES
from ..fitting.config import OBSERVATIONS
from ..foundations.expectation import Expectation
from ..foundations.quantities import TIME_SCALES
from ..foundations.spec import Key, Table
from ..model.body import MassProperties
from ..model.regimes import PERIOD_KEYS, REGIMES
from ..model.sampling import DIRECTION_SIGMA, MODELS
from ..model.state import ATTITUDE_TABLE
from ..model.torques import TORQUE_TABLES
from ..photometry import config as photometry_config
from ..propagation.propagator import METHODS
from ..spinorbit import section as spinorbit_section

# --- the environment wing's [[torques]] types (issue 17): "solar_radiation", "drag" ------
# declared in attitude.environment.config (which registers their builders with torques);
# listed here so that the format does not depend on the order of imports
_TORQUE_VARIANTS = tuple({**TORQUE_TABLES,
                          **{t.name: t for t in ENVIRONMENT_TORQUE_TABLES}}.values())
# --- end of the environment block ------------------------------------------------------

__all__ = ["SCENARIO", "ROTATION", "PART", "CONSERVATION_KEYS", "REDUCTIONS", "EXPECT_KEYS",
           "PRIMITIVE_NAMES", "SPIN_EXPECT_KEYS", "SPIN_EXPECT_UNITS"]

#: Largest relative changes over a run that ``[expect]`` may bound.
CONSERVATION_KEYS = ("angular_momentum_rel_drift", "energy_rel_drift")
#: Reductions of a time series for ``[expect.variables]``.
REDUCTIONS = ("start", "end", "max", "min", "mean")
#: Names of ``primitive`` in ``[body] parts`` (with the short aliases).
PRIMITIVE_NAMES = MassProperties.PRIMITIVES + ("box", "cylinder", "tube", "sphere", "shell",
                                               "ellipsoid", "rod", "plate")

SCENARIO_TABLE = Table("scenario", (
    Key("name", "string", doc="default: the file name"),
    Key("description", "string"),
))

#: An attitude (body -> inertial): a quaternion or Euler angles (the model layer's
#: declaration, shared with the binary wing's scenario files).
ROTATION = ATTITUDE_TABLE

#: One part of a composite body (``[body] parts``).
PART = Table("part", (
    Key("primitive", "string", required=True, choices=PRIMITIVE_NAMES),
    Key("mass", "quantity", unit="kg", positive=True),
    Key("masses", "quantity", unit="kg", shape=None, positive=True,
        doc="point_masses: one per position"),
    Key("size", "quantity", unit="m", shape=((2,), (3,)), positive=True,
        doc="box: 3 edges; plate: 2 edges"),
    Key("radius", "quantity", unit="m", positive=True),
    Key("length", "quantity", unit="m", positive=True),
    Key("inner_radius", "quantity", unit="m", nonnegative=True),
    Key("outer_radius", "quantity", unit="m", positive=True),
    Key("semi_axes", "quantity", unit="m", shape=(3,), positive=True),
    Key("positions", "quantity", unit="m", shape=None, doc="point_masses: (n, 3)"),
    Key("offset", "quantity", unit="m", shape=(3,), doc="centre of mass in the body frame"),
    Key("orientation", "table", table=ROTATION, doc="part axes -> body axes"),
))

BODY = Table("body", (
    Key("principal_moments", "quantity", unit="kg m2", shape=(3,), positive=True,
        doc="principal moments; body frame = principal frame"),
    Key("inertia", "quantity", unit="kg m2", shape=(3, 3),
        doc="3x3 tensor in the body frame"),
    Key("shape", "string", doc="OBJ shape model, path relative to the scenario file"),
    Key("density", "quantity", unit="kg/m3", positive=True, doc="bulk density of `shape`"),
    Key("length_unit", "unit", unit="m", default="m",
        doc="unit of the vertex coordinates of `shape`"),
    Key("parts", "tables", table=PART, doc="composite body: an array of primitives"),
    Key("mass", "quantity", unit="kg", positive=True, doc="optional; not with shape"),
    Key("name", "string", doc="label"),
), exactly_one=(("principal_moments", "inertia", "shape", "parts"),),
    needs=(("shape", ("density",)), ("density", ("shape",)), ("length_unit", ("shape",))),
    excludes=(("shape", ("mass",)),),
    doc="Exactly one way of giving the mass properties.")

STATE = Table("state", (
    Key("epoch", "time", required=True, doc="ISO 8601, in `time_scale`"),
    Key("time_scale", "string", choices=TIME_SCALES + tuple(s.upper() for s in TIME_SCALES),
        default="tdb"),
    Key("frame", "string", default="ICRF", doc="inertial frame label (attitude.INERTIAL_FRAMES)"),
    Key("attitude", "table", table=ROTATION, doc="body -> inertial; default identity"),
    Key("omega_body", "quantity", unit="rad/s", shape=(3,), doc="body-frame rates"),
    Key("spin_axis", "table", table=Table("spin_axis", (
        Key("ra", "quantity", unit="rad", required=True, doc="right ascension"),
        Key("dec", "quantity", unit="rad", required=True, doc="declination"),
    )), doc="principal-axis spin along (ra, dec) of `frame`, with spin_rate or spin_period; "
            "instead of attitude and omega_body"),
    Key("spin_rate", "quantity", unit="rad/s", nonnegative=True),
    Key("spin_period", "quantity", unit="s", positive=True),
    Key("spin_about", "string", choices=("A", "B", "C"), default="C",
        doc="principal axis along the spin axis"),
), at_most_one=(("spin_rate", "spin_period"),),
    needs=(("spin_rate", ("spin_axis",)), ("spin_period", ("spin_axis",)),
           ("spin_about", ("spin_axis",))),
    excludes=(("spin_axis", ("attitude", "omega_body")),),
    doc="The initial state. With [ensemble] only epoch, time_scale and frame.")

PROPAGATION = Table("propagation", (
    Key("duration", "quantity", unit="s", required=True, positive=True),
    Key("step", "quantity", unit="s", required=True, positive=True, doc="output step"),
    Key("method", "string", choices=METHODS,
        doc="default: exact without torques, splitting with"),
    Key("rtol", "number", positive=True, bounds=(None, 1.0),
        doc="DOP853 tolerance (selects it with torques), or with method = \"splitting\" "
            "the splitting's error control"),
    Key("integrator_step", "quantity", unit="s", positive=True,
        doc="splitting integrator: longest step"),
    Key("order", "integer", choices=(2, 4, 6), doc="splitting integrator order"),
))

OUTPUT = Table("output", (
    Key("netcdf", "string", doc="relative to the scenario file unless -o is given"),
))

_PERIOD = Expectation.table("period", unit="s", default_unit="s")

_VARIABLE = Expectation.table("variable", unit=None, unit_doc="default: the variable's unit",
                              before=(
    Key("variable", "string", doc="the dataset variable; default: the key"),
    Key("at", "string", choices=REDUCTIONS, doc="reduction of a time series"),
    Key("component", "any", doc="an index (0-based) or \"norm\", for vectors"),
))

# --- the spin period and its trend (attitude.spindown; issue 17) ---
#: ``[expect]`` keys on the spin period of a run and its least-squares trend.
SPIN_EXPECT_KEYS = ("spin_period", "spin_period_trend", "spin_down_efolding")
#: Default units of the spin expectations.
SPIN_EXPECT_UNITS = {"spin_period": "s", "spin_period_trend": "ms/day",
                     "spin_down_efolding": "d"}
_SPIN_EXPECT = (
    Key("spin_period", "table", table=Expectation.table(
        "spin_period", unit="s", default_unit="s", after=(
            Key("at", "string", choices=("start", "end"), default="end",
                doc="the first or last epoch"),)),
        doc="spin period 2 pi L / (2 E), 2 pi / omega for a principal-axis spin "
            "(attitude.spindown)"),
    Key("spin_period_trend", "table", table=Expectation.table(
        "spin_period_trend", unit="", default_unit="ms/day", unit_doc="e.g. ms/day, s/yr"),
        doc="dP/dt, least-squares slope of the spin period over the run"),
    Key("spin_down_efolding", "table", table=Expectation.table(
        "spin_down_efolding", unit="s", default_unit="d"),
        doc="1 / (d ln P / dt) over the run: tau of P = P0 exp(t / tau); negative for a "
            "spin-up"),
)
# --- end spin period ---

_FRACTION = Expectation.table("fraction", with_unit=False, value=Key(
    "value", "number", required=True, bounds=(0.0, 1.0)))

EXPECT = Table("expect", (
    Key("regime", "string", choices=REGIMES),
    *(Key(k, "table", table=_PERIOD, doc=f"the {k} period") for k in PERIOD_KEYS),
    *(Key(k, "table", table=Table("bound", (Key("max", "number", required=True,
                                                nonnegative=True),)),
          doc="largest relative change over the run") for k in CONSERVATION_KEYS),
    Key("nutation_range", "table", table=Table("nutation_range", (
        Key("min", "number", required=True), Key("max", "number", required=True),
        Key("unit", "unit", unit="rad", default="rad"),
        Key("abs_tol", "number", required=True, nonnegative=True)))),
    Key("variables", "map", table=_VARIABLE,
        doc="dataset variables reduced over the run"),
    *_SPIN_EXPECT,                           # the spin period and its trend (issue 17)
    Key("regime_fractions", "map", table=_FRACTION, choices=REGIMES,
        nonempty=True, doc="[ensemble] only: fraction of the valid bodies per regime"),
    # the wings' keys, declared by the wings (spinorbit.section, photometry.config)
    *spinorbit_section.EXPECT,
    *photometry_config.EXPECT,
), doc="What the run should give; a failed expectation exits with 1.")

_PARAMETER_UNITS = {k: v for spec in MODELS.values() for k, v in spec.items()}
_DIRECTION_KEYS = tuple(DIRECTION_SIGMA.values())

ENSEMBLE = Table("ensemble", (
    Key("model", "string", choices=tuple(MODELS), default="tumbling",
        doc="sampling model"),
    Key("size", "integer", positive=True, doc="bodies"),
    Key("seed", "integer", nonnegative=True, doc="the same seed gives the same cloud"),
    Key("mean", "table", table=Table("mean", tuple(
        Key(k, "quantity", unit=unit) for k, unit in _PARAMETER_UNITS.items())),
        doc="the model's parameters (attitude.sampling.MODELS)"),
    Key("sigma", "table", table=Table("sigma", tuple(
        Key(k, "quantity", unit=unit, nonnegative=True)
        for k, unit in {**_PARAMETER_UNITS, **dict.fromkeys(_DIRECTION_KEYS, "rad")}.items())),
        doc="1-sigma normal errors"),
    Key("table", "string", doc="a CSV/Parquet table of bodies, relative to the scenario"),
    Key("chunk", "integer", positive=True, doc="bodies per dask task"),
    Key("include_nominal", "boolean", default=True, doc="body 0 is the mean state"),
), exactly_one=(("table", "mean"),),
    needs=(("mean", ("size", "seed")),),
    excludes=(("table", ("size", "seed", "model", "sigma", "include_nominal")),),
    doc="A population: a sampled cloud (model, size, seed, mean, sigma) or a table of "
        "bodies. Table columns: A, B, C (or Ixx, Iyy, Izz[, Ixy, Ixz, Iyz]), qx, qy, qz, "
        "qw, wx, wy, wz, name; units in brackets (`wx [deg/s]`), SI without.")

#: ``[[events]]`` types and their keys (attitude.propagation.events).
EVENT_TABLES = (
    Table("nutation_crossing", (
        Key("angle", "quantity", unit="rad", required=True, bounds=(0.0, 3.141592653589793),
            doc="angle between L and the principal axis"),
        Key("axis", "string", choices=("A", "B", "C"), default="C",
            doc="principal axis (A <= B <= C)"),
        Key("terminal", "boolean", default=False, doc="stop the run at the first crossing"),
        Key("direction", "integer", choices=(-1, 0, 1), default=0,
            doc="+1 increasing, -1 decreasing, 0 both"),
    ), doc="The nutation angle between L and a principal axis crosses `angle` "
           "(attitude.nutation_crossing)."),
)

#: The whole scenario file.
SCENARIO = Table("", (
    Key("scenario", "table", table=SCENARIO_TABLE),
    Key("body", "table", table=BODY),
    Key("state", "table", table=STATE, required=True),
    Key("propagation", "table", table=PROPAGATION, required=True),
    Key("torques", "tables", variants=_TORQUE_VARIANTS,
        doc="any number; they add (docs/torques.md)"),
    Key("events", "tables", variants=EVENT_TABLES,
        doc="located on the run and recorded in the ephemeris (event_time, event_name)"),
    Key("output", "table", table=OUTPUT),
    Key("expect", "table", table=EXPECT),
    Key("ensemble", "table", table=ENSEMBLE),
    Key("observations", "table", table=OBSERVATIONS,
        doc="what was measured, for `attitude fit` (docs/tutorial_fitting.md)"),
    Key("section", "table", table=spinorbit_section.SECTION,
        doc="surface of section for `attitude section` (docs/spinorbit.md; read by "
            "attitude.spinorbit.section)"),
    Key("photometry", "table", table=photometry_config.PHOTOMETRY,
        doc="lightcurve for `attitude lightcurve` (docs/photometry.md; read by "
            "attitude.photometry.config)"),
), exactly_one=(("body", "ensemble"),), excludes=(("ensemble", ("body",)),))

#: Keys of the ``[expect]`` table.
EXPECT_KEYS = EXPECT.names()

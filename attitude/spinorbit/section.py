"""Scenario glue of the spin-orbit wing: the ``[section]`` table, the ``[expect]`` keys
``libration_amplitude`` and ``resonance``, and ``attitude section`` (netCDF + figure).

``scenario.py`` and ``cli.py`` only call the functions here (:func:`parse_expect`,
:func:`parse_section`, :func:`expectation_values`, :func:`run_section`), so the scenario
reader can change without touching the physics.  A spin-orbit scenario is an ordinary
scenario whose ``[[torques]]`` hold one ``gravity_gradient`` with a Keplerian ``orbit``;
:func:`spin_orbit_of` builds the :class:`SpinOrbit` from it.

``[section]`` keys::

    [section]
    n_orbits = 200                                         # map iterations
    angles = { min = -90, max = 90, count = 20, unit = "deg" }   # or a list (rad)
    rates = { min = 0.0, max = 3.5, count = 20 }           # spin rate / mean motion
    lyapunov = true                                        # chaotic / regular verdicts
    rtol = 1e-9
    seed = 0
    netcdf = "section.nc"                                  # relative to the file

The grid is the outer product of ``angles`` and ``rates`` (``count_a * count_r``
initial conditions), or, when both are lists of equal length, their pairs.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import xarray as xr

from ..foundations.errors import AttitudeError, SpinOrbitError
from ..foundations.expectation import Expectation
from ..foundations.figures import agg_figure
from ..foundations.quantities import to_si
from ..foundations.spec import Key, Table, json_schema, validate
from ..model.ephemeris import write_atomically
from ..model.orbit import KeplerOrbit
from ..model.torques import GravityGradient, SumTorque
from .libration import long_axis_angle, measure_libration
from .model import SpinOrbit
from .planar import periodic_orbit

#: The ``{min, max, count, unit}`` form of a grid axis of the ``[section]`` table.
GRID = Table("grid", (
    Key("min", "number", required=True),
    Key("max", "number", required=True),
    Key("count", "integer", required=True, positive=True),
    Key("unit", "unit", doc="angles: default rad"),
))
#: A grid axis: a list of numbers, or :data:`GRID` (checked by :func:`parse_section`).
_GRID_SCHEMA = {"oneOf": [
    {"type": "array", "items": {"type": "number"}, "minItems": 1},
    json_schema(GRID, root=False),
]}

#: The ``[section]`` table (in :data:`attitude.app.scenario_spec.SCENARIO`; read by
#: :func:`parse_section`).
SECTION = Table("section", (
    Key("n_orbits", "integer", bounds=(1, 100_000), default=200, doc="map iterations"),
    Key("angles", "any", required=True, schema=_GRID_SCHEMA,
        doc="long-axis angle from periapsis: a list (rad) or { min, max, count, unit }"),
    Key("rates", "any", required=True, schema=_GRID_SCHEMA,
        doc="spin rate / mean motion: a list or { min, max, count }"),
    Key("lyapunov", "boolean", default=True, doc="chaotic / regular verdicts"),
    Key("rtol", "number", bounds=(1e-14, 1e-3), default=1e-9,
        doc="integrator tolerance, below 1e-3"),
    Key("seed", "integer", nonnegative=True, default=0),
    Key("netcdf", "string", doc="relative to the scenario file"),
), doc="Spin-orbit surface of section (attitude section): grid of initial conditions at "
       "periapsis, angles (rad or {min, max, count, unit}) and rates (spin rate / mean "
       "motion).")

#: The spin-orbit ``[expect]`` keys (in :data:`attitude.app.scenario_spec.SCENARIO`; read by
#: :func:`parse_expect`).
EXPECT = (
    Key("libration_amplitude", "table", table=Expectation.table(
        "libration_amplitude", unit="rad", default_unit="rad",
        value=Key("value", "number", required=True, nonnegative=True)),
        doc="Forced libration in longitude measured from the run (spin-orbit wing)."),
    Key("resonance", "string",
        schema={"type": "string", "pattern": "^(none|[0-9]+:[0-9]+)$"},
        doc="The p:q spin-orbit state of the run (\"1:1\", \"3:2\", or \"none\")."),
)

__all__ = ["EXPECT", "EXPECT_KEYS", "GRID", "SECTION", "SECTION_KEYS", "SectionConfig",
           "parse_expect", "parse_section", "load_tables", "spin_orbit_of", "expectation_values",
           "mean_spin_resonance", "run_section", "write_section", "island_centres",
           "section_figure"]

#: ``[expect]`` keys owned by the spin-orbit wing.
EXPECT_KEYS = tuple(k.name for k in EXPECT)
#: Keys of the ``[section]`` table.
SECTION_KEYS = SECTION.names()

Fail = Callable[[str, str], Exception]


def _fail_default(key: str, message: str) -> Exception:
    return SpinOrbitError(message, key=key)


# --- [expect] ---------------------------------------------------------------------------

def _checked(table, spec: Table, where: str, fail: Fail) -> dict:
    """``table`` validated against ``spec`` (:func:`attitude.foundations.spec.validate`),
    its errors raised by ``fail(key, message)``."""
    try:
        return validate(table, spec, where=where, error=SpinOrbitError)
    except AttitudeError as exc:
        raise fail(exc.key, exc.reason) from None


def parse_expect(key: str, spec, fail: Fail = _fail_default) -> Expectation:
    """Validate one spin-orbit ``[expect]`` entry at load time.

    ``libration_amplitude = { value = 1.14, unit = "deg", rel_tol = 0.05 }`` (or
    ``abs_tol`` in the same unit): the forced libration measured from the run
    (:func:`measure_libration`).  ``resonance = "1:1"``: the p:q state of the run
    (:func:`mean_spin_resonance`).

    Examples
    --------
    >>> e = parse_expect("libration_amplitude", {"value": 1.2, "unit": "deg", "rel_tol": 0.1})
    >>> e.entry()
    {'key': 'libration_amplitude', 'expected': 1.2, 'unit': 'deg', 'tolerance': 0.12}
    """
    where = f"expect.{key}"
    if key not in EXPECT_KEYS:
        raise fail(where, f"not a spin-orbit expectation (known: {', '.join(EXPECT_KEYS)})")
    if key == "resonance":
        if not isinstance(spec, str) or not _ratio(spec):
            raise fail(where, f"expected a string \"p:q\" such as \"1:1\" or \"3:2\", or "
                              f"\"none\", got {spec!r}")
        return Expectation.exact(key, spec.strip().replace(" ", ""))
    table = _checked({key: spec}, Table("expect", EXPECT), "expect", fail)[key]
    return Expectation.from_table(key, table, default_unit="rad")


def _ratio(text: str) -> tuple[int, int] | None:
    text = text.strip().replace(" ", "")
    if text == "none":
        return (0, 0)
    parts = text.split(":")
    if len(parts) != 2 or not all(p.isdigit() for p in parts) or int(parts[1]) == 0:
        return None
    return int(parts[0]), int(parts[1])


def spin_orbit_of(body, torques) -> SpinOrbit:
    """The :class:`SpinOrbit` of a scenario: its body and the Keplerian orbit of its one
    gravity-gradient torque.

    Raises
    ------
    SpinOrbitError
        When there is no gravity-gradient torque on a :class:`KeplerOrbit`.

    Examples
    --------
    >>> import attitude as att
    >>> body = att.RigidBody.from_principal_moments([0.5, 0.8, 1.0])
    >>> gg = GravityGradient(orbit=KeplerOrbit(mu=1.0, a=1.0, e=0.1))
    >>> round(spin_orbit_of(body, [gg]).omega0, 4)
    0.9487
    """
    terms = []
    for t in torques or ():
        terms.extend(t.terms if isinstance(t, SumTorque) else [t])
    gg = [t for t in terms if isinstance(t, GravityGradient)
          and isinstance(t.orbit, KeplerOrbit)]
    if len(gg) != 1:
        raise SpinOrbitError("a spin-orbit scenario needs exactly one [[torques]] table "
                             "with type = \"gravity_gradient\" and a Keplerian orbit = "
                             "{ a = ..., e = ... }", key="torques")
    return SpinOrbit(body, gg[0].orbit)


def mean_spin_resonance(ephemeris, orbit: KeplerOrbit, *, max_q: int = 2,
                        tolerance: float = 0.02) -> tuple[str, float]:
    """The p:q state of a run: the ratio ``p/q`` (``q <= max_q``) nearest the mean spin
    rate (long-axis angle advanced over the run / mean anomaly advanced), when within
    ``tolerance`` and the angle ``theta - (p/q) M`` stays within ``pi/2`` of its mean
    (the long axis librates instead of circulating); else ``"none"``.

    Returns
    -------
    name, mean_rate : str, float

    Examples
    --------
    >>> so = SpinOrbit.from_omega0(0.5, KeplerOrbit(mu=1.0, a=1.0, e=0.0))
    >>> eph = so.propagate(np.linspace(0.0, 4 * math.pi, 65), so.initial_state(0.0, 1.5))
    >>> mean_spin_resonance(eph, so.orbit)[0]       # a circular orbit: no 3:2 lock
    'none'
    """
    t = np.asarray(ephemeris.time, dtype=float)
    theta = long_axis_angle(ephemeris.dataset["quaternion"].values, ephemeris.body, orbit)
    M = orbit.mean_anomaly_at(t)
    dM = M[-1] - M[0]
    if not dM > 0:
        raise SpinOrbitError("the run is too short to measure the mean spin rate",
                             key="ephemeris")
    rate = float((theta[-1] - theta[0]) / dM)
    best, name = math.inf, "none"
    for q in range(1, max_q + 1):
        p = round(rate * q)
        miss = abs(rate - p / q)
        if p < 1 or miss >= min(best, tolerance):
            continue
        g = theta - (p / q) * M
        if np.max(np.abs(g - np.mean(g))) < math.pi / 2:
            k = math.gcd(p, q)
            name, best = f"{p // k}:{q // k}", miss
    return name, rate


def expectation_values(scenario, ephemeris) -> dict:
    """What the spin-orbit ``[expect]`` keys of a scenario got from its run:
    ``{"libration_amplitude": value in the expected unit, "resonance": "p:q"}`` (a key
    whose value cannot be computed maps to None).

    Examples
    --------
    >>> from attitude.app.scenario import load_scenario
    >>> sc = load_scenario("scenarios/phobos_libration.toml")    # expects 1:1 and 1.14 deg
    >>> so = spin_orbit_of(sc.body, sc.torques)
    >>> eph = so.propagate(np.linspace(0.0, so.orbit.period, 33))  # one orbit, locked
    >>> got = expectation_values(sc, eph)
    >>> got["resonance"], round(got["libration_amplitude"], 2)
    ('1:1', 1.14)
    """
    wanted = {e.key: e for e in scenario.expect if e.key in EXPECT_KEYS}
    if not wanted:
        return {}
    out = dict.fromkeys(wanted)
    try:
        so = spin_orbit_of(scenario.body, scenario.torques)
    except SpinOrbitError:
        return out
    if "libration_amplitude" in wanted:
        try:
            m = measure_libration(ephemeris, so.orbit)
            unit = wanted["libration_amplitude"].unit
            out["libration_amplitude"] = m.amplitude / to_si(f"1 {unit}", "rad", name="unit")
        except SpinOrbitError:
            pass
    if "resonance" in wanted:
        try:
            out["resonance"] = mean_spin_resonance(ephemeris, so.orbit)[0]
        except SpinOrbitError:
            pass
    return out


# --- [section] --------------------------------------------------------------------------

@dataclass(frozen=True, eq=False)
class SectionConfig:
    """A parsed ``[section]`` table (angles in rad, rates in units of n).

    Examples
    --------
    >>> cfg = parse_section({"angles": [0.0, 0.5], "rates": [1.0, 1.5], "n_orbits": 10})
    >>> cfg.angles.tolist(), cfg.rates.tolist(), cfg.n_orbits, cfg.lyapunov
    ([0.0, 0.5], [1.0, 1.5], 10, True)
    """

    angles: np.ndarray
    rates: np.ndarray
    n_orbits: int = 200
    lyapunov: bool = True
    rtol: float = 1e-9
    seed: int = 0
    netcdf: Path | None = None


def _axis(spec, key: str, unit: str, fail: Fail) -> tuple[np.ndarray, bool]:
    """A grid axis: a list (SI / dimensionless), or { min, max, count, unit }."""
    if isinstance(spec, list):
        try:
            values = np.array([float(v) for v in spec])
        except (TypeError, ValueError):
            raise fail(key, f"expected a list of numbers, got {spec!r}") from None
        if values.size == 0 or not np.all(np.isfinite(values)):
            raise fail(key, "expected a non-empty list of finite numbers")
        return values, True
    if not isinstance(spec, Mapping):
        raise fail(key, "expected { min = ..., max = ..., count = ... } or a list")
    spec = _checked(spec, GRID, key, fail)
    try:
        scale = 1.0 if unit == "" else to_si(f"1 {spec.get('unit', unit)}", unit,
                                             key=f"{key}.unit")
    except AttitudeError as exc:
        raise fail(f"{key}.unit", exc.reason) from None
    lo, hi, count = spec["min"] * scale, spec["max"] * scale, spec["count"]
    if not (math.isfinite(lo) and math.isfinite(hi) and hi >= lo):
        raise fail(key, f"expected finite min <= max, got {spec.get('min')!r}, "
                        f"{spec.get('max')!r}")
    return np.linspace(lo, hi, count), False


def parse_section(table, folder: Path | None = None, fail: Fail = _fail_default
                  ) -> SectionConfig:
    """Validate a ``[section]`` table (see the module docstring).

    Examples
    --------
    >>> cfg = parse_section({"angles": {"min": -90, "max": 90, "count": 3, "unit": "deg"},
    ...                      "rates": [1.0, 2.0], "n_orbits": 10})
    >>> cfg.angles.size, round(float(cfg.angles[0]), 6), cfg.n_orbits
    (6, -1.570796, 10)
    """
    if not isinstance(table, Mapping):
        raise fail("section", "expected a table [section]")
    table = _checked(table, SECTION, "section", fail)
    a, a_list = _axis(table["angles"], "section.angles", "rad", fail)
    r, r_list = _axis(table["rates"], "section.rates", "", fail)
    if a_list and r_list and a.size == r.size:
        angles, rates = a, r
    else:
        A, R = np.meshgrid(a, r, indexing="ij")
        angles, rates = A.ravel(), R.ravel()
    n_orbits = table.get("n_orbits", 200)
    lyap = table.get("lyapunov", True)
    rtol = table.get("rtol", 1e-9)
    if not rtol < 1e-3:
        raise fail("section.rtol", f"expected a float in [1e-14, 1e-3), got {rtol!r}")
    seed = table.get("seed", 0)
    netcdf = table.get("netcdf")
    path = None if netcdf is None else (Path(folder or ".") / netcdf)
    return SectionConfig(angles=angles, rates=rates, n_orbits=n_orbits, lyapunov=lyap,
                         rtol=rtol, seed=seed, netcdf=path)


def load_tables(doc: Mapping, *, body, torques, expect, ensemble=None,
                folder: Path | None = None, fail: Fail = _fail_default
                ) -> SectionConfig | None:
    """The scenario reader's hook: parse the ``[section]`` table of a TOML document and
    check that a scenario with a ``[section]`` or a spin-orbit ``[expect]`` key is a
    spin-orbit problem (one body, one gravity-gradient torque on a Keplerian orbit).

    Parameters
    ----------
    doc : mapping
        The whole TOML document.
    body, torques, expect, ensemble
        What the scenario reader built (``expect``: the parsed entries).
    folder : Path
        The scenario's folder (``netcdf`` is relative to it).
    fail : callable
        ``fail(key, message) -> Exception`` of the reader (names the file).

    Returns
    -------
    SectionConfig or None

    Examples
    --------
    >>> load_tables({}, body=None, torques=(), expect=()) is None
    True
    """
    section = None
    if "section" in doc:
        section = parse_section(doc["section"], folder, fail)
    keys = [e.key for e in expect if e.key in EXPECT_KEYS]
    if keys and ensemble is not None:
        raise fail(f"expect.{keys[0]}", "not for [ensemble] scenarios (one body on one "
                                        "orbit)")
    if keys or section is not None:
        try:
            spin_orbit_of(body, torques)
        except SpinOrbitError as exc:
            raise fail("torques", exc.reason) from None
    return section


def run_section(so: SpinOrbit, config: SectionConfig) -> xr.Dataset:
    """The surface of section of a ``[section]`` table (:meth:`SpinOrbit.surface_of_section`).

    Examples
    --------
    >>> so = SpinOrbit.from_omega0(0.89, KeplerOrbit(mu=1.0, a=1.0, e=0.1))
    >>> cfg = parse_section({"angles": [0.0], "rates": [3.3], "n_orbits": 10})
    >>> run_section(so, cfg)["chaotic"].values.tolist()
    [False]
    """
    return so.surface_of_section(config.angles, config.rates, config.n_orbits,
                                 lyapunov=config.lyapunov, rtol=config.rtol,
                                 seed=config.seed)


def write_section(section: xr.Dataset, path) -> Path:
    """Write a surface of section to netCDF atomically (temporary file + rename); the
    boolean ``chaotic`` is stored as a 0/1 flag (CF ``flag_values``).

    Examples
    --------
    >>> import tempfile
    >>> so = SpinOrbit.from_omega0(0.89, KeplerOrbit(mu=1.0, a=1.0, e=0.1))
    >>> sec = so.surface_of_section([0.0], [3.3], n_orbits=3)
    >>> path = write_section(sec, Path(tempfile.mkdtemp()) / "s.nc")
    >>> xr.open_dataset(path).sizes["orbit"]
    4
    """
    path = Path(path)
    ds = section.copy()
    if "chaotic" in ds:
        ds["chaotic"] = ds["chaotic"].astype("i1")
        ds["chaotic"].attrs.update({"flag_values": [0, 1],
                                    "flag_meanings": "regular chaotic"})
    return write_atomically(path, lambda tmp: ds.to_netcdf(tmp))


def island_centres(so: SpinOrbit, max_rate: float = 3.0) -> list[tuple[str, float, float,
                                                                         float]]:
    """The p:q periodic orbits at periapsis, ``(name, angle, rate, trace)``, for each
    resonance of :meth:`SpinOrbit.resonances` whose periodic orbit is found from the
    resonance centre (``|trace| < 2``: an island; else unstable, in a chaotic zone).

    Examples
    --------
    >>> import attitude as att
    >>> so = SpinOrbit.from_omega0(0.89, att.KeplerOrbit(mu=1.0, a=1.0, e=0.1))
    >>> [(name, abs(tr) < 2) for name, _, _, tr in island_centres(so, 2.0)]
    [('1:2', True), ('1:1', True), ('2:1', True)]
    """
    out = []
    for r in so.resonances(max_rate=max_rate):
        try:
            th, w, mono = periodic_orbit(so.omega0, so.e, r.p, r.q)
        except SpinOrbitError:
            continue
        out.append((r.name, th, w, float(np.trace(mono))))
    return out


def section_figure(section: xr.Dataset, *, title: str | None = None, centres=()):
    """The surface of section as a matplotlib Figure: regular orbits in colour, chaotic
    ones in grey, the p:q periodic orbits of ``centres`` (:func:`island_centres`) marked
    (filled: an island, open: unstable).

    Raises
    ------
    PlotUnavailableError
        Without matplotlib.

    Examples
    --------
    >>> import attitude as att
    >>> so = att.SpinOrbit.from_omega0(0.89, att.KeplerOrbit(mu=1.0, a=1.0, e=0.1))
    >>> cfg = parse_section({"angles": [0.0, 0.5], "rates": [1.0, 1.5], "n_orbits": 10})
    >>> section = run_section(so, cfg)
    >>> section.angle.shape                                 # 2 orbits, 10 crossings + start
    (2, 11)
    >>> fig = section_figure(section, title="Hyperion")
    >>> fig.axes[0].get_title()
    'Hyperion'
    """
    fig = agg_figure(figsize=(7.0, 6.0), layout="constrained")
    ax = fig.add_subplot()
    ang = np.degrees(section["angle"].values)
    rate = section["rate"].values
    chaotic = section["chaotic"].values.astype(bool) if "chaotic" in section else \
        np.zeros(ang.shape[0], bool)
    if chaotic.any():
        ax.plot(ang[chaotic].ravel(), rate[chaotic].ravel(), ",", color="0.55",
                rasterized=True)
    reg = np.flatnonzero(~chaotic)
    colours = ["C0", "C1", "C2", "C3", "C4", "C5", "C6", "C8", "C9"]
    for k, i in enumerate(reg):
        ax.plot(ang[i], rate[i], ".", ms=1.0, color=colours[k % len(colours)],
                rasterized=True)
    for name, th, w, trace in centres:
        x = math.degrees(th - math.pi * math.floor(th / math.pi + 0.5))
        ax.plot([x], [w], "o", ms=5, mec="k", mfc="k" if abs(trace) < 2 else "none")
        ax.annotate(name, (x, w), xytext=(4, 4), textcoords="offset points", fontsize=9)
    ax.set_xlim(-90, 90)
    ax.set_xlabel("angle of the long axis from periapsis at periapsis (deg)")
    ax.set_ylabel("spin rate / mean motion at periapsis")
    e, w0 = section.attrs.get("eccentricity"), section.attrs.get("omega0")
    n = int(chaotic.sum())
    ax.set_title(title or f"surface of section, e = {e:.3g}, omega0 = {w0:.3g}: "
                          f"{n}/{chaotic.size} chaotic (grey)")
    return fig

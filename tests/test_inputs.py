"""Every bad input gets exit 2 and one line naming the file and the key (issue 14 item 2).

The mutations are generated from the declaration of the format
(:data:`attitude.app.scenario_spec.SCENARIO`): for every key of every table that the base
scenarios below use, each kind of bad value the key's declaration rules out (wrong type,
wrong length, empty, NaN/inf, non-positive, a date that does not exist, a unit of the wrong
dimension), plus the examples of the issue.  Each runs ``attitude run`` in-process and
must exit 2 with one line ``attitude: error: FILE: KEY: ...`` on stderr.  A property test
feeds randomly mutated shipped scenarios to the command: exit 0/1/2/3, never a traceback.
"""

from __future__ import annotations

import copy
import importlib.util
import json
import math
import tomllib
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from attitude.app.cli import main
from attitude.app.scenario import load_scenario
from attitude.app.scenario_spec import SCENARIO
from attitude.foundations.quantities import to_si

ROOT = Path(__file__).resolve().parents[1]
SHIPPED = sorted((ROOT / "scenarios").glob("*.toml"))

# --- a small TOML writer (tomllib reads only) ------------------------------------------


def _value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if math.isnan(v):
            return "nan"
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return repr(v)
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, list):
        return "[" + ", ".join(_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{_name(k)} = {_value(x)}" for k, x in v.items()) + " }"
    raise TypeError(type(v))


def _name(k: str) -> str:
    return k if k.replace("_", "").replace("-", "").isalnum() else json.dumps(k)


def dump_toml(doc: dict) -> str:
    """TOML text of ``doc``: top-level tables as [name], arrays of tables as [[name]],
    anything deeper inline."""
    lines = []
    for k, v in doc.items():
        if not isinstance(v, (dict, list)) or (isinstance(v, list) and not (
                v and all(isinstance(x, dict) for x in v))):
            lines.append(f"{_name(k)} = {_value(v)}")
    for k, v in doc.items():
        if isinstance(v, dict):
            lines.append(f"\n[{_name(k)}]")
            lines += [f"{_name(a)} = {_value(b)}" for a, b in v.items()]
        elif isinstance(v, list) and v and all(isinstance(x, dict) for x in v):
            for item in v:
                lines.append(f"\n[[{_name(k)}]]")
                lines += [f"{_name(a)} = {_value(b)}" for a, b in item.items()]
    return "\n".join(lines) + "\n"


# --- base scenarios that together use every key ----------------------------------------

ORBIT = {"a": "7000 km", "e": 0.01, "i": "51.6 deg", "raan": "10 deg", "argp": "20 deg",
         "mean_anomaly": "30 deg", "epoch": "2029-12-31T23:00:00"}

BASES = {
    "single": {
        "scenario": {"name": "single", "description": "a body with torques and events"},
        "body": {"principal_moments": [1.0, 2.0, 3.0], "name": "b", "mass": "10 kg"},
        "state": {"epoch": "2030-01-01T00:00:00", "time_scale": "tdb", "frame": "ICRF",
                  "attitude": {"quaternion_scalar_last": [0, 0, 0, 1]},
                  "omega_body": {"value": [5.0, 0.0, 20.0], "unit": "deg/s"}},
        "propagation": {"duration": "1 min", "step": "10 s", "method": "integrator",
                        "rtol": 1e-10},
        "torques": [{"type": "gravity_gradient", "mu": "3.986004418e14 m3/s2",
                     "orbit": dict(ORBIT)},
                    {"type": "constant", "torque": {"value": [0, 0, 1e-6], "unit": "N m"},
                     "frame": "inertial"},
                    {"type": "dissipation", "time_constant": "30 min"}],
        "events": [{"type": "nutation_crossing", "angle": "30 deg", "axis": "C",
                    "terminal": False, "direction": 1}],
        "output": {"netcdf": "out.nc"},
        "expect": {"regime": "SAM",
                   "precession": {"value": 1.0, "unit": "h", "rel_tol": 0.1},
                   "energy_rel_drift": {"max": 1e-6},
                   "nutation_range": {"min": 1.0, "max": 2.0, "unit": "deg", "abs_tol": 0.1},
                   "variables": {"kinetic_energy": {"at": "end", "value": 1.0, "unit": "J",
                                                    "abs_tol": 1.0}}},
    },
    "spin": {
        "body": {"inertia": [[1.0, 0, 0], [0, 2.0, 0], [0, 0, 3.0]]},
        "state": {"epoch": "2030-01-01T00:00:00", "time_scale": "utc",
                  "spin_axis": {"ra": "10 deg", "dec": "20 deg"}, "spin_period": "1 h",
                  "spin_about": "C"},
        "propagation": {"duration": "1 min", "step": "10 s", "method": "splitting",
                        "integrator_step": "1 s", "order": 4},
        "torques": [{"type": "eddy_current",
                     "shell": {"radius": "0.5 m", "thickness": "2 mm",
                               "conductivity": "3.5e7 S/m"},
                     "field": {"model": "dipole", "moment": "8e22 A m2", "tilt": "11 deg",
                               "pole_longitude": "-72 deg", "rotation_angle": "0 deg",
                               "rotation_rate": "7.29e-5 rad/s"},
                     "mu": "3.986004418e14 m3/s2", "orbit": {"a": "7000 km"}},
                    {"type": "heavy_top", "pivot_to_com": {"value": [0, 0, 4], "unit": "cm"},
                     "mass": "1 kg", "g": "9.81 m/s2", "up": [0, 0, 1]}],
    },
    "parts": {
        "body": {"parts": [
            {"primitive": "box", "mass": 500.0, "size": [1.0, 1.0, 2.0],
             "offset": [0.0, 0.0, 0.1],
             "orientation": {"euler": "ZXZ", "angles": {"value": [10, 20, 30],
                                                         "unit": "deg"}}},
            {"primitive": "tube", "mass": 5.0, "length": 1.0, "inner_radius": 0.1,
             "outer_radius": 0.2},
            {"primitive": "ellipsoid", "mass": 5.0, "semi_axes": [1.0, 2.0, 3.0]},
            {"primitive": "sphere", "mass": 5.0, "radius": 0.3},
            {"primitive": "point_masses", "masses": [1.0, 2.0],
             "positions": [[1.0, 0, 0], [0, 1.0, 0]]}]},
        "state": {"epoch": "2030-01-01T00:00:00",
                  "spin_axis": {"ra": 0.1, "dec": 0.2}, "spin_rate": "1 deg/s"},
        "propagation": {"duration": "1 min", "step": "10 s"},
        "torques": [{"type": "eddy_current", "sphere": {"radius": 0.5, "conductivity": 3e7},
                     "field": {"model": "uniform", "vector": {"value": [45000, 0, 0],
                                                              "unit": "nT"}}},
                    {"type": "eddy_current", "magnetic_tensor": 9000.0,
                     "field": {"model": "uniform", "vector": [4.5e-5, 0, 0]}}],
    },
    "euler": {
        "body": {"principal_moments": [1.0, 2.0, 3.0]},
        "state": {"epoch": "2030-01-01T00:00:00",
                  "attitude": {"quaternion_scalar_first": [1, 0, 0, 0]},
                  "omega_body": [0.1, 0.0, 0.3]},
        "propagation": {"duration": "1 min", "step": "10 s", "method": "exact"},
    },
    "cloud": {
        "state": {"epoch": "2029-03-14T00:00:00", "frame": "ECLIPJ2000"},
        "ensemble": {"model": "tumbling", "size": 4, "seed": 1, "chunk": 2,
                     "include_nominal": True,
                     "mean": {"angular_momentum_ra": "250 deg",
                              "angular_momentum_dec": "-75 deg", "energy_ratio": 1.024,
                              "ratio_a": 0.61, "ratio_b": 0.965,
                              "precession_period": "27.38 h", "precession_angle": "0 deg",
                              "rotation_angle": "0 deg", "moment_c": 1.0},
                     "sigma": {"energy_ratio": 0.0043, "precession_period": "0.0233 h",
                               "angular_momentum_direction": "2 deg"}},
        "propagation": {"duration": "1 min", "step": "10 s"},
        "expect": {"regime_fractions": {"SAM": {"value": 0.9, "abs_tol": 0.1}}},
    },
    "spin_cloud": {
        "state": {"epoch": "2029-03-14T00:00:00"},
        "ensemble": {"model": "spin", "size": 3, "seed": 0,
                     "mean": {"spin_ra": "10 deg", "spin_dec": "20 deg",
                              "spin_rate": "10 deg/h", "ratio_a": 0.5, "ratio_b": 0.8},
                     "sigma": {"spin_direction": "1 deg"}},
        "propagation": {"duration": "1 min", "step": "10 s"},
    },
    "catalogue": {
        "state": {"epoch": "2030-01-01T00:00:00", "time_scale": "tt", "frame": "GCRF"},
        "ensemble": {"table": "bodies.csv"},
        "propagation": {"duration": "1 min", "step": "10 s"},
    },
    "shape": {
        "body": {"shape": "cube.obj", "density": "2.6 g/cm3", "length_unit": "km"},
        "state": {"epoch": "2030-01-01T00:00:00", "omega_body": [0.0, 0.0, 1e-4]},
        "propagation": {"duration": "1 min", "step": "10 s"},
    },
    # the environment's torque types (issue 17): facets of every kind, named materials
    "environment": {
        "body": {"principal_moments": [100.0, 120.0, 150.0]},
        "state": {"epoch": "2016-10-19T00:00:00", "time_scale": "utc", "frame": "GCRF",
                  "omega_body": [0.0, 0.0, 0.1]},
        "propagation": {"duration": "1 min", "step": "10 s"},
        "torques": [
            {"type": "solar_radiation", "orbit": {"a": "7715 km", "i": "66 deg"},
             "mu": "3.986004418e14 m3/s2", "shadow": "cylindrical",
             "pressure": "4.56e-6 N/m2", "center_of_mass": [0.0, 0.01, 0.0],
             "material": "mli",
             "materials": {"mli": {"specular": 0.3, "diffuse": 0.1},
                           "cells": {"specular": 0.05, "diffuse": 0.05}},
             "facets": [{"type": "box", "size": [1.0, 1.0, 2.0], "center": [0.0, 0.0, 0.1],
                         "material": "mli"},
                        {"type": "plate", "area": "4 m2", "normal": [1.0, 0.0, 1.0],
                         "center": [0.0, 2.0, 0.0], "material": "cells",
                         "back_material": "mli"},
                        {"type": "facet", "area": 0.5, "normal": [0.0, 0.0, 1.0],
                         "center": [0.0, 0.0, 1.2], "specular": 0.2, "diffuse": 0.3}]},
            {"type": "drag", "orbit": {"a": "6778 km", "i": "51.6 deg"}, "cd": 2.2,
             "atmosphere": "exponential", "corotation": True,
             "facets": [{"type": "box", "size": [1.0, 1.0, 2.0]}]},
        ],
    },
    "environment_shape": {
        "body": {"shape": "cube.obj", "density": "2.6 g/cm3"},
        "state": {"epoch": "2016-10-19T00:00:00", "time_scale": "utc", "frame": "GCRF",
                  "omega_body": [0.0, 0.0, 1e-4]},
        "propagation": {"duration": "1 min", "step": "10 s"},
        "torques": [
            {"type": "solar_radiation", "orbit": {"a": "7715 km", "i": "66 deg"},
             "materials": {"white": {"specular": 0.0, "diffuse": 0.8}},
             "surface": [{"faces": [0, 4], "material": "white"}]},
        ],
    },
}
if importlib.util.find_spec("pymsis") is not None:    # the msis extra: its keys too
    BASES["environment"]["torques"][1].update(atmosphere="msis", f107=150.0, f107a=140.0,
                                              ap=15.0)

CSV = "name,A [kg m2],B,C,qx,qy,qz,qw,wx [deg/s],wy,wz\nx,1,2,3,0,0,0,1,1,0,0.001\n"
CUBE_OBJ = ("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
            "f 1 4 3\nf 1 3 2\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\nf 2 3 7\nf 2 7 6\n"
            "f 3 4 8\nf 3 8 7\nf 4 1 5\nf 4 5 8\n")


def _write(folder: Path, doc: dict, name: str = "s.toml") -> Path:
    (folder / "bodies.csv").write_text(CSV)
    (folder / "cube.obj").write_text(CUBE_OBJ)
    path = folder / name
    path.write_text(dump_toml(doc))
    return path


@pytest.mark.parametrize("name", list(BASES))
def test_every_base_scenario_is_valid(tmp_path, name):
    load_scenario(_write(tmp_path, BASES[name]))


# --- the mutations, from the spec ------------------------------------------------------


def _leaves(doc, prefix=()):
    """(path, value) of every key in ``doc``, tables included (depth first)."""
    for k, v in doc.items():
        p = prefix + (k,)
        yield p, v
        if isinstance(v, dict) and not ({"value", "unit"} >= set(v) and "value" in v):
            yield from _leaves(v, p)
        elif isinstance(v, list) and v and all(isinstance(x, dict) for x in v):
            for i, item in enumerate(v):
                yield from _leaves(item, p + (i,))


def _lookup(doc: dict, path: tuple):
    """The declared Key of ``path`` in ``doc``, following [[torques]]/[[events]] variants
    (by their ``type``) and the free names of maps."""
    table, key, node = SCENARIO, None, doc
    for part in path:
        node = node[part]
        if isinstance(part, int):       # an entry of an array of tables
            table = key.table if not key.variants else next(
                t for t in key.variants if t.name == node.get(key.discriminator))
            continue
        if table is None:               # the free name of a map entry
            table = key.table
            continue
        if part not in table:
            return None                 # the discriminator ("type")
        key = table[part]
        table = key.table if key.kind in ("table", "tables") else None
    return key


def _bad_values(key, value) -> list:
    """Values that the declaration of ``key`` rules out."""
    kind = key.kind
    bad = [("table", {}), ("bool", True)] if kind not in ("table", "map", "tables", "boolean") \
        else [("string", "x")]
    if kind == "quantity":
        shapes = key.shape if key.shape and isinstance(key.shape[0], tuple) else [key.shape]
        if key.shape is not None:
            scalar = () in shapes
            bad += [("length", [1.0, 2.0, 3.0, 4.0, 5.0] if scalar else [1.0]),
                    ("empty", []), ("nan", math.nan if scalar else [math.nan] * 5),
                    ("inf", math.inf if scalar else [math.inf] * 5)]
            if key.positive and scalar:
                bad += [("zero", 0.0), ("negative", "-1 " + (key.unit or ""))]
            if key.nonnegative and scalar:
                bad += [("negative", -1.0)]
        else:
            bad += [("empty", []), ("nan", [math.nan])]
        bad += [("dimension", "1 kg" if key.unit != "kg" else "1 s"),
                ("unparseable", "three")]
    elif kind == "time":
        bad += [("date", "2023-02-30T00:00:00"), ("hour", "2023-01-01T25:00:00"),
                ("number", 2030)]
    elif kind == "string":
        bad += [("number", 3), ("list", ["a"])]
        if key.choices:
            bad += [("choice", "no-such-choice")]
    elif kind == "integer":
        bad += [("float", 2.5), ("string", "2")]
        if key.positive:
            bad += [("zero", 0)]
        if key.nonnegative:
            bad += [("negative", -1)]
    elif kind == "number":
        bad += [("string", "x"), ("list", [1, 2, 3]), ("nan", math.nan), ("inf", math.inf)]
        if key.positive or key.nonnegative:
            bad += [("negative", -1.0)]
    elif kind == "unit":
        bad += [("number", 1.0), ("dimension", "kg" if key.unit != "kg" else "s")
                if key.unit is not None else ("unknown", "parsecs per fortnight")]
    elif kind == "boolean":
        bad += [("number", 1), ("string", "yes")]
    elif kind in ("table", "map"):
        bad += [("list", [1, 2, 3])]
    elif kind == "tables":
        bad += [("table", {"a": 1}), ("list", [1, 2])]
    return bad


def _set(doc, path, value):
    target = doc
    for part in path[:-1]:
        target = target[part]
    target[path[-1]] = value


def _delete(doc, path):
    target = doc
    for part in path[:-1]:
        target = target[part]
    del target[path[-1]]


def _key_text(path) -> str:
    out = ""
    for part in path:
        out += f"[{part}]" if isinstance(part, int) else (f".{part}" if out else part)
    return out


def _mutations():
    cases = []
    for base, doc in BASES.items():
        for path, value in _leaves(doc):
            key = _lookup(doc, path)
            if key is None or key.kind == "any" or (key.name == "type" and path[0] in (
                    "torques", "events")):
                continue
            for label, bad in _bad_values(key, value):
                cases.append(pytest.param(base, path, bad,
                                          id=f"{base}:{_key_text(path)}:{label}"))
    return cases


# the examples of the issue, and a few more that are not about one key's value
ISSUE = [
    ("single", ("propagation", "duration"), [1, 2, 3]),
    ("single", ("propagation", "rtol"), [1, 2, 3]),
    ("single", ("propagation", "step"), []),
    ("cloud", ("ensemble", "mean", "ratio_a"), [0, 0, 0, 0]),
    ("spin", ("state", "spin_axis", "ra"), []),
    ("single", ("torques", 0, "type"), {}),
    ("single", ("torques", 1, "type"), "gravity"),
    ("single", ("events", 0, "type"), {}),
    ("single", ("state", "epoch"), "2023-02-29T00:00:00"),
    ("single", ("state", "epoch"), "2023-01-01T23:59:60"),
    ("spin", ("state", "spin_axis", "dec"), "100 deg"),
    ("single", ("state", "omega_body"), "2 Hz"),
    ("single", ("body", "principal_moments"), [1.0, 1.0, 3.0]),
    ("single", ("torques", 0, "orbit", "e"), 1.5),
    ("single", ("events", 0, "angle"), "200 deg"),
    # the environment's torques: a facet of zero area, an unknown material, no orbit,
    # a zero normal, reflectances adding up to more than 1, face ranges off the shape
    ("environment", ("torques", 0, "facets", 2, "area"), 0.0),
    ("environment", ("torques", 0, "facets", 1, "material"), "gold"),
    ("environment", ("torques", 0, "facets", 1, "back_material"), "gold"),
    ("environment", ("torques", 0, "material"), "gold"),
    ("environment", ("torques", 0, "orbit"), None),
    ("environment", ("torques", 1, "orbit"), None),
    ("environment", ("torques", 0, "facets", 1, "normal"), [0.0, 0.0, 0.0]),
    ("environment", ("torques", 0, "materials", "mli", "diffuse"), 0.9),
    ("environment", ("torques", 0, "facets"), []),
    ("environment_shape", ("torques", 0, "surface", 0, "faces"), [0, 13]),
    ("environment_shape", ("torques", 0, "surface", 0, "material"), "black"),
    ("euler", ("torques",), [{"type": "drag", "orbit": {"a": "7000 km"}}]),
]


@pytest.mark.parametrize("base, path, bad", [*_mutations(), *(
    pytest.param(*case, id=f"issue:{case[0]}:{_key_text(case[1])}") for case in ISSUE)])
def test_every_bad_value_exits_2_naming_file_and_key(tmp_path, capsys, base, path, bad):
    doc = copy.deepcopy(BASES[base])
    _set(doc, path, bad)
    if bad is None:                     # a missing key
        _delete(doc, path)
    scenario = _write(tmp_path, doc)
    code = main(["run", str(scenario), "--quiet", "-o", str(tmp_path / "o.nc")])
    err = capsys.readouterr().err
    assert code == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    key = _key_text(path)
    # the key named is the one mutated, or the table that holds it (a rule between keys)
    assert lines[0].startswith(f"attitude: error: {scenario}: "), lines[0]
    named = lines[0][len(f"attitude: error: {scenario}: "):].split(": ", 1)[0]
    assert key.startswith(named) or named.startswith(key), (named, key, lines[0])
    assert "Traceback" not in err


@pytest.mark.parametrize("csv, column", [
    ("name,A,B,C,wx,wy,wz\nx,1,2,3,a,0,0\n", "wx"),        # not a number
    ("name,A,B,C,wx [kg],wy,wz\nx,1,2,3,1,0,0\n", "wx"),   # wrong dimension
    ("name,A,B,C,wx [furlongs],wy,wz\nx,1,2,3,1,0,0\n", "wx"),   # unknown unit
    ("name,A,B,C,wx,wy,wz\n", "A"),                        # no rows
    ("name,A,B,wx,wy,wz\nx,1,2,1,0,0\n", None),            # no C column
    ("name,A,B,C,wx,wy\nx,1,2,3,1,0\n", None),             # no wz column
])
def test_bad_ensemble_tables_exit_2(tmp_path, capsys, csv, column):
    path = _write(tmp_path, BASES["catalogue"])
    (tmp_path / "bodies.csv").write_text(csv)
    code = main(["run", str(path), "--quiet", "-o", str(tmp_path / "o.nc")])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1, err
    assert err.startswith(f"attitude: error: {path}: ensemble.table"), err
    if column is not None:
        assert f"column {column}" in err, err


def test_nan_rows_of_a_table_are_invalid_bodies_not_errors(tmp_path):
    path = _write(tmp_path, BASES["catalogue"])
    (tmp_path / "bodies.csv").write_text(CSV + "y,1,2,3,0,0,0,1,nan,0,0\n")
    sc = load_scenario(path)
    assert list(sc.ensemble.invalid) == [1]


def test_a_bug_is_one_line_and_exit_3_with_the_traceback_on_request(tmp_path, capsys,
                                                                    monkeypatch):
    import attitude.app.commands.run as run_command

    def boom(*args, **kwargs):
        raise ZeroDivisionError("float division by zero")

    monkeypatch.setattr(run_command, "run_scenario", boom)
    path = _write(tmp_path, BASES["euler"])
    assert main(["run", str(path), "--quiet"]) == 3
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "internal error: ZeroDivisionError" in err
    monkeypatch.setenv("ATTITUDE_DEBUG", "1")
    assert main(["run", str(path), "--quiet"]) == 3
    assert "Traceback" in capsys.readouterr().err


# --- property test: mutated shipped scenarios ---------------------------------------------


def _shortened(path: Path) -> dict:
    """A shipped scenario cut to five output steps (and eight bodies), so runs are fast."""
    doc = tomllib.loads(path.read_text())
    prop = doc.get("propagation", {})
    step = to_si(prop.get("step", 1.0), "s")
    prop["duration"] = 5 * step
    if "ensemble" in doc and "size" in doc["ensemble"]:
        doc["ensemble"]["size"] = min(doc["ensemble"]["size"], 8)
    doc.pop("output", None)
    return doc


SHORT = {p.name: _shortened(p) for p in SHIPPED}

toml_values = st.recursive(
    st.none().map(lambda _: "") | st.booleans() | st.integers(-10**6, 10**6)
    | st.floats(allow_nan=True, allow_infinity=True) | st.text(max_size=12)
    | st.sampled_from(["1 s", "2 1/s", "3 Hz", "1 kg", "2023-02-30T00:00:00", "deg", "nan"]),
    lambda inner: st.lists(inner, max_size=4) | st.dictionaries(
        st.sampled_from(["value", "unit", "type", "a", "x"]), inner, max_size=3),
    max_leaves=6)


@settings(max_examples=40, deadline=None, derandomize=True, database=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture,
                                 HealthCheck.too_slow])
@given(name=st.sampled_from(sorted(SHORT)), data=st.data())
def test_mutated_shipped_scenarios_never_give_a_traceback(tmp_path, capsys, name, data):
    doc = copy.deepcopy(SHORT[name])
    paths = [p for p, _ in _leaves(doc)]
    path = data.draw(st.sampled_from(paths), label="key")
    if data.draw(st.booleans(), label="delete"):
        target = doc
        for part in path[:-1]:
            target = target[part]
        del target[path[-1]]
    else:
        _set(doc, path, data.draw(toml_values, label="value"))
    folder = ROOT / "scenarios"   # relative paths (tables, shapes) resolve as shipped
    scenario = tmp_path / f"mutated_{name}"
    text = dump_toml(doc).replace('table = "data/', f'table = "{folder}/data/')
    scenario.write_text(text)
    code = main(["run", str(scenario), "--quiet", "-o", str(tmp_path / "o.nc")])
    err = capsys.readouterr().err
    assert code in (0, 1, 2, 3), err
    assert "Traceback" not in err, err
    if code == 2:
        assert len(err.strip().splitlines()) == 1, err
        assert err.startswith(f"attitude: error: {scenario}"), err

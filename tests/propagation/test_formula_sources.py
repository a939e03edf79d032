"""One source per torque formula (docs/architecture.md, "One source per formula").

Each term of the compiled torque kernel (:mod:`attitude.propagation.compiled_torques`)
compiles the function of the model layer that the model's ``evaluate`` calls, rather
than a copy of its formula: these tests fail if a kernel compiles something else, if a
model stops calling its function, or if a formula is written out again in the kernels
(a cross product, the arithmetic of every torque here).  The last test runs each
formula compiled on floats and as numpy on arrays of the same numbers: the same bits
for the arithmetic ones (numba compiles the choices, ``np.maximum`` and ``L2 == 0``, on
floats as numpy evaluates them on arrays), a few ulps where numpy's vectorised
``exp``/``cos``/``sin`` may round otherwise than libm.
"""

from __future__ import annotations

import ast
import inspect
import textwrap
from pathlib import Path

import numpy as np
import pytest

from attitude.environment import AerodynamicDrag, ExponentialAtmosphere, SolarRadiationPressure
from attitude.environment.tabulation import TimeTable
from attitude.model import freebody as fb
from attitude.model.orbit import KeplerOrbit
from attitude.model.torques import (
    EddyCurrentDamping,
    EnergyDissipation,
    GravityGradient,
    HeavyTopPivot,
    MagneticDipole,
    TiltedDipoleField,
)
from attitude.model.torques import surface_forces as sf
from attitude.model.torques.dissipation import dissipation_torque
from attitude.propagation import compiled
from attitude.propagation import compiled_torques as ct

SOURCE = Path(ct.__file__).read_text()


def _compiled_from(kernel, function) -> bool:
    """``kernel`` is ``function`` compiled (numba: its ``py_func`` runs the same code
    object; without numba: the function itself)."""
    if not compiled.NUMBA:
        return kernel is function
    return getattr(kernel, "py_func", None) is not None and \
        kernel.py_func.__code__ is function.__code__


@pytest.mark.parametrize("name", sorted(ct.FORMULAS))
def test_each_kernel_compiles_the_model_function(name):
    ct.body_torque(np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64), np.zeros(0),
                   0.0, np.array([0.0, 0.0, 0.0, 1.0]), np.zeros(3), np.zeros(3))
    kernel = getattr(ct, name)                      # the dispatcher after the first call
    assert _compiled_from(kernel, ct.FORMULAS[name])
    assert kernel is compiled.jit_formula(ct.FORMULAS[name])          # compiled once


def test_the_free_flow_twins_are_the_freebody_functions():
    assert _compiled_from(compiled._invariants, fb.invariants)
    assert _compiled_from(compiled._half_theta, fb.half_theta_scalar)


def _function(tree: ast.Module, name: str) -> ast.FunctionDef:
    return next(n for n in ast.walk(tree) if isinstance(n, ast.FunctionDef) and n.name == name)


def _called(node: ast.AST) -> set[str]:
    return {n.func.id if isinstance(n.func, ast.Name) else n.func.attr
            for n in ast.walk(node) if isinstance(n, ast.Call)
            and isinstance(n.func, (ast.Name, ast.Attribute))}


def test_the_kernels_write_no_torque_formula_of_their_own():
    """No ``a * b - c * d`` (a component of a cross product) anywhere in the module; each
    term of ``body_torque`` is one compiled formula (or a kernel that ends in one)."""
    tree = ast.parse(SOURCE)
    crosses = [f"line {n.lineno}" for n in ast.walk(tree)
               if isinstance(n, ast.BinOp) and isinstance(n.op, ast.Sub)
               and all(isinstance(x, ast.BinOp) and isinstance(x.op, ast.Mult)
                       for x in (n.left, n.right))]
    assert not crosses, f"a cross product written in compiled_torques.py: {crosses}"
    allowed = set(ct.FORMULAS) | {"_three", "_radiation", "_drag"}
    for node in ast.walk(_function(tree, "body_torque")):
        if isinstance(node, ast.Assign) and any(isinstance(t, ast.Name) and t.id == "m"
                                                for t in node.targets):
            assert isinstance(node.value, ast.Call) and node.value.func.id in allowed, \
                f"line {node.lineno}: a term computed in body_torque itself"
    for name, formula in (("_radiation", "_radiation_torque"), ("_drag", "_drag_torque")):
        last = max((n for n in ast.walk(_function(tree, name)) if isinstance(n, ast.Return)),
                   key=lambda n: n.lineno)
        assert isinstance(last.value, ast.Call) and last.value.func.id == formula


def _calls(method) -> set[str]:
    return _called(ast.parse(textwrap.dedent(inspect.getsource(method))))


@pytest.mark.parametrize("method, formulas", [
    (GravityGradient.evaluate, {"gravity_gradient_torque"}),
    (HeavyTopPivot.evaluate, {"heavy_top_torque"}),
    (EddyCurrentDamping.evaluate, {"eddy_current_torque"}),
    (MagneticDipole.evaluate, {"magnetic_dipole_torque"}),
    (EnergyDissipation.evaluate, {"dissipation_torque"}),
    (TiltedDipoleField.__call__, {"dipole_field"}),
    (TiltedDipoleField._direction, {"dipole_direction"}),
    (SolarRadiationPressure.sunlight, {"sunlight"}),
    (SolarRadiationPressure._one_epoch, {"sunlight"}),
    (SolarRadiationPressure._facet_weights, {"facing", "radiation_weights"}),
    (SolarRadiationPressure._torque, {"radiation_torque"}),
    (AerodynamicDrag.airflow, {"corotating_air", "drag_pressure"}),
    (AerodynamicDrag._one_epoch, {"corotating_air", "drag_pressure", "drag_torque"}),
    (AerodynamicDrag._facing, {"facing"}),
    (AerodynamicDrag.evaluate, {"drag_torque"}),
    (ExponentialAtmosphere.density, {"exponential_density"}),
    (KeplerOrbit.state, {"kepler_position", "kepler_velocity"}),
    (TimeTable._horner, {"cubic_value", "cubic_rate"}),
], ids=lambda x: getattr(x, "__qualname__", None))
def test_each_model_calls_its_formula(method, formulas):
    assert formulas <= _calls(method)


def _random_arguments(rng, function):
    """Arguments of ``function`` as floats, and the same numbers as arrays of 64."""
    n = 64
    draw = {  # name -> shape of one value (3: a vector, 9: a matrix, 0: a number)
        "inertia": 9, "tensor": 9, "r": 3, "w": 3, "b": 3, "up": 3, "lever": 3,
        "moment": 3, "m_hat": 3, "sun": 3, "body": 3, "W": 3, "U": 3, "s": 3, "S": 3,
        "v": 3, "v_hat": 3, "normal": 3, "direction": 3, "toward_periapsis": 3,
        "ahead": 3,
    }
    floats, arrays = [], []
    for name in inspect.signature(function).parameters:
        size = draw.get(name, 0)
        values = rng.normal(size=(max(size, 1), n)) * 10.0 ** rng.uniform(-3, 3)
        if name in ("sin_tilt", "cos_tilt", "p", "q", "rho", "cd", "scale_height",
                    "density", "mu", "mg", "k", "pressure", "astronomical_unit",
                    "coefficient"):
            values = np.abs(values)
        if size:
            floats.append([tuple(float(x) for x in values[:, i]) for i in range(n)])
            arrays.append(tuple(values))
        else:
            floats.append([float(x) for x in values[0]])
            arrays.append(values[0])
    return [list(a) for a in zip(*floats)], arrays


#: Formulas with numpy's vectorised transcendental functions: ulps allowed.
TRANSCENDENTAL = {"_exponential_density": 4, "_dipole_direction": 4}


@pytest.mark.parametrize("name", sorted(set(ct.FORMULAS) - {
    "_eccentric_anomaly", "_illumination_fraction", "_to_body"}))
def test_compiled_on_floats_equals_numpy_on_arrays(name):
    """The kernel (compiled, or plain Python without numba) on one set of floats gives
    what the function gives on arrays, element by element."""
    rng = np.random.default_rng(sum(map(ord, name)))
    function, kernel = ct.FORMULAS[name], getattr(ct, name)
    per_call, arrays = _random_arguments(rng, function)
    with np.errstate(all="ignore"):
        vectorised = np.broadcast_arrays(*_flat(function(*arrays)))
        one = np.array([_flat(kernel(*args)) for args in per_call], dtype=float).T
    assert len(one) == len(vectorised)
    for got, want in zip(one, vectorised):
        if name in TRANSCENDENTAL:
            with np.errstate(invalid="ignore"):
                close = np.abs(got - want) <= TRANSCENDENTAL[name] * np.spacing(np.abs(want))
            assert np.all((got == want) | close), name
        else:
            np.testing.assert_array_equal(got, want, err_msg=name)


def _flat(result) -> list:
    """The numbers or arrays of a formula's (possibly nested) tuple, in order."""
    if isinstance(result, tuple):
        return [x for part in result for x in _flat(part)]
    return [result]


def test_rotation_compiled_equals_numpy():
    rng = np.random.default_rng(7)
    q = rng.normal(size=(4, 50))
    q /= np.linalg.norm(q, axis=0)
    v = rng.normal(size=(3, 50))
    want = np.array(ct.FORMULAS["_to_body"](tuple(q), tuple(v), True))
    got = np.array([ct._to_body(tuple(q[:, i].tolist()), tuple(v[:, i].tolist()), True)
                    for i in range(50)]).T
    np.testing.assert_array_equal(got, want)


def test_a_facet_facing_away_adds_nothing_in_both_forms():
    """The choice written for floats and arrays alike: ``max(n . d, 0)``."""
    normal = (np.array([1.0, -1.0, 0.0]), np.zeros(3), np.zeros(3))
    assert sf.facing(normal, (1.0, 0.0, 0.0)).tolist() == [1.0, 0.0, 0.0]
    assert ct._facing((-1.0, 0.0, 0.0), (1.0, 0.0, 0.0)) == 0.0
    assert ct._facing((1.0, 0.0, 0.0), (0.5, 0.0, 0.0)) == 0.5


def test_a_body_at_rest_feels_no_dissipation():
    """``L2 + (L2 == 0)``: no division by zero, zero torque, floats and arrays alike."""
    inertia = (1.0, 0.0, 0.0, 0.0, 2.0, 0.0, 0.0, 0.0, 3.0)
    assert ct._dissipation(0.5, np.array(inertia), (0.0, 0.0, 0.0)) == (0.0, 0.0, 0.0)
    w = (np.array([0.0, 1.0]), np.array([0.0, 0.0]), np.array([0.0, 0.0]))
    torque = dissipation_torque(0.5, inertia, w)
    assert [x.tolist() for x in torque] == [[0.0, 0.0], [0.0, 0.0], [0.0, 0.0]]

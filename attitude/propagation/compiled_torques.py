"""Compiled forms of the built-in torque models, for the one-body splitting loop.

A torque model is a Python object; calling it costs microseconds of dispatch, more
than the physics.  :func:`compile_torques` asks each model for its compiled form
(:meth:`attitude.model.torques.TorqueModel.compiled_parameters`: the formula's name, its SI
parameters and the paths or fields it reads, each with a ``compiled_parameters`` of its
own) and lays the models out in three flat arrays, ``kinds`` (one formula per term),
``offsets`` (where each term's numbers start) and ``params`` (all the numbers);
:func:`body_torque` evaluates their sum at one time, attitude and rate.

One source per formula: the kernels write no formula of a model.  Each model's formula
is a function of the model layer in component form, written on floats or arrays alike
(:func:`~attitude.model.torques.gravity_gradient.gravity_gradient_torque`,
``heavy_top_torque``, ``eddy_current_torque``, ``magnetic_dipole_torque``,
``dissipation_torque``, the tilted dipole of :mod:`attitude.model.torques.fields`, the
radiation pressure and drag of :mod:`attitude.model.torques.surface_forces`, the
rotation :func:`attitude.foundations.quaternion.rotate_parts`, the shadow test of
:mod:`attitude.model.shadow`, Kepler's equation of :mod:`attitude.model.orbit`): the
model's ``evaluate`` runs it on arrays over time, and this module compiles it with
:func:`~attitude.propagation.compiled.jit_formula` (:data:`FORMULAS`: each compiled name
and its function).  What stays here is reading the numbers of ``params``, the facet
sums (a loop, where numpy takes a matrix product: the one place where the two paths
round differently, besides numpy's vectorised ``sin``/``cos``/``exp``) and, for paths
and fields, the Keplerian position and velocity and the cubics' Horner rule (written as
:meth:`attitude.model.orbit.KeplerOrbit.state` and
:class:`attitude.environment.TimeTable` write them).  A new torque model is then its
function, its ``compiled_parameters``, a term code and its layout here.

==========================  =============================================================
term                        numbers from ``offsets[k] + 1``
==========================  =============================================================
``gravity_gradient``        ``mu``, inertia (9, row-major), path
``constant_body``           torque (3)
``constant_inertial``       torque (3)
``heavy_top``               ``m g``, up (3), pivot -> centre of mass (3)
``eddy_current``            isotropic (0 or 1), scalar, tensor (9: an isotropic one's
                            scalar times the identity, which the kernel uses), field
``magnetic_dipole``         moment (3), field
``dissipation``             ``k``, inertia (9)
``radiation_pressure``      time offset, pressure at 1 au, au, shadow (0 none, 1 conical,
                            2 cylindrical), Earth and Sun radii, facets ``n``, Sun's path,
                            body's path, normals (3n), ``r`` (3n), ``r x n`` (3n),
                            ``A (1 - rho_s)``, ``A rho_s``, ``A rho_d / 3`` (n each)
``drag``                    time offset, ``C_D``, co-rotation (0 or 1), Earth rotation
                            rate and radius, layers ``L``, facets ``n``, path, base
                            altitudes, densities, scale heights (L each), normals (3n),
                            ``A r`` (3n)
==========================  =============================================================

Each term's numbers start with its time shift, ``params[offsets[k]]`` (the term is read
at ``t`` plus it, 0 but for a model wrapped by ``shifted``).  A path or a field entry is
the index of its block in ``params``; each path or field is
stored once however many terms read it.  A path block is its kind then its numbers:
``fixed`` (0: position), ``kepler`` (1: ``a, e, b = sqrt(1 - e^2), M0, n, mu, P (3),
Q (3)``, Kepler's equation solved as :func:`attitude.model.orbit.solve_kepler`),
``piecewise_cubic`` (2: the number ``N`` of breakpoints, their spacing if uniform else
0, the breakpoints, the coefficients ``(4, N - 1, 3)`` highest power first).  A field
block is ``uniform`` (0: vector), ``tilted_dipole`` (1: ``mu0 m / 4 pi``, sine and
cosine of the tilt, rotation angle, rate, pole longitude, the index of the orbit's path)
or ``piecewise_cubic`` (2, as a path).

Tabulated paths and fields (:class:`~attitude.model.orbit.TabulatedPath`,
:class:`~attitude.environment.TLEOrbit`, :class:`~attitude.environment.SunPath`,
:class:`~attitude.environment.IGRF`) hand over their own interpolating cubics over the
run's ``t_span`` (the segments of :class:`~attitude.environment.TimeTable` that cover
it; a ``TabulatedPath`` its whole spline), so the compiled path adds no interpolation
error of its own: it evaluates the polynomials the Python path evaluates.  Without
``t_span`` the environment's tables have no compiled form.

numba is optional: without it (or with ``ATTITUDE_NO_NUMBA=1``) the same functions run as
plain Python, slowly but with the same results.  A model without a compiled form (a
user's function or subclass, a :class:`~attitude.model.orbit.CallablePath`) makes
:func:`compile_torques` return None: the caller then uses the Python models.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..foundations.cubic import cubic_rate, cubic_value
from ..foundations.errors import InvalidStateError
from ..foundations.quaternion import rotate_parts
from ..model.body import RigidBody
from ..model.orbit import kepler_position, kepler_velocity, solve_kepler_scalar
from ..model.shadow import illumination_fraction
from ..model.torques import TorqueModel
from ..model.torques.dissipation import dissipation_torque
from ..model.torques.eddy_current import eddy_current_torque
from ..model.torques.fields import dipole_direction, dipole_field
from ..model.torques.gravity_gradient import gravity_gradient_torque
from ..model.torques.heavy_top import heavy_top_torque
from ..model.torques.magnetic_dipole import magnetic_dipole_torque
from ..model.torques.surface_forces import (
    corotating_air,
    drag_pressure,
    drag_torque,
    exponential_density,
    facing,
    radiation_torque,
    radiation_weights,
    sunlight,
)
from .compiled import NUMBA, jit_formula
from .compiled import jit as _jit

__all__ = ["CompiledTorques", "compile_torques", "compile_torques_shared", "body_torque",
           "NUMBA", "TERM_KINDS", "user_torque", "callback_model"]

#: Codes of the terms in ``kinds``.
TERM_KINDS = {"gravity_gradient": 0, "constant_body": 1, "constant_inertial": 2,
              "heavy_top": 3, "eddy_current": 4, "dissipation": 5,
              "radiation_pressure": 6, "drag": 7, "magnetic_dipole": 8}
(_GRAVITY_GRADIENT, _CONSTANT_BODY, _CONSTANT_INERTIAL, _HEAVY_TOP, _EDDY, _DISSIPATION,
 _RADIATION, _DRAG, _MAGNETIC_DIPOLE) = range(9)
#: Codes of the shadow models of radiation pressure.
_SHADOWS = {None: 0.0, "conical": 1.0, "cylindrical": 2.0}
#: Codes of the paths (first number of a path block).
_PATHS = {"fixed": 0, "kepler": 1, "piecewise_cubic": 2}
_FIXED, _KEPLER, _PIECEWISE = 0.0, 1.0, 2.0
#: Codes of the fields (first number of a field block).
_FIELDS = {"uniform": 0, "tilted_dipole": 1, "piecewise_cubic": 2}
_UNIFORM, _DIPOLE = 0.0, 1.0

# --- kernels ----------------------------------------------------------------------------


#: The formulas of the models, compiled from their one source (module notes): each kernel
#: below is ``jit_formula(f)`` of the function ``f`` the model's ``evaluate`` calls.
FORMULAS = {
    "_eccentric_anomaly": solve_kepler_scalar,     # attitude.model.orbit.solve_kepler
    "_kepler_position": kepler_position,           # attitude.model.orbit.KeplerOrbit.state
    "_kepler_velocity": kepler_velocity,
    "_cubic_value": cubic_value,                   # attitude.environment.TimeTable
    "_cubic_rate": cubic_rate,
    "_illumination_fraction": illumination_fraction,
    "_to_body": rotate_parts,
    "_gravity_gradient": gravity_gradient_torque,
    "_heavy_top": heavy_top_torque,
    "_eddy_current": eddy_current_torque,
    "_magnetic_dipole": magnetic_dipole_torque,
    "_dissipation": dissipation_torque,
    "_dipole_direction": dipole_direction,
    "_dipole_field": dipole_field,
    "_sunlight": sunlight,
    "_facing": facing,
    "_radiation_weights": radiation_weights,
    "_radiation_torque": radiation_torque,
    "_corotating_air": corotating_air,
    "_exponential_density": exponential_density,
    "_drag_pressure": drag_pressure,
    "_drag_torque": drag_torque,
}
(_eccentric_anomaly, _kepler_position, _kepler_velocity, _cubic_value, _cubic_rate,
 _illumination_fraction, _to_body, _gravity_gradient, _heavy_top, _eddy_current,
 _magnetic_dipole, _dissipation, _dipole_direction, _dipole_field, _sunlight, _facing,
 _radiation_weights, _radiation_torque, _corotating_air, _exponential_density,
 _drag_pressure, _drag_torque) = (jit_formula(f) for f in FORMULAS.values())


@_jit
def _interval(params, i, t):
    """The interval of the piecewise cubic block at ``params[i]`` (number ``N`` of
    breakpoints, spacing ``h`` if uniform else 0, breakpoints, coefficients) holding
    ``t``: the last breakpoint <= t (the end intervals extrapolate, as scipy's ``PPoly``).
    Returns the index of its first coefficient, the stride between powers and ``t`` minus
    its breakpoint."""
    nb = int(params[i])
    h = params[i + 1]
    x0 = i + 2
    n = nb - 1
    if h > 0.0:                           # uniform: start from the index, then step
        j = int(min(max((t - params[x0]) / h, 0.0), n - 1.0))
        while j < n - 1 and params[x0 + j + 1] <= t:
            j += 1
        while j > 0 and params[x0 + j] > t:
            j -= 1
    else:                                 # bisection
        j, hi = 0, n - 1
        while j < hi:
            mid = (j + hi + 1) // 2
            if params[x0 + mid] <= t:
                j = mid
            else:
                hi = mid - 1
    return x0 + nb + 3 * j, 3 * n, t - params[x0 + j]


@_jit
def _piecewise(params, i, t):
    """The piecewise cubic block at ``params[i]`` at ``t``, Horner's rule (as
    :class:`attitude.environment.TimeTable`)."""
    j, stride, d = _interval(params, i, t)
    return (_cubic_value(params[j], params[j + stride], params[j + 2 * stride],
                         params[j + 3 * stride], d),
            _cubic_value(params[j + 1], params[j + 1 + stride], params[j + 1 + 2 * stride],
                         params[j + 1 + 3 * stride], d),
            _cubic_value(params[j + 2], params[j + 2 + stride], params[j + 2 + 2 * stride],
                         params[j + 2 + 3 * stride], d))


@_jit
def _piecewise_rate(params, i, t):
    """The time derivative of the piecewise cubic block at ``params[i]`` at ``t``."""
    j, stride, d = _interval(params, i, t)
    return (_cubic_rate(params[j], params[j + stride], params[j + 2 * stride], d),
            _cubic_rate(params[j + 1], params[j + 1 + stride], params[j + 1 + 2 * stride], d),
            _cubic_rate(params[j + 2], params[j + 2 + stride], params[j + 2 + 2 * stride], d))


@_jit
def _velocity(params, i, t):
    """The path block at ``params[i]`` at ``t``: inertial velocity, m/s (Kepler:
    ``v = sqrt(mu a) / r (-sin E P + b cos E Q)``; a table: its derivative)."""
    kind = params[i]
    if kind == _FIXED:
        return 0.0, 0.0, 0.0
    if kind == _KEPLER:
        e = params[i + 2]
        E = _eccentric_anomaly(params[i + 4] + params[i + 5] * t, e, 50)
        return _kepler_velocity(params[i + 6], params[i + 1], e, params[i + 3],
                                _three(params, i + 7), _three(params, i + 10),
                                math.cos(E), math.sin(E))
    return _piecewise_rate(params, i + 1, t)


@_jit
def _three(params, i):
    """The three numbers at ``params[i]``, as a tuple."""
    return params[i], params[i + 1], params[i + 2]


@_jit
def _radiation(params, i, t, q):
    """Solar radiation pressure (:class:`attitude.environment.SolarRadiationPressure`):
    the formulas of :mod:`attitude.model.torques.surface_forces`, the facet sums in a loop."""
    t = t + params[i]
    n = int(params[i + 6])
    sun = _position(params, int(params[i + 7]), t)
    here = _position(params, int(params[i + 8]), t)
    p, s_in = _sunlight(params[i + 1], params[i + 2], sun, here)
    if params[i + 3] != 0.0:
        p *= _illumination_fraction(here[0], here[1], here[2], sun[0], sun[1], sun[2],
                                    params[i + 3] != 2.0, params[i + 4], params[i + 5])
    if p == 0.0:                                # in the umbra: no facet sums
        return 0.0, 0.0, 0.0
    s = _to_body(q, s_in, True)
    normals = i + 9
    r = normals + 3 * n
    rxn = r + 3 * n
    one_minus_s = rxn + 3 * n
    spec = one_minus_s + n
    diff = spec + n
    W0 = W1 = W2 = U0 = U1 = U2 = 0.0
    for k in range(n):
        c = _facing(_three(params, normals + 3 * k), s)
        if c > 0.0:                             # a facet facing away adds nothing
            w, u = _radiation_weights(c, params[one_minus_s + k], params[spec + k],
                                      params[diff + k])
            W0 += w * params[r + 3 * k]
            W1 += w * params[r + 3 * k + 1]
            W2 += w * params[r + 3 * k + 2]
            U0 += u * params[rxn + 3 * k]
            U1 += u * params[rxn + 3 * k + 1]
            U2 += u * params[rxn + 3 * k + 2]
    return _radiation_torque(p, (W0, W1, W2), (U0, U1, U2), s)


@_jit
def _drag(params, i, t, q):
    """Free-molecular drag (:class:`attitude.environment.AerodynamicDrag`): the formulas
    of :mod:`attitude.model.torques.surface_forces`, the facet sum in a loop."""
    t = t + params[i]
    layers, n = int(params[i + 5]), int(params[i + 6])
    orbit = int(params[i + 7])
    x, y, z = _position(params, orbit, t)
    v = _velocity(params, orbit, t)
    if params[i + 2] != 0.0:
        v = _corotating_air(params[i + 3], (x, y, z), v)
    h = math.sqrt(x * x + y * y + z * z) - params[i + 4]
    bases = i + 8
    k = 0                              # the last layer whose base is <= h (or the first)
    while k + 1 < layers and params[bases + k + 1] <= h:
        k += 1
    rho = _exponential_density(h, params[bases + k], params[bases + layers + k],
                               params[bases + 2 * layers + k])
    vx, vy, vz = v
    v2 = vx * vx + vy * vy + vz * vz
    if v2 == 0.0 or rho == 0.0:                 # no flow: no direction
        return 0.0, 0.0, 0.0
    speed = math.sqrt(v2)
    v_hat = _to_body(q, (vx / speed, vy / speed, vz / speed), True)
    normals = bases + 3 * layers
    ar = normals + 3 * n
    S0 = S1 = S2 = 0.0
    for j in range(n):
        c = _facing(_three(params, normals + 3 * j), v_hat)
        if c > 0.0:                             # a facet facing away adds nothing
            S0 += c * params[ar + 3 * j]
            S1 += c * params[ar + 3 * j + 1]
            S2 += c * params[ar + 3 * j + 2]
    return _drag_torque(_drag_pressure(rho, v2, params[i + 1]), (S0, S1, S2), v_hat)


@_jit
def _position(params, i, t):
    """The path block at ``params[i]`` at ``t``: inertial position, m (as
    :meth:`attitude.model.orbit.KeplerOrbit.state`: ``r = a ((cos E - e) P + b sin E Q)``)."""
    kind = params[i]
    if kind == _FIXED:
        return params[i + 1], params[i + 2], params[i + 3]
    if kind == _KEPLER:
        e = params[i + 2]
        E = _eccentric_anomaly(params[i + 4] + params[i + 5] * t, e, 50)
        return _kepler_position(params[i + 1], e, params[i + 3], _three(params, i + 7),
                                _three(params, i + 10), math.cos(E), math.sin(E))
    return _piecewise(params, i + 1, t)


@_jit
def _field(params, i, t):
    """The field block at ``params[i]`` at ``t``: inertial field, T (the tilted dipole by
    the formulas of :mod:`attitude.model.torques.fields`)."""
    kind = params[i]
    if kind == _UNIFORM:
        return params[i + 1], params[i + 2], params[i + 3]
    if kind == _DIPOLE:
        lam = (params[i + 4] + params[i + 5] * t) + params[i + 6]
        m_hat = _dipole_direction(params[i + 2], params[i + 3], lam)
        return _dipole_field(params[i + 1], m_hat, _position(params, int(params[i + 7]), t))
    return _piecewise(params, i + 1, t)


@_jit
def body_torque(kinds, offsets, params, t0, q_b, w_b, out):
    """Sum of the compiled torque models, body frame, N m, written into ``out``.

    Parameters
    ----------
    kinds, offsets : (n,) int64 arrays
        Term codes and where each term's numbers start in ``params``
        (:class:`CompiledTorques`).
    params : (m,) float64 array
    t0 : float
        Seconds since the run's epoch (the models' time).
    q_b : (4,) float64 array
        Attitude, body -> inertial, scalar-last (normalised here, as the models do).
    w_b : (3,) float64 array
        Body rates, rad/s.
    out : (3,) float64 array
        Receives the torque; nothing is allocated.

    Examples
    --------
    >>> import numpy as np
    >>> from attitude import RigidBody
    >>> from attitude.model.torques import ConstantTorque
    >>> c = compile_torques([ConstantTorque([0.0, 0.0, 1e-3], frame="inertial")],
    ...                     RigidBody.from_principal_moments([1.0, 2.0, 3.0]))
    >>> out = np.zeros(3)
    >>> half_turn_x = np.array([1.0, 0.0, 0.0, 0.0])
    >>> body_torque(c.kinds, c.offsets, c.params, 0.0, half_turn_x, np.zeros(3), out)
    >>> out + 0.0
    array([ 0.   ,  0.   , -0.001])
    """
    norm = math.sqrt(q_b[0] * q_b[0] + q_b[1] * q_b[1] + q_b[2] * q_b[2] + q_b[3] * q_b[3])
    q = (q_b[0] / norm, q_b[1] / norm, q_b[2] / norm, q_b[3] / norm)
    w = (w_b[0], w_b[1], w_b[2])
    out[0] = 0.0
    out[1] = 0.0
    out[2] = 0.0
    for k in range(kinds.shape[0]):
        kind = kinds[k]
        t = t0 + params[offsets[k]]             # the term's time shift
        i = offsets[k] + 1
        if kind == _GRAVITY_GRADIENT:
            r = _to_body(q, _position(params, int(params[i + 10]), t), True)
            m = _gravity_gradient(params[i], params[i + 1:i + 10], r)
        elif kind == _CONSTANT_BODY:
            m = _three(params, i)
        elif kind == _CONSTANT_INERTIAL:
            m = _to_body(q, _three(params, i), True)
        elif kind == _HEAVY_TOP:
            m = _heavy_top(params[i], _to_body(q, _three(params, i + 1), True),
                           _three(params, i + 4))
        elif kind == _EDDY:                     # the tensor (an isotropic one's too)
            b = _to_body(q, _field(params, int(params[i + 11]), t), True)
            m = _eddy_current(params[i + 2:i + 11], w, b)
        elif kind == _MAGNETIC_DIPOLE:
            b = _to_body(q, _field(params, int(params[i + 3]), t), True)
            m = _magnetic_dipole(_three(params, i), b)
        elif kind == _RADIATION:
            m = _radiation(params, i, t, q)
        elif kind == _DRAG:
            m = _drag(params, i, t, q)
        else:
            m = _dissipation(params[i], params[i + 1:i + 10], w)
        out[0] += m[0]
        out[1] += m[1]
        out[2] += m[2]


# --- layout -----------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class CompiledTorques:
    """Torque models laid out for :func:`body_torque` (read-only arrays).

    Attributes
    ----------
    kinds : (n,) int64
        Code of each term (:data:`TERM_KINDS`).
    offsets : (n,) int64
        Index in ``params`` where each term's numbers start.
    params : (m,) float64
        The numbers (see the module docstring for the layout).
    names : tuple of str
        The terms' kinds, by name.

    Examples
    --------
    >>> import numpy as np
    >>> from attitude import RigidBody
    >>> from attitude.model.torques import ConstantTorque, GravityGradient
    >>> body = RigidBody.from_principal_moments([100.0, 200.0, 250.0])
    >>> c = compile_torques(GravityGradient(3.986004418e14, [7e6, 0.0, 0.0])
    ...                     + ConstantTorque([0.0, 0.0, 1e-6]), body)
    >>> c.names, c.offsets        # the position's block (4 numbers) comes first
    (('gravity_gradient', 'constant_body'), array([ 4, 16]))
    >>> c(0.0, [0.0, 0.0, 0.0, 1.0], [0.0, 0.0, 0.0])
    array([0.e+00, 0.e+00, 1.e-06])
    """

    kinds: np.ndarray
    offsets: np.ndarray
    params: np.ndarray
    names: tuple

    def __call__(self, t, quaternion, omega_body) -> np.ndarray:
        """The torque (body frame, N m, ``(3,)``) at one time ``t`` (s), attitude
        (body -> inertial, scalar-last) and rate (rad/s), through :func:`body_torque`."""
        out = np.zeros(3)
        body_torque(self.kinds, self.offsets, self.params, float(t),
                    np.ascontiguousarray(quaternion, dtype=float),
                    np.ascontiguousarray(omega_body, dtype=float), out)
        return out

    def __repr__(self) -> str:
        return f"CompiledTorques({' + '.join(self.names) or 'nothing'}, numba={NUMBA})"


def _vector(values, key: str, n: int) -> np.ndarray:
    v = np.asarray(values[key], dtype=float).reshape(-1)
    if v.shape != (n,):
        raise ValueError(f"{key}: expected {n} numbers, got {v.shape}")
    return v


class _Layout:
    """``params`` being built: blocks appended in order; each path or field stored once
    however many terms read it (a year of a tabulated orbit is ~10^7 numbers)."""

    def __init__(self, t_span):
        self.t_span = t_span
        self.blocks: list[np.ndarray] = []
        self.size = 0
        self._sources: dict[int, tuple] = {}       # id -> (object, index or None)

    def add(self, *parts) -> int:
        """Append ``parts`` (numbers or arrays) as one block; its index in ``params``."""
        block = np.concatenate([np.asarray(p, dtype=float).reshape(-1) for p in parts])
        self.blocks.append(block)
        self.size += block.size
        return self.size - block.size

    def source(self, obj, codes: dict) -> int | None:
        """Index of the block of a path or field (``codes``: its kinds), or None without
        a compiled form."""
        known = self._sources.get(id(obj))
        if known is not None and known[0] is obj:
            return known[1]
        index = self._encode(obj, codes)
        self._sources[id(obj)] = (obj, index)
        return index

    def _encode(self, obj, codes: dict) -> int | None:
        describe = getattr(obj, "compiled_parameters", None)
        if not callable(describe):
            return None
        part = describe(self.t_span)
        if part is None or part[0] not in codes:
            return None
        kind, v = part
        code = float(codes[kind])
        if kind in ("fixed", "uniform"):
            return self.add(code, _vector(v, "position" if kind == "fixed" else "vector", 3))
        if kind == "kepler":
            return self.add(code, [float(v[k]) for k in ("a", "e", "b", "mean_anomaly",
                                                         "mean_motion", "mu")],
                            _vector(v, "P", 3), _vector(v, "Q", 3))
        if kind == "tilted_dipole":
            path = self.source(v["orbit"], _PATHS)
            if path is None:
                return None
            return self.add(code, [float(v[k]) for k in (
                "coefficient", "sin_tilt", "cos_tilt", "rotation_angle", "rotation_rate",
                "pole_longitude")], float(path))
        x = np.asarray(v["breakpoints"], dtype=float)                 # piecewise cubic
        c = np.asarray(v["coefficients"], dtype=float)
        if x.ndim != 1 or x.size < 2 or c.shape != (4, x.size - 1, 3):
            raise ValueError(f"piecewise cubic: expected breakpoints (N,) and coefficients "
                             f"(4, N - 1, 3), got {x.shape} and {c.shape}")
        h = (x[-1] - x[0]) / (x.size - 1)
        uniform = np.all(np.abs(np.diff(x) - h) <= 1e-9 * h)   # start lookups by index
        return self.add(code, float(x.size), h if uniform else 0.0, x, c)

    def term(self, kind: str, v: dict) -> int | None:
        """Append the numbers of one term, its time shift first; their index, or None
        without a compiled form."""
        numbers = self._term(kind, v)
        if numbers is None:
            return None
        return self.add(float(v.get("time_shift", 0.0)), *numbers)

    def _term(self, kind: str, v: dict) -> tuple | None:
        """The numbers of one term (after its time shift), or None."""
        if kind == "gravity_gradient":
            path = self.source(v["orbit"], _PATHS)
            if path is None:
                return None
            return float(v["mu"]), _vector(v, "inertia", 9), float(path)
        if kind in ("constant_body", "constant_inertial"):
            return (_vector(v, "torque", 3),)
        if kind == "heavy_top":
            return float(v["mass_g"]), _vector(v, "up", 3), _vector(v, "pivot_to_com", 3)
        if kind == "eddy_current":
            field = self.source(v["field"], _FIELDS)
            if field is None:
                return None
            return (1.0 if v["isotropic"] else 0.0, float(v["scalar"]),
                    _vector(v, "tensor", 9), float(field))
        if kind == "magnetic_dipole":
            field = self.source(v["field"], _FIELDS)
            if field is None:
                return None
            return _vector(v, "moment", 3), float(field)
        if kind == "dissipation":
            return float(v["k"]), _vector(v, "inertia", 9)
        if kind == "radiation_pressure":
            sun, orbit = self.source(v["sun"], _PATHS), self.source(v["orbit"], _PATHS)
            if sun is None or orbit is None or v["shadow"] not in _SHADOWS:
                return None
            n = len(v["one_minus_s"])
            facets = tuple(_vector(v, key, size * n) for key, size in (
                ("normals", 3), ("r", 3), ("rxn", 3), ("one_minus_s", 1), ("spec", 1),
                ("diff", 1)))
            return (float(v["time_offset"]), float(v["pressure"]),
                    float(v["astronomical_unit"]), _SHADOWS[v["shadow"]],
                    float(v["earth_radius"]), float(v["sun_radius"]), float(n),
                    float(sun), float(orbit)) + facets
        if kind == "drag":
            orbit = self.source(v["orbit"], _PATHS)
            if orbit is None:
                return None
            layers, n = len(v["bases"]), len(v["ar"])
            table = tuple(_vector(v, key, layers)
                          for key in ("bases", "densities", "scale_heights"))
            return (float(v["time_offset"]), float(v["cd"]),
                    1.0 if v["corotation"] else 0.0, float(v["rotation_rate"]),
                    float(v["earth_radius"]), float(layers), float(n),
                    float(orbit)) + table + (_vector(v, "normals", 3 * n),
                                             _vector(v, "ar", 3 * n))
        return None


def compile_torques(models, body, t_span=None) -> CompiledTorques | None:
    """Lay out torque models for :func:`body_torque`, or None when one of them has no
    compiled form.

    Parameters
    ----------
    models : TorqueModel or sequence of them
        Sums are taken apart; an empty sequence compiles to no term (zero torque).
    body : RigidBody
        The one body the torques act on (its inertia and mass enter the parameters).
    t_span : (float, float), optional
        The times (s since the epoch) the run covers.  The environment's tabulated
        paths and fields (a TLE orbit, the Sun, IGRF) hand over their cubics over it, so
        they need it (without it they have no compiled form); a
        :class:`~attitude.model.orbit.TabulatedPath` hands over its whole spline and checks
        ``t_span`` against its table.

    Returns
    -------
    CompiledTorques or None
        None if a model is a plain function, a :class:`~attitude.model.torques.FunctionTorque`,
        a user's subclass (or the generic wrapper of ``shifted`` around one of the
        models whose ``shifted`` has no form of its own), or reads a path or field
        without a compiled form (a :class:`~attitude.model.orbit.CallablePath`, a user's field
        function, a density function): the caller then calls the models in Python.

    Raises
    ------
    InvalidStateError
        If ``body`` is not one :class:`~attitude.model.body.RigidBody`.

    Notes
    -----
    The environment's tables over ``t_span`` are built here, at once, rather than one
    segment at a time as a Python run reaches them: the same SGP4 or IGRF evaluations,
    paid up front (about 1.5 s per day of a TLE orbit at 20 s nodes), and ~12 numbers
    per node held twice (the table's and the compiled copy: ~0.2 GB for a year).  The
    bodies of a batch share one copy (:func:`compile_torques_shared`).

    Examples
    --------
    >>> from attitude import RigidBody
    >>> from attitude.model.orbit import KeplerOrbit
    >>> from attitude.model.torques import FunctionTorque, GravityGradient
    >>> body = RigidBody.from_principal_moments([100.0, 200.0, 250.0])
    >>> orbit = KeplerOrbit(mu=3.986004418e14, a=7.0e6, e=0.01)
    >>> compile_torques([GravityGradient(orbit=orbit)], body)
    CompiledTorques(gravity_gradient, numba=...)
    >>> compile_torques([FunctionTorque(lambda t, q, w, b: 0 * w)], body) is None
    True
    """
    shared = compile_torques_shared([models], [body], t_span)
    return None if shared is None else shared[0][0]


def _lay_out(models, body, layout: _Layout):
    """``(names, kinds, offsets)`` of ``models`` on ``body``, their numbers appended to
    ``layout``; None when one of them has no compiled form."""
    if not isinstance(body, RigidBody):
        raise InvalidStateError(f"expected one RigidBody, got {type(body).__name__}",
                                key="body")
    if isinstance(models, TorqueModel) or not isinstance(models, Sequence):
        models = [models]
    names, kinds, offsets = [], [], []
    for model in models:
        if not isinstance(model, TorqueModel):
            return None
        parts = model.compiled_parameters(body, layout.t_span)
        if parts is None:
            return None
        for kind, values in parts:
            index = layout.term(kind, values)
            if index is None:
                return None
            names.append(kind)
            kinds.append(TERM_KINDS[kind])
            offsets.append(index)
    return tuple(names), np.array(kinds, dtype=np.int64), np.array(offsets, dtype=np.int64)


def compile_torques_shared(groups, bodies, t_span=None
                           ) -> list[list[CompiledTorques]] | None:
    """:func:`compile_torques` for several groups of models on several bodies, all in
    one ``params`` array: each path or field (a TLE orbit's, the Sun's, IGRF's tables)
    is stored once for the whole batch, and each body adds only its own terms' numbers.

    Parameters
    ----------
    groups : sequence of (TorqueModel or sequence of them)
        The groups of models (the splitting's kick, drag and internal torques; one
        group for DOP853).
    bodies : sequence of RigidBody
    t_span : (float, float), optional
        As for :func:`compile_torques`.

    Returns
    -------
    list of list of CompiledTorques, or None
        ``[body][group]``, every one with the same (read-only) ``params`` array; None
        when a model has no compiled form.

    Examples
    --------
    >>> from attitude import RigidBody
    >>> from attitude.model.orbit import KeplerOrbit
    >>> from attitude.model.torques import GravityGradient
    >>> gg = GravityGradient(orbit=KeplerOrbit(mu=3.986004418e14, a=7.0e6, e=0.01))
    >>> bodies = [RigidBody.from_principal_moments(m) for m in ([1, 2, 3], [2, 3, 4])]
    >>> one = compile_torques([gg], bodies[0])
    >>> both = compile_torques_shared([[gg]], bodies)
    >>> both[0][0].params is both[1][0].params       # one array for the batch
    True
    >>> both[0][0].params.size - one.params.size     # the second body's own term:
    12
    >>> # time shift, mu, inertia (9), the index of the orbit's block (stored once)
    """
    layout = _Layout(t_span)
    rows = []
    for body in bodies:
        row = []
        for models in groups:
            laid = _lay_out(models, body, layout)
            if laid is None:
                return None
            row.append(laid)
        rows.append(row)
    params = np.concatenate(layout.blocks) if layout.blocks else np.zeros(0)
    layout.blocks.clear()
    params.setflags(write=False)
    out = []
    for row in rows:
        compiled = []
        for names, kinds, offsets in row:
            kinds.setflags(write=False)
            offsets.setflags(write=False)
            compiled.append(CompiledTorques(kinds, offsets, params, names))
        out.append(compiled)
    return out


# --- a user's own compiled torque (numba callback) --------------------------------------
#: Compiled callbacks made so far, by the user's function (each compiled once).
_CALLBACKS: dict = {}


def _no_torque(t, q, omega, out):
    """The callback of a run without a user torque (never called: ``has_user`` False)."""
    out[0] = 0.0
    out[1] = 0.0
    out[2] = 0.0


def callback_model(torques):
    """The one model of ``torques`` that the compiled DOP853 runs by its own
    ``numba_torque`` (:func:`user_torque`), or None: an external model (not ``internal``)
    carrying one, when it is the only such model (with two, the Python path runs).

    Examples
    --------
    >>> from attitude.propagation.compiled_torques import callback_model
    >>> class Drag:
    ...     numba_torque = staticmethod(lambda t, q, omega, out: None)
    ...     def __call__(self, t, quaternion, omega_body, body):
    ...         return [0.0, 0.0, 0.0]
    >>> drag = Drag()
    >>> callback_model([drag]) is drag, callback_model([drag, Drag()])
    (True, None)
    """
    user = [m for m in torques if getattr(m, "numba_torque", None) is not None
            and getattr(m, "internal", False) is not True]
    return user[0] if len(user) == 1 else None


def user_torque(model):
    """The callback that the compiled DOP853 calls for ``model``'s ``numba_torque`` (or a
    no-op one for ``model=None``): ``(callback, has_user)``.

    The protocol: a torque model (any callable ``torque(t, quaternion, omega_body, body)``,
    which the Python paths call) may carry a ``numba_torque`` attribute, an
    ``@numba.njit`` function ``(t, q, omega, out) -> None`` that writes the same
    body-frame torque (N m) into ``out`` (3,), from ``t`` (s since the epoch), ``q``
    (4,), body -> inertial scalar-last as the integrator carries it (unit to the
    tolerance), and ``omega`` (3,) body-frame rad/s.  Its body's numbers are its own
    (globals or closure constants of the compiled function).  With numba the callback is
    a ``numba.cfunc`` of that signature, which the kernel calls through its address: one
    compiled kernel serves every user function.  Without numba (the kernels in plain
    Python) it is the function itself.

    Examples
    --------
    >>> import numpy as np
    >>> from attitude.propagation.compiled_torques import user_torque
    >>> callback, has_user = user_torque(None)
    >>> has_user
    False
    """
    function = _no_torque if model is None else model.numba_torque
    known = _CALLBACKS.get(function)
    if known is None:
        known = function
        if NUMBA:
            import numba  # optional (the compiled paths): the callback's signature
            from numba import types

            sig = types.void(types.float64, types.float64[:], types.float64[:],
                             types.float64[:])
            # (the no-op is cached beside this file; a user's function has no such file)
            known = numba.cfunc(sig, cache=function is _no_torque)(function)
        _CALLBACKS[function] = known
    return known, model is not None

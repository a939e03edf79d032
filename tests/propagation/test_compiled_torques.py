"""The compiled torque models (attitude.propagation.compiled_torques) against the models'
own Python calls.

The second method is the model itself: ``body_torque`` compiles each model's own formula
(one source: tests/propagation/test_formula_sources.py), reads Kepler's equation by the
same iteration and the tabulated orbits, Sun and IGRF by the same cubics, so the two
differ only where a library function rounds differently (numpy's SIMD ``sin``/``cos``/
``exp`` against libm, a matrix product against a plain sum over facets):
:data:`tests.tolerances.TORQUE_EVAL` ulps of the scale of the terms, times what the
time-dependent inputs amplify an ulp by (see ``_models``: the Kepler solve, the
dipole's angle, the lit fraction in the penumbra, the density's exponential).  Each
comparison runs on the numba-compiled kernel, on its ``py_func`` (the loop in Python,
calling the compiled helpers) and, in a subprocess with ``ATTITUDE_NO_NUMBA=1``, on the
pure-Python fallback.
"""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pytest

from attitude import RigidBody
from attitude.environment import (
    ASTRONOMICAL_UNIT,
    EARTH_RADIUS,
    IGRF,
    SOLAR_PRESSURE_1AU,
    SUN_RADIUS,
    AerodynamicDrag,
    ExponentialAtmosphere,
    Facets,
    SolarRadiationPressure,
    SunPath,
    TLEOrbit,
    illumination,
)
from attitude.foundations.errors import InvalidStateError, OrbitError, TorqueConfigError
from attitude.model.orbit import CallablePath, KeplerOrbit, TabulatedPath
from attitude.model.torques import (
    EARTH_MU,
    EARTH_ROTATION_RATE,
    ConstantTorque,
    EddyCurrentDamping,
    EnergyDissipation,
    FunctionTorque,
    GravityGradient,
    HeavyTopPivot,
    TiltedDipoleField,
    TorqueModel,
    UniformField,
)
from attitude.propagation import compiled_torques as ct
from tests.tolerances import TORQUE_EVAL, assert_agree

#: A satellite with a full inertia tensor (kg m^2) and a mass (kg).
BODY = RigidBody(np.array([[120.0, 4.0, -3.0], [4.0, 210.0, 6.0], [-3.0, 6.0, 260.0]]),
                 mass=500.0)
ORBIT = KeplerOrbit(mu=EARTH_MU, a=7.0e6, e=0.3, i=0.9, raan=0.3, argp=1.1,
                    mean_anomaly=0.4)
CIRCULAR = KeplerOrbit(mu=EARTH_MU, a=6.9e6, e=0.0, i=1.7, raan=-2.0)
ECCENTRIC = KeplerOrbit(mu=EARTH_MU, a=4.0e7, e=0.97, i=0.2, argp=2.0, mean_anomaly=-0.1)
LEO = KeplerOrbit(mu=EARTH_MU, a=6.8e6, e=0.001, i=0.9, raan=1.0)
ISS = ("1 25544U 98067A   24061.50000000  .00016717  00000-0  10270-3 0  9005",
       "2 25544  51.6416 247.4627 0006703 130.5360 325.0288 15.72125391563537")
SPAN = (0.0, 3 * ORBIT.period)


def _tabulated() -> TabulatedPath:
    t = np.linspace(-100.0, 3 * ORBIT.period, 400)
    return TabulatedPath(t, ORBIT.position(t))


def _models():
    """``name -> (model, scale(t, w))``: each model, and the scale of its terms at time
    ``t`` and rate ``w`` (N m; the largest torque over attitudes, bounded by the
    product of the factors' norms) times the amplification of an ulp by the time
    dependence: a Kepler solve returns ``E`` within a few ulps of ``M``, times
    ``dE/dM <= 1 / (1 - e)``; the dipole turns with ``lam`` (an ulp of ``lam``)."""
    inertia = np.linalg.norm(BODY.inertia, 2)
    kappa = np.linalg.cond(BODY.inertia)

    def kepler(orbit, t):
        if not isinstance(orbit, KeplerOrbit):
            return 1.0
        return max(1.0, abs(orbit.mean_anomaly + orbit.mean_motion * t)) / (1.0 - orbit.e)

    def gravity(orbit):
        def scale(t, w):
            r = np.linalg.norm(orbit.position(t))
            return 3.0 * EARTH_MU / r**3 * inertia * kepler(orbit, t)
        return scale

    def eddy(tensor, field, orbit=None):
        m = np.linalg.norm(np.atleast_2d(tensor), 2)

        def scale(t, w):
            b = np.linalg.norm(field(t))
            amplify = 1.0 if orbit is None else 2.0 * max(
                kepler(orbit, t), abs(field.rotation_angle + field.rotation_rate * t))
            return m * np.linalg.norm(w) * b * b * amplify
        return scale

    dipole = TiltedDipoleField(ORBIT, rotation_angle=0.7)
    uniform = UniformField([1.0e-5, -2.0e-5, 3.0e-5])
    tensor = np.array([[3.0e3, 200.0, 0.0], [200.0, 1.0e3, -50.0], [0.0, -50.0, 2.0e3]])
    damper = EnergyDissipation(300.0)
    k = damper.coefficient(BODY)
    top = HeavyTopPivot(pivot_to_com=[0.1, -0.2, 0.3], up=[0.2, 0.3, 1.0])
    torque = np.array([1e-3, -2e-3, 5e-4])
    tle = TLEOrbit(*ISS)
    sun = SunPath(tle.epoch)
    igrf = IGRF(tle, max_degree=3)
    box = Facets.box([1.0, 1.5, 2.0], center=[0.05, -0.1, 0.12], specular=0.2, diffuse=0.3)
    arms = np.linalg.norm(box.centroids, axis=1)
    layers = np.asarray(ExponentialAtmosphere().table) * [1e3, 1.0, 1e3]

    def radiation(model):
        def scale(t, w):
            # |(sum_k w_k r_k) x s + 2 sum_k u_k (r_k x n_k)| <= 3 P sum_k A_k |r_k|; in the
            # penumbra the lit fraction turns with the angles (a few ulps of 1 rad) over
            # the Sun's apparent radius a: amplified by 1 / a
            r_sat, r_sun = model.orbit.position(t), model.sun.position(t)
            d = np.linalg.norm(r_sun - r_sat)
            p = SOLAR_PRESSURE_1AU * (ASTRONOMICAL_UNIT / d) ** 2
            lit = illumination(r_sat, r_sun, model.shadow)
            return 3.0 * p * np.sum(box.areas * arms) * (
                2.0 * d / SUN_RADIUS if 0.0 < lit < 1.0 else 1.0)
        return scale

    def drag(model):
        def scale(t, w):
            # |(sum_k A_k c_k r_k) x v_hat| <= sum_k A_k |r_k| times 1/2 rho v^2 C_D; an
            # ulp of |r| changes the density by |r| / H ulps (H the scale height)
            r, v = model.orbit.position(t), model.orbit.velocity(t)
            v_air = v - EARTH_ROTATION_RATE * np.array([-r[1], r[0], 0.0])
            h = np.linalg.norm(r) - EARTH_RADIUS
            k = max(np.searchsorted(layers[:, 0], h, side="right") - 1, 0)
            rho = layers[k, 1] * np.exp(-(h - layers[k, 0]) / layers[k, 2])
            return (0.5 * rho * np.dot(v_air, v_air) * 2.2 * np.sum(box.areas * arms)
                    * 2.0 * np.linalg.norm(r) / layers[k, 2])
        return scale

    srp = SolarRadiationPressure(box, sun=sun, orbit=tle)
    srp_cylinder = SolarRadiationPressure(box, sun=sun, orbit=tle, shadow="cylindrical")
    drag_tle = AerodynamicDrag(box, tle).shifted(100.0)
    drag_kepler = AerodynamicDrag(box, LEO, cd=2.2)
    return {
        "gravity_gradient_kepler": (GravityGradient(orbit=ORBIT), gravity(ORBIT)),
        "gravity_gradient_e0.97": (GravityGradient(orbit=ECCENTRIC), gravity(ECCENTRIC)),
        "gravity_gradient_tle": (GravityGradient(EARTH_MU, tle), gravity(tle)),
        "eddy_igrf": (EddyCurrentDamping(tensor, igrf), eddy(tensor, igrf)),
        "radiation_conical": (srp, radiation(srp)),
        "radiation_cylindrical": (srp_cylinder, radiation(srp_cylinder)),
        "drag_tle_shifted": (drag_tle, drag(drag_tle)),
        "drag_kepler": (drag_kepler, drag(drag_kepler)),
        "gravity_gradient_circular": (GravityGradient(orbit=CIRCULAR), gravity(CIRCULAR)),
        "gravity_gradient_fixed": (GravityGradient(EARTH_MU, [4e6, -5e6, 2e6]),
                                   lambda t, w: 3.0 * EARTH_MU / 6.7e6**3 * inertia),
        "gravity_gradient_tabulated": (GravityGradient(EARTH_MU, _tabulated()),
                                       gravity(ORBIT)),
        "constant_body": (ConstantTorque(torque), lambda t, w: np.linalg.norm(torque)),
        "constant_inertial": (ConstantTorque(torque, frame="inertial"),
                              lambda t, w: np.linalg.norm(torque)),
        "heavy_top": (top, lambda t, w: BODY.mass * top.g * np.linalg.norm(top.pivot_to_com)),
        "eddy_uniform_isotropic": (EddyCurrentDamping(2.0e3, uniform),
                                   eddy(2.0e3, uniform)),
        "eddy_uniform_tensor": (EddyCurrentDamping(tensor, uniform), eddy(tensor, uniform)),
        "eddy_dipole_kepler": (EddyCurrentDamping(tensor, dipole),
                               eddy(tensor, dipole, ORBIT)),
        "dissipation": (damper, lambda t, w: k * np.linalg.norm(w) * kappa),
    }


MODELS = _models()          # cheap: the environment's tables are built on first use
KERNELS = {"numba": ct.body_torque} if ct.NUMBA else {"python": ct.body_torque}
if ct.NUMBA:
    KERNELS["py_func"] = ct.body_torque.py_func


def _states(seed: int, n: int = 40):
    """Random times (within three periods of the eccentric orbit), attitudes (not
    normalised: the models normalise) and rates up to ~0.5 rad/s."""
    rng = np.random.default_rng(seed)
    t = rng.uniform(0.0, 3 * ORBIT.period, n)
    q = rng.normal(size=(n, 4)) * rng.uniform(0.5, 2.0, (n, 1))
    w = rng.normal(size=(n, 3)) * 0.3
    return t, q, w


def check_model(name: str, kernel=ct.body_torque, seed: int = 0) -> None:
    """The compiled ``name`` model against its Python call at random states."""
    model, scale = MODELS[name]
    c = ct.compile_torques([model], BODY, t_span=SPAN)
    assert c is not None, name
    out = np.full(3, np.nan)
    for t, q, w in zip(*_states(seed), strict=True):
        kernel(c.kinds, c.offsets, c.params, float(t), q, w, out)
        assert_agree(out, model(t, q, w, BODY), ulps=TORQUE_EVAL, magnitude=scale(t, w),
                     what=f"{name} at t = {t}")


def check_all() -> None:
    """Every model, and their sum, through :func:`body_torque` (as imported)."""
    for name in MODELS:
        check_model(name)
    check_sum()


def check_sum(kernel=ct.body_torque) -> None:
    models = [m for m, _ in MODELS.values()]
    c = ct.compile_torques(models, BODY, t_span=SPAN)
    assert c.names[0] == "gravity_gradient" and len(c.names) == len(models)
    out = np.empty(3)
    for t, q, w in zip(*_states(7), strict=True):
        kernel(c.kinds, c.offsets, c.params, float(t), q, w, out)
        desired = sum(m(t, q, w, BODY) for m in models)
        magnitude = sum(s(t, w) for _, s in MODELS.values())
        assert_agree(out, desired, ulps=TORQUE_EVAL * len(models), magnitude=magnitude,
                     what=f"sum at t = {t}")


@pytest.mark.parametrize("kernel", list(KERNELS))
@pytest.mark.parametrize("name", list(MODELS))
def test_compiled_model_matches_python_call(name, kernel):
    check_model(name, KERNELS[kernel], seed=list(MODELS).index(name))


@pytest.mark.parametrize("kernel", list(KERNELS))
def test_sum_of_all_models(kernel):
    """A sum (with ``+`` or a list) is the terms one after another, as SumTorque adds."""
    check_sum(KERNELS[kernel])
    both = MODELS["gravity_gradient_kepler"][0] + MODELS["dissipation"][0]
    assert ct.compile_torques(both, BODY).names == ("gravity_gradient", "dissipation")


def test_pure_python_fallback_in_a_subprocess():
    """With ``ATTITUDE_NO_NUMBA=1`` nothing is compiled and the same checks pass."""
    code = ("import attitude.propagation.compiled_torques as ct; assert not ct.NUMBA; "
            "import tests.propagation.test_compiled_torques as t; t.check_all()")
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    env = {**os.environ, "ATTITUDE_NO_NUMBA": "1",
           "PYTHONPATH": os.pathsep.join([root, os.environ.get("PYTHONPATH", "")])}
    run = subprocess.run([sys.executable, "-c", code], env=env, cwd=root,
                         capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr[-2000:]


def test_shifted_kepler_models_compile_and_agree():
    """``shifted`` advances a Keplerian orbit (and the Earth's rotation): the compiled
    shifted model is the shifted model's formulas."""
    for name in ("gravity_gradient_kepler", "eddy_dipole_kepler"):
        model, _ = MODELS[name]
        later = model.shifted(1234.5)
        c = ct.compile_torques(later, BODY)
        t, q, w = _states(3, 5)
        for k in range(5):
            desired = later(t[k], q[k], w[k], BODY)
            assert_agree(c(t[k], q[k], w[k]), desired, ulps=TORQUE_EVAL,
                         magnitude=np.max(np.abs(desired)) * 10, what=name)


def test_shifted_wrappers_read_their_terms_later():
    """``shifted`` on a tabulated path (the generic wrapper, ``inner(t + dt)``) and on an
    environment torque (its time offset): the compiled terms read the same times."""
    for name in ("gravity_gradient_tabulated", "gravity_gradient_tle", "drag_tle_shifted"):
        model, scale = MODELS[name]
        later = model.shifted(321.25)
        c = ct.compile_torques([later], BODY, t_span=(0.0, 2 * ORBIT.period))
        assert c.params[c.offsets[0]] == (321.25 if name != "drag_tle_shifted" else 0.0)
        for t, q, w in zip(*_states(13, 10), strict=True):
            t = t * 2 / 3
            assert_agree(c(t, q, w), later(t, q, w, BODY), ulps=TORQUE_EVAL,
                         magnitude=scale(t + 321.25, w), what=f"{name} shifted, t = {t}")


def test_output_is_overwritten_not_accumulated():
    c = ct.compile_torques([MODELS["constant_body"][0]], BODY)
    out = np.array([1.0, 2.0, 3.0])
    for _ in range(2):
        ct.body_torque(c.kinds, c.offsets, c.params, 0.0, np.array([0, 0, 0, 1.0]),
                       np.zeros(3), out)
        np.testing.assert_array_equal(out, [1e-3, -2e-3, 5e-4])


def test_no_models_is_zero_torque():
    c = ct.compile_torques([], BODY)
    assert c.names == () and c(10.0, [0, 0, 0, 1.0], [1.0, 2.0, 3.0]).tolist() == [0, 0, 0]


class _UserModel(TorqueModel):
    velocity_dependent = False

    def evaluate(self, t, quaternion, omega_body, body):
        return np.zeros(3)


@pytest.mark.parametrize("model", [
    FunctionTorque(lambda t, q, w, b: -1e-3 * np.asarray(w)),
    lambda t, q, w, b: np.zeros(3),
    _UserModel(),
    GravityGradient(EARTH_MU, CallablePath(lambda t: np.array([7e6, 0.0, 0.0]))),
    EddyCurrentDamping(1.0, lambda t: np.array([0.0, 0.0, 3e-5])),
    _UserModel().shifted(10.0),                                   # the generic wrapper
], ids=["FunctionTorque", "function", "subclass", "CallablePath", "field function",
        "shifted subclass"])
def test_models_without_compiled_form_give_none(model):
    assert ct.compile_torques([ConstantTorque([0, 0, 1.0]), model], BODY) is None


def test_errors():
    with pytest.raises(InvalidStateError, match="body: expected one RigidBody"):
        ct.compile_torques([], [BODY, BODY])
    massless = RigidBody.from_principal_moments([1.0, 2.0, 3.0])
    with pytest.raises(TorqueConfigError, match="mass: the body has no mass"):
        ct.compile_torques(HeavyTopPivot(pivot_to_com=[0, 0, 1.0]), massless)
    with pytest.raises(OrbitError, match="outside the tabulated span"):
        ct.compile_torques(GravityGradient(EARTH_MU, _tabulated()), BODY,
                           t_span=(0.0, 10 * ORBIT.period))


def test_layout_is_read_only():
    c = ct.compile_torques(MODELS["eddy_dipole_kepler"][0], BODY)
    assert c.kinds.dtype == np.int64 and c.params.dtype == np.float64
    with pytest.raises(ValueError, match="read-only"):
        c.params[0] = 1.0


def test_radiation_pressure_through_the_penumbra():
    """The conical shadow's partial phases (lens of two disks), where random times rarely
    fall: every 0.25 s across the penumbrae of the first orbits."""
    model, scale = MODELS["radiation_conical"]
    t = np.arange(SPAN[0], SPAN[1], 0.25)
    lit = illumination(model.orbit.position(t), model.sun.position(t), "conical")
    partial = t[(lit > 0.0) & (lit < 1.0)]
    assert partial.size > 20                       # ~8 s of penumbra per crossing
    c = ct.compile_torques(model, BODY, t_span=SPAN)
    rng = np.random.default_rng(5)
    for x in partial:
        q, w = rng.normal(size=4), np.zeros(3)
        assert_agree(c(x, q, w), model(x, q, w, BODY), ulps=TORQUE_EVAL,
                     magnitude=scale(x, w), what=f"penumbra at t = {x}")


def test_a_path_read_by_several_terms_is_stored_once():
    """Gravity gradient and the dipole field on one orbit share its block (13 numbers)."""
    gg, eddy = MODELS["gravity_gradient_kepler"][0], MODELS["eddy_dipole_kepler"][0]
    apart = [ct.compile_torques(m, BODY).params.size for m in (gg, eddy)]
    assert ct.compile_torques([gg, eddy], BODY).params.size == sum(apart) - 13


def test_tabulated_paths_need_the_time_span():
    assert ct.compile_torques(MODELS["gravity_gradient_tle"][0], BODY) is None
    assert ct.compile_torques(MODELS["gravity_gradient_tabulated"][0], BODY) is not None


def test_tables_at_breakpoints_and_segment_ends():
    """The interval lookup (an index on a uniform grid, bisection otherwise) at
    breakpoints, just beside them and across a TimeTable segment end, on the same
    cubics as the Python path: a TLE orbit tabulated every second (segments of 4320 s)
    and a path sampled at uneven times."""
    tle = TLEOrbit(*ISS, spacing=1.0)
    rng = np.random.default_rng(9)
    uneven = np.sort(rng.uniform(0.0, 3000.0, 300))
    cases = [(GravityGradient(EARTH_MU, tle), (4000.0, 4700.0),
              [4320.0, np.nextafter(4320.0, 0), np.nextafter(4320.0, 1e9), 4319.0, 4321.0,
               4000.0, 4700.0, 4500.5]),
             (GravityGradient(EARTH_MU, TabulatedPath(uneven, ORBIT.position(uneven))),
              (uneven[0], uneven[-1]), list(uneven[::7]) + [uneven[-1], uneven[0]])]
    inertia = np.linalg.norm(BODY.inertia, 2)
    for model, span, times in cases:
        c = ct.compile_torques(model, BODY, t_span=span)
        for t in times:
            q, w = rng.normal(size=4), np.zeros(3)
            scale = 3.0 * EARTH_MU / np.linalg.norm(model.orbit.position(t)) ** 3 * inertia
            assert_agree(c(t, q, w), model(t, q, w, BODY), ulps=TORQUE_EVAL,
                         magnitude=scale, what=f"{model.orbit!r} at t = {t!r}")

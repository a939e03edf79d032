"""The torque of a residual magnetic dipole, ``M = m x B`` (attitude.torques.MagneticDipole).

Independent references: the cross product and the rotation computed by scipy; the
compass needle, whose planar swing in a uniform field is a pendulum (small-angle
frequency ``sqrt(m B / I)``, the exact period ``4 K(sin^2(theta_0 / 2)) / omega_0`` at any
amplitude); the conservation of ``E_kin - m . B`` in a uniform field (the splitting is
symplectic, so its energy error stays bounded at the level of its local error); DOP853
on Euler's equations (the second method); and the model's own Python call for the
compiled kernel (:data:`tests.tolerances.TORQUE_EVAL`, as
tests/propagation/test_compiled_torques.py).
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from astropy.time import Time
from scipy.interpolate import CubicSpline
from scipy.spatial.transform import Rotation
from scipy.special import ellipk

import attitude as att
from attitude.app.scenario import load_scenario, run_scenario
from attitude.environment import IGRF
from attitude.foundations.errors import TorqueConfigError
from attitude.model.orbit import KeplerOrbit
from attitude.model.torques import (
    EARTH_MU,
    MagneticDipole,
    TiltedDipoleField,
    UniformField,
    from_config,
)
from attitude.propagation import compiled_torques as ct
from tests.app.test_scenario import GOOD, write
from tests.tolerances import FEW_OPS, TORQUE_EVAL, assert_agree, attitude_angle

ROOT = Path(__file__).resolve().parents[2]
EPOCH = Time("2024-03-01T00:00:00", scale="utc")
#: A satellite with a full inertia tensor, kg m^2.
SAT = att.RigidBody(np.array([[12.0, 0.4, -0.3], [0.4, 21.0, 0.6], [-0.3, 0.6, 26.0]]))
LEO = KeplerOrbit(mu=EARTH_MU, a=6.878e6, e=0.002, i=0.9, raan=0.4, argp=1.0,
                  mean_anomaly=0.3)
MOMENT = np.array([0.6, -0.3, 0.8])                     # A m^2
#: Splitting at the default step against DOP853 at rtol 1e-13: the default step is
#: calibrated for ~1e-10 relative accuracy over a few orbits at order 4
#: (attitude.propagation.splitting.choose_step, docs/integrators.md); DOP853's own error
#: is ~INTEGRATOR_PATHS * rtol = 1e-12.
SPLITTING_DEFAULT = 1e-10


def _random_states(seed: int, n: int = 30):
    rng = np.random.default_rng(seed)
    return (rng.uniform(0.0, 2 * LEO.period, n),
            rng.normal(size=(n, 4)) * rng.uniform(0.5, 2.0, (n, 1)),
            rng.normal(size=(n, 3)) * 0.1)


# --- the formula ----------------------------------------------------------------------


def test_torque_is_m_cross_b_in_body_axes():
    """Against scipy: ``m x R^T B`` (R body -> inertial), one epoch and a stack; the
    closed forms ``|m| |B|`` at right angles and zero along the field."""
    field = UniformField([1e-5, -2e-5, 3e-5])
    model = MagneticDipole(MOMENT, field)
    t, q, w = _random_states(1)
    expected = np.cross(MOMENT, Rotation.from_quat(q).inv().apply(field.vector))
    scale = np.linalg.norm(MOMENT) * np.linalg.norm(field.vector)
    # a rotation and a cross product per side (FEW_OPS each), two sides
    assert_agree(model(t, q, w, SAT), expected, ulps=4 * FEW_OPS, magnitude=scale)
    for k in range(5):
        assert_agree(model(t[k], q[k], w[k], SAT), expected[k], ulps=4 * FEW_OPS,
                     magnitude=scale)
    needle = MagneticDipole({"value": [2.0, 0.0, 0.0], "unit": "A m2"}, [0.0, 3e-5, 0.0])
    assert needle(0.0, [0, 0, 0, 1], np.zeros(3), SAT).tolist() == [0.0, 0.0, 6e-5]
    along = MagneticDipole([0.0, 2.0, 0.0], [0.0, 3e-5, 0.0])
    assert along(0.0, [0, 0, 0, 1], np.zeros(3), SAT).tolist() == [0.0, 0.0, 0.0]


def test_vectorised_call_equals_per_element_call():
    """Stacked ``(n,)``, ``(n, 4)``, ``(n, 3)`` == n single calls; a scalar time with
    stacked attitudes, a Rotation stack, a sequence of bodies and unnormalised
    quaternions (integrators pass raw stage values) give the same torques."""
    model = MagneticDipole(MOMENT, TiltedDipoleField(LEO, rotation_angle=0.7))
    t, q, w = _random_states(3, 6)
    stacked = model(t, q, w, SAT)
    assert stacked.shape == (6, 3)
    scale = np.linalg.norm(MOMENT) * 6e-5

    def agree(a, b, what):
        assert_agree(a, b, ulps=TORQUE_EVAL, magnitude=scale, what=what)

    for k in range(6):
        single = model(float(t[k]), q[k], w[k], SAT)
        assert single.shape == (3,)
        agree(stacked[k], single, f"element {k}")
    agree(model(t[0], q, w, SAT)[2], model(t[0], q[2], w[2], SAT), "scalar time")
    agree(model(t, Rotation.from_quat(q), w, SAT), stacked, "Rotation stack")
    agree(model(t, q, w, [SAT] * 6), stacked, "sequence of bodies")
    agree(model(t, 1.001 * q, w, SAT), stacked, "unnormalised quaternions")
    agree(model.potential(t, q), -np.einsum("i,ni->n", MOMENT, Rotation.from_quat(q).inv()
                                            .apply(model.field(t))), "potential")


def test_torque_is_minus_the_gradient_of_the_potential():
    """``M . e = -dV/dphi`` for a rotation by ``phi`` about any body axis ``e``
    (central differences, error ~ (h^2 / 6) |V'''| + eps |V| / h)."""
    model = MagneticDipole(MOMENT, UniformField([1e-5, -2e-5, 3e-5]))
    rng = np.random.default_rng(2)
    scale = np.linalg.norm(MOMENT) * 1e-5 * np.sqrt(14.0)
    h = 1e-5
    for _ in range(10):
        q = Rotation.from_quat(rng.normal(size=4))
        e = rng.normal(size=3)
        e /= np.linalg.norm(e)
        plus = (q * Rotation.from_rotvec(h * e)).as_quat()
        minus = (q * Rotation.from_rotvec(-h * e)).as_quat()
        dV = (model.potential(0.0, plus) - model.potential(0.0, minus)) / (2 * h)
        torque = model(0.0, q.as_quat(), np.zeros(3), SAT)
        assert abs(torque @ e + dV) < scale * (h * h + 1e-16 / h) * 10


def test_quantities_and_errors():
    from astropy import units as u
    for moment in ({"value": [1000.0, 0.0, 500.0], "unit": "mA m2"},
                   [1.0, 0.0, 0.5] * u.A * u.m**2):
        model = MagneticDipole(moment, UniformField([0.0, 0.0, 3e-5]))
        assert_agree(model.moment, [1.0, 0.0, 0.5], ulps=1)
    with pytest.raises(TorqueConfigError, match="moment"):
        MagneticDipole([1.0, 0.0], [0.0, 0.0, 3e-5])
    with pytest.raises(TorqueConfigError, match="moment"):
        MagneticDipole({"value": [1.0, 0.0, 0.0], "unit": "N m"}, [0.0, 0.0, 3e-5])
    with pytest.raises(TorqueConfigError, match="field"):
        MagneticDipole([1.0, 0.0, 0.0], None)
    assert MagneticDipole.velocity_dependent is False


# --- the compass needle ---------------------------------------------------------------


def _swing_period(theta0: float, periods: int = 10) -> tuple[float, float]:
    """The period of a needle (moment along body x, moments 2, 3, 4 kg m^2) swinging
    about body z (``C = 4``) in a uniform field along inertial x, started at rest
    ``theta0`` from the field, measured from the zero crossings of ``theta(t)`` (a cubic
    spline through 400 outputs a period: interpolation error ~1e-12 of the period);
    and the small-angle period ``2 pi / sqrt(m B / C)``."""
    body = att.RigidBody.from_principal_moments([2.0, 3.0, 4.0])
    m, b = 1.0, 3e-5
    model = MagneticDipole([m, 0.0, 0.0], UniformField([b, 0.0, 0.0]))
    small = 2.0 * np.pi / np.sqrt(m * b / 4.0)
    state = att.AttitudeState("2030-01-01", Rotation.from_rotvec([0.0, 0.0, theta0]),
                              [0.0, 0.0, 0.0])
    times = np.linspace(0.0, 1.01 * periods * small, 400 * periods)
    eph = att.propagate(body, state, times, torques=[model], method="splitting")
    q = eph.dataset["quaternion"].values
    assert np.abs(q[:, :2]).max() == 0.0                 # the swing stays in its plane
    theta = 2.0 * np.arctan2(q[:, 2], q[:, 3])
    roots = CubicSpline(times, theta).roots(extrapolate=False)
    assert len(roots) >= 2 * periods
    return (roots[-1] - roots[0]) / ((len(roots) - 1) / 2.0), small


def test_compass_needle_swings_at_sqrt_m_b_over_i():
    """Small angle (1 mrad): the period is ``2 pi / sqrt(m B / I)`` to the pendulum's
    finite-amplitude correction ``theta_0^2 / 16 = 6e-8``: 1e-6 is that plus margin."""
    period, small = _swing_period(1e-3)
    assert abs(period / small - 1.0) < 1e-6


def test_compass_needle_at_large_amplitude_has_the_pendulum_period():
    """At 0.5 rad the period is the pendulum's, ``4 K(k^2) / omega_0`` with ``k =
    sin(theta_0 / 2)`` (1.6 % above the small-angle one), to the splitting's accuracy."""
    period, small = _swing_period(0.5)
    exact = 4.0 * ellipk(np.sin(0.25) ** 2) * small / (2.0 * np.pi)
    assert abs(period / small - 1.0) > 0.015
    assert abs(period / exact - 1.0) < SPLITTING_DEFAULT


def test_energy_with_the_magnetic_potential_is_conserved():
    """A triaxial body tumbling with a skew moment in a uniform field (a chaotic motion:
    an asymmetric heavy top), 40 swing periods at the default splitting step:
    ``E_kin - m . B`` stays constant to 1e-10 of ``max E_kin + |m| |B|`` (the
    splitting is symplectic: its energy error is bounded by its local accuracy, no
    drift)."""
    body = att.RigidBody.from_principal_moments([2.0, 3.0, 4.0])
    field = UniformField([1e-5, 2e-5, -2.2e-5])
    model = MagneticDipole(MOMENT, field)
    rate = model.characteristic_rate(0.0, [0, 0, 0, 1], np.zeros(3), body)
    state = att.AttitudeState("2030-01-01", Rotation.from_rotvec([0.3, -0.2, 1.0]),
                              [2e-3, -1e-3, 3e-3])
    times = np.linspace(0.0, 40 * 2 * np.pi / rate, 2001)
    eph = att.propagate(body, state, times, torques=[model], method="splitting")
    kinetic = eph.dataset["kinetic_energy"].values
    potential = model.potential(times, eph.dataset["quaternion"].values)
    assert np.ptp(potential) > np.linalg.norm(MOMENT) * 1e-5      # it does swing
    scale = kinetic.max() + np.linalg.norm(MOMENT) * np.linalg.norm(field.vector)
    assert np.ptp(kinetic + potential) < 1e-10 * scale


# --- the second method: DOP853 ----------------------------------------------------------


@pytest.mark.parametrize("case", ["symmetric_top_uniform", "satellite_leo_dipole"])
def test_splitting_agrees_with_dop853(case):
    """A symmetric body with its moment along its axis in a uniform field (the
    Lagrange top: integrable, so ulps are not amplified exponentially), ten swing
    periods; a triaxial satellite tumbling through the tilted dipole along one LEO
    orbit.  Default splitting step against DOP853 at rtol 1e-13."""
    if case == "symmetric_top_uniform":
        body = att.RigidBody.from_principal_moments([2.0, 3.0, 3.0])
        model = MagneticDipole([0.8, 0.0, 0.0], UniformField([0.0, 0.0, 3e-5]))
        state = att.AttitudeState("2030-01-01", Rotation.from_rotvec([0.0, -1.0, 0.0]),
                                  [0.02, 1e-3, 0.0])
        rate = model.characteristic_rate(0.0, [0, 0, 0, 1], np.zeros(3), body)
        times = np.linspace(0.0, 10 * 2 * np.pi / rate, 401)
    else:
        body = SAT
        model = MagneticDipole([0.5, 0.2, -0.3], TiltedDipoleField(LEO, rotation_angle=0.3))
        state = att.AttitudeState("2030-01-01", Rotation.from_rotvec([0.3, -0.2, 1.0]),
                                  [0.02, -0.01, 0.03])
        times = np.linspace(0.0, LEO.period, 301)
    split = att.propagate(body, state, times, torques=[model], method="splitting")
    ref = att.propagate(body, state, times, torques=[model], method="integrator",
                        rtol=1e-13)
    q, q_ref = split.dataset["quaternion"].values, ref.dataset["quaternion"].values
    w, w_ref = (split.dataset["angular_velocity"].values,
                ref.dataset["angular_velocity"].values)
    assert attitude_angle(q, q_ref).max() < SPLITTING_DEFAULT
    assert np.abs(w - w_ref).max() < SPLITTING_DEFAULT * np.abs(w_ref).max()


def test_compiled_and_python_splitting_agree():
    """A field given as a plain function has no compiled form: the same run goes
    through the Python kicks.  Both make the same steps, so they differ by round-off
    accumulated over the steps (~10^3 steps of a few ulps of 1)."""
    field = TiltedDipoleField(LEO, rotation_angle=0.3)
    compiled = MagneticDipole(MOMENT, field)
    python = MagneticDipole(MOMENT, lambda t: field(t))
    assert ct.compile_torques(python, SAT) is None
    assert ct.compile_torques(compiled, SAT) is not None
    state = att.AttitudeState("2030-01-01", Rotation.from_rotvec([0.3, -0.2, 1.0]),
                              [0.02, -0.01, 0.03])
    times = np.linspace(0.0, 0.2 * LEO.period, 21)
    a = att.propagate(SAT, state, times, torques=[compiled], method="splitting")
    b = att.propagate(SAT, state, times, torques=[python], method="splitting")
    assert attitude_angle(a.dataset["quaternion"].values,
                          b.dataset["quaternion"].values).max() < 1e-11


# --- the model's protocol ---------------------------------------------------------------


def test_characteristic_rate_and_shift():
    body = att.RigidBody.from_principal_moments([1.0, 1.5, 2.0])
    uniform = MagneticDipole([0.0, 0.0, 2.0], UniformField([0.0, 0.0, 4e-5]))
    assert uniform.characteristic_rate(0.0, [0, 0, 0, 1], np.zeros(3), body) == \
        pytest.approx(np.sqrt(2.0 * 4e-5 / 1.0), rel=1e-15)
    assert uniform.shifted(100.0) is uniform
    # a weak moment in an orbit field: the orbit (the field turning) is faster
    weak = MagneticDipole([1e-6, 0.0, 0.0], TiltedDipoleField(LEO))
    rate = weak.characteristic_rate(0.0, [0, 0, 0, 1], np.zeros(3), SAT)
    assert rate > LEO.mean_motion
    # shifted on a Keplerian orbit: its own class, the same torque dt later
    later = MagneticDipole(MOMENT, TiltedDipoleField(LEO, rotation_angle=0.3)).shifted(777.0)
    original = MagneticDipole(MOMENT, TiltedDipoleField(LEO, rotation_angle=0.3))
    assert isinstance(later, MagneticDipole)
    t, q, w = _random_states(4, 5)
    scale = np.linalg.norm(MOMENT) * 6e-5 * 100     # an ulp of the angles, amplified
    assert_agree(later(t, q, w, SAT), original(t + 777.0, q, w, SAT), ulps=TORQUE_EVAL,
                 magnitude=scale)


# --- compiled kernel against the Python call ------------------------------------------


def _compiled_cases():
    """``name -> (model, t_span, scale(t))``: the scale of the terms (``|m| |B(t)|``)
    times what an ulp of the time-dependent inputs is amplified by (the Kepler solve,
    ``dE/dM <= 1 / (1 - e)``, and the dipole's angle; as
    tests/propagation/test_compiled_torques.py)."""
    span = (0.0, 2 * LEO.period)
    norm_m = np.linalg.norm(MOMENT)
    uniform = UniformField([1e-5, -2e-5, 3e-5])
    dipole = TiltedDipoleField(LEO, rotation_angle=0.7)
    igrf = IGRF(LEO, epoch=EPOCH, max_degree=4)

    def dipole_scale(field):
        def scale(t):
            angle = abs(field.rotation_angle + field.rotation_rate * t)
            kepler = max(1.0, abs(LEO.mean_anomaly + LEO.mean_motion * t)) / (1.0 - LEO.e)
            return norm_m * np.linalg.norm(field(t)) * 2.0 * max(kepler, angle)
        return scale

    return {
        "uniform": (MagneticDipole(MOMENT, uniform), span,
                    lambda t: norm_m * np.linalg.norm(uniform.vector)),
        "tilted_dipole": (MagneticDipole(MOMENT, dipole), span, dipole_scale(dipole)),
        "tilted_dipole_shifted": (MagneticDipole(MOMENT, dipole).shifted(321.0), span,
                                  lambda t: dipole_scale(dipole)(t + 321.0)),
        "igrf": (MagneticDipole(MOMENT, igrf), span,
                 lambda t: norm_m * np.linalg.norm(igrf(t))),
        "igrf_shifted": (MagneticDipole(MOMENT, igrf).shifted(100.0), span,
                         lambda t: norm_m * np.linalg.norm(igrf(t + 100.0))),
    }


CASES = _compiled_cases()
KERNELS = {"numba": ct.body_torque} if ct.NUMBA else {"python": ct.body_torque}
if ct.NUMBA:
    KERNELS["py_func"] = ct.body_torque.py_func


def check_case(name: str, kernel=ct.body_torque) -> None:
    model, span, scale = CASES[name]
    c = ct.compile_torques([model], SAT, t_span=span)
    assert c is not None and c.names == ("magnetic_dipole",), name
    out = np.full(3, np.nan)
    for t, q, w in zip(*_random_states(list(CASES).index(name)), strict=True):
        kernel(c.kinds, c.offsets, c.params, float(t), q, w, out)
        assert_agree(out, model(t, q, w, SAT), ulps=TORQUE_EVAL, magnitude=scale(t),
                     what=f"{name} at t = {t}")


def check_all() -> None:
    for name in CASES:
        check_case(name)


@pytest.mark.parametrize("kernel", list(KERNELS))
@pytest.mark.parametrize("name", list(CASES))
def test_compiled_matches_python_call(name, kernel):
    check_case(name, KERNELS[kernel])


def test_compiled_sum_with_gravity_gradient_shares_the_orbit():
    """With gravity gradient on the same orbit: the orbit's block is stored once
    (13 numbers), the sum is the two terms'."""
    gg = att.torques.GravityGradient(orbit=LEO)
    md = CASES["tilted_dipole"][0]
    apart = [ct.compile_torques(m, SAT).params.size for m in (gg, md)]
    both = ct.compile_torques(gg + md, SAT)
    assert both.names == ("gravity_gradient", "magnetic_dipole")
    assert both.params.size == sum(apart) - 13
    t, q, w = _random_states(6, 10)
    for k in range(10):
        desired = gg(t[k], q[k], w[k], SAT) + md(t[k], q[k], w[k], SAT)
        magnitude = 3 * EARTH_MU / LEO.periapsis**3 * 30.0 + CASES["tilted_dipole"][2](t[k])
        assert_agree(both(t[k], q[k], w[k]), desired, ulps=2 * TORQUE_EVAL,
                     magnitude=magnitude)


def test_function_field_has_no_compiled_form():
    assert MagneticDipole(MOMENT, lambda t: np.array([0.0, 0.0, 3e-5])
                          ).compiled_parameters(SAT) is None


def test_pure_python_fallback_in_a_subprocess():
    """With ``ATTITUDE_NO_NUMBA=1`` nothing is compiled and the same checks pass."""
    code = ("import attitude.propagation.compiled_torques as ct; assert not ct.NUMBA; "
            "import tests.model.test_magnetic_dipole as t; t.check_all()")
    env = {**os.environ, "ATTITUDE_NO_NUMBA": "1",
           "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}
    run = subprocess.run([sys.executable, "-c", code], env=env, cwd=ROOT,
                         capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr[-2000:]


# --- scenario files ---------------------------------------------------------------------

UNIFORM_TABLE = """
[[torques]]
type = "magnetic_dipole"
moment = { value = [0.5, 0.0, 0.0], unit = "A m2" }
field = { model = "uniform", vector = { value = [0, 30000, 0], unit = "nT" } }
"""


def test_scenario_builds_and_runs(tmp_path):
    scenario = load_scenario(write(tmp_path, GOOD + UNIFORM_TABLE))
    (model,) = scenario.torques
    assert isinstance(model, MagneticDipole)
    assert model.moment.tolist() == [0.5, 0.0, 0.0]
    assert_agree(model.field.vector, [0.0, 3e-5, 0.0], ulps=1)
    result = run_scenario(scenario, write_outputs=False)
    assert result.ephemeris.dataset.sizes["time"] > 1


@pytest.mark.parametrize("field", ["igrf", {"model": "dipole"}, None])
def test_scenario_fields_along_an_orbit(field):
    """``field = "igrf"`` (IGRF-14), the tilted dipole, and the default (the dipole)
    along ``orbit``, as for eddy currents."""
    table = {"type": "magnetic_dipole", "moment": {"value": [0.1, 0.2, 0.3], "unit": "A m2"},
             "orbit": {"a": "6878 km", "i": "51.6 deg"}}
    if field is not None:
        table["field"] = field
    model = from_config(table, base_epoch=EPOCH)
    expected = IGRF if field == "igrf" else TiltedDipoleField
    assert isinstance(model.field, expected)
    b = np.linalg.norm(model.field(0.0))
    assert 1.5e-5 < b < 6e-5                          # T: the Earth's field in LEO


@pytest.mark.parametrize(("table", "key"), [
    ({"field": "uniform"}, "moment"),                                          # missing
    ({"moment": [1.0, 0.0], "field": "igrf"}, "moment"),                       # shape
    ({"moment": {"value": [1.0, 0, 0], "unit": "N m"}, "field": "igrf"}, "moment"),
    ({"moment": [1.0, 0, 0], "field": "igrf"}, "orbit"),                       # no orbit
    ({"moment": [1.0, 0, 0], "field": {"model": "uniform"}}, "field.vector"),
    ({"moment": [1.0, 0, 0], "field": {"model": "uniform", "vector": [0, 0, 3e-5]},
      "orbit": {"a": 7e6}}, "orbit"),                                          # not used
    ({"moment": [1.0, 0, 0], "dipole": 1.0}, "dipole"),                        # unknown key
])
def test_bad_tables_name_the_key(table, key):
    with pytest.raises(TorqueConfigError) as err:
        from_config({"type": "magnetic_dipole", **table}, base_epoch=EPOCH)
    assert str(err.value).startswith(f"{key}:"), str(err.value)


@pytest.mark.parametrize(("text", "key"), [
    (UNIFORM_TABLE.replace("[0.5, 0.0, 0.0]", "[0.5, 0.0]"), "moment"),
    (UNIFORM_TABLE.replace('field = { model = "uniform", vector = { value = [0, 30000, 0], '
                           'unit = "nT" } }', 'field = "igrf"'), "orbit"),
])
def test_bad_scenario_exits_2_naming_the_key(tmp_path, text, key):
    path = write(tmp_path, GOOD + text)
    proc = subprocess.run([sys.executable, "-m", "attitude", "run", str(path)],
                          capture_output=True, text=True, cwd=ROOT,
                          env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert proc.returncode == 2, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in proc.stderr, proc.stderr
    assert key in lines[0] and str(path) in lines[0], lines[0]

"""The chaotic regime of a binary: the finite-time Lyapunov exponent (attitude.binary.chaos).

Independent facts: a locked secondary in a small libration on a circular orbit is regular
(its tangent vectors grow only linearly: the exponent is the Keplerian control's, within
the error, and the e-folds gained when the run doubles are those of linear growth, about
ln 2); an elongated secondary on an eccentric orbit started at the 1:1 separatrix (long
axis across the line of centres) is chaotic (Wisdom, Peale & Mignard 1984, Hyperion: e =
0.1, omega_0 / n = 0.89; here e = 0.2, omega_0 / n = 0.98), with an exponent a fraction of
the mean motion, independent of the initial separation.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import attitude as att
from attitude.binary.chaos import kepler_control, lyapunov_exponent
from attitude.foundations.errors import BinarySystemError
from attitude.model.regimes import Thresholds

ELLIPSOID = att.MassProperties.solid_ellipsoid


def _system(axes=(140.0, 100.0, 90.0)):
    return att.BinarySystem(
        att.RigidBody.from_mass_properties(att.MassProperties.solid_sphere(5.2e11, 400.0)),
        att.RigidBody.from_mass_properties(ELLIPSOID(4.3e9, list(axes))))


def _at_periapsis(system, e, angle_deg, rp=1190.0):
    """A state at periapsis, the secondary turning at the orbit's rate there, its long
    axis ``angle_deg`` from the line of centres; returns (state, mean motion)."""
    a = rp / (1 - e)
    n = math.sqrt(system.mu / a**3)
    vp = math.sqrt(system.mu * (1 + e) / rp)
    state = att.BinaryState("2026-12-01", [rp, 0, 0], [0, vp, 0], Rotation.identity(),
                            [0, 0, 0], Rotation.from_euler("z", angle_deg, degrees=True),
                            [0, 0, vp / rp])
    return state, n


def _run(system, state, n, orbits, separation=1e-8, intervals=40):
    P = 2 * math.pi / n
    times = np.linspace(0.0, orbits * P, 4 * intervals + 1)
    return lyapunov_exponent(system, state, times, intervals=intervals, step=P / 40,
                             separation=separation)


def test_regular_librating_secondary():
    system = _system()
    state, n = _at_periapsis(system, 0.0, 5.0)
    short, long = _run(system, state, n, 5), _run(system, state, n, 10)
    for r in (short, long):
        assert not r.chaotic
        combined = math.hypot(r.uncertainty, r.control_uncertainty)
        assert abs(r.exponent - r.control_exponent) < 3 * combined
    # regular: the e-folds of a doubled run grow like ln(2) (linear growth), not double
    gained = long.exponent * long.duration - short.exponent * short.duration
    assert gained < math.log(2) + 1.0
    assert long.exponent < 0.75 * short.exponent          # ln(T)/T: falls with T


def test_chaotic_secondary_near_the_separatrix():
    system = _system()
    state, n = _at_periapsis(system, 0.2, 90.0)
    one, two = _run(system, state, n, 20), _run(system, state, n, 20, separation=2e-8)
    for r in (one, two):
        assert r.chaotic
        assert r.excess_efolds >= Thresholds().lyapunov_efolds
        assert 0.05 < r.exponent / n < 1.0                 # a fraction of the mean motion
    assert abs(one.exponent - two.exponent) < 3 * math.hypot(one.uncertainty,
                                                             two.uncertainty)


def test_diagnose_with_chaos_calls_the_regime_chaotic():
    system = _system()
    state, n = _at_periapsis(system, 0.2, 90.0)
    P = 2 * math.pi / n
    eph = att.propagate(system, state, np.linspace(0.0, 20 * P, 161), step=P / 40)
    plain = att.binary.diagnose(eph)
    assert plain.secondary_regime != "chaotic" and math.isnan(plain.lyapunov_exponent)
    d = att.binary.diagnose(eph, chaos=True, intervals=40)
    assert d.secondary_regime == "chaotic"
    assert d.lyapunov.method == "lgvi" and d.lyapunov.duration == pytest.approx(20 * P)
    assert 0.05 < d.lyapunov_exponent / n < 1.0


def test_chaos_beyond_order_2_needs_the_system():
    system = att.BinarySystem(_system().primary, _system().secondary, order=3)
    state, n = _at_periapsis(system, 0.0, 0.0)
    eph = att.propagate(system, state, np.linspace(0.0, 3600.0, 5), step=600.0)
    with pytest.raises(BinarySystemError, match="system="):
        att.binary.diagnose(eph, chaos=True)
    d = att.binary.diagnose(eph, chaos=True, system=system, intervals=4)
    assert math.isfinite(d.lyapunov_exponent)


def test_control_keeps_the_masses():
    system = _system()
    control = kepler_control(system)
    assert np.array_equal(control.masses, system.masses)
    assert np.allclose(np.trace(control.secondary.inertia), np.trace(system.secondary.inertia),
                       rtol=1e-14)


@pytest.mark.parametrize("kwargs, match", [({"separation": 0.0}, "separation"),
                                           ({"intervals": 1}, "intervals"),
                                           ({"method": "rk4"}, "method")])
def test_bad_input(kwargs, match):
    system = _system()
    state, _ = _at_periapsis(system, 0.0, 0.0)
    with pytest.raises(BinarySystemError, match=match):
        lyapunov_exponent(system, state, 3600.0, **kwargs)


def test_scenario_expects_chaos(tmp_path):
    from attitude.binary.config import load_binary, run_binary
    system = _system()
    state, n = _at_periapsis(system, 0.2, 90.0)
    P = 2 * math.pi / n
    w = float(state.secondary_omega[2])
    (tmp_path / "hyperion.toml").write_text(f'''
[scenario]
name = "Hyperion-like"
[binary]
epoch = "2026-12-01T00:00:00"
duration = "{20 * P} s"
output_step = "{P / 8} s"
step = "{P / 40} s"
[binary.primary]
primitive = "sphere"
mass = 5.2e11
radius = 400.0
[binary.secondary]
primitive = "ellipsoid"
mass = 4.3e9
semi_axes = [140.0, 100.0, 90.0]
attitude = {{ euler = "z", angles = {{ value = [90.0], unit = "deg" }} }}
omega = [0.0, 0.0, {w}]
[binary.orbit]
semi_major_axis = "{1190.0 / 0.8} m"
eccentricity = 0.2
[expect]
secondary_regime = "chaotic"
lyapunov_exponent = {{ value = {0.5 * n}, abs_tol = {0.45 * n} }}
''')
    run = run_binary(load_binary(tmp_path / "hyperion.toml"), write_outputs=False)
    assert run.diagnosis.secondary_regime == "chaotic", run.expect
    assert run.ok, run.expect

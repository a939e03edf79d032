"""AttitudeState: constructors, units, derived quantities, validation."""

import numpy as np
import pytest
from astropy import units as u
from astropy.time import Time
from scipy.spatial.transform import Rotation

from attitude import AttitudeState, InvalidStateError, RigidBody

EPS = float(np.finfo(float).eps)

EPOCH = Time("2029-04-13T00:00:00", scale="tdb")


def test_rates_in_deg_per_s_rev_per_day_and_rpm():
    s = AttitudeState(EPOCH, Rotation.identity(), [0, 0, 360.0] * u.deg / u.s)
    np.testing.assert_allclose(s.omega_body, [0, 0, 2 * np.pi], rtol=1e-15)
    s = AttitudeState(EPOCH, Rotation.identity(), u.Quantity([0, 0, 1.0], "rev/day"))
    np.testing.assert_allclose(s.omega_body, [0, 0, 2 * np.pi / 86400], rtol=1e-15)
    s = AttitudeState(EPOCH, Rotation.identity(), u.Quantity([0, 0, 750.0], "rpm"))
    np.testing.assert_allclose(s.omega_body, [0, 0, 750 * 2 * np.pi / 60], rtol=1e-15)


def test_quaternion_orders_and_euler_angles_agree():
    q_last = np.array([0.1, -0.2, 0.3, 0.9])
    q_last /= np.linalg.norm(q_last)
    a = AttitudeState.from_quaternion(q_last, epoch=EPOCH, omega_body=[0, 0, 1])
    b = AttitudeState.from_quaternion(np.roll(q_last, 1), scalar_first=True, epoch=EPOCH,
                                      omega_body=[0, 0, 1])
    angles = a.attitude.as_euler("ZXZ", degrees=True)
    c = AttitudeState.from_euler("ZXZ", angles * u.deg, epoch=EPOCH, omega_body=[0, 0, 1])
    d = AttitudeState.from_euler("ZXZ", angles, degrees=True, epoch=EPOCH, omega_body=[0, 0, 1])
    for s in (b, c, d):
        assert (s.attitude * a.attitude.inv()).magnitude() < 1e-14


def test_derived_quantities_match_hand_calculation():
    body = RigidBody.from_principal_moments([1.0, 2.0, 3.0])
    R = Rotation.from_euler("z", 90, degrees=True)
    s = AttitudeState(EPOCH, R, [1.0, 1.0, 1.0])
    np.testing.assert_allclose(s.angular_momentum_body(body), [1, 2, 3])
    np.testing.assert_allclose(s.angular_momentum(body), [-2, 1, 3], atol=1e-15)
    assert s.kinetic_energy(body) == pytest.approx(3.0)
    assert s.dynamic_inertia(body) == pytest.approx(14 / 6)
    at_rest = AttitudeState(EPOCH, R, [0, 0, 0])
    assert np.isnan(at_rest.dynamic_inertia(body))


def test_string_epoch_is_tdb_and_frame_is_canonical():
    s = AttitudeState("2029-04-13T00:00:00", Rotation.identity(), [0, 0, 1], frame="eme2000")
    assert s.epoch.scale == "tdb" and s.frame == "EME2000"


@pytest.mark.parametrize("kwargs, match", [
    (dict(omega_body=[np.nan, 0, 1]), r"omega_body = \[nan, 0.0, 1.0\] rad/s: every component"),
    (dict(omega_body=[0, 1]), "expected 3 components"),
    (dict(omega_body=[0, 0, 1] * u.m), "cannot be converted"),
    (dict(frame="ICFR"), "did you mean 'ICRF'"),
    (dict(frame="MARS_FIXED"), "not a known inertial frame"),
    (dict(epoch="yesterday"), "cannot parse 'yesterday'"),
    (dict(epoch=Time(["2029-01-01", "2029-01-02"])), "expected a single time"),
    (dict(attitude=np.array([0, 0, 0, 1.0])), "expected a single scipy Rotation"),
])
def test_invalid_states_are_refused(kwargs, match):
    args = dict(epoch=EPOCH, attitude=Rotation.identity(), omega_body=[0, 0, 1], frame="ICRF")
    args.update(kwargs)
    with pytest.raises(InvalidStateError, match=match):
        AttitudeState(**args)


def test_non_unit_quaternion_is_refused():
    with pytest.raises(InvalidStateError, match="norm 2, not 1"):
        AttitudeState.from_quaternion([0, 0, 0, 2.0], epoch=EPOCH, omega_body=[0, 0, 1])
    with pytest.raises(ValueError):  # InvalidStateError is also a ValueError
        AttitudeState.from_euler("ZQZ", [1, 2, 3], epoch=EPOCH, omega_body=[0, 0, 1])


def test_from_spin_axis_points_the_axis_and_matches_the_scenario_and_sampling_paths():
    """One spin-axis construction (attitude.state.spin_axis_quaternion) behind
    AttitudeState.from_spin_axis, scenario.spin_axis_state and the "spin" sampling
    model: the axis points to (ra, dec), the rate is about it, all three agree to a few
    ulps of the unit vectors (8 eps) and of the rate (1e-3 * eps)."""
    from attitude.app.scenario import spin_axis_state
    from attitude.model.sampling import spin_state

    body = RigidBody.from_principal_moments([1.0, 2.0, 3.0])
    ra, dec, rate = np.radians(250.0), np.radians(-75.0), 1e-3
    n = np.array([np.cos(dec) * np.cos(ra), np.cos(dec) * np.sin(ra), np.sin(dec)])
    for about, k in (("A", 0), ("B", 1), ("C", 2)):
        s = AttitudeState.from_spin_axis(body, ra * u.rad, dec * u.rad, rate,
                                         epoch="2030-01-01", about=about)
        axis = body.principal_axes[:, k]
        np.testing.assert_allclose(s.attitude.apply(axis), n, atol=8 * EPS)
        np.testing.assert_allclose(s.omega_body, rate * axis, atol=1e-19)
        rot, w = spin_axis_state(body, ra, dec, rate, about)
        assert (rot.inv() * s.attitude).magnitude() < 8 * EPS
        np.testing.assert_allclose(w, s.omega_body, atol=1e-19)
    _, q, w, bad = spin_state(ra, dec, rate, 1 / 3, 2 / 3, moment_c=3.0)
    s = AttitudeState.from_spin_axis(body, ra, dec, rate, epoch="2030-01-01")
    assert not bad
    assert (Rotation.from_quat(q[0]).inv() * s.attitude).magnitude() < 8 * EPS
    np.testing.assert_allclose(w[0], s.omega_body, atol=1e-19)

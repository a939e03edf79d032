"""``att.propagate``: the exact solution against the independent reference integrator,
through arbitrary body frames; batches against single runs; time inputs."""

import numpy as np
import pytest
from astropy import units as u
from astropy.time import Time
from scipy.spatial.transform import Rotation

import attitude as att

from ..tolerances import EXACT_SOLUTION, assert_agree

EPOCH = Time("2030-01-01T00:00:00", scale="tdb")


def rotated_body(moments, euler_deg):
    R = Rotation.from_euler("xyz", euler_deg, degrees=True).as_matrix()
    return att.RigidBody(R @ np.diag(moments) @ R.T)


@pytest.mark.parametrize("moments, omega", [
    ([1.0, 2.0, 2.5], [0.3, -0.2, 0.4]),       # triaxial, generic
    ([1.0, 1.0, 2.0], [0.3, 0.1, 0.5]),        # oblate, regular precession
    ([0.5, 2.0, 2.0], [0.4, 0.2, -0.1]),       # prolate
    ([3.0, 3.0, 3.0], [0.2, -0.1, 0.3]),       # spherical
    ([1.0, 2.0, 3.0], [0.0, 0.0, 0.0]),        # at rest
])
def test_exact_matches_reference_integrator_in_a_rotated_body_frame(moments, omega):
    """Two independent routes: closed form in the principal frame mapped back to the
    body frame, versus DOP853 on Euler's equations in the body frame itself."""
    body = rotated_body(moments, [20, -35, 50])
    state = att.AttitudeState(EPOCH, Rotation.from_euler("ZXZ", [10, 30, -20], degrees=True),
                              omega)
    t = np.linspace(-100.0, 300.0, 41)
    exact = att.propagate(body, state, t)
    ref = att.propagate(body, state, t, method="integrator")
    scale = max(np.linalg.norm(omega), 1e-300)
    np.testing.assert_allclose(exact.dataset.angular_velocity, ref.dataset.angular_velocity,
                               rtol=0, atol=1e-11 * scale)
    assert np.max((exact.rotation * ref.rotation.inv()).magnitude()) < 1e-10
    assert exact.conservation()["angular_momentum_rel_drift"] < 1e-14
    assert exact.conservation()["energy_rel_drift"] < 1e-14


def test_batch_equals_single_runs():
    rng = np.random.default_rng(7)
    bodies, states = [], []
    for _ in range(6):
        m = np.sort(rng.uniform(1.0, 2.0, 3))
        bodies.append(rotated_body(m, rng.uniform(-180, 180, 3)))
        states.append(att.AttitudeState(EPOCH, Rotation.random(random_state=rng),
                                        rng.normal(size=3)))
    t = np.linspace(0.0, 50.0, 11)
    batch = att.propagate(bodies, states, t)
    assert batch.dataset.quaternion.shape == (6, 11, 4)
    for i, (b, s) in enumerate(zip(bodies, states)):
        single = att.propagate(b, s, t)
        # two paths of the exact solution: a few ulps of |q| = 1 and of |omega|, not bits
        # (they differed by 1.36e-15 under another OpenBLAS kernel, issue 14)
        assert_agree(batch.dataset.quaternion.values[i], single.dataset.quaternion.values,
                     ulps=EXACT_SOLUTION, magnitude=1.0, what=f"quaternion of body {i}")
        w = single.dataset.angular_velocity.values
        assert_agree(batch.dataset.angular_velocity.values[i], w, ulps=EXACT_SOLUTION,
                     magnitude=np.linalg.norm(w, axis=-1, keepdims=True),
                     what=f"angular velocity of body {i}")


def test_time_inputs_seconds_quantity_and_time_array_agree():
    body = att.RigidBody.from_principal_moments([1.0, 2.0, 3.0])
    state = att.AttitudeState(EPOCH, Rotation.identity(), [0.01, 0.02, 0.03])
    a = att.propagate(body, state, [0.0, 3600.0, 7200.0])
    b = att.propagate(body, state, [0.0, 1.0, 2.0] * u.h)
    # a Time array in another scale is converted to the epoch's scale (TDB)
    c = att.propagate(body, state, (EPOCH + [0.0, 1.0, 2.0] * u.h).tt)
    for other in (b, c):
        np.testing.assert_allclose(other.time, a.time, rtol=0, atol=1e-9)
        np.testing.assert_allclose(other.dataset.quaternion, a.dataset.quaternion, atol=1e-12)


@pytest.mark.parametrize("kwargs, match", [
    (dict(times=[0.0, np.nan]), "every time must be finite"),
    (dict(times=[[0.0, 1.0]]), "1-D array"),
    (dict(times=[1.0] * u.m), "not a time unit"),
    (dict(method="rk4"), "method 'rk4' is unknown"),
    (dict(method="exact", torques=[lambda t, q, w, b: np.zeros(3)]), "torque-free"),
])
def test_bad_propagation_arguments(kwargs, match):
    body = att.RigidBody.from_principal_moments([1.0, 2.0, 3.0])
    state = att.AttitudeState(EPOCH, Rotation.identity(), [0.0, 0.0, 1.0])
    args = dict(times=[0.0, 1.0])
    args.update(kwargs)
    with pytest.raises(att.InvalidStateError, match=match):
        att.propagate(body, state, **args)


def test_batch_needs_matching_lengths_and_one_epoch():
    body = att.RigidBody.from_principal_moments([1.0, 2.0, 3.0])
    s1 = att.AttitudeState(EPOCH, Rotation.identity(), [0.0, 0.0, 1.0])
    s2 = s1.replace(epoch=EPOCH + 1 * u.s)
    with pytest.raises(att.InvalidStateError, match="1 bodies and 2 states"):
        att.propagate([body], [s1, s2], [0.0])
    with pytest.raises(att.InvalidStateError, match=r"states\[1\].epoch differs"):
        att.propagate([body, body], [s1, s2], [0.0])

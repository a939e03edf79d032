"""A user's torque on the compiled DOP853 through a numba callback (issue 26): a torque
model with a ``numba_torque`` (an ``@numba.njit`` function ``(t, q, omega, out)``) runs
inside the compiled kernel (:func:`attitude.propagation.compiled_torques.user_torque`),
its Python ``__call__`` on scipy's path; the two agree within the integrator's tolerance
over two paths (tests/tolerances.py: ``INTEGRATOR_PATHS * rtol``)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import attitude as att
from attitude.model.orbit import KeplerOrbit
from attitude.model.torques import EARTH_MU, GravityGradient
from attitude.propagation import compiled_dop853
from attitude.propagation.compiled import NUMBA
from attitude.propagation.reference import integrate_reference

from ..tolerances import EPS, INTEGRATOR_PATHS, assert_agree, attitude_angle

pytestmark = pytest.mark.skipif(not NUMBA, reason="the callback is compiled by numba")

K = 2e-4                                     # N m s: the damper's coefficient
RTOL = 1e-12
BODY = att.RigidBody.from_principal_moments([2.0, 3.0, 4.0])
Q0 = Rotation.from_euler("xyz", [0.3, 0.2, 0.1]).as_quat()
W0 = np.array([2e-3, -1e-3, 3e-3])
TIMES = np.linspace(0.0, 3000.0, 31)


def _damper_kernel(t, q, omega, out):
    out[0] = -K * omega[0]
    out[1] = -K * omega[1]
    out[2] = -K * omega[2]


def _pulse_kernel(t, q, omega, out):
    out[0] = 0.0
    out[1] = 0.0
    out[2] = 1e-5 * np.sin(2.0 * np.pi * t / 200.0)


class Damper:
    """``-k omega``, external (a viscous drag on the body)."""

    def __init__(self, numba_kernel=True):
        if numba_kernel:
            import numba  # optional: the test is skipped without it

            self.numba_torque = numba.njit(_damper_kernel)

    def __call__(self, t, quaternion, omega_body, body):
        return -K * np.asarray(omega_body, dtype=float)


class Pulse:
    """A body-fixed torque oscillating with a period of 200 s (smooth: an adaptive
    integrator's error at a switch is not bounded by its tolerance)."""

    def __init__(self):
        import numba  # optional: the test is skipped without it

        self.numba_torque = numba.njit(_pulse_kernel)

    def __call__(self, t, quaternion, omega_body, body):
        return np.array([0.0, 0.0, 1e-5 * np.sin(2.0 * np.pi * t / 200.0)])


def _agree(a, b):
    (q1, w1), (q2, w2) = a, b
    assert_agree(attitude_angle(q1, q2), 0.0 * TIMES, ulps=INTEGRATOR_PATHS * RTOL / EPS,
                 magnitude=1.0, what="attitude angle")
    assert_agree(w1, w2, ulps=INTEGRATOR_PATHS * RTOL / EPS, magnitude=np.max(np.abs(w2)),
                 what="rate")


def test_callback_with_a_built_in_torque_equals_scipys_python_path():
    orbit = KeplerOrbit.from_elements(mu=EARTH_MU, a="7000 km", e=0.01, i="51.6 deg")
    torques = [GravityGradient(orbit=orbit), Damper()]
    compiled = integrate_reference(BODY, Q0, W0, TIMES, torques=torques, rtol=RTOL,
                                   compiled=True)
    scipy = integrate_reference(BODY, Q0, W0, TIMES, torques=torques, rtol=RTOL,
                                compiled=False)
    _agree(compiled, scipy)


def test_principal_spin_decays_as_the_exact_exponential():
    """A spin about C under ``-k omega`` stays about C and decays as
    ``exp(-k t / C)``: DOP853's global error, ``INTEGRATOR_PATHS rtol`` relative."""
    w0 = np.array([0.0, 0.0, 1e-2])
    _, w = integrate_reference(BODY, [0, 0, 0, 1.0], w0, TIMES, torques=[Damper()],
                               rtol=RTOL, compiled=True)
    exact = w0[2] * np.exp(-K * TIMES / 4.0)
    assert_agree(w[:, 2], exact, ulps=INTEGRATOR_PATHS * RTOL / EPS, magnitude=w0[2],
                 what="spin about C")
    assert np.all(w[:, :2] == 0.0)


def test_one_kernel_serves_every_user_function():
    """The callback goes by its address: a second user function compiles no new kernel."""
    integrate_reference(BODY, Q0, W0, TIMES[:3], torques=[Damper()], compiled=True)
    before = len(compiled_dop853.dop853_block.signatures)
    pulsed = integrate_reference(BODY, Q0, W0, TIMES, torques=[Pulse()], rtol=RTOL,
                                 compiled=True)
    assert len(compiled_dop853.dop853_block.signatures) == before
    _agree(pulsed, integrate_reference(BODY, Q0, W0, TIMES, torques=[Pulse()], rtol=RTOL,
                                       compiled=False))


def test_without_a_numba_torque_the_python_path_runs():
    plain = Damper(numba_kernel=False)
    with pytest.raises(att.InvalidStateError, match="numba_torque"):
        integrate_reference(BODY, Q0, W0, TIMES, torques=[plain], compiled=True)
    # two user callbacks: scipy's path with their Python calls
    both = integrate_reference(BODY, Q0, W0, TIMES, torques=[Damper(), Pulse()], rtol=RTOL)
    python = integrate_reference(BODY, Q0, W0, TIMES, torques=[Damper(False), Pulse()],
                                 rtol=RTOL, compiled=False)
    _agree(both, python)


def test_propagate_runs_the_callback():
    state = att.AttitudeState("2030-01-01", Rotation.from_quat(Q0), W0)
    eph = att.propagate(BODY, state, TIMES, torques=[Damper()], method="integrator",
                        rtol=RTOL)
    _agree((eph.dataset.quaternion.values, eph.dataset.angular_velocity.values),
           integrate_reference(BODY, Q0, W0, TIMES, torques=[Damper()], rtol=RTOL,
                               compiled=False))


def test_the_automatic_method_runs_the_callback_on_dop853():
    """With nothing given, a model with a ``numba_torque`` (beside a built-in one) runs on
    the compiled DOP853, the one compiled path that can call it, at the automatic rtol."""
    state = att.AttitudeState("2030-01-01", Rotation.from_quat(Q0), W0)
    eph = att.propagate(BODY, state, TIMES, torques=[Damper()])
    attrs = eph.dataset.attrs
    assert attrs["method"] == "integrator" and "numba_torque" in attrs["method_reason"]
    reference = integrate_reference(BODY, Q0, W0, TIMES, torques=[Damper()], rtol=RTOL,
                                    compiled=False)
    # the automatic accuracy is ~1e-8 rad over the run (choice.AUTO_ACCURACY): 100 times
    # that bounds the error model's spread
    assert attitude_angle(eph.dataset.quaternion.values, reference[0]).max() < 1e-6

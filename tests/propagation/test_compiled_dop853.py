"""The compiled DOP853 (:mod:`attitude.propagation.compiled_dop853`) against scipy's
``solve_ivp`` and against the exact torque-free solution (issue 18).

Both run the same method with the same step control on the same right-hand side; they
differ by rounding only, which can flip one step's acceptance, after which the two runs
follow different step sequences and differ by the integrator's tolerance
(tests/tolerances.py: ``INTEGRATOR_PATHS * rtol``).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import attitude as att
from attitude.foundations.errors import InvalidStateError
from attitude.model.orbit import KeplerOrbit
from attitude.model.torques import (
    ConstantTorque,
    EddyCurrentDamping,
    EnergyDissipation,
    FunctionTorque,
    GravityGradient,
    TiltedDipoleField,
)
from attitude.propagation import compiled
from attitude.propagation.reference import integrate_reference, integrate_reference_batch
from attitude.propagation.torquefree import free_rotation

from ..tolerances import EPS, INTEGRATOR_PATHS, assert_agree, attitude_angle

MU = 3.986004418e14
INERTIA = np.array([[120.0, 8.0, -5.0], [8.0, 150.0, 12.0], [-5.0, 12.0, 90.0]])
ORBIT = KeplerOrbit.from_elements(mu=MU, a="7000 km", e=0.01, i="51.6 deg")
Q0 = Rotation.from_euler("xyz", [0.3, 0.2, 0.1]).as_quat()
W0 = np.array([5e-4, -1e-3, 1.1e-3])
# outputs inside steps (dense output), backward ones, t = 0, a repeated time, in no order
TIMES = np.concatenate([np.arange(0.0, 3000.0, 37.0), [-45.0, -170.0, 1234.5, 74.0]])
RTOL = 1e-10


def _cases():
    gg = GravityGradient(orbit=ORBIT)
    return {
        "gravity gradient": [gg],
        "gravity gradient + eddy currents": [gg, EddyCurrentDamping(5.0e3,
                                                                    TiltedDipoleField(ORBIT))],
        "constant inertial torque": [ConstantTorque([0.0, 1e-5, 2e-5], frame="inertial")],
        "internal dissipation": [EnergyDissipation(900.0)],
    }


CASES = _cases()


@pytest.mark.parametrize("case", CASES)
def test_compiled_dop853_equals_scipy(case):
    """Same method, steps and dense output as scipy's: agreement within the tolerance."""
    body = att.RigidBody(INERTIA)
    kw = {"torques": CASES[case], "rtol": RTOL}
    q1, w1 = integrate_reference(body, Q0, W0, TIMES, compiled=True, **kw)
    q2, w2 = integrate_reference(body, Q0, W0, TIMES, compiled=False, **kw)
    assert_agree(attitude_angle(q1, q2), 0.0 * TIMES, ulps=INTEGRATOR_PATHS * RTOL / EPS,
                 magnitude=1.0, what="attitude angle")
    assert_agree(w1, w2, ulps=INTEGRATOR_PATHS * RTOL / EPS, magnitude=np.max(np.abs(w2)),
                 what="rate")
    zero = TIMES == 0.0
    assert_agree(q1[zero], Q0[None], ulps=2, magnitude=1.0, what="t = 0")  # y0, normalised


def test_internal_torque_keeps_the_inertial_momentum():
    """Dissipation turns L in the body frame only: the inertial L stays put to the
    tolerance, while the energy decays."""
    body = att.RigidBody(INERTIA)
    t = np.linspace(0.0, 4000.0, 9)
    q, w = integrate_reference(body, Q0, W0, t, torques=[EnergyDissipation(900.0)],
                               rtol=RTOL, compiled=True)
    L = Rotation.from_quat(q).apply(w @ INERTIA.T)
    assert_agree(L, np.tile(L[0], (t.size, 1)), ulps=INTEGRATOR_PATHS * RTOL / EPS,
                 magnitude=np.linalg.norm(L[0]), what="inertial L")
    energy = np.einsum("ti,ij,tj->t", w, INERTIA, w)
    assert energy[-1] < 0.99 * energy[0]


def test_torque_free_run_matches_the_exact_solution():
    """With no torque the compiled integrator's error against the closed form is the
    method's own: that of scipy's DOP853 on the same problem, up to rounding."""
    moments = np.array([90.0, 120.0, 150.0])
    body = att.RigidBody(np.diag(moments))
    w0 = np.array([0.02, 0.001, 0.018])                        # tumbling, near separatrix
    t = np.linspace(-400.0, 2000.0, 97)
    q_exact, w_exact = free_rotation(moments, Q0, w0, t)
    errors = []
    for flag in (True, False):
        q, w = integrate_reference(body, Q0, w0, t, rtol=1e-12, compiled=flag)
        errors.append(attitude_angle(q, q_exact).max())
    assert errors[1] > 0.0
    assert errors[0] <= 2.0 * errors[1] + INTEGRATOR_PATHS * 1e-12


def test_batch_runs_each_body_as_alone():
    """On threads or not, a batch gives each body the bits of its own run."""
    bodies = [att.RigidBody(INERTIA), att.RigidBody(np.diag([100.0, 130.0, 160.0]))]
    q0 = np.stack([Q0, Rotation.from_euler("z", 1.0).as_quat()])
    w0 = np.stack([W0, 2.0 * W0])
    gg = [GravityGradient(orbit=ORBIT)]
    qb, wb = integrate_reference_batch(bodies, q0, w0, TIMES, torques=gg, rtol=RTOL,
                                       compiled=True)
    for i, b in enumerate(bodies):
        q, w = integrate_reference(b, q0[i], w0[i], TIMES, torques=gg, rtol=RTOL,
                                   compiled=True)
        np.testing.assert_array_equal(qb[i], q)
        np.testing.assert_array_equal(wb[i], w)


def test_python_torques_take_scipys_path():
    """A torque written in Python has no compiled form: ``compiled=None`` runs scipy,
    ``compiled=True`` says why it cannot."""
    body = att.RigidBody(INERTIA)
    mine = FunctionTorque(lambda t, q, w, b: np.array([0.0, 0.0, 1e-6]))
    t = np.array([0.0, 100.0])
    q1, w1 = integrate_reference(body, Q0, W0, t, torques=[mine], rtol=RTOL)
    q2, w2 = integrate_reference(body, Q0, W0, t, torques=[mine], rtol=RTOL,
                                 compiled=False)
    np.testing.assert_array_equal(q1, q2)
    with pytest.raises(InvalidStateError, match="compiled form"):
        integrate_reference(body, Q0, W0, t, torques=[mine], compiled=True)
    with pytest.raises(InvalidStateError, match="only DOP853"):
        integrate_reference(body, Q0, W0, t, method="RK45", compiled=True)


def test_propagate_integrator_uses_it():
    """``propagate(..., method="integrator")`` runs the compiled integrator when numba is
    there; the ephemeris is the one integrate_reference gives."""
    body = att.RigidBody(INERTIA)
    state = att.AttitudeState("2024-01-01", Rotation.from_quat(Q0), W0)
    gg = [GravityGradient(orbit=ORBIT)]
    eph = att.propagate(body, state, TIMES, torques=gg, method="integrator", rtol=RTOL)
    q, _ = integrate_reference(body, Q0, W0, TIMES, torques=gg, rtol=RTOL,
                               compiled=compiled.NUMBA)
    assert_agree(attitude_angle(eph.dataset.quaternion.values, q), 0.0 * TIMES,
                 ulps=8, magnitude=1.0, what="attitude angle")


@pytest.mark.parametrize("rtol", [0.0, -1e-3, float("nan"), 1.0, "1e-8"])
def test_bad_rtol_is_refused(rtol):
    """rtol outside (0, 1) is an error naming the key, on both paths (the compiled loop
    would otherwise creep at atol-sized steps or never accept one)."""
    body = att.RigidBody(INERTIA)
    for flag in (True, False):
        with pytest.raises(InvalidStateError, match="rtol"):
            integrate_reference(body, Q0, W0, [0.0, 10.0], rtol=rtol, compiled=flag)


def test_tiny_rtol_is_raised_to_100_eps_as_scipy_does():
    """Below 100 eps scipy raises rtol to 100 eps; the compiled path does the same, so
    the two stay within the tolerance of each other."""
    body = att.RigidBody(INERTIA)
    t = np.linspace(0.0, 200.0, 5)
    q1, _ = integrate_reference(body, Q0, W0, t, rtol=1e-17, compiled=True)
    q2, _ = integrate_reference(body, Q0, W0, t, rtol=1e-17, compiled=False)
    assert_agree(attitude_angle(q1, q2), 0.0 * t, ulps=INTEGRATOR_PATHS * 100.0,
                 magnitude=1.0, what="attitude angle")

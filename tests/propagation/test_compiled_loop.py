"""The compiled one-body loop against the numpy path, and the loop's features: outputs
inside steps, the ``rtol`` error control (issue 18).

The compiled loop (:mod:`attitude.propagation.compiled_loop`, numba when installed)
and the numpy path compute the same composition with the same steps; they differ only
by rounding: at most :data:`tolerances.SPLITTING_STEP` ulp per step, adding over the
steps of the run (``n * SPLITTING_STEP`` ulp of the magnitude, see tests/tolerances.py).
"""

from __future__ import annotations

import math
import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import attitude as att
from attitude.foundations.quaternion import canonical
from attitude.model.orbit import KeplerOrbit
from attitude.model.torques import (
    ConstantTorque,
    EddyCurrentDamping,
    EnergyDissipation,
    GravityGradient,
    TiltedDipoleField,
)
from attitude.propagation import compiled_loop
from attitude.propagation.reference import integrate_reference
from attitude.propagation.splitting import choose_step, integrate_splitting

from ..tolerances import SPLITTING_STEP, assert_agree, attitude_angle

MU = 3.986004418e14
INERTIA = np.array([[120.0, 4.0, -3.0], [4.0, 95.0, 6.0], [-3.0, 6.0, 70.0]])  # full tensor
ORBIT = KeplerOrbit.from_elements(mu=MU, a="7000 km", e=0.01, i="51.6 deg")
Q0 = Rotation.from_euler("xyz", [0.3, 0.2, 0.1]).as_quat()
W0 = np.array([5e-4, -1e-3, 1.1e-3])


def _cases():
    gg = GravityGradient(orbit=ORBIT)
    field = TiltedDipoleField(ORBIT)
    ec = EddyCurrentDamping(5.0e3, field)
    return {
        "gravity gradient": [gg],
        "gravity gradient + eddy currents": [gg, ec],
        "constant inertial torque": [ConstantTorque([0.0, 1e-5, 2e-5], frame="inertial")],
        "dissipation": [EnergyDissipation(900.0)],
    }


CASES = _cases()
MODES = {
    "dense, default step": {},
    "dense, long step": {"step": 90.0},
    "cut at outputs": {"step": 60.0, "dense": False},
    "rtol": {"rtol": 1e-9},
}
TIMES = np.concatenate([np.arange(0.0, 2400.0, 30.0), [-45.0, -170.0]])


@pytest.mark.parametrize("mode", MODES)
@pytest.mark.parametrize("case", CASES)
def test_compiled_loop_equals_numpy_path(case, mode):
    """Same composition, same steps: the two paths agree to the rounding of the steps."""
    body = att.RigidBody(INERTIA)
    kw = MODES[mode]
    torques = CASES[case]
    q1, w1 = integrate_splitting(body, Q0, W0, TIMES, torques=torques, compiled=True, **kw)
    q2, w2 = integrate_splitting(body, Q0, W0, TIMES, torques=torques, compiled=False, **kw)
    h = kw.get("step") or choose_step(body, Q0, W0, torques)
    if "rtol" in kw:              # the controller's steps are longer than the rule's
        h = choose_step(body, Q0, W0, torques)
    n = math.ceil(np.max(np.abs(TIMES)) / h) + 2
    assert_agree(canonical(q1), canonical(q2), ulps=n * SPLITTING_STEP, magnitude=1.0,
                 what="quaternion")
    assert_agree(w1, w2, ulps=n * SPLITTING_STEP, magnitude=np.max(np.abs(w2)),
                 what="rate")


def test_outputs_do_not_change_the_trajectory():
    """An output inside a step is a partial step on the side: the states on the step grid
    are the same bits with or without outputs between them (same code, same inputs)."""
    body = att.RigidBody(INERTIA)
    gg = GravityGradient(orbit=ORBIT)
    grid = np.arange(0.0, 1801.0, 90.0)
    dense = np.union1d(grid, np.arange(0.0, 1801.0, 7.0))
    for compiled in (False, True):
        q1, w1 = integrate_splitting(body, Q0, W0, grid, torques=[gg], step=90.0,
                                     compiled=compiled)
        q2, w2 = integrate_splitting(body, Q0, W0, dense, torques=[gg], step=90.0,
                                     compiled=compiled)
        on_grid = np.isin(dense, grid)
        np.testing.assert_array_equal(q2[on_grid], q1)
        np.testing.assert_array_equal(w2[on_grid], w1)


def test_outputs_inside_steps_are_as_accurate_as_the_steps():
    """Against DOP853 at rtol 1e-13: an output inside a step carries the global error of
    the step before it plus the local error of one partial step (far smaller), so the
    worst error over all outputs stays within 1.5x the worst at the step ends."""
    body = att.RigidBody(INERTIA)
    gg = GravityGradient(orbit=ORBIT)
    h = 120.0
    t = np.arange(0.0, 17400.0 + 1.0, 30.0)
    q, _ = integrate_splitting(body, Q0, W0, t, torques=[gg], step=h)
    qr, _ = integrate_reference(body, Q0, W0, t, torques=[gg], rtol=1e-13)
    err = attitude_angle(q, qr)
    on_step = np.isclose(np.mod(t, h), 0.0)
    assert err[on_step].max() > 1e-7            # the step's truncation error shows
    assert err.max() <= 1.5 * err[on_step].max()


def test_rtol_controls_the_error():
    """rtol bounds each step's local error estimate, as DOP853's does: the error against
    DOP853 at 1e-13 falls with rtol and stays within a few rtol over three orbits (the
    estimate, from Yoshida's triple jump, is larger than the error of the propagated
    order-4 step)."""
    body = att.RigidBody(INERTIA)
    gg = GravityGradient(orbit=ORBIT)
    t = np.arange(0.0, 17400.0 + 1.0, 60.0)
    qr, _ = integrate_reference(body, Q0, W0, t, torques=[gg], rtol=1e-13)
    errors = []
    for rtol in (1e-5, 1e-7, 1e-9):
        q, _ = integrate_splitting(body, Q0, W0, t, torques=[gg], rtol=rtol)
        errors.append(attitude_angle(q, qr).max())
        assert errors[-1] <= 10.0 * rtol
    assert errors[0] > 10.0 * errors[1] > 100.0 * errors[2]


def test_rtol_through_propagate():
    body = att.RigidBody(INERTIA)
    state = att.AttitudeState("2030-01-01", Rotation.from_quat(Q0), W0)
    gg = GravityGradient(orbit=ORBIT)
    eph = att.propagate(body, state, [0.0, 600.0], torques=[gg], method="splitting",
                        rtol=1e-9)
    assert "method=splitting" in eph.dataset.attrs["source"]
    with pytest.raises(att.AttitudeError, match="rtol"):
        integrate_splitting(body, Q0, W0, [60.0], torques=[gg], rtol=2.0)


def test_a_python_torque_takes_the_numpy_path():
    body = att.RigidBody(INERTIA)
    gg = GravityGradient(orbit=ORBIT)

    def mine(t, q, w, b):
        return gg(t, q, w, b)

    with pytest.raises(att.AttitudeError, match="compiled"):
        integrate_splitting(body, Q0, W0, [60.0], torques=[mine], compiled=True)
    q1, _ = integrate_splitting(body, Q0, W0, [600.0], torques=[mine])
    q2, _ = integrate_splitting(body, Q0, W0, [600.0], torques=[mine], compiled=False)
    np.testing.assert_array_equal(q1, q2)


def test_without_numba_the_same_loop_runs_as_python():
    """ATTITUDE_NO_NUMBA=1: no numba; the default is the numpy path, and the scalar loop
    still runs as plain Python when asked (the same source as the compiled one)."""
    code = textwrap.dedent("""
        import numpy as np
        import attitude as att
        from attitude.propagation import compiled_loop
        from attitude.propagation.splitting import integrate_splitting
        from attitude.model.torques import GravityGradient
        assert not compiled_loop.NUMBA
        gg = GravityGradient(3.986004418e14, [7.0e6, 0.0, 0.0])
        args = ([1.0, 2.0, 3.0], [0, 0, 0, 1], [1e-3, 2e-3, 3e-3], [0.0, 95.0, 300.0])
        a = integrate_splitting(*args, torques=[gg], step=10.0, compiled=True)
        b = integrate_splitting(*args, torques=[gg], step=10.0, compiled=False)
        print(float(np.max(np.abs(a[0] - b[0]))), float(np.max(np.abs(a[1] - b[1]))))
    """)
    env = dict(os.environ, ATTITUDE_NO_NUMBA="1")
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                         text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    dq, dw = (float(x) for x in out.stdout.split())
    assert dq <= 32 * SPLITTING_STEP * np.finfo(float).eps
    assert dw <= 32 * SPLITTING_STEP * np.finfo(float).eps * 3e-3


def test_numba_flag_is_what_the_platform_offers():
    try:
        import numba  # noqa: F401  (optional: is it installed here?)
    except ImportError:
        assert not compiled_loop.NUMBA
    else:
        assert compiled_loop.NUMBA == (os.environ.get("ATTITUDE_NO_NUMBA") != "1")


@pytest.mark.skipif(not compiled_loop.NUMBA, reason="numba's cache only exists with numba")
def test_the_kernels_cache_is_keyed_by_all_three_sources(tmp_path):
    """numba checks only a function's own file: the package clears the cached code of
    its kernels when any of their sources changes (the loop inlines the others)."""
    import hashlib
    from pathlib import Path

    from attitude.propagation import compiled
    from attitude.propagation import jit as jit_module

    here = Path(compiled.__file__).parent
    stamp = here / "__pycache__" / "attitude-kernels.sha1"
    digest = hashlib.sha1(b"".join((here / n).read_bytes()
                                   for n in compiled.KERNEL_SOURCES)).hexdigest()
    if stamp.is_file():                  # absent only where the folder is read-only
        assert stamp.read_text() == digest
        stale = here / "__pycache__" / "compiled_loop.stale-test.nbi"
        stale.write_text("x")
        stamp.write_text("changed")
        jit_module._drop_stale_cache()
        assert not stale.exists() and stamp.read_text() == digest


def test_rtol_with_the_splitting_method_in_a_scenario(tmp_path):
    """[propagation] method = "splitting" with rtol: the run is the splitting's error-
    controlled one (the same numbers as att.propagate with those keywords)."""
    from attitude.app.scenario import load_scenario, run_scenario

    path = tmp_path / "gg.toml"
    path.write_text(textwrap.dedent("""
        [scenario]
        name = "gravity gradient, error-controlled splitting"
        [body]
        principal_moments = [70.0, 95.0, 120.0]
        [state]
        epoch = "2030-01-01T00:00:00"
        attitude = { quaternion_scalar_last = [0, 0, 0, 1] }
        omega_body = { value = [5e-4, -1e-3, 1.1e-3], unit = "rad/s" }
        [propagation]
        duration = "1 h"
        step = "5 min"
        method = "splitting"
        rtol = 1e-9
        [[torques]]
        type = "gravity_gradient"
        mu = "3.986004418e14 m3/s2"
        orbit = { a = "7000 km", e = 0.01, i = "51.6 deg" }
    """))
    scenario = load_scenario(path)
    result = run_scenario(scenario, write_outputs=False)
    eph = result.ephemeris
    assert "method=splitting" in eph.dataset.attrs["source"]
    again = att.propagate(scenario.body, scenario.state, eph.dataset.time.values,
                          torques=list(scenario.torques), method="splitting", rtol=1e-9)
    np.testing.assert_array_equal(eph.dataset.quaternion.values,
                                  again.dataset.quaternion.values)

"""The bodies of a batch share one block of path and field numbers in the compiled
torques (compile_torques_shared): the params grow by each body's own numbers only, and
a batch gives the same bits as its bodies run one by one."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import attitude as att
from attitude.model.orbit import KeplerOrbit, TabulatedPath
from attitude.model.torques import (
    EARTH_MU,
    GravityGradient,
    MagneticDipole,
    TiltedDipoleField,
)
from attitude.propagation.compiled import NUMBA
from attitude.propagation.compiled_torques import compile_torques, compile_torques_shared

ORBIT = KeplerOrbit(EARTH_MU, 7.0e6, 0.01)
#: Each body's own numbers, from the layout in compiled_torques' docstring: gravity
#: gradient (time shift, mu, inertia 9, the path's index) and a dipole (time shift,
#: moment 3, the field's index); the Kepler path and the tilted-dipole field are shared.
OWN = (1 + 1 + 9 + 1) + (1 + 3 + 1)


def _bodies(n):
    return [att.RigidBody.from_principal_moments([1.5 + 0.1 * k, 2.0, 3.0 + 0.1 * k])
            for k in range(n)]


def test_params_grow_by_each_bodys_own_numbers():
    torques = [GravityGradient(EARTH_MU, ORBIT),
               MagneticDipole([0.0, 0.0, 1.0], TiltedDipoleField(ORBIT))]
    one = compile_torques(torques, _bodies(1)[0])
    sizes = [compile_torques_shared([torques], _bodies(n))[0][0].params.size
             for n in (1, 2, 3)]
    assert sizes[0] == one.params.size
    assert sizes[1] - sizes[0] == OWN and sizes[2] - sizes[1] == OWN
    shared = compile_torques_shared([torques], _bodies(3))
    assert all(row[0].params is shared[0][0].params for row in shared)
    # each body evaluates its own torque from the shared block, as alone
    q, w = np.array([0.1, 0.2, 0.3, 0.9]) / np.linalg.norm([0.1, 0.2, 0.3, 0.9]), np.zeros(3)
    for body, row in zip(_bodies(3), shared):
        np.testing.assert_array_equal(row[0](100.0, q, w),
                                      compile_torques(torques, body)(100.0, q, w))


def test_a_tabulated_path_is_stored_once():
    t = np.linspace(0.0, 6000.0, 2001)
    path = TabulatedPath(t, np.stack([ORBIT.position(x) for x in t]))
    gg = GravityGradient(EARTH_MU, path)
    one = compile_torques([gg], _bodies(1)[0], t_span=(0.0, 6000.0))
    two = compile_torques_shared([[gg], []], _bodies(2), t_span=(0.0, 6000.0))
    table = one.params.size - 12                       # the spline's block
    assert table > 2000 * 12                            # the cubics of 2000 intervals
    assert two[0][0].params.size == table + 2 * 12     # once, and two gravity terms
    assert two[1][1].kinds.size == 0                   # an empty group: no term


@pytest.mark.skipif(not NUMBA, reason="the numpy path advances a batch together (same "
                                      "results to round-off, not bits)")
@pytest.mark.parametrize("method, options", [("splitting", {"step": 20.0}),
                                             ("integrator", {"rtol": 1e-10})])
def test_batch_equals_separate_runs(method, options):
    torques = [GravityGradient(EARTH_MU, ORBIT),
               MagneticDipole([0.0, 0.0, 1.0], TiltedDipoleField(ORBIT))]
    bodies = _bodies(3)
    rng = np.random.default_rng(5)
    states = [att.AttitudeState("2030-01-01", Rotation.random(random_state=rng),
                                rng.normal(size=3) * 0.01) for _ in bodies]
    t = np.linspace(0.0, 1200.0, 7)
    batch = att.propagate(bodies, states, t, torques=torques, method=method, **options)
    for i, (body, state) in enumerate(zip(bodies, states)):
        one = att.propagate(body, state, t, torques=torques, method=method, **options)
        np.testing.assert_array_equal(batch.dataset.quaternion.values[i],
                                      one.dataset.quaternion.values)
        np.testing.assert_array_equal(batch.dataset.angular_velocity.values[i],
                                      one.dataset.angular_velocity.values)

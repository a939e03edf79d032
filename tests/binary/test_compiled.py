"""The LGVI's compiled step loop (attitude.binary.compiled) against the numpy path of
attitude.binary.lgvi: the same map, so the two agree to round-off, at orders 2 and 4,
with an ellipsoid and a small non-convex polyhedron, an impulse included."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import attitude as att
from attitude.binary.dynamics import pack
from attitude.binary.lgvi import integrate_lgvi_batch, step_grid
from attitude.foundations.errors import PropagationError
from attitude.model.body import MassDistribution, RigidBody
from attitude.model.shape import Polyhedron
from attitude.propagation.jit import NUMBA
from tests.binary.test_integrals import l_prism
from tests.tolerances import EPS

pytestmark = pytest.mark.skipif(not NUMBA, reason="numba absent or ATTITUDE_NO_NUMBA=1: "
                                "the numpy path is the only one")

PRIMARY = att.RigidBody.from_mass_properties(
    att.MassProperties.solid_ellipsoid(1e9, [60.0, 50.0, 40.0]))


def secondary(kind: str) -> RigidBody:
    """An ellipsoid, or the L prism (non-convex, 30 m) of uniform density."""
    if kind == "ellipsoid":
        return att.RigidBody.from_mass_properties(
            att.MassProperties.solid_ellipsoid(2e7, [20.0, 12.0, 9.0]))
    prism = l_prism(1.5)
    shape = Polyhedron(10.0 * np.asarray(prism.vertices), prism.faces)
    mass, com, inertia = shape.mass_properties(2000.0)
    return RigidBody(inertia, mass=mass, center_of_mass=com,
                     distribution=MassDistribution("polyhedron", mass, shape=shape))


def family(order: int, kind: str):
    """Two members off every symmetry (inclined, eccentric, tilted, spins off the axes)
    and an impulse on the first (a velocity change and an angular impulse)."""
    systems = [att.BinarySystem(PRIMARY, secondary(kind), order=order),
               att.BinarySystem(secondary(kind), PRIMARY, order=order)]
    y0 = []
    for s, r in zip(systems, (200.0, 230.0)):
        n = np.sqrt(s.mu / r**3)
        y0.append(pack([r, 5.0, 0.0], [0.0, 1.05 * n * r, 0.02 * n * r],
                       Rotation.from_euler("xyz", [0.1, 0.2, 0.3]).as_quat(),
                       [1e-5, 0.0, 3 * n], Rotation.from_euler("xyz", [0.05, -0.1, 0.2]).as_quat(),
                       [0.0, 2e-5, 1.3 * n]))
    kick = att.Impulse(0.0, body="secondary", delta_v=[0.0, 1e-4, 2e-5],
                       angular_impulse=[1e3, -2e3, 5e3])
    return systems, np.array(y0), kick


#: The state vector's blocks: position, velocity, quaternion, spin (each body).
BLOCKS = (slice(0, 3), slice(3, 6), slice(6, 10), slice(10, 13), slice(13, 17),
          slice(17, 20))


@pytest.mark.parametrize("compensated", [True, False])
@pytest.mark.parametrize("kind", ["ellipsoid", "polyhedron"])
@pytest.mark.parametrize("order", [2, 4])
def test_compiled_loop_is_the_numpy_map_to_round_off(order, kind, compensated):
    """One orbit of 200 steps with an impulse at 0.3 of it: each block of the state
    vector agrees within steps x eps x its magnitude (a few ulps of round-off per step,
    from the two paths' different orders of summation, carried along)."""
    systems, y0, kick = family(order, kind)
    period = 2 * np.pi * np.sqrt(200.0**3 / systems[0].mu)
    t, h = np.linspace(0.0, period, 5), period / 200
    impulses = [[(0.3 * period, kick)], []]
    numpy_path = integrate_lgvi_batch(systems, y0, t, h, impulses, compiled=False,
                                      compensated=compensated)
    compiled = integrate_lgvi_batch(systems, y0, t, h, impulses, compiled=True,
                                    compensated=compensated)
    steps = step_grid(np.append(t, 0.3 * period), h).size - 1
    for block in BLOCKS:
        magnitude = np.abs(numpy_path[..., block]).max()
        np.testing.assert_array_less(np.abs(compiled[..., block] - numpy_path[..., block]),
                                     steps * EPS * magnitude)
    # the impulse acted: without it the first member ends elsewhere
    free = integrate_lgvi_batch(systems, y0, t, h, compiled=True)
    assert np.abs(free[0, -1, 3:6] - compiled[0, -1, 3:6]).max() > 1e-6


def test_compiled_loop_names_a_member_whose_rotation_fails():
    """A step far too long for the second member's spin: the compiled loop stops and
    says which member, as a PropagationError."""
    systems, y0, _ = family(2, "ellipsoid")
    y0 = y0.copy()
    y0[1, 10:13] = [0.0, 0.0, 5.0]           # 5 rad/s: a 60 s step turns it ~300 rad
    with pytest.raises(PropagationError, match="member 1"):
        integrate_lgvi_batch(systems, y0, [0.0, 600.0], 60.0, compiled=True)


@pytest.mark.parametrize("kind", ["ellipsoid", "polyhedron"])
@pytest.mark.parametrize("order", [2, 4])
def test_compiled_loads_are_mutual_gravity_forces(order, kind):
    """The compiled force and body-frame torques, walking mutual.py's tables, against
    MutualGravity.forces on rotated integrals at one configuration off every symmetry:
    each within 64 eps of the sum of its terms' magnitudes (bounded here by the
    largest of |R| |F| / |R| for the force, |R| |F| for the torques, which balance it)."""
    from attitude.binary import compiled
    from attitude.binary.integrals import rotated

    system = att.BinarySystem(PRIMARY, secondary(kind), order=order)
    R = np.array([150.0, -40.0, 25.0])
    A = np.stack([Rotation.from_euler("xyz", [0.3, -0.2, 0.9]).as_matrix(),
                  Rotation.from_euler("zyx", [1.1, 0.4, -0.6]).as_matrix()])
    f = system.gravity.forces(R, rotated(system.integrals[0], A[0]),
                              rotated(system.integrals[1], A[1]))
    tables = compiled.kernel_tables(order)
    size = tables[1][order + 2]
    scratch = tuple(np.zeros(size) for _ in range(5)) + (np.zeros(2 * 3**max(order, 2)),
                                                        np.zeros((2, 3)))
    force, M = np.zeros(3), np.zeros((2, 3))
    T1b, T2b = (np.concatenate(system.integrals[b].degrees[:order + 1]) for b in range(2))
    compiled._loads(R, A, T1b, T2b, float(system.G), tables, scratch, force, M)
    scale = np.linalg.norm(R) * np.linalg.norm(f.force)
    assert np.abs(force - f.force).max() <= 64 * EPS * np.linalg.norm(f.force)
    for b, tau in enumerate((f.torque_primary, f.torque_secondary)):
        assert np.abs(A[b] @ M[b] - tau).max() <= 64 * EPS * scale
    # the torques are not trivially zero: the bodies are far from spheres
    assert np.linalg.norm(f.torque_secondary) > 1e3 * 64 * EPS * scale

"""Whether a secondary stays locked, and for which shapes (docs/binary.md, "Does Dimorphos
tumble"): against the pendulum of the planar spin-orbit problem.

On a circular orbit about a point mass, a secondary spinning about its largest-moment
axis along the orbit normal has the libration angle phi (its long axis from the line of
centres) of the pendulum ``phi'' = -(omega_0^2 / 2) sin 2 phi``, ``omega_0 = n sqrt(3 (B -
A) / C)`` (exact in that limit, not an average).  Its energy ``phi'^2 / 2 + (omega_0^2 / 2)
sin^2 phi`` is conserved, so a secondary locked at phi = 0 and given the rate ``delta``
relative to the orbit librates with the amplitude ``arcsin(delta / omega_0)`` when
``delta < omega_0``, and circulates when ``delta > omega_0``.  The lock's strength grows
with the elongation: ``(B - A) / C = (a^2 - b^2) / (a^2 + b^2)`` for an ellipsoid, so one
kick leaves a near-spherical secondary circulating and an elongated one librating, and a
large enough kick unlocks any.

The kick here is an angular impulse ``C delta`` about the orbit normal: it leaves the
orbit as it was.  The departures from the pendulum are the secondary's size against the
separation (its octupole-free order-2 potential adds ``(size / r)^2``, 1e-3 at 3 km), and
the orbit's answer to the spin's change (its angular momentum is 1e3 times the spin's);
both change ``omega_0`` by about 1e-3, the amplitude by ``tan(phi) / phi`` times that.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import attitude as att
from attitude.binary.dynamics import mutual_forces

SEPARATION = 3000.0
ELLIPSOID = att.MassProperties.solid_ellipsoid


def locked_secondary(elongation: float, kick: float):
    """A Dimorphos-volume ellipsoid of long-to-intermediate ratio ``elongation`` (b/c
    1.47) locked on a circular orbit about a Didymos-mass sphere, given the spin rate
    ``kick`` (in units of its omega_0) about the orbit normal: ``(member, omega_0,
    n)``."""
    bc = 84.5 / 57.5
    c = (89.5 * 84.5 * 57.5 / (elongation * bc**2)) ** (1 / 3)
    secondary = att.RigidBody.from_mass_properties(
        ELLIPSOID(4.3e9, [elongation * bc * c, bc * c, c]))
    primary = att.RigidBody.from_mass_properties(
        att.MassProperties.solid_sphere(5.282e11, 390.0))
    system = att.BinarySystem(primary, secondary)
    r = SEPARATION
    force = mutual_forces(system, np.array([r, 0.0, 0.0]), np.eye(3), np.eye(3)).force
    n = np.sqrt(-float(force[0]) / (system.reduced_mass * r))       # circular in the force
    A, B, C = secondary.principal_moments
    omega_0 = n * np.sqrt(3 * (B - A) / C)
    state = att.BinaryState("2022-10-01", [r, 0.0, 0.0], [0.0, n * r, 0.0],
                            Rotation.identity(), [0.0, 0.0, 0.0], Rotation.identity(),
                            [0.0, 0.0, n])
    impulse = att.Impulse(0.0, body="secondary",
                          angular_impulse=[0.0, 0.0, C * kick * omega_0])
    return (system, state, [impulse], {"elongation": elongation, "kick": kick}), omega_0, n


@pytest.fixture(scope="module")
def outcomes():
    cases = [(1.3, 0.5), (1.3, 1.2), (1.05, 0.5 * 0.8765 / 0.3824)]
    members, omegas = [], []
    for elongation, kick in cases:
        member, omega_0, n = locked_secondary(elongation, kick)
        members.append(member)
        omegas.append(omega_0 / n)
    period = 2 * np.pi / n
    times = np.arange(0.0, 2.5 * period, period / 100)
    ds = att.binary.ensemble(members, times, method="integrator", rtol=1e-10)
    return ds, np.array(omegas)


def test_the_pendulum_amplitude_of_an_elongated_secondary(outcomes):
    """a/b = 1.3 (omega_0 = 0.88 n) kicked at half its omega_0: librating with the
    amplitude arcsin(1/2) = 30 deg; the departures above (1e-3 of omega_0) and the
    sampling of the peak (100 samples an orbit, a libration phase of at most
    0.88 * 2 pi / 100 between samples: its square over 2, 1.5e-3 of the angle) stay
    below 1 %."""
    ds, omegas = outcomes
    assert abs(omegas[0] - 0.8765) < 1e-3       # the shape's omega_0 / n
    assert ds.status.values[0] == 0
    assert ds.secondary_regime.values[0] == "librating"
    expected = np.arcsin(0.5)
    assert abs(ds.libration_amplitude.values[0] / expected - 1) < 0.01


def test_a_kick_beyond_omega_0_unlocks_it(outcomes):
    """The same shape kicked at 1.2 omega_0: over the separatrix, it circulates."""
    ds, _ = outcomes
    assert ds.secondary_regime.values[1] == "circulating"
    assert np.isnan(ds.libration_amplitude.values[1])


def test_the_same_kick_unlocks_a_near_spherical_secondary(outcomes):
    """a/b = 1.05 (omega_0 = 0.38 n) given the kick that left a/b = 1.3 librating at
    30 deg (0.44 n, now 1.15 of its omega_0): a rounder secondary is held more weakly,
    and this one leaves the lock."""
    ds, omegas = outcomes
    assert abs(omegas[2] - 0.3824) < 1e-3
    kick_rate = ds.kick.values[2] * omegas[2]
    assert abs(kick_rate - 0.5 * omegas[0]) < 1e-3
    assert kick_rate > omegas[2]                       # beyond its separatrix
    assert ds.secondary_regime.values[2] == "circulating"

"""The free libration after an impulse (attitude.binary.diagnostics.free_libration)
against the linear theory of the planar full two-body problem, the one
tests/binary/test_diagnostics.py checks for the unperturbed case.

A Dimorphos-like ellipsoid locked to a spherical primary at 2380 m is slowed along its
track by 0.2 % of its speed half an orbit in: the orbit turns eccentric (e ~ 0.004),
which forces a libration at the anomalistic frequency, and the kick sets the secondary
swinging at its own frequency.  The fit must find the free one; the zero crossings of the
angle (``libration_period``) mix both.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import attitude as att
from attitude.binary.diagnostics import free_libration
from attitude.binary.dynamics import mutual_forces

SPHERE = att.MassProperties.solid_sphere
ELLIPSOID = att.MassProperties.solid_ellipsoid
R0, KICK, ORBITS = 2380.0, 0.002, 12


def linear_libration(system, a):
    """The free libration frequency of the linearised planar problem at separation a
    (tests/binary/test_diagnostics.py, the docs): the root near w0^2 of
        w^2 (n^2 - w^2) = w0^2 [(n^2 - w^2) - eps (w^2 + 3 n^2)],
    w0^2 = 3 G M (B - A) / (C a^3), eps = C / (mu_r a^2), n^2 = G (M + m) / a^3; and
    eta, the relative size of the neglected order-2 terms of the secondary in the orbit,
    amplified near the 1:1 resonance."""
    A, B, C = system.secondary.principal_moments
    M, m = system.masses
    G = system.G
    w0sq = 3 * G * M * (B - A) / (C * a**3)
    eps = C / (system.reduced_mass * a**2)
    nk2 = G * (M + m) / a**3
    roots = np.roots([1.0, -(nk2 + w0sq * (1 + eps)), w0sq * nk2 * (1 - 3 * eps)]).real
    w = math.sqrt(roots[np.argmin(abs(roots - w0sq))])
    formula2 = nk2 * 3 * (B - A) / C
    eta = 3 * (B + C - 2 * A) / (2 * m * a**2) * nk2 / (nk2 - formula2)
    return w, eta


@pytest.fixture(scope="module")
def kicked():
    M, m = 5.2e11, 4.3e9
    system = att.BinarySystem(att.RigidBody.from_mass_properties(SPHERE(M, 390.0)),
                              att.RigidBody.from_mass_properties(
                                  ELLIPSOID(m, [103.16, 79.35, 66.13])))
    f = mutual_forces(system, [R0, 0.0, 0.0], np.eye(3), np.eye(3))
    v = math.sqrt(R0 * -f.force[0] / system.reduced_mass)   # circular in the mutual force
    n = v / R0
    period = 2 * math.pi / n
    state = att.BinaryState("2026-12-01", [R0, 0, 0], [0, v, 0], Rotation.identity(),
                            [0, 0, 0], Rotation.identity(), [0, 0, n])
    t_kick = 0.5 * period                                    # at -x, moving along -y
    kick = att.Impulse(t_kick, body="secondary", delta_v=[0, KICK * v, 0])
    times = np.arange(0.0, (ORBITS + 0.5) * period, period / 40)
    eph = att.propagate(system, state, times, events=[kick], rtol=1e-10)
    a = 1 / (2 / R0 - (v * (1 - KICK)) ** 2 / system.mu)      # vis-viva after the kick
    return system, eph, t_kick, a


def test_free_libration_after_a_kick_is_the_linear_theorys(kicked):
    """Bound: the theory's neglected orders, eta (as for the unperturbed case), the
    nonlinearity of the restoring torque (~ sin 2 phi: a free swing of amplitude A slows
    itself by A^2 / 4, and the forced swing F the free one by F^2 / 2, the mean of
    cos(2 F sin)), and the eccentricity's e^2 (the mean of (a / r)^3 is (1 - e^2)^-3/2)."""
    system, eph, t_kick, a = kicked
    fl = free_libration(eph, after=t_kick)
    w, eta = linear_libration(system, a)
    e = 1 - R0 / a if a > R0 else R0 / a - 1                   # the kick's point is an apse
    bound = eta + fl.amplitude**2 / 4 + fl.forced_amplitude**2 / 2 + 3 * e**2
    assert abs(2 * math.pi / fl.period / w - 1) <= bound
    assert fl.residual < 0.05 * fl.amplitude                  # two lines hold the motion
    # the forced line is the orbit's, the anomalistic period: n' within the same orders
    n_after = math.sqrt(system.mu / a**3)
    assert abs(2 * math.pi / fl.forced_period / n_after - 1) <= 2 * eta + 3 * e**2
    # diagnose reports the same after the impulse; its zero crossings mix both lines
    b = att.binary.diagnose(eph, impulses=[t_kick])
    assert b.free_libration_period == fl.period
    assert abs(b.libration_period / fl.period - 1) > bound


def test_no_free_libration_from_too_short_a_run(kicked):
    """Two orbits cannot tell the free line from the orbit's (2 pi / span > |w - n|)."""
    system, eph, t_kick, a = kicked
    two_orbits = eph.time < t_kick + 2 * (2 * t_kick)
    short = att.Ephemeris(eph.dataset.isel(time=np.nonzero(two_orbits)[0]))
    assert math.isnan(free_libration(short, after=t_kick).period)

"""The classical secular apsidal rate of an orbit in the equator of an oblate primary,
    d(varpi)/dt = 3/2 n J2 (R / p)^2,
(first order in J2; for a homogeneous spheroid of radii a, c: J2 R^2 = (a^2 - c^2) / 5)
against the rate att.binary.diagnose measures on a propagated sphere + oblate pair: the
formula docs/binary.md uses to ask what J2 of Didymos the observed rate implies.

Bound: the exact rate near a circular orbit is Omega - kappa (the angular and epicyclic
frequencies, tests/binary/test_diagnostics.py); expanded in x = 3/2 J2 (R / a)^2, the
formula (with n and p of the Keplerian elements at the start) differs from it by
3.5 x to first order (the guiding radius is p (1 - x), Omega - kappa = n_g x (1 + O(x^2)));
bound 4 x, plus 4 e^2 for the epicyclic rate's own next order in e.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.spatial.transform import Rotation

import attitude as att
from attitude.model.orbit import KeplerOrbit

ELLIPSOID = att.MassProperties.solid_ellipsoid
SPHERE = att.MassProperties.solid_sphere


def j2_apsidal_rate(mu, a, e, j2_r2):
    """3/2 n J2 R^2 / p^2, rad/s."""
    return 1.5 * math.sqrt(mu / a**3) * j2_r2 / (a * (1 - e * e)) ** 2


def test_apsidal_rate_about_an_oblate_primary_is_the_j2_rate():
    primary = att.RigidBody.from_mass_properties(ELLIPSOID(5.2e11, [394.0, 394.0, 290.0]))
    system = att.BinarySystem(primary, att.RigidBody.from_mass_properties(SPHERE(4.3e9, 80.0)))
    a, e = 2000.0, 0.05
    j2_r2 = (394.0**2 - 290.0**2) / 5
    orbit = KeplerOrbit(system.mu, a, e=e, mean_anomaly=2.0)
    state = att.BinaryState("2026-12-01", orbit.position(0.0), orbit.velocity(0.0),
                            Rotation.identity(), [0, 0, 0], Rotation.identity(), [0, 0, 0])
    eph = att.propagate(system, state, np.linspace(0.0, 3.2 * orbit.period, 300),
                        rtol=1e-10)
    measured = att.binary.diagnose(eph).apsidal_rate
    formula = j2_apsidal_rate(system.mu, a, e, j2_r2)
    x = 1.5 * j2_r2 / a**2
    assert abs(measured / formula - 1) <= 4 * x + 4 * e**2
    assert measured > formula               # the next order adds (3.5 x above)

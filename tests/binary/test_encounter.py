"""The close-encounter ensemble (attitude.binary.encounter) against independent references.

- The hyperbola against the bracketed root of the hyperbolic Kepler equation
  (tests/binary/test_flyby.py's ``Hyperbola``, scipy's brentq).
- Each drawn member's rotation state has the drawn Pravec parameters (E/E0 from the
  body-frame rates, the precession period), read back by ``att.diagnose``.
- A member at the nominal state gives what one ``att.propagate`` + ``att.diagnose`` of the
  same encounter gives.
- Each member keeps the total angular momentum to the integrator's bound, and its spin
  changes by at most the tidal-torque bound ``(3/2) G M (C - A) int dt / r^3``.
- In the weak-tide limit the change is linear in the tide: doubling the planet's mass at
  a fixed perigee and speed doubles each member's change (the tidal parameter
  ``G M / r_p^3`` doubles).
"""

from __future__ import annotations

import numpy as np
import pytest
from astropy import units as u
from scipy.spatial.transform import Rotation

import attitude as att
from attitude.binary.encounter import (
    APOPHIS,
    EARTH_MASS,
    EARTH_RADIUS,
    close_encounter,
    ellipsoid_from_ratios,
    encounter_ensemble,
    hyperbola,
    sample_encounter,
)
from tests.binary.test_flyby import Hyperbola
from tests.tolerances import EPS

SPAN = 12 * 3600.0
TIMES = np.array([0.0, 2 * SPAN])
RTOL = 1e-10


@pytest.fixture(scope="module")
def apophis_members():
    members = sample_encounter(2, rng=7)
    return members, encounter_ensemble(members, TIMES, rtol=RTOL)


def test_the_hyperbola_is_keplers():
    """Newton's method on ``e sinh H - H = n t`` against the bracketed root: both solve
    the same equation to a few ulp of H; the state's error is then a few ulp of its size
    times ``|dr/dH| / |r|`` (below 2 on this hyperbola): 64 ulp bound it."""
    gm = att.binary.G * EARTH_MASS
    reference = Hyperbola(gm, 38_000e3, 5.84e3)
    t = np.array([-3e5, -SPAN, -600.0, 0.0, 1.0, 7200.0, SPAN, 3e5])
    r, v = hyperbola(gm, 38_000e3 * u.m, 5.84 * u.km / u.s, t)
    for i, ti in enumerate(t):
        r_ref, v_ref = reference.state(ti)
        assert np.linalg.norm(r[i] - r_ref) <= 64 * EPS * np.linalg.norm(r_ref)
        assert np.linalg.norm(v[i] - v_ref) <= 64 * EPS * np.linalg.norm(v_ref)


def test_each_member_starts_in_its_drawn_state(apophis_members):
    """The drawn E/E0 and precession period are the rotation state's (att.diagnose of the
    body's state at the start, a different evaluation of the periods than the
    sampler's): E/E0 to a few ulp through the rates, the period to the free-body
    solution's 1e-12; the moment ratios are the ellipsoid's."""
    members, ds = apophis_members
    for (system, state, _, inputs), i in zip(members, range(len(members))):
        body = system.secondary
        A, B, C = body.principal_moments
        assert abs(A / C - inputs["ratio_a"]) <= 64 * EPS
        assert abs(B / C - inputs["ratio_b"]) <= 64 * EPS
        d = att.diagnose(body, att.AttitudeState(state.epoch, state.secondary_attitude,
                                                 state.secondary_omega))
        assert d.regime == "SAM" == ds.before_regime.values[i]
        assert abs(C / d.dynamic_inertia - inputs["energy_ratio"]) <= 1e-12
        assert abs(d.periods["precession"] / inputs["precession_period"] - 1) <= 1e-10
        # the direction of L is the drawn one, in the state's frame
        L = state.secondary_attitude.apply(body.inertia @ state.secondary_omega)
        lon, lat = inputs["angular_momentum_lon"], inputs["angular_momentum_lat"]
        n = [np.cos(lat) * np.cos(lon), np.cos(lat) * np.sin(lon), np.sin(lat)]
        assert np.linalg.norm(np.cross(L / np.linalg.norm(L), n)) <= 1e-12


def test_a_member_is_the_single_run():
    """The nominal member (no draw, both phases 0) against the encounter built by hand
    and run by att.propagate, its end diagnosed by att.diagnose: the same equations at
    the same tolerance, so they agree to round-off of the final state (the free-body
    diagnosis of both agrees to 1e-13)."""
    members = sample_encounter(1, rng=0, phases=False, energy_ratio=1.024, ratio_a=0.61,
                               ratio_b=0.965, precession_period=27.38 * 3600.0)
    ds = encounter_ensemble(members, TIMES, rtol=RTOL)
    _, q, w, _ = att.model.sampling.tumbling_state(
        np.radians(250.0), np.radians(-75.0), 1.024, 0.61, 0.965, 27.38 * 3600.0)
    body = ellipsoid_from_ratios(0.61, 0.965, 2600.0 * 4 / 3 * np.pi * 170.0**3, 170.0)
    system, state = close_encounter(EARTH_MASS * u.kg, EARTH_RADIUS * u.m, body,
                                    Rotation.from_quat(q[0]), w[0],
                                    perigee_distance=38_000 * u.km, v_infinity=5.84e3,
                                    perigee_epoch=APOPHIS["perigee_epoch"][0],
                                    before=12 * u.h)
    eph = att.propagate(system, state, TIMES, method="integrator", rtol=RTOL)
    end = eph.dataset.isel(time=-1)
    d = att.diagnose(body, att.AttitudeState(state.epoch + TIMES[-1] * u.s,
                                             Rotation.from_quat(end.quaternion.values[1]),
                                             end.angular_velocity.values[1]))
    C = body.principal_moments[-1]
    assert ds.after_regime.values[0] == d.regime
    assert abs(ds.after_energy_ratio.values[0] - C / d.dynamic_inertia) <= 1e-12
    assert abs(ds.after_precession_period.values[0] / d.periods["precession"] - 1) <= 1e-12
    assert abs(ds.after_rotation_period.values[0] / d.periods["rotation"] - 1) <= 1e-12


def test_each_member_conserves_and_stays_under_the_tidal_bound(apophis_members):
    """Total angular momentum: DOP853's local error below rtol per step over some 50
    steps, 1e3 rtol.  The spin's change: at most ``(3/2) G M (C - A) int dt / r^3``
    along the member's hyperbola (closed form); and it is a real change (the tide of
    2029 moves Apophis's spin by tens of percent at most, by far more than rtol)."""
    members, ds = apophis_members
    assert np.all(ds.status.values == 0)
    assert np.all(ds.angular_momentum_drift.values <= 1e3 * RTOL)
    for (system, state, _, inputs), i in zip(members, range(len(members))):
        orbit = Hyperbola(system.mu, inputs["perigee_distance"], inputs["v_infinity"])
        nu = np.arccos(np.clip((orbit.p / np.array(
            [np.linalg.norm(orbit.state(-SPAN)[0]), np.linalg.norm(orbit.state(SPAN)[0])])
            - 1) / orbit.e, -1, 1)) * np.array([-1, 1])
        A, _, C = system.secondary.principal_moments
        H0 = np.linalg.norm(system.secondary.inertia @ state.secondary_omega)
        bound = 1.5 * system.G * EARTH_MASS * (C - A) * orbit.inverse_cube_integral(*nu)
        assert 1e3 * RTOL < ds.spin_momentum_change.values[i] <= bound / H0


def test_the_change_is_linear_in_the_tide():
    """Weak tide: a planet of 1 % and 2 % of the Earth's mass passing at 38,000 km with
    the Earth's perigee speed.  To first order each member's change of spin angular
    momentum is proportional to the tidal parameter ``G M / r_p^3`` (the torque is, the
    path is nearly the same straight line), so doubling M doubles it.  Two effects
    leave first order: the spin's own change (relative size eps = |dH|/|H|, a second-
    order term of that relative size) and the bending of the path (deflection
    ``2 arcsin(1/e)``, ``e = 1 + r_p v_inf^2 / G M``); twice both, for the two runs,
    bound the ratio's departure from 2."""
    runs = []
    for k in (1, 2):
        members = sample_encounter(3, rng=5, planet_mass=0.01 * k * EARTH_MASS,
                                   v_infinity=7.42e3)
        runs.append(encounter_ensemble(members, TIMES, step=300.0))
    small, large = (r.spin_momentum_change.values for r in runs)
    e = 1 + 38_000e3 * 7.42e3**2 / (att.binary.G * 0.02 * EARTH_MASS)
    tolerance = 2 * (2 * large.max() + 2 * np.arcsin(1 / e))
    assert tolerance < 0.05                               # the limit is weak enough
    assert np.all(np.abs(large / small / 2 - 1) <= tolerance)
    # and the spread over the members (the phases) scales the same way
    ratio = np.std(runs[1].energy_ratio_change) / np.std(runs[0].energy_ratio_change)
    assert abs(ratio / 2 - 1) <= 2 * tolerance


def test_a_draw_no_ellipsoid_has_is_bad_input():
    """B/C below A/C: no body; the member is reported, the others run."""
    members = sample_encounter(2, rng=1, ratio_a=0.61, ratio_b=(0.965, 0.0))
    members[1] = sample_encounter(1, rng=1, ratio_a=0.9, ratio_b=0.8)[0]
    assert isinstance(members[1][0], att.AttitudeError)
    ds = encounter_ensemble(members, TIMES, step=600.0)
    assert ds.status.values.tolist() == [0, 1]
    assert "B/C" in ds.message.values[1]
    assert ds.attrs["regime_fractions"] == {"SAM": 1.0}


def test_on_dask_the_members_give_the_same_outcomes():
    """One dask task a member (threads: no process start-up) gives each member's row as
    in this process: the same steps on the same numbers."""
    pytest.importorskip("distributed")
    from attitude.propagation.cluster import local_cluster

    members = sample_encounter(2, rng=3)
    here = encounter_ensemble(members, TIMES, step=600.0)
    with local_cluster(1, processes=False) as client:
        there = encounter_ensemble(members, TIMES, step=600.0, client=client, chunk_size=1)
    for key in ("after_energy_ratio", "after_precession_period", "spin_momentum_change"):
        np.testing.assert_array_equal(there[key].values, here[key].values)
    assert there.attrs == here.attrs

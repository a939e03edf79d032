"""The Lie-group variational integrator of the full two-body problem (attitude.binary.lgvi),
each property against something independent: the conservation laws the map keeps by
construction, the DOP853 reference, the Kepler solution and the same impulse under DOP853.
"""

from __future__ import annotations

import astropy.units as u
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import attitude as att
from attitude.binary.dynamics import energy_momentum, integrate_dop853, pack
from attitude.binary.lgvi import (
    cayley_step,
    default_step,
    integrate_lgvi,
    integrate_lgvi_batch,
    step_grid,
)
from attitude.foundations.errors import BinarySystemError, PropagationError
from attitude.model.orbit import KeplerOrbit
from attitude.propagation.jit import NUMBA
from tests.tolerances import EPS

ELLIPSOID = att.MassProperties.solid_ellipsoid
PRIMARY_SPIN = 2 * np.pi / 8136.0          # 2.26 h


@pytest.fixture(scope="module")
def didymos():
    """A Didymos-like pair of ellipsoids at order 2 (what these short runs need), and a
    state off every symmetry: an inclined, slightly eccentric orbit, tilted attitudes and
    spins off the principal axes."""
    system = att.BinarySystem(
        att.RigidBody.from_mass_properties(ELLIPSOID(5.2e11, [425.0, 410.0, 390.0])),
        att.RigidBody.from_mass_properties(ELLIPSOID(4.3e9, [103.16, 79.35, 66.13])))
    n = np.sqrt(system.mu / 1190.0**3)
    y0 = pack([1190.0, 0, 0], [0, 1.02 * n * 1190.0, 0.002],
              Rotation.from_euler("xyz", [0.1, 0.2, 0.3]).as_quat(),
              [0.0, 1e-5, PRIMARY_SPIN],
              Rotation.from_euler("xyz", [0.05, -0.1, 0.02]).as_quat(), [1e-5, 0.0, n])
    return system, y0


def _state(y0):
    return att.BinaryState("2026-12-01", y0[0:3], y0[3:6], Rotation.from_quat(y0[6:10]),
                           y0[10:13], Rotation.from_quat(y0[13:17]), y0[17:20])


def _relative(E, L):
    dE = np.abs(E / E[0] - 1.0)
    dL = np.linalg.norm(L - L[0], axis=-1) / np.linalg.norm(L[0])
    return dE, dL


def test_cayley_step_solves_the_implicit_equation():
    """``h S(g) = F J - J F^T`` with ``F`` a rotation, for a full (non-principal) inertia
    tensor: each side a few products of numbers of size ``h |g|`` and ``|I|``."""
    inertia = np.array([[2.0, 0.1, 0.0], [0.1, 3.0, 0.2], [0.0, 0.2, 4.0]])
    g, h = np.array([0.3, -0.2, 0.5]), 0.7
    F = cayley_step(g, inertia, h)
    J = 0.5 * np.trace(inertia) * np.eye(3) - inertia
    S = np.array([[0, -g[2], g[1]], [g[2], 0, -g[0]], [-g[1], g[0], 0]])
    scale = np.abs(inertia).max() * 3
    assert np.abs(h * S - (F @ J - J @ F.T)).max() <= 16 * EPS * scale
    assert np.abs(F @ F.T - np.eye(3)).max() <= 16 * EPS
    assert np.linalg.det(F) == pytest.approx(1.0, abs=16 * EPS)


def test_step_too_long_for_the_spin_raises():
    """One rotation cannot carry ``h |I w|`` beyond ~2 |I|: no solution, a clear error."""
    with pytest.raises(PropagationError, match="step"):
        cayley_step([0.0, 0.0, 3.0 * 50.0], np.diag([1.0, 2.0, 3.0]), 1.0)


def test_momentum_kept_to_round_off_and_energy_bounded(didymos):
    """2000 steps of 60 s (1.4 orbits, 15 primary turns).  The map keeps
    ``mu R x V + sum A_i I_i w_i`` exactly (each step adds ``h/2 (R x F + tau1 + tau2)``,
    zero for the mutual potential), so the drift is round-off: a few ulps of |L| per step
    (bounded here by 2 ulps per step, linearly).  The energy error of a symplectic map
    is ``h^2`` times a function of the state: no secular growth, the second half's
    largest excursion no larger than the first's (the state covers both halves alike:
    many spin periods and most of an orbit each; 10% for the different phases)."""
    system, y0 = didymos
    steps = 2000
    t = np.arange(steps + 1) * 60.0
    E, L = energy_momentum(system, integrate_lgvi(system, y0, t, 60.0))
    dE, dL = _relative(E, L)
    assert dL.max() <= steps * 2 * EPS
    half = steps // 2
    assert dE[half:].max() <= 1.1 * dE[:half + 1].max()
    assert dE.max() > 100 * steps * EPS          # the energy error is the method's, not round-off


def test_energy_error_scales_as_h_squared(didymos):
    """Halving the step divides the energy error by 4: ``E_h - E = h^2 e2(state) +
    O(h^4)`` so the ratio is ``4 (1 + O((w h)^2))``, (w h)^2 = 0.011 at the 150 s step for
    the 2.26 h primary: a 5% band.  The output spacing (300 s) is a multiple of both
    steps, so the steps are exactly 150 s and 75 s."""
    system, y0 = didymos
    t = np.linspace(0.0, 30000.0, 101)
    errors = []
    for h in (150.0, 75.0):
        E, _ = energy_momentum(system, integrate_lgvi(system, y0, t, h))
        errors.append(np.abs(E / E[0] - 1.0).max())
    assert errors[0] / errors[1] == pytest.approx(4.0, rel=0.05)


def _full_tensors(y0):
    """The same pair at order 2 with inertia tensors off their principal axes (a shape
    model in its own axes): the implicit rotation with a full tensor."""
    Q = Rotation.from_euler("xyz", [0.3, -0.5, 0.8]).as_matrix()
    system = att.BinarySystem(
        att.RigidBody(Q @ np.diag([3.28e16, 3.34e16, 3.43e16]) @ Q.T, mass=5.2e11),
        att.RigidBody(Q.T @ np.diag([1.07e13, 1.50e13, 1.69e13]) @ Q, mass=4.3e9))
    return system, y0


@pytest.mark.parametrize("axes", ["principal", "full tensors"])
def test_second_order_convergence_to_dop853(didymos, axes):
    """The state after 12000 s against DOP853 at rtol 1e-13 (its error ~1e-12 relative,
    10^5 below the LGVI's at these steps): every part's error falls by 4 when the step
    halves, ``4 (1 + O((w h)^2))`` with (w h)^2 <= 0.009: a 5% band."""
    system, y0 = didymos if axes == "principal" else _full_tensors(didymos[1])
    t = np.array([0.0, 12000.0])
    ref = integrate_dop853(system, y0, t, rtol=1e-13)[-1]
    parts = (slice(0, 3), slice(3, 6), slice(6, 10), slice(10, 13), slice(13, 17),
             slice(17, 20))
    errors = []
    for h in (120.0, 60.0):
        y = integrate_lgvi(system, y0, t, h)[-1]
        errors.append([np.linalg.norm(y[s] - ref[s]) for s in parts])
    ratio = np.array(errors[0]) / np.array(errors[1])
    assert ratio == pytest.approx(np.full(6, 4.0), rel=0.05)
    # and the error itself is the method's, well above the reference's
    assert errors[1][0] > 1e-6 * 1190.0


def test_two_spheres_follow_kepler_and_keep_their_spins():
    """Spheres attract as point masses (at order 4 too) and feel no torque.  For a
    circular orbit velocity Verlet (the LGVI's orbit part) has a discrete circular
    solution turning by ``2 asin(n h / 2)`` per step; the exact initial velocity is
    ``(n h)^2 / 8`` too fast for it, which puts it on a nearby ellipse (``e = (n h)^2 / 4``)
    of mean motion lower by ``3/8 (n h)^2 n``: the secondary falls behind Kepler by
    ``r (n h)^2 n t / 3`` plus the ellipse's periodic excursion, ``2 a e`` along the track
    and ``a e`` radially, ``0.56 r (n h)^2`` at most.  Bound: ``r (n h)^2 (n t / 3 + 1)``.
    The spins stay constant: ``F^T Pi = Pi`` for a sphere, ~1e-15 per step from the
    Newton tolerance and round-off: 8 ulps per step."""
    ball = att.MassProperties.solid_sphere
    system = att.BinarySystem(att.RigidBody.from_mass_properties(ball(5e11, 400.0)),
                              att.RigidBody.from_mass_properties(ball(4e9, 80.0)), order=4)
    orbit = KeplerOrbit(mu=system.mu, a=1200.0, e=0.0, i=0.3, raan=0.2)
    R0, V0 = orbit.state(0.0)
    w1, w2 = np.array([1e-4, 2e-4, 7e-4]), np.array([-3e-5, 1e-4, 1.4e-4])
    y0 = pack(R0, V0, [0, 0, 0, 1.0], w1, Rotation.from_euler("z", 0.4).as_quat(), w2)
    t = np.linspace(0.0, 2 * orbit.period, 9)
    h = orbit.period / 400
    y = integrate_lgvi(system, y0, t, h)
    nh, n = orbit.mean_motion * h, orbit.mean_motion
    error = np.linalg.norm(y[:, :3] - orbit.position(t), axis=-1)
    assert np.all(error <= 1200.0 * nh**2 * (n * t / 3 + 1.0))
    assert error[-1] >= 0.9 * 1200.0 * nh**2 * n * t[-1] / 3    # the predicted drift
    steps = 800
    for w, s in ((w1, slice(10, 13)), (w2, slice(17, 20))):
        assert np.abs(y[:, s] - w).max() <= steps * 8 * EPS * np.linalg.norm(w)


def test_impulse_off_the_grid_lands_at_its_time(didymos):
    """An impulse at 1000.7 s (not a multiple of the 30 s step): its effect at 1200 s
    equals DOP853's with the same impulse (rtol 1e-13) to the LGVI's relative error on
    the orbit, ~(n h)^2 = 2e-5 (bound 10x that).  Applied at a grid point instead, 0.7 s
    early or 19.3 s late, the effect would differ by dv dt: 0.7 / 199.3 = 3.5e-3
    relative.  At a sample time the ephemeris holds the state just after the impulse."""
    system, y0 = didymos
    state = _state(y0)
    dv = [-3e-3, 1e-3, 0.0]
    kick = att.Impulse(1000.7, body="secondary", delta_v=dv)
    t = [0.0, 600.0, 1200.0]
    runs = {}
    for method, options in (("lgvi", {"step": 30.0}), ("integrator", {"rtol": 1e-13})):
        plain = att.propagate(system, state, t, method=method, **options)
        kicked = att.propagate(system, state, t, method=method, events=[kick], **options)
        runs[method] = (kicked.dataset.relative_position.values[-1]
                        - plain.dataset.relative_position.values[-1])
    n = np.sqrt(system.mu / 1190.0**3)
    effect = np.linalg.norm(runs["integrator"])
    assert effect > 0.15      # ~ |dv| 199 s: the impulse did something
    assert np.linalg.norm(runs["lgvi"] - runs["integrator"]) <= 10 * (n * 30.0)**2 * effect

    at = att.propagate(system, state, [0.0, 1000.7], step=30.0, events=[kick]).dataset
    before = att.propagate(system, state, [0.0, 1000.7], step=30.0).dataset
    jump = at.relative_velocity.values[-1] - before.relative_velocity.values[-1]
    speed = np.linalg.norm(before.relative_velocity.values[-1])
    assert np.abs(jump - dv).max() <= 4 * EPS * speed
    assert np.array_equal(at.relative_position.values, before.relative_position.values)


def test_angular_impulse_changes_the_body_momentum(didymos):
    """An angular impulse on the primary at a sample time adds to the total angular
    momentum exactly that vector (its frame and the body frame differ: rotated by A)."""
    system, y0 = didymos
    state = _state(y0)
    dH = np.array([1e12, -2e12, 5e11])
    kick = att.Impulse(90.0, body="primary", angular_impulse=dH)
    ds = att.propagate(system, state, [0.0, 90.0, 180.0], step=30.0, events=[kick]).dataset
    plain = att.propagate(system, state, [0.0, 90.0, 180.0], step=30.0).dataset
    L = ds.total_angular_momentum.values
    Lp = plain.total_angular_momentum.values
    scale = np.linalg.norm(Lp[0])
    assert np.abs(L[1:] - Lp[1:] - dH).max() <= 64 * EPS * scale


def test_default_method_step_rule_and_units(didymos):
    """No method: the LGVI, at 1/200 of the shortest period (here the primary's 2.26 h
    spin, |w1| a little above 2 pi / 8136 s); "30 s", 0.5 min and 30.0 give one run."""
    system, y0 = didymos
    state = _state(y0)
    assert default_step(system, y0) == pytest.approx(
        2 * np.pi / np.linalg.norm(y0[10:13]) / 200, rel=4 * EPS)
    t = [0.0, 100.0, 200.0]
    eph = att.propagate(system, state, t)
    assert eph.dataset.attrs["method"] == "lgvi"
    assert eph.dataset.attrs["step"] == default_step(system, y0)
    runs = [att.propagate(system, state, t, method="lgvi", step=s).dataset
            for s in ("30 s", 0.5 * u.min, 30.0)]
    for ds in runs[:2]:
        np.testing.assert_array_equal(ds.relative_position.values,
                                      runs[2].relative_position.values)
    assert att.propagate(system, state, t, rtol=1e-10).dataset.attrs["method"] == "integrator"


def test_output_times_shorten_the_steps():
    """Equal steps no longer than h between consecutive knots; knots never inside a step."""
    grid = step_grid(np.array([45.0, 100.0, 100.0, 130.0]), 30.0)
    assert grid.tolist() == [0.0, 22.5, 45.0, 72.5, 100.0, 130.0]
    assert np.diff(grid).max() <= 30.0


@pytest.mark.parametrize("step, why", [(-30.0, "positive"), (0.0, "positive"),
                                        (float("nan"), "finite"), ("30 m", "time unit"),
                                        ([30.0, 60.0], "single")])
def test_bad_step_names_step(didymos, step, why):
    system, y0 = didymos
    with pytest.raises(BinarySystemError, match=f"^step: .*{why}"):
        att.propagate(system, _state(y0), [0.0, 60.0], method="lgvi", step=step)


def test_rtol_with_lgvi_is_refused(didymos):
    system, y0 = didymos
    with pytest.raises(BinarySystemError, match="^rtol"):
        att.propagate(system, _state(y0), [0.0, 60.0], method="lgvi", rtol=1e-10)


def test_impulse_at_the_epoch_and_after_the_last_output(didymos):
    """A kick at t = 0 shows in the first sample (the state just after it); one after the
    last output time changes nothing that is sampled (same steps, same numbers)."""
    system, y0 = didymos
    state = _state(y0)
    dv = np.array([1e-3, 0.0, -2e-3])
    t = [0.0, 300.0]
    plain = att.propagate(system, state, t, step=30.0).dataset
    first = att.propagate(system, state, t, step=30.0,
                          events=[att.Impulse(0.0, delta_v=dv)]).dataset
    assert np.abs(first.relative_velocity.values[0] - y0[3:6] - dv).max() \
        <= 4 * EPS * np.linalg.norm(y0[3:6])
    late = att.propagate(system, state, t, step=30.0,
                         events=[att.Impulse(301.0, delta_v=dv)]).dataset
    for name in ("relative_position", "relative_velocity", "quaternion", "angular_velocity"):
        np.testing.assert_array_equal(late[name].values, plain[name].values)


def test_a_batch_is_its_members_run_one_by_one():
    """integrate_lgvi_batch vectorises the same map over members (here 3 systems, 6
    bodies: the implicit rotations solved as arrays, not floats): each member equals its
    own run.  The arithmetic per member is the same; only sums inside einsum may be
    ordered differently, a few ulps per step, so 1e-9 of the state's scale after 400
    steps is a generous bound."""
    from attitude.binary.lgvi import FLOAT_MEMBERS

    ball = att.RigidBody.from_mass_properties(att.MassProperties.solid_sphere(5e11, 400.0))
    shapes = ([103.0, 79.0, 66.0], [110.0, 70.0, 60.0], [95.0, 85.0, 70.0])
    systems = [att.BinarySystem(ball, att.RigidBody.from_mass_properties(
        att.MassProperties.solid_ellipsoid(4.3e9, a))) for a in shapes]
    assert 2 * len(systems) > FLOAT_MEMBERS
    y0 = []
    for k, s in enumerate(systems):
        n = np.sqrt(s.mu / 1190.0**3)
        q = Rotation.from_euler("z", 5.0 * k, degrees=True).as_quat()
        y0.append(pack([1190.0, 0, 0], [0, n * 1190.0, 0], [0, 0, 0, 1.0], [0, 0, 7.7e-4],
                       q, [0, 1e-6 * k, n]))
    y0 = np.array(y0)
    t = np.linspace(0.0, 12000.0, 5)
    batch = integrate_lgvi_batch(systems, y0, t, 30.0, compiled=False)   # the numpy path
    for k, s in enumerate(systems):
        alone = integrate_lgvi(s, y0[k], t, 30.0)
        np.testing.assert_allclose(batch[k, :, :3], alone[:, :3], rtol=0, atol=1e-9 * 1190.0)
        np.testing.assert_allclose(batch[k, :, 6:10], alone[:, 6:10], rtol=0, atol=1e-9)
        np.testing.assert_allclose(batch[k, :, 13:17], alone[:, 13:17], rtol=0, atol=1e-9)


def test_compensated_and_plain_sums_are_the_same_map(didymos):
    """The compensated sums change only the round-off: 500 steps of 60 s with an impulse,
    the two agree within steps x eps x each block's magnitude (each path rounds a few
    ulps per step, differently)."""
    system, y0 = didymos
    t = np.linspace(0.0, 30000.0, 11)
    kick = [[(9000.0, att.Impulse(0.0, body="secondary", delta_v=[0, -2.7e-3, 0],
                                  angular_impulse=[0.0, 1e5, 2e5]))]]
    runs = [integrate_lgvi_batch([system], y0[None], t, 60.0, kick, compensated=c)[0]
            for c in (True, False)]
    for block in (slice(0, 3), slice(3, 6), slice(6, 10), slice(10, 13), slice(13, 17),
                  slice(17, 20)):
        magnitude = np.abs(runs[1][:, block]).max()
        assert np.abs(runs[0][:, block] - runs[1][:, block]).max() <= 500 * EPS * magnitude


@pytest.mark.skipif(not NUMBA,
                    reason="4e5 steps: seconds compiled, minutes on the numpy path")
def test_angular_momentum_over_ten_thousand_orbits():
    """1e4 orbits of 40 steps (4e5 steps, the benchmark's case): with compensated sums a
    step's error is the rounding of its increments, a few eps of the step's turn of the
    orbit ``n h`` relative to H, uncorrelated from step to step, so the drift is a random
    walk: |dH/H| <= 4 eps n h sqrt(N), plus 16 eps for the output's own rounding (the
    plain sums of ``h/mu p + h^2/(2 mu) F``, before, drifted linearly to 2.7e-13)."""
    system = att.BinarySystem(
        att.RigidBody.from_mass_properties(att.MassProperties.solid_sphere(5.2e11, 400.0)),
        att.RigidBody.from_mass_properties(ELLIPSOID(4.3e9, [103.16, 79.35, 66.13])))
    n = np.sqrt(system.mu / 1190.0**3)
    period, steps_per_orbit, orbits = 2 * np.pi / n, 40, 10_000
    y0 = pack([1190.0, 0, 0], [0, n * 1190.0, 0], [0, 0, 0, 1.0], [0, 0, 0],
              Rotation.from_euler("z", 10.0, degrees=True).as_quat(), [0, 0, n])
    t = np.arange(orbits + 1) * period
    _, L = energy_momentum(system, integrate_lgvi(system, y0, t, period / steps_per_orbit))
    dL = np.linalg.norm(L - L[0], axis=-1) / np.linalg.norm(L[0])
    N = orbits * steps_per_orbit
    assert dL.max() <= 4 * EPS * (2 * np.pi / steps_per_orbit) * np.sqrt(N) + 16 * EPS

"""Tests of attitude.diagnostics: measured periods against the analytic ``att.diagnose``
(Landau & Lifshitz §37 through the exact solution), Euler angles against the exact
solution's own angles (the Jacobi-function kernel of attitude.propagation.torquefree),
invariants and osculating periods against ``diagnose``, conservation drift under a
dissipative torque, netCDF round trip of the added variables, and bad input.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import attitude as att
from attitude.analysis.diagnostics import (
    DIAGNOSTIC_VARIABLES,
    DiagnosticsError,
    InsufficientDataError,
    add_diagnostics,
    attitude_noise,
    conservation_drift,
    invariants,
    measure_periods,
    momentum_frame_angles,
    osculating_polhode_period,
    principal_series,
)
from attitude.model import freebody as fb
from attitude.model.torques import EnergyDissipation
from attitude.propagation import torquefree as tf

from ..tolerances import EXACT_SOLUTION, FEW_OPS, assert_agree

EPOCH = "2030-01-01T00:00:00"

# (moments, principal-frame omega): one state per torque-free regime with periods
STATES = {
    "SAM": ([0.61, 0.965, 1.0], [0.02, 0.0, 0.1]),
    "SAM-2": ([1.0, 2.0, 3.0], [0.1, -0.5, -1.0]),
    "LAM": ([1.0, 2.0, 3.0], [1.0, 0.1, 0.2]),
    "oblate": ([2.0, 2.0, 3.0], [0.3, 0.1, 1.0]),
    "prolate": ([1.0, 3.0, 3.0], [1.0, 0.3, 0.1]),
    "PA-short": ([1.0, 2.0, 3.0], [0.0, 0.0, 1.0]),
    "PA-long": ([1.0, 2.0, 3.0], [-1.0, 0.0, 0.0]),
    "transverse": ([2.0, 2.0, 3.0], [1.0, 0.0, 0.0]),
    "spherical": ([2.0, 2.0, 2.0], [1.0, 0.3, 0.0]),
}


def _rotated_body(moments, seed=3):
    """A body whose frame is not principal (exercises body_to_principal)."""
    R = Rotation.random(random_state=seed).as_matrix()
    return att.RigidBody(R @ np.diag(moments) @ R.T)


def _case(name, *, rotated=False, cycles=10.0, samples=2001):
    moments, w = STATES[name]
    body = _rotated_body(moments) if rotated else att.RigidBody.from_principal_moments(moments)
    w_body = body.body_to_principal.inv().apply(w)
    state = att.AttitudeState(EPOCH, Rotation.random(random_state=5), w_body)
    d = att.diagnose(body, state)
    P = max(d.periods.values())
    eph = att.propagate(body, state, np.linspace(0.0, cycles * P, samples))
    return body, state, d, eph


# --- periods ----------------------------------------------------------------------------


@pytest.mark.parametrize("name", ["SAM", "SAM-2", "LAM", "oblate", "prolate"])
@pytest.mark.parametrize("rotated", [False, True])
def test_measured_periods_match_diagnose(name, rotated):
    """Acceptance (issue 5): torque-free periods measured from the series agree with the
    analytic ones to 1e-6 relative; the stated uncertainty covers the difference."""
    _, _, d, eph = _case(name, rotated=rotated)
    m = measure_periods(eph)
    assert set(m) == set(d.periods) == {"polhode", "precession", "rotation"}
    for key, got in m.items():
        assert got.value == pytest.approx(d.periods[key], rel=1e-6)
        assert abs(got.value - d.periods[key]) <= 5 * got.uncertainty + 1e-12 * got.value
        assert got.cycles >= 8


@pytest.mark.parametrize("name", ["PA-short", "PA-long", "transverse", "spherical"])
def test_measured_spin_periods(name):
    _, _, d, eph = _case(name)
    m = measure_periods(eph)
    assert set(m) == set(d.periods)
    for key, got in m.items():
        assert got.value == pytest.approx(d.periods[key], rel=1e-9)


def test_periods_coarse_sampling_still_within_1e6():
    """Twenty samples per shortest period, not aligned with it; too coarse a sampling
    (the precession angle could alias) is refused, not mismeasured."""
    moments, w = STATES["SAM-2"]
    body = att.RigidBody.from_principal_moments(moments)
    state = att.AttitudeState(EPOCH, Rotation.identity(), w)
    d = att.diagnose(body, state)
    P, Pmin = d.periods["polhode"], min(d.periods.values())
    eph = att.propagate(body, state, np.arange(0.0, 12.3 * P, Pmin / 20.3))
    m = measure_periods(eph)
    for key in d.periods:
        assert m[key].value == pytest.approx(d.periods[key], rel=1e-6)
    coarse = att.propagate(body, state, np.arange(0.0, 12.3 * P, Pmin / 1.7))
    with pytest.raises(InsufficientDataError, match="sampled too coarsely"):
        measure_periods(coarse)


def test_periods_with_attitude_noise_have_honest_uncertainties():
    """Attitude noise (1e-3 rad) leaves the rates, hence the polhode, untouched; the
    precession period (which needs the attitude) stays within its uncertainty."""
    body, state, d, eph = _case("SAM", cycles=20, samples=4001)
    rng = np.random.default_rng(7)
    q = eph.dataset["quaternion"].values
    noisy = (Rotation.from_quat(q) * Rotation.from_rotvec(rng.normal(scale=1e-3, size=(
        q.shape[0], 3)))).as_quat()
    eph_n = att.Ephemeris.from_arrays(eph.time, noisy, eph.dataset["angular_velocity"].values,
                                      body=body, epoch=state.epoch, frame="ICRF")
    m = measure_periods(eph_n)
    P = m["precession"]
    assert abs(P.value - d.periods["precession"]) < 4 * P.uncertainty
    assert P.uncertainty / P.value < 1e-4
    assert m["polhode"].value == pytest.approx(d.periods["polhode"], rel=1e-9)
    assert attitude_noise(principal_series(eph_n)) == pytest.approx(1e-3, rel=0.3)
    assert attitude_noise(principal_series(eph)) < 1e-12


# --- Euler angles -----------------------------------------------------------------------


def _kernel_angles(moments, w, t):
    """phi, theta, psi of the exact solution's own kernel (attitude.propagation.torquefree)."""
    I = np.asarray(moments, float)[None]
    wv = np.asarray(w, float)[None]
    sI, sw = fb.unit_scales(I, wv)
    Is, ws = I / sI[:, None], wv / sw[:, None]
    br, dhi, dlo = fb.branches(Is, ws)
    c, _ = tf._triaxial_setup(Is, ws, dhi, dlo, int(br[0]) == fb.BRANCH_LAM)
    phi, ct, st, psi = tf._triaxial_eval(c, (t * sw[0])[None, :], angles_only=True)
    return phi[0], 2.0 * np.arctan2(st[0], ct[0]), psi[0]


def _wrap(x):
    return np.angle(np.exp(1j * x))


@pytest.mark.parametrize("name, axis", [("SAM", 3), ("SAM-2", 3), ("LAM", 1)])
def test_euler_angles_match_exact_solution(name, axis):
    """phi (up to its constant origin), theta and psi agree with the closed form's."""
    moments, w = STATES[name]
    body = att.RigidBody.from_principal_moments(moments)
    state = att.AttitudeState(EPOCH, Rotation.random(random_state=11), w)
    P = att.diagnose(body, state).periods["polhode"]
    t = np.linspace(0.0, 5 * P, 1001)
    eph = att.propagate(body, state, t)
    a = momentum_frame_angles(principal_series(eph), axis)
    kphi, ktheta, kpsi = _kernel_angles(moments, w, t)
    np.testing.assert_allclose(_wrap(a["precession"] - a["precession"][0] - kphi), 0,
                               atol=1e-11)
    np.testing.assert_allclose(a["nutation"], ktheta, atol=1e-13)
    np.testing.assert_allclose(_wrap(a["rotation"] - kpsi), 0, atol=1e-12)
    # unwrapped: phi advances monotonically, psi by one turn per polhode period
    assert np.all(np.diff(a["precession"]) > 0)
    assert abs(a["rotation"][-1] - a["rotation"][0]) == pytest.approx(10 * np.pi, rel=1e-9)
    sign = 1.0 if np.median(np.cos(a["nutation"])) >= 0 else -1.0   # phi + psi or phi - psi
    np.testing.assert_allclose(_wrap(a["spin"] - a["precession"] - sign * a["rotation"]), 0,
                               atol=1e-9)


def test_euler_angles_rebuild_the_attitude():
    """R_z(phi) R_x(theta) R_z(psi) in the angular-momentum frame is the attitude: with
    L fixed along inertial z (so the frame's X is inertial x), the Euler angles give back
    the quaternion of the ephemeris."""
    moments, w = STATES["SAM-2"]
    body = att.RigidBody.from_principal_moments(moments)
    L = np.asarray(moments) * np.asarray(w)
    # attitude that maps body L onto +z: then the angular-momentum frame is the inertial one
    align = Rotation.align_vectors([[0, 0, 1.0]], [L / np.linalg.norm(L)])[0]
    state = att.AttitudeState(EPOCH, align, w)
    eph = att.propagate(body, state, np.linspace(0.0, 40.0, 201))
    a = momentum_frame_angles(principal_series(eph), 3)
    R = Rotation.from_euler("ZXZ", np.column_stack([a["precession"],
                                                    a["nutation"], a["rotation"]]))
    # the frame's X is the node of L on the xy plane: along x for L = +z
    diff = (R.inv() * eph.rotation).magnitude()
    assert diff.max() < 1e-12


def test_momentum_frame_follows_a_turning_L():
    """A constant inertial torque turns L by 180 deg: the X axis of the
    angular-momentum frame stays perpendicular to L and continuous (re-anchoring), and
    the Euler angles stay finite and continuous."""
    body = att.RigidBody.from_principal_moments([1.0, 2.0, 3.0])
    state = att.AttitudeState(EPOCH, Rotation.identity(), [0.1, 0.0, 1.0])
    turn = np.array([0.0, 0.2, 0.0])          # dL/dt = turn x L: L turns about inertial y

    def turning(t, quaternion, omega_body, b):
        return np.cross(Rotation.from_quat(quaternion).inv().apply(turn), b.inertia @ omega_body)

    t = np.linspace(0.0, 30.0, 3001)
    eph = att.propagate(body, state, t, torques=[turning], rtol=1e-10)
    s = principal_series(eph)
    Li = s.momentum_inertial
    assert (Li @ Li[0]).min() < -0.9 * (Li[0] @ Li[0])         # turned by about 180 deg
    a = momentum_frame_angles(s, 3)
    for key in ("precession", "nutation", "rotation", "spin"):
        assert np.all(np.isfinite(a[key]))
        assert np.abs(np.diff(a[key])).max() < 0.5


# --- invariants ---------------------------------------------------------------------------


@pytest.mark.parametrize("name", ["SAM", "SAM-2", "LAM", "PA-short"])
def test_invariants_match_diagnose(name):
    moments, w = STATES[name]
    d = fb.diagnose_principal(moments, w)
    inv = invariants(np.asarray(w, float)[None], moments)
    assert inv["L"][0] == pytest.approx(d.angular_momentum, rel=1e-15)
    assert inv["E"][0] == pytest.approx(d.kinetic_energy, rel=1e-15)
    assert inv["dynamic_inertia"][0] == pytest.approx(d.dynamic_inertia, rel=1e-15)
    assert inv["excitation"][0] == pytest.approx(d.excitation, rel=1e-14, abs=1e-300)
    assert inv["separatrix_distance"][0] == pytest.approx(d.separatrix_distance, rel=1e-12)
    if d.regime in ("SAM", "LAM"):                 # largest angle to the axis line
        key = "nutation_max_C" if d.regime == "SAM" else "nutation_max_A"
        expected = max(min(x, np.pi - x) for x in d.nutation_range)
        assert inv[key][0] == pytest.approx(expected, rel=1e-12)
    if "polhode" in d.periods:
        assert osculating_polhode_period(w, moments) == pytest.approx(d.periods["polhode"],
                                                                      rel=1e-12)


def test_invariants_vectorised_and_osculating_period_near_separatrix():
    moments = [1.0, 2.0, 3.0]
    rng = np.random.default_rng(2)
    w = rng.normal(size=(50, 3))
    stacked = invariants(w, moments)
    for i in (0, 17, 49):
        single = invariants(w[i], moments)
        for k, v in single.items():   # elementwise formulas; arcsin's SIMD loop may differ
            assert_agree(stacked[k][i], v, ulps=FEW_OPS, magnitude=np.abs(v), what=k)
    # the polhode period diverges logarithmically at the separatrix (inf on it)
    w1 = np.sqrt(3.0)                     # L^2 = 2EB for omega = (sqrt 3, 0, 1)
    P = osculating_polhode_period(np.array([[w1 * (1 - 1e-4), 0, 1], [w1 * (1 - 1e-8), 0, 1],
                                            [w1, 0, 1]]), moments)
    assert 10 < P[0] < P[1] < P[2]
    assert osculating_polhode_period([1.0, 0.0, 1.0], [2.0, 2.0, 2.0]) != \
        osculating_polhode_period([1.0, 0.0, 1.0], [2.0, 2.0, 2.0])        # NaN: spherical


# --- conservation -----------------------------------------------------------------------


def test_conservation_drift_torque_free_and_dissipating():
    body, _, _, eph = _case("SAM", cycles=3, samples=601)
    c = conservation_drift(principal_series(eph))
    assert c["L_rel_drift"] < 1e-14 and c["E_rel_drift"] < 1e-14
    # dissipation: |L| kept, E decreasing at the rate omega . M
    body = att.RigidBody.from_principal_moments([1.0, 1.5, 2.0])
    damper = EnergyDissipation(30.0)
    state = att.AttitudeState(EPOCH, Rotation.identity(), [1.0, 0.05, 0.05])
    t = np.linspace(0.0, 100.0, 2001)
    eph = att.propagate(body, state, t, torques=[damper], rtol=1e-12)
    s = principal_series(eph)
    c = conservation_drift(s)
    assert c["L_rel_drift"] < 1e-9
    assert c["E_drift"][-1] < -0.01 and c["E_drift_rate"] < 0
    power = np.einsum("ij,ij->i", s.omega, damper(t, [0, 0, 0, 1], s.omega, body))
    np.testing.assert_allclose(c["E_rate"][1:-1], power[1:-1], rtol=2e-3,
                               atol=1e-4 * np.abs(power).max())


# --- dataset, netCDF ----------------------------------------------------------------------


def test_add_diagnostics_netcdf_round_trip(tmp_path):
    body, state, d, eph = _case("LAM", rotated=True, cycles=4, samples=801)
    out = add_diagnostics(eph)
    ds = out.dataset
    for name, (units, long_name) in DIAGNOSTIC_VARIABLES.items():
        assert ds[name].attrs["units"] == units and ds[name].attrs["long_name"] == long_name
    assert ds["nutation_angle"].attrs["reference_axis"] == "A"          # LAM
    assert ds["momentum_axis_angle"].dims == ("time", "principal_axis")
    for key, P in d.periods.items():
        assert float(ds[f"period_{key}"]) == pytest.approx(P, rel=1e-6)
        assert ds[f"period_{key}"].attrs["units"] == "s"
    assert "period_spin" not in ds
    assert float(ds["energy_rel_drift"]) < 1e-13
    # the original ephemeris is untouched
    assert "nutation_angle" not in eph.dataset
    path = out.to_netcdf(tmp_path / "diag.nc")
    back = att.Ephemeris.from_netcdf(path).dataset
    for name in list(DIAGNOSTIC_VARIABLES) + [f"period_{k}" for k in d.periods]:
        np.testing.assert_array_equal(back[name].values, ds[name].values)
        assert back[name].attrs["units"] == ds[name].attrs["units"]
        assert back[name].attrs["long_name"] == ds[name].attrs["long_name"]
    # and again on the file read back: same numbers
    again = add_diagnostics(att.Ephemeris.from_netcdf(path)).dataset
    np.testing.assert_allclose(again["precession_angle"], ds["precession_angle"], atol=1e-12)


def test_add_diagnostics_batch_equals_single():
    bodies = [att.RigidBody.from_principal_moments(STATES[n][0]) for n in ("SAM", "LAM")]
    states = [att.AttitudeState(EPOCH, Rotation.identity(), STATES[n][1])
              for n in ("SAM", "LAM")]
    t = np.linspace(0.0, 2000.0, 1001)
    batch = add_diagnostics(att.propagate(bodies, states, t)).dataset
    assert list(batch["reference_axis"].values) == ["C", "A"]
    for i in range(2):
        single = add_diagnostics(att.propagate(bodies[i], states[i], t)).dataset
        # ephemerides that agree to a few ulps (batch against single), then the same
        # well-conditioned formulas (atan2 of rotation-matrix elements, unwrapping by
        # 2 pi k; excitation in [0, 1]; the period of states far from the separatrix)
        for name in ("nutation_angle", "precession_angle", "excitation", "period_polhode"):
            x = single[name].values
            magnitude = (np.maximum(1.0, np.abs(x)) if name.endswith("angle") else
                         1.0 if name == "excitation" else np.abs(x))
            assert_agree(batch[name].values[i], x, ulps=EXACT_SOLUTION + FEW_OPS,
                         magnitude=magnitude, what=name)


def test_add_diagnostics_short_ephemeris_keeps_angles_and_says_why():
    body, state, d, _ = _case("SAM")
    eph = att.propagate(body, state, np.linspace(0.0, 0.3 * d.periods["polhode"], 50))
    ds = add_diagnostics(eph).dataset
    assert "nutation_angle" in ds and not any(v.startswith("period_") for v in ds.data_vars)
    assert "polhode cycle" in ds.attrs["periods_not_measured"]
    with pytest.raises(InsufficientDataError):
        add_diagnostics(eph, periods="require")


# --- bad input ----------------------------------------------------------------------------


def test_too_short_raises_a_clear_error():
    body, state, d, _ = _case("SAM")
    P = d.periods["polhode"]
    eph = att.propagate(body, state, np.linspace(0.0, 0.6 * P, 100))
    with pytest.raises(InsufficientDataError, match=r"one full polhode cycle.*expected "
                                                    r"polhode period is about") as info:
        measure_periods(eph)
    assert isinstance(info.value, att.AttitudeError) and isinstance(info.value, ValueError)
    with pytest.raises(InsufficientDataError, match="at least 6 are needed"):
        measure_periods(att.propagate(body, state, [0.0, 1.0, 2.0]))
    spin = att.propagate(att.RigidBody.from_principal_moments([1, 2, 3]), att.AttitudeState(
        EPOCH, Rotation.identity(), [0, 0, 1.0]), np.linspace(0, 3.0, 30))
    with pytest.raises(InsufficientDataError, match="at least one full turn"):
        measure_periods(spin)
    with pytest.raises(InsufficientDataError, match="does not nutate"):
        measure_periods(spin, keys=("polhode",))


def test_separatrix_has_no_period():
    body = att.RigidBody.from_principal_moments([1.0, 2.0, 3.0])
    state = att.AttitudeState(EPOCH, Rotation.identity(), [np.sqrt(3.0), 1e-3, 1.0])
    with pytest.warns(att.NearSeparatrixWarning):
        d = att.diagnose(body, state)
    eph = att.propagate(body, state, np.linspace(0.0, 20.0, 400))
    with pytest.raises(InsufficientDataError, match="polhode"):
        measure_periods(eph)
    assert d.separatrix_distance < 1e-5


def test_bad_ephemerides():
    body, state, _, eph = _case("SAM", cycles=1, samples=50)
    ds = eph.dataset.copy(deep=True)
    ds["angular_velocity"][5, 0] = np.nan
    with pytest.raises(DiagnosticsError, match="non-finite"):
        principal_series(att.Ephemeris(ds))
    ds = eph.dataset.isel(time=[0, 2, 1, 3, 4, 5, 6, 7])
    with pytest.raises(DiagnosticsError, match="increase strictly"):
        principal_series(att.Ephemeris(ds))
    batch = att.propagate([body, body], [state, state], [0.0, 1.0])
    with pytest.raises(DiagnosticsError, match="body_index"):
        principal_series(batch)

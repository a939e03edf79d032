"""Ensembles: constructors, sampling, invalid rows, statistics, chunked propagation.

Independent references: single-body propagation of each member, the scalar
``diagnose_principal``, scipy ``Rotation`` algebra for the attitude spread, the
sample moments of the drawn parameters, and ``att.classify`` on the propagated motion.
"""

import io
import warnings

import astropy.units as u
import numpy as np
import pytest
import xarray as xr
from astropy.time import Time
from scipy.spatial.transform import Rotation

import attitude as att
from attitude import ensemble as en
from attitude.model.freebody import diagnose, diagnose_many, diagnose_principal
from attitude.propagation.reference import DEFAULT_RTOL

from ..tolerances import (
    EPS,
    EXACT_SOLUTION,
    FEW_OPS,
    INTEGRATOR_PATHS,
    SPLITTING_STEP,
    assert_agree,
    attitude_angle,
    ulps,
)

EPOCH = "2029-04-13T00:00:00"
APOPHIS = {"angular_momentum_ra": 250 * u.deg, "angular_momentum_dec": -75 * u.deg,
           "energy_ratio": 1.024, "ratio_a": 0.61, "ratio_b": 0.965,
           "precession_period": 27.38 * u.h, "precession_angle": 40 * u.deg,
           "rotation_angle": 75 * u.deg}


def random_population(n, seed=0):
    rng = np.random.default_rng(seed)
    inertia = []
    while len(inertia) < n:
        m = np.sort(rng.uniform(1.0, 3.0, 3))
        if m[0] + m[1] >= m[2]:
            inertia.append(_rotated(np.diag(m), rng))
    q = Rotation.random(n, random_state=rng).as_quat()
    w = rng.normal(scale=0.05, size=(n, 3))
    return np.array(inertia), q, w


def _rotated(tensor, rng):
    r = Rotation.random(random_state=rng).as_matrix()
    return r @ tensor @ r.T


# --- construction and propagation ---------------------------------------------------
def test_ensemble_propagation_matches_each_body_alone():
    inertia, q, w = random_population(12)
    ens = att.Ensemble(inertia, q, w, epoch=EPOCH, frame="ICRF")
    t = np.linspace(0.0, 2000.0, 41)
    eph = att.propagate(ens, t)
    assert eph.dataset.quaternion.dims == ("body", "time", "quaternion_component")
    assert (eph.dataset.status.values == en.STATUS_OK).all()
    for i in (0, 5, 11):
        one = att.propagate(att.RigidBody(inertia[i]), att.AttitudeState(
            EPOCH, Rotation.from_quat(q[i]), w[i]), t)
        # the same motion: angle between the attitudes, and the rates
        # two paths of the exact solution (ulps, not bits; 11 ulp measured)
        angle = attitude_angle(eph.dataset.quaternion.values[i], one.dataset.quaternion.values)
        assert angle.max() <= ulps(1.0, EXACT_SOLUTION)
        w1 = one.dataset.angular_velocity.values
        assert_agree(eph.dataset.angular_velocity.values[i], w1, ulps=EXACT_SOLUTION,
                     magnitude=np.linalg.norm(w1, axis=-1, keepdims=True))
    # conservation of L and E per body
    assert eph.conservation()["angular_momentum_rel_drift"] < 1e-12
    assert eph.conservation()["energy_rel_drift"] < 1e-12


def test_bodies_and_states_lists_and_chunks_give_the_same_ephemeris():
    inertia, q, w = random_population(7, seed=3)
    bodies = [att.RigidBody(m, name=f"b{i}") for i, m in enumerate(inertia)]
    states = [att.AttitudeState(EPOCH, Rotation.from_quat(qi), wi) for qi, wi in zip(q, w)]
    t = np.linspace(0.0, 500.0, 11)
    eager = att.propagate(bodies, states, t)
    lazy = att.propagate(bodies, states, t, chunks=3)
    assert type(lazy.dataset.quaternion.data).__module__.startswith("dask")
    assert list(lazy.dataset.body_name.values) == [f"b{i}" for i in range(7)]
    # chunks against the whole: the exact solution along two paths (a few ulps)
    assert_agree(lazy.dataset.quaternion.values, eager.dataset.quaternion.values,
                 ulps=EXACT_SOLUTION, magnitude=1.0, what="quaternion")
    ens = att.Ensemble.from_bodies(bodies, states)
    L = eager.dataset.angular_momentum.values
    assert_agree(att.propagate(ens, t).dataset.angular_momentum.values, L,
                 ulps=EXACT_SOLUTION + FEW_OPS,
                 magnitude=np.linalg.norm(L, axis=-1, keepdims=True), what="L")


def test_propagate_ensemble_rejects_a_state_and_events():
    inertia, q, w = random_population(2)
    ens = att.Ensemble(inertia, q, w, epoch=EPOCH)
    with pytest.raises(att.InvalidStateError, match="carries its states"):
        att.propagate(ens, ens.states[0], [0.0, 1.0])
    with pytest.raises(att.InvalidStateError, match="events"):
        att.propagate(ens, [0.0, 1.0], events=att.nutation_crossing(1.0))


def test_ensemble_is_immutable_and_subset_keeps_invalid_rows():
    inertia, q, w = random_population(4)
    w[2] = np.nan
    with pytest.warns(en.InvalidBodiesWarning, match="body 2: omega_body"):
        ens = att.Ensemble(inertia, q, w, epoch=EPOCH)
    with pytest.raises(AttributeError):
        ens.frame = "GCRF"
    with pytest.raises(ValueError):
        ens.omega_body[0, 0] = 1.0
    sub = ens.subset([1, 2])
    assert len(sub) == 2 and sub.invalid == {1: ens.invalid[2]}
    assert sub.valid.tolist() == [True, False]


# --- invalid rows --------------------------------------------------------------------
def test_invalid_rows_are_reported_by_index_and_do_not_sink_the_others():
    inertia, q, w = random_population(6, seed=5)
    inertia[1] = np.diag([1.0, 1.0, 3.0])                  # triangle inequality
    inertia[3] = np.diag([-1.0, 2.0, 2.0])                 # not positive-definite
    w[4] = [np.nan, 0.0, 0.1]                              # NaN rate
    q[5] = 0.0                                             # zero quaternion
    with pytest.warns(en.InvalidBodiesWarning, match="4 of 6 bodies") as rec:
        ens = att.Ensemble(inertia, q, w, epoch=EPOCH)
    assert "body 1: principal moments" in str(rec[0].message)
    assert sorted(ens.invalid) == [1, 3, 4, 5]
    assert "triangle inequality" in ens.invalid[1]
    assert "positive-definite" in ens.invalid[3]
    assert "omega_body" in ens.invalid[4] and "quaternion" in ens.invalid[5]
    t = np.linspace(0.0, 100.0, 5)
    eph = att.propagate(ens, t)
    status = eph.dataset.status.values
    assert status.tolist() == [0, 1, 0, 1, 1, 1]
    assert np.isnan(eph.dataset.quaternion.values[[1, 3, 4, 5]]).all()
    assert "1: principal moments" in eph.dataset.attrs["invalid_bodies"]
    one = att.propagate(att.RigidBody(inertia[2]), att.AttitudeState(
        EPOCH, Rotation.from_quat(q[2]), w[2]), t)
    rel = Rotation.from_quat(eph.dataset.quaternion.values[2]).inv() * one.rotation
    assert rel.magnitude().max() < 1e-11
    with pytest.raises(att.InvalidInertiaError, match="body 1: principal moments"):
        att.Ensemble(inertia, q, w, epoch=EPOCH, on_invalid="raise")


class NaNTorqueFor:
    """A torque that returns NaN for bodies whose largest moment is ``c``: the
    propagation of those bodies fails."""

    def __init__(self, c):
        self.c = c

    def __call__(self, t, q, w, body):
        c = np.asarray(body.principal_moments)[..., 2]
        out = np.zeros_like(w)
        out[..., 0] = np.where(c == self.c, np.nan, 1e-6)
        return out


def test_a_body_whose_propagation_fails_is_flagged_and_the_others_finish():
    moments = np.array([[1.0, 2.0, 2.5], [1.0, 1.5, 2.0], [2.0, 3.0, 4.0]])
    ens = att.Ensemble.from_arrays(principal_moments=moments, omega_body=[[0.1, 0, 0.2]] * 3,
                                   epoch=EPOCH)
    t = np.linspace(0.0, 50.0, 6)
    eph = att.propagate(ens, t, torques=[NaNTorqueFor(2.0)], step=1.0)
    assert eph.dataset.status.values.tolist() == [0, 2, 0]
    assert np.isnan(eph.dataset.quaternion.values[1]).all()
    alone = att.propagate(att.RigidBody.from_principal_moments(moments[2]),
                          att.AttitudeState(EPOCH, Rotation.identity(), [0.1, 0, 0.2]), t,
                          torques=[NaNTorqueFor(2.0)], step=1.0)
    # the batch's fallback (one body at a time) against a single run: 50 splitting steps
    w = alone.dataset.angular_velocity.values
    assert_agree(eph.dataset.angular_velocity.values[2], w, ulps=50 * SPLITTING_STEP,
                 magnitude=np.linalg.norm(w, axis=-1, keepdims=True))


# --- tables --------------------------------------------------------------------------
CSV = """# a small debris catalogue
name, Ixx [kg m2], Iyy [kg m2], Izz [kg m2], Ixy [kg m2], qx, qy, qz, qw, \
wx [deg/s], wy [deg/s], wz [deg/s]
deb-1, 100, 120, 150, 5, 0, 0, 0, 1, 1.0, 0.5, 3.0
deb-2, 30, 40, 50, 0, 0, 0, 0.3826834323650898, 0.9238795325112867, 0.0, 0.0, 6.0
"""


def test_from_table_csv_with_units_and_tensor_columns(tmp_path):
    path = tmp_path / "debris.csv"
    path.write_text(CSV)
    ens = att.Ensemble.from_table(path, epoch=EPOCH, frame="GCRF")
    assert ens.names == ("deb-1", "deb-2") and ens.frame == "GCRF"
    np.testing.assert_allclose(ens.inertia[0], [[100, 5, 0], [5, 120, 0], [0, 0, 150]])
    np.testing.assert_allclose(ens.omega_body[1], [0, 0, np.radians(6.0)])
    np.testing.assert_allclose(Rotation.from_quat(ens.quaternion[1]).magnitude(),
                               np.pi / 4)
    # the same table from an open file, from pandas and from parquet
    import pandas as pd

    df = pd.read_csv(io.StringIO(CSV), comment="#", skipinitialspace=True)
    for src in (io.StringIO(CSV), df):
        np.testing.assert_array_equal(att.Ensemble.from_table(src, epoch=EPOCH).inertia,
                                      ens.inertia)
    pytest.importorskip("pyarrow")
    df.to_parquet(tmp_path / "debris.parquet")
    back = att.Ensemble.from_table(tmp_path / "debris.parquet", epoch=EPOCH)
    np.testing.assert_array_equal(back.omega_body, ens.omega_body)


def test_from_table_xarray_and_errors(tmp_path):
    ds = xr.Dataset({"A": ("body", [1.0, 2.0]), "B": ("body", [2.0, 2.5]),
                     "C": ("body", [2.5, 4.0]),
                     "wx": ("body", [0.0, 1.0], {"units": "deg/s"}),
                     "wy": ("body", [0.0, 0.0]), "wz": ("body", [0.1, 0.0])})
    ens = att.Ensemble.from_table(ds, epoch=EPOCH)
    np.testing.assert_allclose(ens.omega_body[1], [np.radians(1.0), 0, 0])
    with pytest.raises(att.InvalidStateError, match="missing rate column"):
        att.Ensemble.from_table(ds.drop_vars("wz"), epoch=EPOCH)
    with pytest.raises(att.InvalidInertiaError, match="no body columns"):
        att.Ensemble.from_table(ds.drop_vars("A"), epoch=EPOCH)
    with pytest.raises(att.InvalidStateError, match="no such table file"):
        att.Ensemble.from_table(tmp_path / "missing.csv", epoch=EPOCH)
    bad = io.StringIO("A,B,C,wx [furlong],wy,wz\n1,2,2.5,1,0,0\n")
    with pytest.raises(att.InvalidStateError, match=r"column wx: unknown unit 'furlong'"):
        att.Ensemble.from_table(bad, epoch=EPOCH)


# --- sampling ------------------------------------------------------------------------
def test_sampled_nominal_reproduces_the_published_state():
    ens = att.Ensemble.sample(50, rng=1, epoch=EPOCH, frame="ECLIPJ2000", mean=APOPHIS,
                              sigma={"energy_ratio": 0.004})
    d = diagnose(ens.bodies[0], ens.states[0])
    assert d.regime == "SAM"
    assert d.energy_ratio == pytest.approx(1.024, rel=1e-12)
    assert d.periods["precession"] == pytest.approx(27.38 * 3600, rel=1e-12)
    # rotation period: an independent check of the shape (Pravec: 263 +- 6 h)
    assert 257 * 3600 < d.periods["rotation"] < 269 * 3600
    L = d.angular_momentum_inertial / d.angular_momentum
    lon, lat = np.degrees(np.arctan2(L[1], L[0])) % 360, np.degrees(np.arcsin(L[2]))
    assert lon == pytest.approx(250.0, abs=1e-9) and lat == pytest.approx(-75.0, abs=1e-9)
    # the propagated ephemeris keeps the sampled parameters per body
    eph = att.propagate(ens.subset(slice(0, 5)), [0.0, 3600.0])
    np.testing.assert_allclose(eph.dataset.parameter_energy_ratio.values,
                               ens.parameters["energy_ratio"][:5])
    assert eph.dataset.parameter_precession_period.attrs["units"] == "s"


def test_euler_angles_of_the_tumbling_model_are_those_of_the_reference_axis():
    # theta from the energy, psi as given: compare with L in the principal frame
    m, q, w, bad = en.tumbling_state(0.3, 0.2, 1.05, 0.5, 0.8, 3600.0, 0.1, 0.7)
    assert not bad
    A, B, C = m[0]
    L = m[0] * w[0]
    L /= np.linalg.norm(L)
    theta, psi = np.arccos(L[2]), np.arctan2(L[0], L[1])
    assert psi == pytest.approx(0.7, abs=1e-12)
    two_e_c = C * np.sum(m[0] * w[0] ** 2) / np.sum((m[0] * w[0]) ** 2)
    assert two_e_c == pytest.approx(1.05, rel=1e-12)
    # the precession angle phi: the node of the reference axis (C) on the L-plane
    Lin = Rotation.from_quat(q[0]).apply(m[0] * w[0])
    Lin /= np.linalg.norm(Lin)
    np.testing.assert_allclose(Lin, [np.cos(0.2) * np.cos(0.3), np.cos(0.2) * np.sin(0.3),
                                     np.sin(0.2)], atol=1e-12)
    assert 0 < theta < np.pi / 2


def test_lam_and_spin_models():
    lam = dict(APOPHIS, energy_ratio=1.4)
    ens = att.Ensemble.sample(3, rng=0, epoch=EPOCH, mean=lam)
    d = diagnose(ens.bodies[0], ens.states[0])
    assert d.regime == "LAM" and d.energy_ratio == pytest.approx(1.4, rel=1e-12)
    assert d.periods["precession"] == pytest.approx(27.38 * 3600, rel=1e-12)
    spin = att.Ensemble.sample(
        4, rng=0, epoch=EPOCH, model="spin",
        mean={"spin_ra": "30 deg", "spin_dec": "60 deg", "spin_rate": "2 rev/h",
              "ratio_a": 0.7, "ratio_b": 0.8})
    d = diagnose(spin.bodies[0], spin.states[0])
    assert d.regime == "PA-short"
    assert d.periods["spin"] == pytest.approx(1800.0, rel=1e-12)
    axis = Rotation.from_quat(spin.quaternion[0]).apply([0, 0, 1.0])
    np.testing.assert_allclose(axis, [np.cos(np.radians(60)) * np.cos(np.radians(30)),
                                      np.cos(np.radians(60)) * np.sin(np.radians(30)),
                                      np.sin(np.radians(60))], atol=1e-12)


def test_sampling_is_seeded_and_has_the_requested_moments():
    sigma = {"energy_ratio": 0.004, "precession_period": 0.02 * u.h, "ratio_a": 0.02}
    a = att.Ensemble.sample(4000, rng=7, epoch=EPOCH, mean=APOPHIS, sigma=sigma)
    b = att.Ensemble.sample(4000, rng=np.random.default_rng(7), epoch=EPOCH,
                            mean=APOPHIS, sigma=sigma)
    c = att.Ensemble.sample(4000, rng=8, epoch=EPOCH, mean=APOPHIS, sigma=sigma)
    np.testing.assert_array_equal(a.omega_body, b.omega_body)
    assert not np.array_equal(a.omega_body, c.omega_body)
    er = a.parameters["energy_ratio"][1:]
    # sample mean within 4 standard errors, sample std within 5 %
    assert abs(er.mean() - 1.024) < 4 * 0.004 / np.sqrt(er.size)
    assert er.std() == pytest.approx(0.004, rel=0.05)
    assert a.parameters["precession_period"][1:].std() == pytest.approx(72.0, rel=0.05)
    # the bodies really have the drawn energy ratios and precession periods
    d = en.diagnose_ensemble(a)
    ok = d.valid.values
    np.testing.assert_allclose(d.energy_ratio.values[ok], a.parameters["energy_ratio"][ok],
                               rtol=1e-12)
    np.testing.assert_allclose(d.precession.values[ok],
                               a.parameters["precession_period"][ok], rtol=1e-10)


def test_sampling_with_a_covariance_matrix_and_a_user_sampler():
    mean = {"energy_ratio": 1.024, "ratio_a": 0.61, "ratio_b": 0.965,
            "angular_momentum_ra": np.radians(250), "angular_momentum_dec": np.radians(-75),
            "precession_period": 27.38 * 3600}
    cov = np.zeros((6, 6))
    cov[:2, :2] = [[1e-5, 5e-5], [5e-5, 4e-4]]             # correlation 0.79
    ens = att.Ensemble.sample(5001, rng=3, epoch=EPOCH, mean=mean, cov=cov)
    x = np.stack([ens.parameters["energy_ratio"][1:], ens.parameters["ratio_a"][1:]])
    # standard errors for n = 5000: 2 % on the variances, 0.006 on the correlation
    np.testing.assert_allclose(np.diag(np.cov(x)), [1e-5, 4e-4], rtol=0.06)
    assert np.corrcoef(x)[0, 1] == pytest.approx(0.79, abs=0.02)

    def sampler(rng, n):
        return {"energy_ratio": rng.uniform(1.0, 1.03, n)}

    ens = att.Ensemble.sample(300, rng=3, epoch=EPOCH, mean=mean, sampler=sampler)
    er = ens.parameters["energy_ratio"]
    assert er[0] == 1.024 and 1.0 <= er[1:].min() and er[1:].max() <= 1.03
    with pytest.raises(att.InvalidStateError, match="cov: expected shape"):
        att.Ensemble.sample(10, rng=3, epoch=EPOCH, mean=mean, cov=np.eye(2))


def test_sampling_errors_and_invalid_draws():
    with pytest.raises(att.InvalidStateError, match="did you mean 'energy_ratio'"):
        att.Ensemble.sample(5, epoch=EPOCH, mean=dict(APOPHIS, energy_ration=1.0))
    with pytest.raises(att.InvalidStateError, match="missing parameter.*precession_period"):
        att.Ensemble.sample(5, epoch=EPOCH, mean={k: v for k, v in APOPHIS.items()
                                                  if k != "precession_period"})
    with pytest.raises(att.InvalidStateError, match="energy_ratio.*cannot be converted"):
        att.Ensemble.sample(5, epoch=EPOCH, mean=dict(APOPHIS, energy_ratio="3 s"))
    # draws across B/C = 1 or E/E0 < 1 are reported, not resampled silently
    with pytest.warns(en.InvalidBodiesWarning, match="bodies are not physical"):
        ens = att.Ensemble.sample(400, rng=2, epoch=EPOCH, mean=APOPHIS,
                                  sigma={"ratio_b": 0.03, "energy_ratio": 0.02})
    assert ens.invalid and all(("moment ratios" in r) or ("energy ratio" in r)
                               for r in ens.invalid.values())
    bad_b = np.nonzero(ens.parameters["ratio_b"] > 1)[0]
    assert set(bad_b) <= set(ens.invalid)
    eph = att.propagate(ens, [0.0, 60.0])
    assert (eph.dataset.status.values[list(ens.invalid)] == en.STATUS_INVALID).all()
    # statistics skip the invalid bodies (their rates are NaN)
    d = en.diagnose_ensemble(ens)
    assert (d.regime.values[list(ens.invalid)] == "invalid").all()
    assert sum(en.regime_fractions(ens).values()) == pytest.approx(1.0)
    assert int(en.period_quantiles(ens).sel(period="precession").bodies) == \
        len(ens) - len(ens.invalid)


# --- statistics ----------------------------------------------------------------------
def test_diagnose_many_agrees_with_the_scalar_diagnosis():
    rng = np.random.default_rng(11)
    r = np.sort(rng.uniform(0.3, 1.0, (3000, 2)), axis=1)
    M = np.column_stack([r, np.ones(len(r))])
    M = M[M[:, 0] + M[:, 1] >= 1]
    W = rng.normal(size=(len(M), 3))
    W[:3] = [0, 0, 1]                      # principal-axis spin
    M[3] = [1.0, 1.0, 1.5]                 # axisymmetric
    W[4] = 0.0                             # at rest
    W[5] = [0.0, 1.0, 0.0]                 # intermediate axis: separatrix
    d = diagnose_many(M, W)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for i in range(len(M)):
            s = diagnose_principal(M[i], W[i])
            assert d["regime"][i] == s.regime
            for k in ("polhode", "precession", "rotation", "spin"):
                if k in s.periods:
                    assert d[k][i] == pytest.approx(s.periods[k], rel=1e-13)
                else:
                    assert np.isnan(d[k][i])
            if s.nutation_range is not None:
                np.testing.assert_allclose([d["nutation_min"][i], d["nutation_max"][i]],
                                           s.nutation_range, atol=1e-13)
    assert set(d["regime"]) >= {"SAM", "LAM", "PA-short", "axisymmetric", "at-rest",
                                "separatrix"}


def test_regime_fractions_analytic_and_from_the_propagated_motion():
    # three SAM and two LAM tumblers: the analytic labels and att.classify agree
    ers = [1.02, 1.03, 1.01, 1.3, 1.45]

    def sampler(rng, n):
        return {"energy_ratio": np.array(ers[1:])}

    ens = att.Ensemble.sample(5, rng=0, epoch=EPOCH, mean=dict(APOPHIS, energy_ratio=ers[0]),
                              sampler=sampler)
    assert en.regime_fractions(ens) == {"SAM": 0.6, "LAM": 0.4}
    t = np.linspace(0.0, 40 * 86400.0, 1200)
    eph = att.propagate(ens, t)
    assert en.regime_fractions(eph) == {"SAM": 0.6, "LAM": 0.4}


def test_period_quantiles_match_numpy_on_the_scalar_periods():
    ens = att.Ensemble.sample(300, rng=5, epoch=EPOCH, mean=APOPHIS,
                              sigma={"ratio_a": 0.02, "energy_ratio": 0.003})
    pq = en.period_quantiles(ens, q=[0.1, 0.5, 0.9])
    rot = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for b, s in zip(ens.bodies, ens.states):
            if b is not None:
                rot.append(diagnose(b, s).periods["rotation"])
    np.testing.assert_allclose(pq.sel(period="rotation").values,
                               np.quantile(rot, [0.1, 0.5, 0.9]), rtol=1e-12)
    assert int(pq.sel(period="rotation").bodies) == len(rot)


def test_attitude_spread_against_scipy_rotations():
    ens = att.Ensemble.sample(20, rng=9, epoch=EPOCH, mean=APOPHIS,
                              sigma={"precession_period": 0.05 * u.h})
    t = Time(EPOCH, scale="tdb") + np.linspace(0, 20, 21) * u.day
    eph = att.propagate(ens, t)
    spread = en.attitude_spread(eph)
    assert spread.dims == ("body", "time")
    np.testing.assert_array_equal(spread.values[0], 0.0)          # q - q is exactly 0
    r = Rotation.from_quat(eph.dataset.quaternion.values[7])
    r0 = Rotation.from_quat(eph.dataset.quaternion.values[0])
    # 4 atan2 of the chords against scipy's product and magnitude: a few operations on
    # unit quaternions, times the 4 (the spread was 2 arccos|q.q0|, good to 3e-8 only)
    assert_agree(spread.values[7], (r0.inv() * r).magnitude(), ulps=4 * FEW_OPS,
                 magnitude=1.0, what="spread")
    # a period error dP makes the phase drift grow ~ linearly: the spread grows
    sq = en.spread_quantiles(eph, q=[0.5, 0.9])
    assert sq.dims == ("quantile", "time")
    assert sq.sel(quantile=0.5).values[-1] > 5 * sq.sel(quantile=0.5).values[2]
    single = att.propagate(ens.bodies[0], ens.states[0], t)
    # the nominal run alone against body 0 of the batch: two paths of the exact solution
    assert_agree(en.attitude_spread(eph, nominal=single).values, spread.values,
                 ulps=4 * EXACT_SOLUTION, magnitude=1.0, what="spread")


def test_diagnostics_of_an_ensemble_with_an_invalid_body():
    from attitude.analysis.diagnostics import add_diagnostics

    with pytest.warns(en.InvalidBodiesWarning):
        ens = att.Ensemble.from_arrays(principal_moments=[[1, 2, 2.5], [1, 1, 3], [2, 2.5, 4]],
                                       omega_body=[[0.1, 0, 0.2]] * 3, epoch=EPOCH)
    t = np.linspace(0.0, 500.0, 300)
    ds = add_diagnostics(att.propagate(ens, t)).dataset
    assert np.isnan(ds.nutation_angle.values[1]).all() and np.isnan(ds.period_precession[1])
    one = add_diagnostics(att.propagate(ens.bodies[2], ens.states[2], t)).dataset
    # batch against single (exact solution, then atan2 of rotation-matrix elements): ulps
    # of the unit vectors the angle comes from
    assert_agree(ds.nutation_angle.values[2], one.nutation_angle.values,
                 ulps=EXACT_SOLUTION + FEW_OPS, magnitude=1.0, what="nutation angle")
    assert float(ds.period_precession[2]) == pytest.approx(float(one.period_precession),
                                                           rel=1e-12)


def test_a_single_body_with_chunks_runs_in_this_process():
    body = att.RigidBody.from_principal_moments([1.0, 2.0, 3.0])
    state = att.AttitudeState(EPOCH, Rotation.identity(), [0.1, 0.0, 0.2])
    eph = att.propagate(body, state, [0.0, 1.0, 2.0], chunks=3)
    assert eph.dataset.quaternion.dims == ("time", "quaternion_component")
    assert isinstance(eph.dataset.quaternion.data, np.ndarray)


@pytest.mark.parametrize("dec", [-75.0, 89.99])
def test_isotropic_direction_error_is_the_same_at_the_pole(dec):
    mean = dict(APOPHIS, angular_momentum_dec=dec * u.deg)
    ens = att.Ensemble.sample(8001, rng=1, epoch=EPOCH, mean=mean,
                              sigma={"angular_momentum_direction": 3 * u.deg})
    # the inertial L of the propagated bodies, against the mean direction
    L = att.propagate(ens, [0.0]).dataset.angular_momentum.values[:, 0]
    L /= np.linalg.norm(L, axis=1, keepdims=True)
    angle = np.degrees(np.arccos(np.clip(L[1:] @ L[0], -1.0, 1.0)))
    # a 2-D normal error of 3 deg per axis: Rayleigh radius, RMS 3 sqrt(2), median
    # 3 sqrt(2 ln 2); 8000 draws give them to ~1 %
    assert np.sqrt(np.mean(angle ** 2)) == pytest.approx(3 * np.sqrt(2), rel=0.03)
    assert np.median(angle) == pytest.approx(3 * np.sqrt(2 * np.log(2)), rel=0.03)
    # no preferred azimuth: the mean offset across the line of sight vanishes (standard
    # error 0.0006 per axis; along it, the mean is -(1 - cos rho) ~ -sigma^2)
    d = (L[1:] - L[0]).mean(axis=0)
    assert np.linalg.norm(d - (d @ L[0]) * L[0]) < 0.002
    assert d @ L[0] == pytest.approx(-np.radians(3.0) ** 2, rel=0.05)
    with pytest.raises(att.InvalidStateError, match="angular_momentum_direction"):
        att.Ensemble.sample(3, epoch=EPOCH, mean=mean, sigma={"angular_momentum_direction": -1})


def test_masses_travel_with_the_bodies_for_torques_that_need_them():
    """The heavy top takes its mass from the body: chunked (ensemble) and direct batch
    propagation agree, and the ensemble keeps the masses."""
    from attitude.model.torques import HeavyTopPivot

    bodies = [att.RigidBody.from_principal_moments([1.0, 1.0, 0.5], mass=2.0),
              att.RigidBody.from_principal_moments([1.0, 1.0, 0.6], mass=3.0)]
    states = [att.AttitudeState(EPOCH, Rotation.from_euler("x", 0.3), [0.0, 0.0, 30.0])] * 2
    top = [HeavyTopPivot(pivot_to_com=[0.0, 0.0, 0.1])]
    t = np.linspace(0.0, 1.0, 5)
    ref = att.propagate(bodies, states, t, torques=top, method="integrator")
    lazy = att.propagate(bodies, states, t, torques=top, method="integrator", chunks=1)
    assert lazy.dataset.status.values.tolist() == [0, 0]
    # one body per chunk against the batch of two: each body has its own adaptive DOP853
    # steps, but an ulp of difference in the torques (BLAS, SIMD) can flip a step
    # acceptance, after which the two runs differ by up to the integrator's tolerance
    rtol = DEFAULT_RTOL   # the integrator's default
    assert_agree(lazy.dataset.quaternion.values, ref.dataset.quaternion.values,
                 ulps=INTEGRATOR_PATHS * rtol / EPS, magnitude=1.0, what="quaternion")
    ens = att.Ensemble.from_bodies(bodies, states)
    assert ens.mass.tolist() == [2.0, 3.0] and ens.bodies[1].mass == 3.0


def test_classify_ensemble_reads_a_dask_backed_ephemeris_one_chunk_at_a_time(monkeypatch):
    """A lazy ephemeris is classified chunk by chunk along ``body`` (never loaded whole)
    and gives the classes of the in-memory one, invalid bodies included."""
    from attitude.analysis import statistics

    rng = np.random.default_rng(4)
    n = 10
    moments = np.tile([1.0, 2.0, 3.0], (n, 1))
    moments[3] = [1.0, 1.0, 5.0]                            # violates the triangle rule
    w = rng.normal(size=(n, 3)) * [0.3, 0.05, 0.3]          # both sides of the separatrix
    with pytest.warns(en.InvalidBodiesWarning):
        ens = att.Ensemble.from_arrays(principal_moments=moments, omega_body=w, epoch=EPOCH)
    t = np.linspace(0.0, 400.0, 400)
    eager = en.classify_ensemble(att.propagate(ens, t))
    seen = []

    class Spy(att.Ephemeris):
        def __init__(self, ds):
            seen.append(ds.sizes["body"])
            assert not any(hasattr(v.data, "dask") for v in ds.data_vars.values())
            super().__init__(ds)

    monkeypatch.setattr(statistics, "Ephemeris", Spy)
    lazy = en.classify_ensemble(att.propagate(ens, t, chunks=4))
    assert seen == [4, 4, 2]                                  # one chunk in memory at a time
    assert lazy.regime.values.tolist() == eager.regime.values.tolist()
    assert {"SAM", "LAM", "invalid"} <= set(eager.regime.values.tolist())
    assert lazy.reason.values.tolist() == eager.reason.values.tolist()
    # confidence and margin are smooth functions of ephemerides that agree to a few ulps
    # (chunks against the whole); 1e-9 relative allows a condition number of 1e5
    for name in ("confidence", "margin"):
        np.testing.assert_allclose(lazy[name].values, eager[name].values, rtol=1e-9,
                                   atol=1e-9 * np.nanmax(np.abs(eager[name].values)))


def test_an_infinite_table_value_is_an_invalid_row_without_a_numpy_warning():
    """A damaged moment (1e999 reads as inf) marks its row invalid, as NaN does, instead
    of numpy's "invalid value encountered in multiply" from inf * 0 in the tensor."""
    from attitude.model.tables import ensemble_columns
    text = "A,B,C,wx,wy,wz\n1,2,3,0,0,1\n1,1e999,3,0,0,1\n"
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        inertia, _, _, _ = ensemble_columns(io.StringIO(text))
        with pytest.warns(att.InvalidBodiesWarning):
            ens = att.Ensemble.from_table(io.StringIO(text), epoch="2030-01-01")
    assert np.isnan(inertia[1, 1, 1]) and np.all(np.isfinite(inertia[0]))
    assert sorted(ens.invalid) == [1]

"""The tumbler (NPA) convex inversion against synthetic truth.

The lightcurves come from the photometry wing (``att.lightcurve`` of a homogeneous
ellipsoid ``Polyhedron`` on the exact torque-free ephemeris of ``att.propagate``), not from
the inversion's own model: the fit has to bridge a different shape representation (a
triangulated ellipsoid against log areas over a Gaussian image) as a real inversion
does, with 0.01 mag of Gaussian noise.
"""

from __future__ import annotations

import time

import astropy.units as u
import numpy as np
import pytest
from astropy.time import Time
from scipy.spatial.transform import Rotation

import attitude as att
from attitude.foundations.errors import PhotometryError
from attitude.inversion import ConvexModel, GaussianImage, ObservedLightcurve
from attitude.inversion import tumbler as tb
from attitude.inversion.config import load_inversion, run_inversion
from attitude.inversion.invert import _example_tumbler
from attitude.model.freebody import diagnose_many
from attitude.model.sampling import tumbling_state
from attitude.model.state import AttitudeState

from . import inversion_benchmark

EPOCH = Time("2029-01-01", scale="tdb")
#: Apophis-like (Pravec et al. 2014): L toward ecliptic (250, -75) deg, E/E0 1.024,
#: A/C 0.61, B/C 0.965, P_phi 27.38 h (then P_psi 264.6 h).
APOPHIS = (np.radians(250.0), np.radians(-75.0), 1.024, 0.61, 0.965, 27.38 * 3600.0, 0.7,
           2.1)


def synthetic(truth, t, noise=0.01, seed=1):
    """Relative lightcurves (one per day) of the homogeneous ellipsoid of the truth's
    moments tumbling in the truth's state, and their magnitudes."""
    moments, q, w, bad = tumbling_state(*truth)
    assert not bad
    body = att.RigidBody.from_principal_moments(moments[0])
    state = AttitudeState(EPOCH, Rotation.from_quat(q[0]), w[0], frame="ECLIPJ2000")
    eph = att.propagate(body, state, t)
    geom = inversion_benchmark().tumbler_geometry(t)
    sun, seen = geom.sun, geom.observer
    shape = att.Polyhedron.ellipsoid_from_moments(moments[0], subdivisions=4)
    lc = att.lightcurve(eph, shape, att.Geometry(sun=sun, observer=seen), law="ls-lambert")
    mag = (-2.5 * np.log10(np.asarray(lc.dataset["flux"]))
           + noise * np.random.default_rng(seed).standard_normal(t.size))
    y = 10.0 ** (-0.4 * mag)
    sigma = y * max(noise, 0.01) * np.log(10.0) / 2.5     # noise-free data: 0.01 mag weights
    day = np.floor(t / 86400.0).astype(int)
    obs = [ObservedLightcurve(EPOCH, t[day == k], y[day == k],
                              att.Geometry(sun=sun[day == k], observer=seen[day == k]),
                              sigma=sigma[day == k]) for k in np.unique(day)]
    return obs, mag


def angle_between(lon_lat_a, lon_lat_b):
    """deg between two (longitude, latitude) directions in deg, as atan2(|a x b|, a.b):
    accurate near zero (an arccos of the dot product resolves no better than ~1e-6 deg:
    sqrt(2 eps))."""
    def unit(lon_lat):
        lon, lat = np.radians(lon_lat)
        return np.array([np.cos(lat) * np.cos(lon), np.cos(lat) * np.sin(lon), np.sin(lat)])
    a, b = unit(lon_lat_a), unit(lon_lat_b)
    return float(np.degrees(np.arctan2(np.linalg.norm(np.cross(a, b)), a @ b)))


def one_percent_off(truth):
    """Every parameter 1 % off; B/C down rather than up so that the start stays a SAM
    (1 % up would put E/E0 = 1.034 past the separatrix C/B = 1.026)."""
    return np.array(truth) * [1.01, 1.01, 1.01, 1.01, 0.99, 1.01, 1.01, 1.01]


# --- the pieces -------------------------------------------------------------------------

@pytest.mark.parametrize("regime, p", [
    ("SAM", [1.0, -0.5, 1.024, 0.61, 0.965, 98568.0, 0.7, 2.1]),
    ("LAM", [4.0, 0.3, 1.3, 0.5, 0.8, 36000.0, -1.0, 0.4]),
])
def test_internal_parameters_round_trip(regime, p):
    u_ = tb.to_internal(p, regime)
    assert np.all((u_[2:4] > 0) & (u_[2:4] < 1)) and 0.5 < u_[4] < 1
    # the map is a few flops: a round trip to a few ulps of the largest input
    np.testing.assert_allclose(tb.to_physical(u_, regime), p, rtol=1e-14, atol=1e-15)


def test_directions_are_the_propagated_attitude():
    """The body-frame directions of the model are the exact torque-free attitude that
    att.propagate gives for the state of the same parameters."""
    obs, _ = synthetic(APOPHIS, np.arange(0.0, 3 * 86400.0, 3600.0), noise=0.0)
    model = ConvexModel(obs, GaussianImage(rows=2, degree=1))
    o, s = tb.tumbler_directions(model, APOPHIS)
    moments, q, w, _ = tumbling_state(*APOPHIS)
    state = AttitudeState(EPOCH, Rotation.from_quat(q[0]), w[0], frame="ECLIPJ2000")
    eph = att.propagate(att.RigidBody.from_principal_moments(moments[0]), state,
                        model.time)
    r = Rotation.from_quat(np.asarray(eph.dataset["quaternion"]))
    # the same closed form on both sides (documented accuracy ~1e-12 over 3 days)
    np.testing.assert_allclose(o, r.inv().apply(model.observer), atol=1e-10)
    np.testing.assert_allclose(s, r.inv().apply(model.sun), atol=1e-10)


@pytest.mark.parametrize("regime", ["SAM", "LAM"])
def test_energy_for_period_ratio_inverts_the_periods(regime):
    a, b = np.array([0.61, 0.5, 0.8]), np.array([0.965, 0.8, 0.9])
    er = np.array([1.024, 1.1, 1.05]) if regime == "SAM" else np.array([1.3, 1.5, 1.15])
    moments, _, w, bad = tumbling_state(0.0, 0.0, er, a, b, 3600.0)
    assert not bad
    d = diagnose_many(moments, w)
    found = tb.energy_for_period_ratio(a, b, d["rotation"] / d["precession"], regime)
    # 48 bisections of the unit interval: 2^-48 of the mode's energy range
    np.testing.assert_allclose(found, er, rtol=0, atol=1e-12)


def test_period_pairs_hold_the_true_pair():
    """Of a SAM of P_phi 4 h, P_psi 21.34 h, the lightcurve's fundamentals are P_phi and
    1 / (2/P_phi - 2/P_psi); the true pair is among the candidates."""
    p_phi, p_psi = 4.0 * 3600, 21.34 * 3600
    p1 = 1.0 / (2.0 / p_phi - 2.0 / p_psi)
    pairs = tb.period_pairs([p1, p_phi])
    assert any(abs(a / p_phi - 1) < 1e-12 and abs(b / p_psi - 1) < 1e-12 for a, b in pairs)


def test_bad_starts_are_refused():
    model = tb.example_model()
    with pytest.raises(PhotometryError, match="valid SAM"):
        tb.fit_tumbler(model, [0.0, 0.0, 1.2, 0.61, 0.965, 3600.0, 0.0, 0.0], regime="SAM")
    with pytest.raises(PhotometryError, match="8 finite"):
        tb.fit_tumbler(model, [0.0, 0.0, 1.02])
    with pytest.raises(PhotometryError, match="unknown parameter"):
        tb.fit_tumbler(model, tb.EXAMPLE_STATE, free=["energy"])
    with pytest.raises(PhotometryError, match="unknown"):
        att.invert([], rotation="tumbler")


# --- (a) from a start 1 % off -----------------------------------------------------------

def check_apophis(fit, truth, runtime):
    p = fit.parameters
    assert fit.regime == "SAM"
    assert abs(p["precession_period"] / truth[5] - 1) < 1e-3
    assert angle_between(fit.pole, np.degrees(truth[:2])) < 3.0
    assert abs(p["energy_ratio"] - truth[2]) < 3 * fit.uncertainties["energy_ratio"]
    # the noise level: chi2 per point near 1 (the shape series' own misfit adds a little)
    assert 0.8 < fit.rms < 1.3
    print(f"\nApophis-like fit: {runtime:.1f} s, P_phi {p['precession_period'] / 3600:.5f} h "
          f"(truth {truth[5] / 3600:.5f}), L {fit.pole}, E/E0 {p['energy_ratio']:.5f} +- "
          f"{fit.uncertainties['energy_ratio']:.5f}, shape ratios {fit.shape_ratios}")


def test_apophis_like_from_a_start_one_percent_off_hourly():
    """The fast version: 40 days hourly (about 15 s here)."""
    obs, _ = synthetic(APOPHIS, np.arange(0.0, 40 * 86400.0, 3600.0))
    model = ConvexModel(obs, GaussianImage(rows=5, degree=3))
    t0 = time.perf_counter()
    fit = tb.fit_tumbler(model, one_percent_off(APOPHIS))
    check_apophis(fit, APOPHIS, time.perf_counter() - t0)
    # homogeneity: the fitted convex shape of a uniform ellipsoid has its moment ratios
    # (the degree-3 series of the ellipsoid's log areas is good to about 1 %)
    assert abs(fit.shape_ratios[0] - APOPHIS[3]) < 0.02
    assert abs(fit.shape_ratios[1] - APOPHIS[4]) < 0.02


@pytest.mark.slow
def test_apophis_like_from_a_start_one_percent_off():
    """40 days at 30 min cadence with 0.01 mag noise (about 30 s here)."""
    obs, _ = synthetic(APOPHIS, np.arange(0.0, 40 * 86400.0, 1800.0))
    model = ConvexModel(obs, GaussianImage(rows=5, degree=3))
    t0 = time.perf_counter()
    fit = tb.fit_tumbler(model, one_percent_off(APOPHIS))
    check_apophis(fit, APOPHIS, time.perf_counter() - t0)


# --- the API ----------------------------------------------------------------------------

def test_invert_tumbling_gives_the_state_and_its_alternatives():
    obs, truth = tb.example_model(), np.array(tb.EXAMPLE_STATE)
    y = obs.brightness_of(tb.EXAMPLE_SHAPE, *tb.tumbler_directions(obs, truth))
    obs = list(tb.with_brightness(obs, y).observations)
    start = dict(zip(tb.PARAMETERS, truth * [1, 1, 1.001, 1, 1, 1.0005, 1, 1]))
    start["angular_momentum_ra"] = np.degrees(truth[0]) * u.deg
    res = att.invert(obs, rotation="tumbling", start=start, rows=4, degree=2)
    assert res.regime == "SAM"
    # noise-free data of the model itself: the truth to the optimiser's tolerance
    assert abs(res.period / truth[5] - 1) < 1e-6
    assert angle_between(res.pole, np.degrees(truth[:2])) < 1e-3
    assert [text.split()[0] for _, text in res.alternatives] == ["LAM", "mirror"]
    assert all(chi2 > res.chi2 for chi2, _ in res.alternatives)
    # the state reproduces the fitted parameters: its L and its periods
    moments = res.body.principal_moments
    d = att.diagnose(res.body, res.state)
    assert d.regime == "SAM"
    assert abs(d.periods["precession"] / res.period - 1) < 1e-9
    L = res.state.attitude.apply(moments * res.state.omega_body)
    lon = np.degrees(np.arctan2(L[1], L[0])) % 360
    lat = np.degrees(np.arcsin(L[2] / np.linalg.norm(L)))
    assert angle_between((lon, lat), res.pole) < 1e-9
    np.testing.assert_allclose(moments[:2] / moments[2], [res.fit.parameters["ratio_a"],
                                                          res.fit.parameters["ratio_b"]],
                               rtol=1e-12)


def test_scenario_accepts_a_tumbling_start(tmp_path):
    path = tmp_path / "t.toml"
    path.write_text('[scenario]\nname = "t"\n[inversion]\nlightcurves = "lcs"\n'
                    'rotation = "tumbling"\n[inversion.start]\n'
                    'angular_momentum_ra = "250 deg"\nangular_momentum_dec = "-75 deg"\n'
                    'energy_ratio = 1.024\nratio_a = 0.61\nratio_b = 0.965\n'
                    'precession_period = "27.38 h"\nphi0 = 0.7\npsi0 = 2.1\n')
    cfg = load_inversion(path).inversion
    assert cfg["rotation"] == "tumbling"
    assert cfg["start"]["precession_period"] == pytest.approx(27.38 * 3600, rel=1e-15)
    assert cfg["start"]["angular_momentum_ra"] == pytest.approx(np.radians(250.0), rel=1e-15)


# --- (b) from the data alone ------------------------------------------------------------

@pytest.mark.slow
def test_short_period_tumbler_from_the_data_alone():
    """A SAM of P_phi 4 h, P_psi 21.3 h: 12 nights of 8 h at 15 min cadence.  The two
    fundamentals of fit_periods, the period pairs, about 1500 ranked starts, the best
    polished and fitted (about two minutes here)."""
    a, b = 0.6, 0.9
    internal = [np.radians(60.0), np.radians(40.0), 0.4, (a - (1 - b)) / (2 * b - 1), b,
                4 * 3600.0, 0.5, 1.3]
    truth = tb.to_physical(internal, "SAM")
    t = (np.arange(12)[:, None] * 86400.0 + np.arange(0, 8 * 3600, 900.0)[None]).ravel()
    obs, _ = synthetic(truth, t)
    t0 = time.perf_counter()
    res = att.invert(obs, rotation="tumbling", rows=5, degree=3, max_iterations=40)
    runtime = time.perf_counter() - t0
    print(f"\ndata alone: {runtime:.0f} s, {res.regime} P_phi {res.period / 3600:.5f} h, "
          f"L {res.pole}, alternatives {res.alternatives}")
    assert res.regime == "SAM"
    assert abs(res.period / truth[5] - 1) < 0.01
    assert angle_between(res.pole, np.degrees(truth[:2])) < 10.0


def test_scenario_runs_a_tumbler(tmp_path):
    """`attitude invert` of a tumbling scenario: the DAMIT file of the example tumbler,
    its start, the outputs (a state file with the fitted moments)."""
    obs, truth = _example_tumbler()
    lines = [str(len(obs))]
    for o in obs:
        sun, seen = o.sun_and_observer()
        lines.append(f"{len(o)} 0")
        lines += [" ".join(repr(float(x)) for x in (jd, y, *s, *v))
                  for jd, y, s, v in zip(o.times.tdb.jd, o.brightness, sun, seen)]
    (tmp_path / "lcs").write_text("\n".join(lines) + "\n")
    start = "\n".join(f"{k} = {float(v)!r}" for k, v in zip(tb.PARAMETERS, truth * [
        1, 1, 1.001, 1, 1, 1.0005, 1, 1]))
    (tmp_path / "t.toml").write_text(
        '[scenario]\nname = "t"\n[inversion]\nlightcurves = "lcs"\ntime_scale = "tdb"\n'
        'rotation = "tumbling"\nrows = 4\ndegree = 2\nalternatives = false\n'
        f"[inversion.start]\n{start}\n"
        '[expect]\nperiod = { value = 2.0, unit = "h", rel_tol = 1e-6 }\n'
        "rms = { max = 1e-6 }\n")
    run = run_inversion(load_inversion(tmp_path / "t.toml"))
    assert run.ok, run.expect
    assert [p.name for p in run.outputs] == ["t_shape.obj", "t_state.toml",
                                             "t_lightcurves.csv"]
    text = (tmp_path / "t_state.toml").read_text()
    assert "principal_moments = [" in text and "shape =" not in text

"""Tests of attitude.classify: every torque-free regime (and from netCDF), constructed
states at each boundary, noisy input, the energy-dissipation sequence of a long-axis
spinner (Explorer 1), chaos (Hyperion, Wisdom, Peale & Mignard 1984) against a regular
synchronous moon, published rotation states (shared/validation/README.md), the report
formats, and bad input.
"""

from __future__ import annotations

import json
import math
import warnings
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import brentq
from scipy.spatial.transform import Rotation

import attitude as att
from attitude.analysis.classification import (
    Classification,
    ClassificationError,
    LyapunovResult,
    Thresholds,
    classification_json,
    classify,
    format_classification,
    initial_state,
    lyapunov_exponent,
)
from attitude.analysis.diagnostics import InsufficientDataError
from attitude.model.freebody import diagnose_principal
from attitude.model.orbit import KeplerOrbit
from attitude.model.torques import ConstantTorque, EnergyDissipation, GravityGradient

EPOCH = "2030-01-01T00:00:00"
ROOT = Path(__file__).resolve().parents[2]

# (moments, principal omega, expected regime)
REGIME_CASES = [
    ([0.61, 0.965, 1.0], [0.02, 0.0, 0.1], "SAM"),
    ([1.0, 2.0, 3.0], [1.0, 0.1, 0.2], "LAM"),
    ([1.0, 2.0, 3.0], [0.0, 0.0, 1.0], "PA-short"),
    ([1.0, 2.0, 3.0], [-1.0, 0.0, 0.0], "PA-long"),
    ([1.0, 2.0, 3.0], [np.sqrt(3.0), 0.0, 1.0], "separatrix"),     # L^2 = 2EB
    ([1.0, 2.0, 3.0], [0.0, 1.0, 0.0], "separatrix"),              # intermediate axis
    ([2.0, 2.0, 3.0], [0.3, 0.1, 1.0], "axisymmetric"),            # oblate, nutating
    ([1.0, 3.0, 3.0], [1.0, 0.3, 0.1], "axisymmetric"),            # prolate, nutating
    ([2.0, 2.0, 3.0], [0.0, 0.0, 1.0], "PA-short"),                # oblate, pure spin
    ([2.0, 2.0, 2.0], [1.0, 0.3, 0.0], "spherical"),
    ([1.0, 2.0, 3.0], [0.0, 0.0, 0.0], "at-rest"),
]


PERIOD_KEYS_OF = {"SAM": {"polhode", "precession", "rotation"},
                  "LAM": {"polhode", "precession", "rotation"},
                  "axisymmetric": {"polhode", "precession", "rotation"},
                  "PA-short": {"spin"}, "PA-long": {"spin"}, "spherical": {"spin"},
                  "separatrix": set(), "at-rest": set()}


def _torque_free(moments, w, *, cycles=6.0, samples=1201, rotated=True):
    if rotated:
        R = Rotation.random(random_state=3).as_matrix()
        body = att.RigidBody(R @ np.diag(moments) @ R.T)
    else:
        body = att.RigidBody.from_principal_moments(moments)
    state = att.AttitudeState(EPOCH, Rotation.random(random_state=5),
                              body.body_to_principal.inv().apply(w))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", att.NearSeparatrixWarning)
        d = att.diagnose(body, state)
    P = max(d.periods.values()) if d.periods else 10.0
    return body, state, d, att.propagate(body, state, np.linspace(0.0, cycles * P, samples))


# --- every regime ---------------------------------------------------------------------------


@pytest.mark.parametrize("moments, w, regime", REGIME_CASES,
                         ids=[f"{c[2]}-{i}" for i, c in enumerate(REGIME_CASES)])
def test_every_torque_free_regime(moments, w, regime, tmp_path):
    """Each regime of the exact solution, classified from the propagated ephemeris and
    from the same ephemeris read back from netCDF, with a positive margin, a high
    confidence, and the periods of att.diagnose to 1e-6."""
    body, state, d, eph = _torque_free(moments, w)
    path = eph.to_netcdf(tmp_path / "eph.nc")
    for source in (eph, att.Ephemeris.from_netcdf(path)):
        c = classify(source)
        assert isinstance(c, Classification)
        assert c.regime == regime
        assert c.stationary and len(c.segments) == 1 and c.segments[0][2] == regime
        assert c.margin > 0 and c.confidence > 0.95
        assert set(c.periods) == PERIOD_KEYS_OF[regime]
        for key, P in c.periods.items():
            if d.regime == regime:         # a rotated principal-axis spin has a 1e-17 wobble
                assert P == pytest.approx(d.periods[key], rel=1e-6)
    if regime in ("SAM", "LAM"):
        assert c.boundary in ("separatrix", "PA-short", "PA-long")
        assert c.reference_axis == ("C" if regime == "SAM" else "A")
        assert c.excitation == pytest.approx(d.excitation, rel=1e-9)
        lo, hi = d.nutation_range
        assert c.nutation_range[1] == pytest.approx(max(lo, hi), abs=2e-3)   # sampled max


def test_regime_labels_agree_with_diagnose_on_random_states():
    rng = np.random.default_rng(4)
    moments = [1.0, 1.7, 2.2]
    for _ in range(12):
        w = rng.normal(size=3)
        d = diagnose_principal(moments, w)
        P = d.periods["polhode"]
        body = att.RigidBody.from_principal_moments(moments)
        state = att.AttitudeState(EPOCH, Rotation.identity(), w)
        c = classify(att.propagate(body, state, np.linspace(0.0, 3.2 * P, 641)))
        assert c.regime == d.regime
        assert c.separatrix_distance == pytest.approx(d.separatrix_distance, rel=1e-9)


# --- boundaries -------------------------------------------------------------------------------


def _omega_at_m1(m1):
    """Principal rates for moments (1, 2, 3) with omega_2 = 0 and separatrix distance
    m1: SAM ``m1 = 1 - w1^2/3``, LAM ``m1 = 3/w1^2 - 1`` for ``w3 = 1``."""
    w1 = math.sqrt(3.0 * (1.0 - m1)) if m1 >= 0 else math.sqrt(3.0 / (1.0 + m1))
    return [w1, 0.0, 1.0]


def _omega_at_nutation(theta_max):
    """Rates for moments (1, 2, 3), SAM, whose nutation cycle reaches ``theta_max`` from
    C: ``sin^2 theta_max = 4 w1^2 / (w1^2 + 9)`` for ``w2 = 0, w3 = 1``."""
    s2 = math.sin(theta_max) ** 2
    return [math.sqrt(9.0 * s2 / (4.0 - s2)), 0.0, 1.0]


def _classify_state(w, moments=(1.0, 2.0, 3.0), cycles=4.0, **kw):
    body = att.RigidBody.from_principal_moments(moments)
    state = att.AttitudeState(EPOCH, Rotation.identity(), w)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", att.NearSeparatrixWarning)
        P = att.diagnose(body, state).periods.get("polhode", 10.0)
    return classify(att.propagate(body, state, np.linspace(0.0, cycles * P, 801)), **kw)


@pytest.mark.parametrize("m1", [1e-4, -1e-4])
def test_at_the_separatrix_threshold_the_answer_is_not_confident(m1):
    """Exactly at |m1| = separatrix threshold: margin ~0 and confidence ~0.5 whatever
    the label, and the boundary named is the other side."""
    th = Thresholds()
    c = _classify_state(_omega_at_m1(m1), require_periods=False)
    assert c.regime in ("separatrix", "SAM" if m1 > 0 else "LAM")
    assert abs(c.margin) < 1e-2 * th.separatrix and c.margin_units == "1"
    assert 0.4 < c.confidence < 0.6
    other = {"separatrix": "SAM" if m1 > 0 else "LAM"}.get(c.regime, "separatrix")
    assert c.boundary == other


def test_on_the_separatrix_reports_it_with_a_small_margin():
    c = _classify_state(_omega_at_m1(1e-9), require_periods=False)
    assert c.regime == "separatrix" and c.boundary == "SAM"
    assert 0 < c.margin <= 1e-4 and c.decided_by == "separatrix"
    assert c.periods == {}
    # just outside the band: SAM, with a margin of the same size, and not sure of itself
    c = _classify_state(_omega_at_m1(1.2e-4))
    assert c.regime == "SAM" and c.boundary == "separatrix"
    assert 0 < c.margin < 3e-5 and c.confidence < 0.9


def test_at_the_principal_axis_threshold():
    th = Thresholds()
    c = _classify_state(_omega_at_nutation(th.principal_axis_angle))
    assert c.regime in ("PA-short", "SAM")
    assert abs(c.margin) < 1e-6 and c.margin_units == "rad"
    assert 0.4 < c.confidence < 0.6
    c = _classify_state(_omega_at_nutation(0.5 * th.principal_axis_angle))
    assert (c.regime, c.boundary) == ("PA-short", "SAM")
    assert c.margin == pytest.approx(0.5 * th.principal_axis_angle, rel=1e-3)
    assert set(c.periods) == {"spin", "polhode"}          # the wobble is still measured
    c = _classify_state(_omega_at_nutation(2 * th.principal_axis_angle))
    assert (c.regime, c.boundary) == ("SAM", "PA-short")
    assert c.margin == pytest.approx(th.principal_axis_angle, rel=1e-3)


def test_thresholds_are_parameters():
    w = _omega_at_nutation(0.05)
    assert _classify_state(w).regime == "SAM"
    c = _classify_state(w, thresholds=Thresholds(principal_axis_angle=0.1))
    assert c.regime == "PA-short" and c.decided_by == "principal_axis_angle"
    with pytest.raises(ClassificationError, match="separatrix"):
        Thresholds(separatrix=-1.0)


# --- noise ------------------------------------------------------------------------------------


def test_noisy_attitude_still_classified_with_lower_confidence():
    """Attitude noise of 1e-3 rad (random rotation vectors): still SAM with the right
    periods, the noise estimated, the confidence lowered."""
    body, state, d, eph = _torque_free([0.61, 0.965, 1.0], [0.02, 0.0, 0.1], cycles=8,
                                       samples=2001)
    rng = np.random.default_rng(1)
    q = eph.dataset["quaternion"].values
    noisy = (Rotation.from_quat(q) * Rotation.from_rotvec(
        rng.normal(scale=1e-3, size=(q.shape[0], 3)))).as_quat()
    w = eph.dataset["angular_velocity"].values
    w_noisy = w * (1.0 + rng.normal(scale=1e-4, size=w.shape))
    eph_n = att.Ephemeris.from_arrays(eph.time, noisy, w_noisy, body=body,
                                      epoch=state.epoch, frame="ICRF")
    clean, c = classify(eph), classify(eph_n)
    assert c.regime == clean.regime == "SAM"
    assert c.attitude_noise == pytest.approx(1e-3, rel=0.3)
    assert 0.5 < c.confidence < clean.confidence
    assert c.periods["precession"] == pytest.approx(d.periods["precession"], rel=1e-4)
    assert c.periods["polhode"] == pytest.approx(d.periods["polhode"], rel=1e-3)


# --- time-resolved: energy dissipation ----------------------------------------------------------


@pytest.fixture(scope="module")
def dissipating():
    """A long-axis spinner with an energy sink (Explorer 1 in miniature, triaxial so that
    the sequence passes the separatrix): spin about A with 0.03 deg of nutation."""
    body = att.RigidBody.from_principal_moments([1.0, 1.5, 2.0])
    state = att.AttitudeState(EPOCH, Rotation.identity(), [1.0, 2e-4, 2e-4])
    t = np.linspace(0.0, 800.0, 4001)
    eph = att.propagate(body, state, t, torques=[EnergyDissipation(20.0)], rtol=1e-10)
    return body, eph


@pytest.mark.slow      # a long study (> 9 s); the slow tier, which CI runs
def test_dissipation_sequence(dissipating):
    """Issue 5: PA-long -> LAM -> separatrix -> SAM -> PA-short, in that order, with the
    epochs where it changes; the LAM/SAM epoch is where E crosses L^2/2B."""
    body, eph = dissipating
    c = classify(eph)
    seq = [s[2] for s in c.segments]
    assert seq == ["PA-long", "LAM", "separatrix", "SAM", "PA-short"]
    starts = [s[0] for s in c.segments]
    assert starts == sorted(starts) and c.segments[-1][1] == eph.time[-1]
    assert not c.stationary and c.regime == "PA-short"                 # the longest phase
    epochs = [tr.epoch for tr in c.transitions]
    assert epochs == sorted(epochs)
    # E = L^2 / 2B where the osculating separatrix distance changes sign
    E = eph.dataset["kinetic_energy"].values
    L2 = np.sum(eph.dataset["angular_momentum"].values ** 2, axis=-1)
    x = E - L2 / (2 * body.principal_moments[1])
    k = int(np.flatnonzero(np.diff(np.sign(x)))[0])
    t_sep = eph.time[k] + (eph.time[k + 1] - eph.time[k]) * x[k] / (x[k] - x[k + 1])
    sep = [tr for tr in c.transitions if tr.after == "separatrix"][0]
    assert sep.epoch == pytest.approx(t_sep, abs=0.5 * (eph.time[1] - eph.time[0]))
    assert sep.quantity == "separatrix_distance"
    # windows carry their own measured periods: LAM and SAM nutate, PA spins
    w_lam = [w for w in c.windows if w.regime == "LAM"]
    assert w_lam and all("precession" in w.periods for w in w_lam)
    assert "spin" in c.windows[-1].periods


def test_given_window_length(dissipating):
    _, eph = dissipating
    c = classify(eph, window="2 min")
    assert c.window_length == 120.0
    assert [s[2] for s in c.segments] == ["PA-long", "LAM", "separatrix", "SAM", "PA-short"]
    with pytest.raises(ClassificationError, match="window"):
        classify(eph, window="3 kg")
    with pytest.raises(ClassificationError, match="window"):
        classify(eph, window=-1.0)


# --- chaos: Hyperion vs a synchronous moon ---------------------------------------------------

# Hyperion (shared/validation/README.md): Saturn's mu, a = 1.4811e9 m (period 21.28 d),
# e = 0.1 (Wisdom, Peale & Mignard 1984), (B - A)/C = 0.265 (omega_0 = 0.89, WPM 1984);
# A/C = 0.5629 from the 360 x 266 x 205 km ellipsoid (Thomas et al. 2007).
MU_SATURN = 3.7931e16
A_HYPERION = 1.4811e9
HYPERION = att.RigidBody.from_principal_moments(np.array([0.5629, 0.8279, 1.0]) * 5.6e31,
                                               name="Hyperion")


def _moon_run(e, tilt, orbits):
    orbit = KeplerOrbit(mu=MU_SATURN, a=A_HYPERION, e=e)
    n = orbit.mean_motion
    # long axis towards Saturn at periapsis, spin n about C, C tilted from the orbit normal
    state = att.AttitudeState(EPOCH, Rotation.from_euler("x", tilt), [0.0, 0.0, n])
    gg = GravityGradient(orbit=orbit)
    eph = att.propagate(HYPERION, state, np.linspace(0.0, orbits * orbit.period, 40 * orbits + 1),
                        torques=[gg], rtol=1e-10)
    return orbit, gg, eph


def test_hyperion_is_chaotic():
    """Hyperion on its e = 0.1 orbit, started near synchronous spin with its spin axis
    0.1 rad from the orbit normal: chaotic, with a Lyapunov time of the order of the
    orbital period (WPM 1984: a few orbital periods; measured here ~1.2 over 20 orbits,
    ~0.9 over 100 orbits: docs/diagnostics.md)."""
    orbit, gg, eph = _moon_run(0.1, 0.1, 20)
    c = classify(eph, chaos=True, torques=[gg], lyapunov_options={"intervals": 40})
    assert c.regime == "chaotic" and c.decided_by == "lyapunov_efolds"
    ly = c.lyapunov
    assert ly.chaotic and ly.excess_efolds > 8 and c.margin > 3 and c.margin_units == "e-folds"
    assert 0.3 < ly.lyapunov_time / orbit.period < 5
    assert ly.exponent > 3 * ly.control_exponent
    assert "chaotic" in format_classification(c)
    assert classification_json(c)["lyapunov"]["chaotic"] is True


def test_synchronous_moon_is_regular():
    """The same body locked synchronously on a circular orbit (long axis to the planet,
    spin = mean motion about the orbit normal) librates: regular, classified PA-short
    with its spin period equal to the orbital period."""
    orbit, gg, eph = _moon_run(0.0, 0.0, 10)
    ly = lyapunov_exponent(HYPERION, initial_state(eph), [gg], eph.time[-1], intervals=20)
    assert isinstance(ly, LyapunovResult) and not ly.chaotic
    assert ly.exponent < ly.control_exponent and ly.excess_efolds < 0
    c = classify(eph, chaos=ly)
    assert c.regime == "PA-short" and c.lyapunov is ly
    assert c.periods["spin"] == pytest.approx(orbit.period, rel=1e-6)


def test_lyapunov_control_of_a_torque_free_run_is_not_chaotic():
    """Euler-Poinsot motion is integrable: both runs are regular."""
    body = att.RigidBody.from_principal_moments([1.0, 2.0, 3.0])
    state = att.AttitudeState(EPOCH, Rotation.identity(), [0.3, 0.2, 1.0])
    ly = lyapunov_exponent(body, state, [ConstantTorque([0.0, 0.0, 0.0])], 200.0,
                           intervals=16)
    assert not ly.chaotic and abs(ly.excess_efolds) < 1.0
    assert ly.running_exponent.shape == ly.times.shape == (16,)
    with pytest.raises(ClassificationError, match="intervals"):
        lyapunov_exponent(body, state, None, 10.0, intervals=1)
    with pytest.raises(ClassificationError, match="duration"):
        lyapunov_exponent(body, state, None, -1.0)


# --- every propagator -----------------------------------------------------------------------


@pytest.mark.slow      # a long study (> 9 s); the slow tier, which CI runs
def test_classify_numerical_propagators_agree_with_exact():
    from attitude.propagation.propagator import METHODS

    moments, w, _ = REGIME_CASES[0]
    body = att.RigidBody.from_principal_moments(moments)
    state = att.AttitudeState(EPOCH, Rotation.identity(), w)
    d = att.diagnose(body, state)
    t = np.linspace(0.0, 4.2 * d.periods["polhode"], 1201)
    for method in METHODS:
        torques = None if method == "exact" else [ConstantTorque([0.0, 0.0, 0.0])]
        c = classify(att.propagate(body, state, t, torques=torques, method=method))
        assert c.regime == "SAM", method
        rel = 1e-6 if method in ("exact", "integrator") else 1e-3
        for key, P in d.periods.items():
            assert c.periods[key] == pytest.approx(P, rel=rel), (method, key)


# --- published rotation states (shared/validation/README.md) ------------------------------------


def test_apophis_scenario_is_sam_with_published_periods(tmp_path):
    """(99942) Apophis, Pravec et al. 2014: SAM, P_phi = 27.38 +/- 0.07 h,
    P_psi = 263 +/- 6 h (scenarios/apophis.toml, written by ``attitude run`` to a file
    of this test's own, read back)."""
    from attitude.app.cli import main

    out = tmp_path / "apophis.nc"
    assert main(["run", str(ROOT / "scenarios" / "apophis.toml"), "-o", str(out),
                 "--quiet"]) == 0
    c = classify(att.Ephemeris.from_netcdf(out))
    assert c.regime == "SAM" and c.confidence > 0.99
    assert c.periods["precession"] / 3600 == pytest.approx(27.38, abs=0.07)
    assert c.periods["rotation"] / 3600 == pytest.approx(263.0, abs=6.0)
    assert 1.011 < 1.0 / (1.0 - c.excitation * (1 - 0.61)) < 1.037   # E/E0 = 1.024 +/- 0.013


def test_toutatis_period_ratio_only_in_lam():
    """(4179) Toutatis, Hudson & Ostro 1995: P_psi = 5.41 d, P_phi = 7.35 d with moments
    1 : 3.01 : 3.19 (unverified).  That ratio exists only on the LAM side for these
    moments; the state built from it is classified LAM with both periods."""
    moments = np.array([1.0, 3.01, 3.19])
    A, _, C = moments

    def omega(D):                         # omega in the (A, C) plane with L^2/2E = D, |L| = 1
        l1 = (1 / D - 1 / C) / (1 / A - 1 / C)
        return np.array([np.sqrt(l1) / A, 0.0, np.sqrt(1 - l1) / C])

    def ratio(D):
        p = diagnose_principal(moments, omega(D)).periods
        return p["rotation"] / p["precession"] - 5.41 / 7.35

    D = brentq(ratio, 1.0001, 2.9)
    w = omega(D)
    w *= diagnose_principal(moments, w).periods["precession"] / (7.35 * 86400)
    body = att.RigidBody.from_principal_moments(moments)
    state = att.AttitudeState(EPOCH, Rotation.identity(), w)
    c = classify(att.propagate(body, state, np.linspace(0.0, 30 * 86400.0, 2001)))
    assert c.regime == "LAM" and c.reference_axis == "A"
    assert c.periods["rotation"] / 86400 == pytest.approx(5.41, rel=1e-6)
    assert c.periods["precession"] / 86400 == pytest.approx(7.35, rel=1e-6)


def test_earth_rigid_euler_period():
    """Rigid Earth, H = (C - A)/C = 3.273763e-3 (IAG 1999): a principal-axis spin whose
    small free wobble has the Euler period (1 - H)/H = 304.46 sidereal days."""
    H = 3.273763e-3
    body = att.RigidBody.from_principal_moments([1.0 - H, 1.0 - H, 1.0])
    sidereal = 86164.0905
    w3 = 2 * math.pi / sidereal
    state = att.AttitudeState(EPOCH, Rotation.identity(), [1e-6 * w3, 0.0, w3])
    t = np.arange(0.0, 700 * 86400.0, 21600.0)
    c = classify(att.propagate(body, state, t))
    assert c.regime == "PA-short" and c.decided_by == "principal_axis_angle"
    assert c.periods["spin"] == pytest.approx(sidereal, rel=1e-9)
    assert c.periods["polhode"] / sidereal == pytest.approx((1 - H) / H, rel=1e-6)
    assert (1 - H) / H == pytest.approx(304.46, abs=0.01)


# --- report formats and bad input -------------------------------------------------------------


def test_report_formats():
    body, state, d, eph = _torque_free([0.61, 0.965, 1.0], [0.02, 0.0, 0.1])
    c = classify(eph)
    text = format_classification(c)
    assert text.splitlines()[0].startswith("regime          SAM")
    for word in ("decided by", "periods", "precession", "nutation", "excitation",
                 "segments", "thresholds"):
        assert word in text
    doc = classification_json(c, windows=True)
    back = json.loads(json.dumps(doc))
    assert back["regime"] == "SAM" and set(back["periods"]) == set(d.periods)
    assert back["margin"]["units"] in ("1", "rad") and back["segments"][0]["regime"] == "SAM"
    assert len(back["windows"]) == len(c.windows)
    assert back["lyapunov"] is None


def test_batch_and_bad_input():
    body = att.RigidBody.from_principal_moments([1.0, 2.0, 3.0])
    states = [att.AttitudeState(EPOCH, Rotation.identity(), w)
              for w in ([0.0, 0.0, 1.0], [1.0, 0.0, 0.0])]
    batch = att.propagate([body, body], states, np.linspace(0.0, 40.0, 401))
    out = classify(batch)
    assert [c.regime for c in out] == ["PA-short", "PA-long"]
    assert classify(batch, body_index=1).regime == "PA-long"
    # too short to measure a period: a clear error, an AttitudeError and a ValueError
    short = att.propagate(body, states[0], np.linspace(0.0, 2.0, 20))
    with pytest.raises(InsufficientDataError, match="full turn") as info:
        classify(short)
    assert isinstance(info.value, att.AttitudeError) and isinstance(info.value, ValueError)
    assert classify(short, require_periods=False).regime == "PA-short"
    with pytest.raises(InsufficientDataError, match="2 samples"):
        classify(att.propagate(body, states[0], [0.0]))
    with pytest.raises(ClassificationError, match="torques"):
        classify(batch, body_index=0, chaos=True)

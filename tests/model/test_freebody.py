"""Analytic diagnostics (``att.diagnose``) against independent measurements.

* periods measured from propagated series: zero crossings of omega_2 and the
  unwrapped precession angle, from our ephemeris *and* from scipy's DOP853
  (rtol 1e-12), to 1e-9 relative (issue 4, §3);
* the polhode period and the mean precession rate from mpmath (40 digits; the
  rate by quadrature of the kinematic formula, not the Pi closed form);
* published numbers: Earth's rigid Euler period (IAG 1999 H), Apophis (Pravec et
  al. 2014), from ``shared/validation/README.md``.
"""

from __future__ import annotations

import math
import warnings

import mpmath as mp
import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from attitude.foundations.errors import NearSeparatrixWarning
from attitude.model.freebody import diagnose, diagnose_principal
from attitude.model.regimes import PERIOD_KEYS, REGIMES
from attitude.propagation.torquefree import free_rotation

from .. import oracle as O

CASES = {
    "SAM": ([0.61, 0.965, 1.0], [0.05, 0.01, 0.3]),
    "LAM": ([1.0, 2.0, 3.0], [1.0, 0.2, -0.3]),
    "SAM near sep": ([0.2, 0.6, 1.0], [0.6, 0.5, 0.4]),
    "LAM needle": ([0.1, 0.9, 1.0], [2.0, 0.3, 0.1]),
}


def _rhs(I):
    A, B, C = I

    def f(_, y):
        w1, w2, w3, x, yq, z, s = y
        return [(B - C) / A * w2 * w3, (C - A) / B * w3 * w1, (A - B) / C * w1 * w2,
                0.5 * (s * w1 + yq * w3 - z * w2), 0.5 * (s * w2 - x * w3 + z * w1),
                0.5 * (s * w3 + x * w2 - yq * w1), -0.5 * (x * w1 + yq * w2 + z * w3)]
    return f


def _crossings_ours(I, w, P_guess, n):
    """Ascending zero crossings of omega_2 from free_rotation, refined with brentq."""
    t = np.linspace(0.0, (n + 1.2) * P_guess, int(400 * (n + 1.2)))
    w2 = free_rotation(I, [0, 0, 0, 1], w, t)[1][:, 1]
    idx = np.nonzero((w2[:-1] < 0) & (w2[1:] >= 0))[0]

    def f(x):
        return free_rotation(I, [0, 0, 0, 1], w, [x])[1][0, 1]
    return np.array([brentq(f, t[i], t[i + 1], xtol=1e-14, rtol=1e-15) for i in idx])


def _crossings_dop853(I, w, P_guess, n):
    def ev(_, y):
        return y[1]
    ev.direction = 1
    sol = solve_ivp(_rhs(I), (0, (n + 1.2) * P_guess), np.concatenate([w, [0, 0, 0, 1]]),
                    method="DOP853", rtol=1e-13, atol=1e-15, events=ev)
    return sol.t_events[0]


def _precession_angle(q, Lhat, ref):
    """Unwrapped azimuth about L of the reference body axis, from quaternions."""
    e = np.zeros(3)
    e[ref] = 1.0
    u, s = q[:, :3], q[:, 3:]
    tt = 2.0 * np.cross(u, e)
    v = e + s * tt + np.cross(u, tt)
    X = np.cross(Lhat, [0.3, 0.5, 0.8])
    X /= np.linalg.norm(X)
    Y = np.cross(Lhat, X)
    return np.unwrap(np.arctan2(v @ Y, v @ X))


@pytest.mark.parametrize("name", list(CASES))
def test_polhode_period_vs_measured(name):
    """4K/lambda vs zero crossings of omega_2 in our series and in DOP853 (1e-9),
    and vs 4K/lambda in mpmath (1e-13)."""
    I, w = CASES[name]
    d = diagnose_principal(I, w)
    assert d.regime == name.split()[0]
    P = d.periods["polhode"]
    assert d.periods["rotation"] == P
    assert abs(P / O.polhode_period(I, w) - 1) < 1e-13
    for tc in (_crossings_ours(I, w, P, 6), _crossings_dop853(I, w, P, 6)):
        assert len(tc) >= 6
        Pm = (tc[-1] - tc[0]) / (len(tc) - 1)
        assert abs(Pm / P - 1) < 1e-9, (Pm, P)


@pytest.mark.parametrize("name", list(CASES))
def test_precession_period_vs_measured(name):
    """P_phi vs the unwrapped precession angle over 5 polhode periods, from our
    quaternions and from DOP853's (1e-9 relative)."""
    I, w = CASES[name]
    d = diagnose_principal(I, w)
    P, Pphi = d.periods["polhode"], d.periods["precession"]
    ref = d.reference_axis - 1
    assert ref == (2 if d.regime == "SAM" else 0)
    n = 5
    t = np.linspace(0.0, n * P, 4000 * n + 1)
    q = free_rotation(I, [0, 0, 0, 1], w, t)[0]
    sol = solve_ivp(_rhs(I), (0, t[-1]), np.concatenate([w, [0, 0, 0, 1]]), method="DOP853",
                    rtol=1e-13, atol=1e-15, t_eval=t)
    Lhat = np.asarray(I) * w / np.linalg.norm(np.asarray(I) * w)  # q0 = identity
    for qq in (q, sol.y[3:].T):
        phi = _precession_angle(qq, Lhat, ref)
        rate = (phi[-1] - phi[0]) / t[-1]
        assert abs(2 * math.pi / abs(rate) / Pphi - 1) < 1e-9


@pytest.mark.parametrize("name", ["SAM", "LAM"])
def test_mean_precession_rate_vs_mpmath_quadrature(name):
    """<phi'> from Pi(-nu|m)/K against mpmath quadrature of the kinematic rate
    phi' = (L.w - (L.e)(e.w)) / (1 - (L.e)^2) over one polhode period."""
    I, w = CASES[name]
    d = diagnose_principal(I, w)
    ref = d.reference_axis - 1
    P = d.periods["polhode"]
    with mp.workdps(30):
        Im, wm, L2, E2, lam, m, amp, forms, _ = O._setup(I, w)
        signs, u0 = O._find_signs_and_phase(Im, wm, m, lam, amp, forms)
        L = mp.sqrt(L2)

        def rate(t):
            wv = O._rates(lam * t + u0, m, lam, amp, forms, signs)
            Ld = [Im[i] * wv[i] / L for i in range(3)]
            num = mp.fsum(Ld[i] * wv[i] for i in range(3)) - Ld[ref] * wv[ref]
            return num / (1 - Ld[ref] ** 2)
        mean = mp.quad(rate, mp.linspace(0, mp.mpf(P), 9)) / P
    assert abs(float(mean) / d.mean_precession_rate - 1) < 1e-11


def test_nutation_range_vs_series():
    """theta_min/theta_max against the sampled angle between L and the reference axis."""
    for name, (I, w) in CASES.items():
        d = diagnose_principal(I, w)
        ref = d.reference_axis - 1
        t = np.linspace(0.0, d.periods["polhode"], 200001)
        q, ws = free_rotation(I, [0, 0, 0, 1], w, t)
        Lb = np.asarray(I) * ws
        th = np.arccos(np.clip(Lb[:, ref] / np.linalg.norm(Lb, axis=1), -1, 1))
        assert abs(th.min() - d.nutation_range[0]) < 1e-8, name
        assert abs(th.max() - d.nutation_range[1]) < 1e-8, name


def test_regimes_and_fields():
    """Labels, stability, separatrix side, excitation for every regime."""
    exp = [
        ([1, 2, 3], [0.3, 0.2, 1], "SAM", None),
        ([1, 2, 3], [1, 0.2, 0.3], "LAM", None),
        ([1, 2.5, 4], [2, 0.5, 1], "separatrix", None),
        ([1, 2, 3], [0, 0, 2], "PA-short", True),
        ([1, 2, 3], [-2, 0, 0], "PA-long", True),
        ([1, 2, 3], [0, 2, 0], "separatrix", False),
        ([1, 1, 2], [0, 0, 2], "PA-short", True),
        ([1, 2, 2], [2, 0, 0], "PA-long", True),
        ([1, 1, 2], [0.3, 0.2, 1], "axisymmetric", None),
        ([1, 2, 2], [0.3, 0.2, 1], "axisymmetric", None),
        ([1, 1, 2], [0.3, 0.2, 0], "axisymmetric", False),
        ([2, 2, 2], [0.3, 0.2, 1], "spherical", None),
        ([1, 2, 3], [0, 0, 0], "at-rest", None),
    ]
    for I, w, regime, stable in exp:
        d = diagnose_principal(I, w)
        assert d.regime == regime and d.regime in REGIMES, (I, w, d.regime)
        assert d.stable is stable, (I, w)
        assert set(d.periods) <= set(PERIOD_KEYS)
        assert all(isinstance(v, float) and v > 0 for v in d.periods.values())
        if regime == "SAM":
            assert d.separatrix_distance > 0 and set(d.periods) == {"polhode", "precession",
                                                                  "rotation"}
        if regime == "LAM":
            assert d.separatrix_distance < 0
        if regime in ("PA-short", "PA-long", "spherical"):
            assert d.periods == {"spin": pytest.approx(2 * math.pi / np.linalg.norm(w))}
        if regime != "at-rest" and I[0] != I[2]:
            assert 0.0 <= d.excitation <= 1.0
            L = np.linalg.norm(np.multiply(I, w))
            E = 0.5 * np.dot(I, np.square(w))
            assert d.angular_momentum == pytest.approx(L, rel=1e-15)
            assert d.kinetic_energy == pytest.approx(E, rel=1e-15)
            assert d.dynamic_inertia == pytest.approx(L * L / (2 * E), rel=1e-15)
            assert d.energy_ratio == pytest.approx(2 * E * I[2] / L ** 2, rel=1e-14)
    d = diagnose_principal([1, 2, 3], [0, 0, 0])
    assert d.periods == {} and d.nutation_range is None


def test_rotated_principal_spin_is_labelled_principal():
    """A spin about a principal axis given in a rotated body frame keeps a ~1e-17
    wobble from rounding; the label tolerance (rtol_spin = 1e-12) still calls it
    principal-axis spin, while rtol_spin=0 exposes the tiny SAM."""
    w = [1e-17, -2e-17, 0.3]
    assert diagnose_principal([1, 2, 3], w).regime == "PA-short"
    assert diagnose_principal([1, 2, 3], [0.3, 1e-14, 0]).regime == "PA-long"
    assert diagnose_principal([1, 2, 3], [1e-14, 0.3, 0]).regime == "separatrix"
    assert diagnose_principal([1, 2, 3], w, rtol_spin=0).regime == "SAM"
    assert diagnose_principal([1, 2, 3], [0.3, 1e-11, 0]).regime == "LAM"


def test_separatrix_distance_definition():
    """Signed m1 = 1 - k^2 equals the mpmath value from the textbook formulas."""
    for I, w in CASES.values():
        d = diagnose_principal(I, w)
        assert d.separatrix_distance == pytest.approx(O.separatrix_m1(I, w), rel=1e-14)
        assert d.k2 == pytest.approx(1 - abs(d.separatrix_distance), rel=1e-12, abs=1e-15)


def test_near_separatrix_warning():
    with pytest.warns(NearSeparatrixWarning):
        diagnose_principal([1, 2.5, 4], [np.nextafter(2.0, 3.0), 0.5, 1.0])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        diagnose_principal([1, 2, 3], [0.3, 0.2, 1])


def test_earth_euler_period():
    """Rigid-Earth free nutation: (1 - H)/H = 304.46 sidereal days with the IAG 1999
    dynamical ellipticity H = 3.273763e-3 (validation README)."""
    H = 3.273763e-3
    sidereal_day = 86164.0905
    d = diagnose_principal([1 - H, 1 - H, 1.0], [1e-9, 0.0, 2 * math.pi / sidereal_day])
    assert d.regime == "axisymmetric"
    assert d.periods["polhode"] / sidereal_day == pytest.approx(304.46, abs=0.005)


def test_apophis_period_ratio():
    """Apophis (Pravec et al. 2014): SAM, I1/I3 = 0.61, I2/I3 = 0.965, E/E0 = 1.024
    gives P_psi/P_phi of about 9.7 (observed 9.61; validation README), and with
    P_phi = 27.38 h, P_psi within the observed 263 +- 6 h."""
    A, B, C = 0.61, 0.965, 1.0
    x = 0.024 * C ** 2 / (A * (C - 1.024 * A))  # w1^2/w3^2 with w2 = 0 for E/E0 = 1.024
    w = np.array([math.sqrt(x), 0.0, 1.0])
    d = diagnose_principal([A, B, C], w)
    assert d.regime == "SAM" and d.energy_ratio == pytest.approx(1.024, rel=1e-12)
    ratio = d.periods["rotation"] / d.periods["precession"]
    assert ratio == pytest.approx(9.7, abs=0.1)
    scale = d.periods["precession"] / (27.38 * 3600)  # scale rates: P_phi = 27.38 h
    d2 = diagnose_principal([A, B, C], w * scale)
    assert d2.periods["precession"] == pytest.approx(27.38 * 3600, rel=1e-12)
    assert abs(d2.periods["rotation"] / 3600 - 263) < 6


def test_diagnose_with_body_and_state():
    """att.diagnose(body, state) with a body frame that is not the principal frame
    equals diagnose_principal on the principal-frame rates; L inertial matches
    AttitudeState.angular_momentum."""
    att = pytest.importorskip("attitude")
    from scipy.spatial.transform import Rotation

    R = Rotation.from_euler("ZXZ", [0.3, 1.1, -0.7])
    M = R.as_matrix()
    inertia = M @ np.diag([0.61, 0.965, 1.0]) @ M.T
    body = att.RigidBody(inertia)
    wb = M @ np.array([0.02, -0.01, 0.3])  # principal components (0.02, -0.01, 0.3)
    state = att.AttitudeState("2029-04-13", Rotation.from_rotvec([0.1, 0.2, 0.3]), wb)
    d = diagnose(body, state)
    wp = body.body_to_principal.apply(wb)
    dp = diagnose_principal(body.principal_moments, wp)
    assert d.regime == dp.regime == "SAM"
    for k in dp.periods:
        assert d.periods[k] == pytest.approx(dp.periods[k], rel=1e-13)
    assert np.allclose(d.angular_momentum_inertial, state.angular_momentum(body), rtol=1e-13)
    assert att.diagnose is diagnose or att.diagnose(body, state).regime == "SAM"


def test_diagnosis_moved_to_freebody_old_paths_warn():
    """The analytic diagnosis lives in attitude.freebody (the elliptic kernels in
    attitude.elliptic); the earlier paths still work with a DeprecationWarning."""
    import importlib

    import attitude
    import attitude.model.freebody as fb
    import attitude.propagation.torquefree as tf

    for name in ("diagnose", "diagnose_principal", "diagnose_many", "branch_of",
                 "Diagnosis"):
        with pytest.warns(DeprecationWarning, match=f"use attitude.model.freebody.{name}"):
            assert getattr(tf, name) is getattr(fb, name)
    assert attitude.diagnose is fb.diagnose
    old = importlib.import_module("attitude.propagation.elliptic")
    with pytest.warns(DeprecationWarning, match="use attitude.foundations.elliptic.cel"):
        assert old.cel is importlib.import_module("attitude.foundations.elliptic").cel

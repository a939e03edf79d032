"""Lightcurve sessions with unknown zero points: one offset per session, profiled out.

A synthetic lightcurve of a known tumbling state is cut into three sessions (nights),
each shifted by its own arbitrary offset.  Independent references: the same data without
the offsets fitted with a single offset (the state must agree within the stated
uncertainties), the injected offsets themselves, and the covariance of an explicit joint
fit (rotation parameters and offsets together, the Schur complement of its normal
matrix), which the profiled fit must reproduce.
"""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import attitude as att
from attitude.fitting import PARAMETERS, free_parameters
from attitude.fitting.leastsq import project
from tests.fitting.fit_statistics import (
    ALPHA,
    assert_status_is_consistent,
    chi2_bounds,
    chi2_distribution,
)

BODY = att.RigidBody.from_principal_moments([0.6, 0.9, 1.0])
TRUTH = att.AttitudeState("2029-04-13T00:00:00", Rotation.from_rotvec([0.4, -0.3, 0.8]),
                          [0.25, 0.3, 1.0])                          # SAM, rad/s
# 1280 facets: a coarser mesh makes chi^2 kinked (facets crossing the terminator and the
# limb) with spurious local minima about 1 sigma apart, where the solver stops (80
# facets: the fits with and without offsets land 3-4 sigma apart in A/C, B/C)
SHAPE = att.Polyhedron.ellipsoid_from_moments(BODY.principal_moments, subdivisions=3)
GEOM = att.Geometry(sun=[1.0, 0.0, 0.0], observer=[np.cos(0.4), np.sin(0.4), 0.2])
SIGMA = 0.01
# three "nights" of 40 s with gaps between them, 60 magnitudes each
T = np.concatenate([np.linspace(a, a + 40.0, 60) for a in (0.0, 110.0, 230.0)])
NIGHT = np.repeat([0, 1, 2], 60)
OFFSETS = np.array([14.2, 13.55, 15.03])          # arbitrary zero points, mag


def _data(rng):
    q = att.propagate(BODY, TRUTH, T).dataset["quaternion"].values
    clean = att.LightcurveObservations(T, np.zeros(T.size), SIGMA, GEOM, SHAPE)
    return clean.model_magnitudes(q[None])[0] + SIGMA * rng.standard_normal(T.size)


def _guess():
    return att.AttitudeState(TRUTH.epoch, TRUTH.attitude * Rotation.from_rotvec(
        [0.01, -0.008, 0.012]), TRUTH.omega_body * [1.004, 0.996, 1.002])


def _wrap(d, name):
    return (d + np.pi) % (2 * np.pi) - np.pi if name in ("angular_momentum_ra", "phi0",
                                                         "psi0") else d


def test_session_offsets_do_not_change_the_state_and_come_back():
    rng = np.random.default_rng(5)
    mag = _data(rng)
    plain = att.fit(att.LightcurveObservations(T, mag, SIGMA, GEOM, SHAPE), BODY, _guess(),
                    multistart=False)
    shifted = mag + OFFSETS[NIGHT]
    res = att.fit(att.LightcurveObservations(T, shifted, SIGMA, GEOM, SHAPE,
                                             sessions=NIGHT), BODY, _guess(),
                  multistart=False)
    # both converged: the comparison below is of two optima (a fit out of evaluations,
    # even at an acceptable chi2, would compare where the solver happened to stop)
    assert plain.status == res.status == "converged", (plain.message, res.message)
    assert res.regime == plain.regime == "SAM"
    assert res.dof == plain.dof - 2 == T.size - 8 - 3        # three offsets, not one
    # the same noise realisation: the plain fit's state fits the session data as well as
    # the session fit's own, to what the data resolve: their chi2 (the offsets profiled
    # out) differ by less than the (1 - ALPHA) quantile of chi2 with 8 degrees of freedom,
    # a likelihood-ratio test of the 8 parameters.  Not parameter by parameter within a
    # fraction of sigma: the facets make chi2 kinked, with local minima a fraction of a
    # sigma apart, and where each fit stops among them depends on the rounding of the CPU
    def chi2_of(fit):
        r = res.objective.residuals(np.array([fit.parameters[n] for n in res.free]))[0]
        return float(r[:-1] @ r[:-1])                 # without the domain penalty
    # at its own optimum, up to the angles reduced modulo 2 pi (round-off of 2 pi, on a
    # chi2 whose gradient vanishes there)
    assert chi2_of(res) == pytest.approx(res.chi2, rel=1e-9)
    assert abs(chi2_of(plain) - res.chi2) < chi2_distribution.isf(ALPHA, len(PARAMETERS))
    p_true, _ = free_parameters(BODY, TRUTH)
    for name in PARAMETERS:     # both hold the truth within 3 sigma
        assert abs(_wrap(res.parameters[name] - p_true[name], name)) \
            < 3 * res.uncertainties[name], name
        assert abs(_wrap(plain.parameters[name] - p_true[name], name)) \
            < 3 * plain.uncertainties[name], name
    # chi2 of the session fit: the plain fit's minimum plus what the two extra offsets
    # absorb (nothing here: the data were made with one zero point per night)
    lo, hi = chi2_bounds(res.dof, 1)
    assert lo < res.chi2 < hi, (res.chi2, res.dof)
    (lc,) = res.lightcurve_offsets()
    (lc0,) = plain.lightcurve_offsets()
    np.testing.assert_array_equal(lc["session"], [0, 1, 2])
    # the offsets come back: injected + the plain fit's common zero point (the model
    # magnitudes are -2.5 log10 of the flux in arbitrary units), within 3 sigma
    expected = OFFSETS + lc0["offset"][0]
    assert np.all(np.abs(lc["offset"] - expected) < 3 * lc["sigma"]), (lc, expected)
    # sigma of an offset >= that of a weighted mean of its 60 points, and of the order
    assert np.all(lc["sigma"] >= SIGMA / np.sqrt(60) * (1 - 1e-9))
    assert np.all(lc["sigma"] < 10 * SIGMA / np.sqrt(60))


def test_profiled_covariance_equals_the_joint_fit_marginal():
    """The covariance from the profiled residuals equals the rotation block of the
    inverse normal matrix of the joint problem (rotation parameters and three explicit
    offsets), both from central differences of the same model: agreement to the
    finite-difference error, ~eps^(2/3) relative per entry, amplified by the condition
    of the normal matrix (< 1e6 here): 1e-4."""
    rng = np.random.default_rng(6)
    shifted = _data(rng) + OFFSETS[NIGHT]
    obs = att.LightcurveObservations(T, shifted, SIGMA, GEOM, SHAPE, sessions=NIGHT)
    res = att.fit(obs, BODY, _guess(), multistart=False)
    assert_status_is_consistent(res)
    assert res.status in ("converged", "max_nfev at an acceptable chi2"), res.message
    objective = res.objective
    x = np.array([res.parameters[n] for n in res.free])
    h = np.maximum(np.finfo(float).eps ** (1 / 3) * np.abs(x), 1e-8)
    k = x.size
    v, _ = project(objective.full(np.vstack([x + np.diag(h), x - np.diag(h)])))
    q, _ = objective.model.evaluate(v, objective.times)
    m = obs.model_magnitudes(q)
    jac_rot = ((m[:k] - m[k:]) / (2 * h[:, None])).T / SIGMA                    # (n, k)
    jac_off = np.eye(3)[NIGHT] / SIGMA                                       # (n, 3)
    joint = np.hstack([jac_rot, jac_off])
    marginal = np.linalg.inv(joint.T @ joint)[:k, :k]
    scale = np.sqrt(np.outer(np.diag(marginal), np.diag(marginal)))
    np.testing.assert_allclose(res.covariance / scale, marginal / scale, rtol=0, atol=1e-4)
    # and the fixed-offset covariance is smaller: the profiling is what widens it
    fixed = np.linalg.inv(jac_rot.T @ jac_rot)
    assert np.all(np.diag(fixed) <= np.diag(marginal) * (1 + 1e-9))

r"""Convex inversion of a tumbler: shape and non-principal-axis rotation from photometry.

The shape is the convex model of :mod:`attitude.inversion.convex` (log areas over a
fixed Gaussian image, the Lommel-Seeliger + Lambert law with its phase function); the
attitude is the exact torque-free solution (:func:`attitude.propagation.torquefree.
free_rotation`) of the state given by the eight parameters that tumbler inversions
publish (Kaasalainen 2001; Pravec et al. 2005, 2014), built by
:func:`attitude.model.sampling.tumbling_state`:

- ``angular_momentum_ra``, ``angular_momentum_dec``: the direction of L, rad, in the
  frame of the observations' vectors (ecliptic longitude and latitude for DAMIT data);
- ``energy_ratio`` ``E/E0`` (``E0 = L^2 / 2C``): in ``[1, C/B)`` a short-axis mode (SAM),
  in ``(C/B, C/A]`` a long-axis mode (LAM);
- ``ratio_a`` ``A/C``, ``ratio_b`` ``B/C``: the moments of inertia in the model's
  axes (the model's ``x, y, z`` are the principal axes A, B, C);
- ``precession_period`` ``P_phi``, s;
- ``phi0``, ``psi0``: the precession and rotation angles of the reference axis (C in
  SAM, A in LAM) about L at the first epoch, rad.

Inside the fit the energy and ``A/C`` are mapped to the unit interval so that every
point of the box is a valid state of the chosen mode: ``E/E0 = 1 + x (C/B - 1)`` (SAM) or
``C/B + x (C/A - C/B)`` (LAM), ``A/C = (1 - B/C) + y (2 B/C - 1)`` (the triangle
inequality ``A + B >= C`` and ``A <= B``).

:func:`fit_tumbler` fits the shape and the eight parameters together: damped least
squares (:func:`~attitude.inversion.convex.fit_shape_rotation`) with the exact Jacobian
of the shape and central differences of the body-frame directions for the rotation
(the 16 perturbed attitude histories in one vectorised call of the closed form).  A
long time span is reached by continuation: the fit on the first lightcurves, then on
more, so that a start whose phase drifts by a sizeable fraction of a cycle over the
whole span still converges.  :func:`tumbler_starts` builds starts from the data alone:
the two fundamental frequencies of :func:`attitude.photometry.fit_periods`, read as
``(1/P_phi, 1/P_psi)`` and their sums and differences, for each a grid of moment
ratios with the energy that gives the period ratio (:func:`energy_for_period_ratio`),
a few L directions and phases; :func:`rank_starts` ranks them by the chi2 of the best
shape at that attitude history.

The homogeneity test: the moment ratios fitted freely against the ratios of the fitted
convex shape at uniform density (:attr:`TumblerFit.shape_ratios`); Kaasalainen (2001)
and Pravec et al. (2014) use the difference as evidence for (or against) a uniform
interior.

References
----------
.. [1] Kaasalainen, M. (2001). Interpretation of lightcurves of precessing asteroids.
   *A&A* 376, 302-309.
.. [2] Pravec, P. et al. (2005). Tumbling asteroids. *Icarus* 173, 108-131.
.. [3] Pravec, P. et al. (2014). The tumbling spin state of (99942) Apophis. *Icarus*
   233, 48-60.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
from astropy.time import Time

from attitude.foundations import quaternion as quat
from attitude.foundations.errors import PhotometryError
from attitude.inversion.convex import ConvexModel, ShapeFit, fit_shape_rotation
from attitude.inversion.gaussian_image import GaussianImage
from attitude.inversion.minkowski import polyhedron_from_areas
from attitude.inversion.observations import ObservedLightcurve
from attitude.model.freebody import diagnose_many
from attitude.model.sampling import tumbling_state
from attitude.photometry.geometry import Geometry
from attitude.photometry.periods import fit_periods
from attitude.propagation.torquefree import free_rotation

__all__ = ["PARAMETERS", "TumblerFit", "to_internal", "to_physical", "tumbler_directions",
           "fit_tumbler", "energy_for_period_ratio", "COMBINATIONS", "RATIO_GRID",
           "period_pairs", "tumbler_starts", "rank_starts", "search_tumbler",
           "shape_moment_ratios"]

#: The rotation parameters, in the order of the fit's vectors.
PARAMETERS = ("angular_momentum_ra", "angular_momentum_dec", "energy_ratio", "ratio_a",
              "ratio_b", "precession_period", "phi0", "psi0")

#: The margin kept from the edges of the unit intervals (a mode's ends are a principal-axis
#: spin and the separatrix, where the closed form changes branch).
_EDGE = 1e-6

#: Central-difference steps of the internal parameters (angles rad, fractions,
#: the period relative).
_STEPS = np.array([1e-6, 1e-6, 1e-7, 1e-7, 1e-7, 1e-8, 1e-6, 1e-6])


def _mode(regime: str) -> bool:
    """True for LAM, False for SAM."""
    if regime not in ("SAM", "LAM"):
        raise PhotometryError(f"regime {regime!r}: expected 'SAM' or 'LAM'", key="regime")
    return regime == "LAM"


def to_physical(internal, regime: str) -> np.ndarray:
    """The eight parameters of :data:`PARAMETERS` from the fit's internal vector
    ``(ra, dec, x, y, B/C, P_phi, phi0, psi0)`` (``(..., 8)``).

    Examples
    --------
    >>> p = to_physical([1.0, 0.5, 0.5, 0.5, 0.9, 3600.0, 0.0, 0.0], "SAM")
    >>> p[2:5].round(6).tolist()       # E/E0 halfway to C/B; A/C halfway in [0.1, 0.9]
    [1.055556, 0.5, 0.9]
    """
    u = np.array(internal, dtype=float)
    b = u[..., 4]
    a = (1.0 - b) + u[..., 3] * (2.0 * b - 1.0)
    if _mode(regime):
        er = 1.0 / b + u[..., 2] * (1.0 / a - 1.0 / b)
    else:
        er = 1.0 + u[..., 2] * (1.0 / b - 1.0)
    out = u.copy()
    out[..., 2], out[..., 3] = er, a
    return out


def to_internal(parameters, regime: str) -> np.ndarray:
    """The fit's internal vector from the eight parameters (a dict keyed by
    :data:`PARAMETERS`, SI, or an array in that order); the inverse of
    :func:`to_physical`.

    Examples
    --------
    >>> p = [1.0, 0.5, 1.024, 0.61, 0.965, 98568.0, 0.1, 0.2]
    >>> bool(np.allclose(to_physical(to_internal(p, "SAM"), "SAM"), p, rtol=1e-14))
    True
    """
    if isinstance(parameters, dict):
        missing = [k for k in PARAMETERS if k not in parameters]
        if missing:
            raise PhotometryError(f"missing rotation parameter(s) {', '.join(missing)} "
                                  f"(all: {', '.join(PARAMETERS)})", key="start")
        parameters = [float(parameters[k]) for k in PARAMETERS]
    p = np.array(parameters, dtype=float)
    a, b, er = p[..., 3], p[..., 4], p[..., 2]
    u = p.copy()
    u[..., 3] = (a - (1.0 - b)) / (2.0 * b - 1.0)
    if _mode(regime):
        u[..., 2] = (er - 1.0 / b) / (1.0 / a - 1.0 / b)
    else:
        u[..., 2] = (er - 1.0) / (1.0 / b - 1.0)
    return u


def _state(physical, moment_c=1.0):
    """Moments, quaternions (principal -> inertial) and rates of physical parameter
    rows ``(m, 8)``."""
    p = np.atleast_2d(physical)
    moments, q, w, _ = tumbling_state(*p.T, moment_c=moment_c)
    return moments, q, w


def tumbler_directions(model: ConvexModel, physical) -> tuple[np.ndarray, np.ndarray]:
    """Body-frame observer and Sun directions at the data points for rows of the eight
    parameters (``(m, 8)``, physical): ``(m, n, 3)`` each (``(n, 3)`` for one row).

    The time origin of the angles is the model's first point (``model.t0``).

    Examples
    --------
    >>> model = example_model()
    >>> o, s = tumbler_directions(model, [0.3, 0.2, 1.02, 0.6, 0.9, 7200.0, 0.0, 0.0])
    >>> o.shape, bool(np.allclose(np.linalg.norm(s, axis=1), 1.0))
    ((40, 3), True)
    """
    p = np.asarray(physical, dtype=float)
    moments, q0, w0 = _state(p)
    q, _ = free_rotation(moments, q0, w0, model.time)              # (m, n, 4)
    o = quat.rotate(q, model.observer[None], inverse=True)
    s = quat.rotate(q, model.sun[None], inverse=True)
    if p.ndim == 1:
        return o[0], s[0]
    return o, s


@dataclass(frozen=True, eq=False)
class TumblerFit:
    """The result of :func:`fit_tumbler`.

    Attributes
    ----------
    regime : str
        ``"SAM"`` or ``"LAM"``: the mode fitted.
    parameters : dict
        The eight parameters of :data:`PARAMETERS` (SI: rad, s).
    uncertainties : dict
        Their 1-sigma errors from the covariance of the fit (the inverse normal matrix
        scaled by the reduced chi2; shape and rotation parameters together).
    periods : dict
        ``precession`` (``P_phi``) and ``rotation`` (``P_psi``), s, of the fitted state.
    chi2, rms : float
        Of the data, as in :class:`~attitude.inversion.convex.ShapeFit`.
    shape : ShapeFit
        The shape fit at the end.
    shape_ratios : tuple
        ``(A/C, B/C)`` of the fitted convex shape at uniform density, the moments taken
        along the model's axes (NaN when the shape could not be built).
    ratio_difference : tuple
        ``shape_ratios - (ratio_a, ratio_b)``: near zero within the errors for a
        uniform interior.
    axis_misalignment : float
        Angle (deg) between the model's axes and the principal axes of the uniform
        shape (the largest of the three).
    n_evaluations : int
        Model evaluations over all stages.

    Examples
    --------
    See :func:`fit_tumbler`.

    >>> sorted(TumblerFit.__dataclass_fields__)[:3]
    ['axis_misalignment', 'chi2', 'n_evaluations']
    """

    regime: str
    parameters: dict
    uncertainties: dict
    periods: dict
    chi2: float
    rms: float
    shape: ShapeFit = field(repr=False)
    shape_ratios: tuple
    ratio_difference: tuple
    axis_misalignment: float
    n_evaluations: int

    @property
    def model(self) -> np.ndarray:
        """The model brightness as compared with the data."""
        return self.shape.model

    @property
    def pole(self) -> tuple[float, float]:
        """The direction of L ``(longitude, latitude)``, deg, longitude in [0, 360)."""
        ra, dec = self.parameters["angular_momentum_ra"], self.parameters[
            "angular_momentum_dec"]
        return float(np.degrees(ra) % 360.0), float(np.degrees(dec))


def shape_moment_ratios(image, areas) -> tuple[tuple, float]:
    """``(A/C, B/C)`` of the convex shape of a Gaussian image at uniform density, its
    moments about the model's axes, and the angle (deg) between those axes and its
    principal axes.

    Examples
    --------
    >>> from attitude.inversion import GaussianImage
    >>> g = GaussianImage(rows=4, degree=2)
    >>> (ra, rb), tilt = shape_moment_ratios(g, g.areas(np.zeros(9)))
    >>> round(ra, 1), round(rb, 1)                     # a triangulated sphere
    (1.0, 1.0)
    """
    shape, _ = polyhedron_from_areas(image.normals, areas, tolerance=1e-7)
    _, _, inertia = shape.mass_properties(1.0)
    diagonal = np.diag(inertia)
    _, axes = np.linalg.eigh(inertia)
    # each principal axis against the model axis nearest to it; the worst of the three
    nearest = np.max(np.abs(axes), axis=0)
    tilt = float(np.degrees(np.arccos(np.clip(nearest.min(), -1.0, 1.0))))
    return (float(diagonal[0] / diagonal[2]), float(diagonal[1] / diagonal[2])), tilt


def _regime_of(physical) -> str:
    """SAM below the separatrix ``E/E0 = C/B``, LAM above."""
    return "LAM" if physical[2] > 1.0 / physical[4] else "SAM"


def _bounds(free_index):
    """Bounds of the free internal parameters."""
    lower = np.array([-np.inf, -np.pi / 2, _EDGE, _EDGE, 0.5 + _EDGE, 0.0, -np.inf, -np.inf])
    upper = np.array([np.inf, np.pi / 2, 1 - _EDGE, 1 - _EDGE, 1 - _EDGE, np.inf, np.inf,
                      np.inf])
    return lower[free_index], upper[free_index]


def _stages(model: ConvexModel, continuation) -> list[ConvexModel]:
    """Models of the first lightcurves reaching the given fractions of the time span,
    then the whole model (one time origin for all)."""
    obs = list(model.observations)
    span = float(np.ptp(model.time))
    ends = np.array([model.time[model.block == k].max() for k in range(len(obs))])
    stages = []
    for fraction in sorted(continuation):
        k = int(np.searchsorted(ends, fraction * span)) + 1
        if k < len(obs) and (not stages or k > len(stages[-1].observations)):
            stages.append(ConvexModel(obs[:k], model.image, t0=model.t0))
    return stages + [model]


def fit_tumbler(model: ConvexModel, start, *, regime: str | None = None, free=None,
                coefficients=None, continuation=(0.25, 0.5), lambert: float = 0.1,
                convexity: float = 0.1, max_iterations: int = 40,
                tolerance: float = 1e-6, homogeneity: bool = True) -> TumblerFit:
    """Fit a convex shape and the tumbling state of :data:`PARAMETERS` from a start.

    Parameters
    ----------
    model : ConvexModel
        The lightcurves and the Gaussian image.
    start : dict or (8,) array
        Starting parameters (SI), keyed by :data:`PARAMETERS` or in that order.
    regime : {"SAM", "LAM"}, optional
        The mode fitted (default: the mode of the start).
    free : list of str, optional
        The parameters fitted (default: all eight); the others keep their start.
    coefficients : array, optional
        Starting shape (default: a shape fitted at the start's attitude history).
    continuation : sequence of float
        Fractions of the time span fitted first (on the lightcurves that end before
        them), then the whole: each stage starts from the last.  ``()`` fits all at
        once.
    lambert, convexity : float
        As in :func:`~attitude.inversion.convex.fit_convex`.
    max_iterations : int
        Iterations of each stage.
    tolerance : float
        Relative change of the cost that ends a stage.
    homogeneity : bool
        Compute the moment ratios of the fitted shape (:attr:`TumblerFit.shape_ratios`,
        a polyhedron from the areas: about a second); False leaves them NaN (the
        search's coarse fits, which only rank).

    Returns
    -------
    TumblerFit

    Examples
    --------
    Lightcurves of an ellipsoid-like shape in a short-axis mode, refitted from a start
    off in the precession period and the energy:

    >>> model, truth = example_model(), EXAMPLE_STATE
    >>> y = model.brightness_of(EXAMPLE_SHAPE, *tumbler_directions(model, truth))
    >>> model = with_brightness(model, y)
    >>> start = np.array(truth) * [1, 1, 1.002, 1, 1, 1.001, 1, 1]
    >>> fit = fit_tumbler(model, start, continuation=())
    >>> fit.regime, bool(fit.rms < 1e-6)
    ('SAM', True)
    >>> round(fit.parameters["precession_period"] / truth[5], 6)
    1.0
    """
    p_start = np.array([float(start[k]) for k in PARAMETERS] if isinstance(start, dict)
                       else start, dtype=float)
    if p_start.shape != (8,) or not np.isfinite(p_start).all():
        raise PhotometryError(f"start: expected the 8 finite parameters {PARAMETERS}, "
                              f"got {p_start!r}", key="start")
    regime = _regime_of(p_start) if regime is None else regime
    lam = _mode(regime)
    u = to_internal(p_start, regime)
    lower_all, upper_all = _bounds(np.arange(8))
    if not (np.all(u >= lower_all - 1e-12) and np.all(u <= upper_all + 1e-12)):
        raise PhotometryError(f"start: not a valid {regime} state (0 < A/C <= B/C <= 1, "
                              "A/C + B/C >= 1, E/E0 within the mode)", key="start")
    u = np.clip(u, lower_all, upper_all)
    names = list(PARAMETERS) if free is None else list(free)
    unknown = [n for n in names if n not in PARAMETERS]
    if unknown:
        raise PhotometryError(f"free: unknown parameter(s) {unknown}; choose from "
                              f"{PARAMETERS}", key="free")
    free_index = np.array([PARAMETERS.index(n) for n in names], dtype=int)
    del lam
    evaluations = 0
    shape = None
    c = coefficients
    for stage in _stages(model, continuation):
        def full(r, u=u):
            v = np.array(u, dtype=float)
            v = np.broadcast_to(v, np.shape(r)[:-1] + (8,)).copy()
            v[..., free_index] = r
            return v

        def directions(r, stage=stage, full=full):
            return tumbler_directions(stage, to_physical(full(r), regime))

        def columns(r, o, s, grad_o, grad_s, stage=stage, full=full):
            h = _STEPS[free_index] * np.where(free_index == 5, np.abs(r), 1.0)
            k = r.size
            shifted = np.repeat(r[None], 2 * k, axis=0)
            shifted[np.arange(k), np.arange(k)] += h
            shifted[k + np.arange(k), np.arange(k)] -= h
            o_all, s_all = tumbler_directions(stage, to_physical(full(shifted), regime))
            do = (o_all[:k] - o_all[k:]) / (2.0 * h)[:, None, None]
            ds = (s_all[:k] - s_all[k:]) / (2.0 * h)[:, None, None]
            return (np.einsum("nj,knj->nk", grad_o, do)
                    + np.einsum("nj,knj->nk", grad_s, ds))

        if c is None:
            first = fit_shape_rotation(stage, lambda r, d=directions, r0=u[free_index]: d(r0),
                                       lambert=lambert, convexity=convexity,
                                       max_iterations=20)
            c = first.coefficients
            evaluations += first.n_evaluations
        shape = fit_shape_rotation(stage, directions, u[free_index], columns=columns,
                                   bounds=_bounds(free_index), coefficients=c,
                                   lambert=lambert, convexity=convexity,
                                   max_iterations=max_iterations, tolerance=tolerance)
        evaluations += shape.n_evaluations
        c = shape.coefficients
        u = full(shape.rotation)
    physical = to_physical(u, regime)
    sigma = _uncertainties(shape, u, free_index, regime, model.n_points)
    moments, _, w0 = _state(physical)
    d = diagnose_many(moments, w0)
    ratios, tilt = (np.nan, np.nan), np.nan
    if homogeneity:
        try:
            ratios, tilt = shape_moment_ratios(model.image, shape.areas)
        except Exception:  # noqa: BLE001  (a degenerate shape: the test is not available)
            pass
    return TumblerFit(regime=regime,
                      parameters={k: float(v) for k, v in zip(PARAMETERS, physical)},
                      uncertainties={k: float(v) for k, v in zip(PARAMETERS, sigma)},
                      periods={"precession": float(d["precession"][0]),
                               "rotation": float(d["rotation"][0])},
                      chi2=shape.chi2, rms=shape.rms, shape=shape, shape_ratios=ratios,
                      ratio_difference=(ratios[0] - physical[3], ratios[1] - physical[4]),
                      axis_misalignment=tilt, n_evaluations=evaluations)


def _uncertainties(shape: ShapeFit, u, free_index, regime, n_points) -> np.ndarray:
    """1-sigma errors of the physical parameters from the fit's Jacobian (covariance of
    the free internal parameters, scaled by the reduced chi2, mapped by the derivative of
    :func:`to_physical`)."""
    jac = shape.jacobian
    n_par = jac.shape[1]
    scale = shape.chi2 / max(n_points - n_par, 1)
    covariance = np.linalg.pinv(jac.T @ jac) * scale
    k = free_index.size
    rot = covariance[n_par - k:, n_par - k:]
    # d(physical)/d(internal) by central differences (the map is smooth inside the box)
    g = np.zeros((8, k))
    for j, i in enumerate(free_index):
        h = 1e-7 * max(1.0, abs(u[i]))
        up, down = u.copy(), u.copy()
        up[i] += h
        down[i] -= h
        g[:, j] = (to_physical(up, regime) - to_physical(down, regime)) / (2.0 * h)
    return np.sqrt(np.clip(np.diag(g @ rot @ g.T), 0.0, None))


#: The examples' tumbler: a SAM of P_phi 2 h (L toward (17, 11) deg).
EXAMPLE_STATE = (0.3, 0.2, 1.02, 0.6, 0.9, 7200.0, 0.4, 1.1)
#: The examples' shape: harmonic coefficients of an elongated, flattened body.
EXAMPLE_SHAPE = np.array([0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.25, 0.0, 0.35])


def example_model(nights: int = 4, points: int = 10) -> ConvexModel:
    """A model of ``nights`` relative lightcurves of ``points`` points over 6 h, a day
    apart, the Sun and the observer moving slowly (unit brightness: fill it in with
    :func:`_with_brightness`)."""
    epoch = Time("2026-01-01", scale="tdb")
    t = np.linspace(0.0, 6 * 3600.0, points)
    obs = []
    for k in range(nights):
        sun = [np.cos(0.05 * k), np.sin(0.05 * k), 0.1]
        seen = [np.cos(0.05 * k + 0.5 - 0.04 * k), np.sin(0.05 * k + 0.5 - 0.04 * k), -0.1]
        obs.append(ObservedLightcurve(epoch, t + 86400.0 * k, np.ones(points),
                                      Geometry(sun=sun, observer=seen)))
    return ConvexModel(obs, GaussianImage(rows=4, degree=2))


def with_brightness(model: ConvexModel, brightness) -> ConvexModel:
    """The model with the lightcurves' brightness replaced (one value per point)."""
    y = np.asarray(brightness, dtype=float)
    obs = [ObservedLightcurve(o.epoch, o.time, y[model.block == k], o.geometry,
                              sigma=o.sigma, calibrated=o.calibrated)
           for k, o in enumerate(model.observations)]
    return ConvexModel(obs, model.image, t0=model.t0)


def _period_ratio(internal, regime):
    """``P_psi / P_phi`` of internal parameter rows (``(m, 8)``)."""
    moments, _, w0 = _state(to_physical(internal, regime))
    d = diagnose_many(moments, w0)
    return d["rotation"] / d["precession"]


def energy_for_period_ratio(ratio_a, ratio_b, period_ratio, regime: str) -> np.ndarray:
    """The energy ratio ``E/E0`` of the mode at which a body of moment ratios ``A/C``,
    ``B/C`` has ``P_psi / P_phi = period_ratio`` (vectorised; NaN where the mode does not
    reach that ratio).

    ``P_psi / P_phi`` grows monotonically from the principal-axis end of a mode to the
    separatrix, where it diverges; it is found by bisection on the energy.

    Examples
    --------
    >>> er = energy_for_period_ratio(0.61, 0.965, 264.6 / 27.38, "SAM")
    >>> round(float(er[0]), 4)                      # Apophis (Pravec et al. 2014)
    1.024
    >>> bool(np.isnan(energy_for_period_ratio(0.61, 0.965, 2.0, "SAM")[0]))
    True
    """
    a, b, r = np.broadcast_arrays(*(np.atleast_1d(np.asarray(v, dtype=float))
                                    for v in (ratio_a, ratio_b, period_ratio)))
    u = np.zeros(a.shape + (8,))
    u[..., 3] = (a - (1.0 - b)) / (2.0 * b - 1.0)
    u[..., 4], u[..., 5] = b, 1.0
    lam = _mode(regime)
    low, high = np.full(a.shape, _EDGE), np.full(a.shape, 1.0 - _EDGE)

    def ratio(x):
        v = u.copy()
        v[..., 2] = x
        return _period_ratio(v.reshape(-1, 8), regime).reshape(a.shape)

    # SAM: the ratio grows with x toward the separatrix (x = 1); LAM: toward x = 0
    r_low, r_high = ratio(low), ratio(high)
    reach = (np.minimum(r_low, r_high) <= r) & (r <= np.maximum(r_low, r_high))
    for _ in range(48):
        mid = 0.5 * (low + high)
        above = (ratio(mid) > r) != lam
        high = np.where(above, mid, high)
        low = np.where(above, low, mid)
    x = 0.5 * (low + high)
    v = u.copy()
    v[..., 2] = x
    er = to_physical(v, regime)[..., 2]
    return np.where(reach, er, np.nan)


#: Lightcurve frequencies ``n1 f_phi + n2 f_psi`` read as a fundamental of
#: :func:`attitude.photometry.fit_periods`, most likely first (Pravec et al. 2005: the
#: strongest is often ``2 f_phi - 2 f_psi`` or ``2 f_phi + 2 f_psi``).
COMBINATIONS = ((2, -2), (2, 2), (1, -1), (1, 1), (0, 2), (0, 1), (2, -1), (2, 1))

#: Moment ratios ``(A/C, B/C)`` of the coarse grid of starts.
RATIO_GRID = ((0.55, 0.85), (0.7, 0.92), (0.5, 0.75))


def period_pairs(periods) -> list[tuple[float, float]]:
    """Candidate ``(P_phi, P_psi)`` from the two fundamental periods of a tumbler's
    lightcurve: one of them is ``P_phi``, the other ``1 / (n1 / P_phi + n2 / P_psi)`` for
    the :data:`COMBINATIONS`, pairs with ``P_psi > P_phi``; then the same with one of them
    ``P_psi`` (the slow rotation of a SAM seen directly, or a LAM's), pairs with
    ``P_psi > 0.4 P_phi`` (a LAM near its long axis has ``P_psi < P_phi``).

    Examples
    --------
    >>> [(round(a / 3600, 3), round(b / 3600, 2)) for a, b in period_pairs(
    ...     [4.0 * 3600, 2.4636 * 3600])][:2]
    [(4.0, 21.26), (4.0, 6.41)]
    """
    p = np.asarray(periods, dtype=float).ravel()
    if p.size != 2 or not np.all(p > 0):
        raise PhotometryError(f"expected two positive periods, got {p!r}", key="periods")
    pairs = []
    for phi, other in ((p[0], p[1]), (p[1], p[0])):
        for n1, n2 in COMBINATIONS:
            f_psi = (1.0 / other - n1 / phi) / n2
            if f_psi > 0.0 and 1.0 / f_psi > phi * (1 + 1e-9):
                pair = (float(phi), float(1.0 / f_psi))
                if all(abs(pair[1] / q[1] - 1) > 1e-6 or abs(pair[0] / q[0] - 1) > 1e-6
                       for q in pairs):
                    pairs.append(pair)
    for psi, other in ((p[0], p[1]), (p[1], p[0])):
        for n1, n2 in COMBINATIONS:
            if n1 == 0:
                continue
            f_phi = (1.0 / other - n2 / psi) / n1
            if f_phi > 0.0 and psi > 0.4 / f_phi:
                pair = (float(1.0 / f_phi), float(psi))
                if all(abs(pair[1] / q[1] - 1) > 1e-6 or abs(pair[0] / q[0] - 1) > 1e-6
                       for q in pairs):
                    pairs.append(pair)
    return pairs


def tumbler_starts(pairs, *, ratios=RATIO_GRID, directions: int = 8, phases: int = 4
                   ) -> list[tuple[np.ndarray, str]]:
    """Starting states for period pairs: for each ``(P_phi, P_psi)``, each mode and each
    ``(A/C, B/C)`` of ``ratios``, the energy that gives ``P_psi / P_phi``
    (:func:`energy_for_period_ratio`), L along ``directions`` directions over the
    sphere and ``phases`` values each of ``phi0`` and ``psi0``.

    Returns
    -------
    list of ((m, 8) array, regime)
        Physical parameter rows, grouped by mode.

    Examples
    --------
    >>> starts = tumbler_starts([(4.0 * 3600, 21.33 * 3600)], directions=2, phases=2)
    >>> [(rows.shape, regime) for rows, regime in starts]
    [((16, 8), 'SAM'), ((24, 8), 'LAM')]
    """
    out = []
    for regime in ("SAM", "LAM"):
        rows = [group for group, mode, _ in _start_groups(pairs, ratios, directions, phases)
                if mode == regime]
        if rows:
            out.append((np.concatenate(rows), regime))
    return out


def _start_groups(pairs, ratios, directions, phases):
    """The starts of :func:`tumbler_starts`, one group per pair, moment ratios and mode:
    ``[(rows, regime, (pair, ratios)), ...]``; the energies of all groups of a mode come
    from one vectorised bisection."""
    k = np.arange(directions) + 0.5
    dec = np.arcsin(1.0 - 2.0 * k / directions)
    ra = (np.pi * (3.0 - np.sqrt(5.0)) * np.arange(directions)) % (2.0 * np.pi)
    angles = 2.0 * np.pi * np.arange(phases) / phases
    grid = np.stack(np.meshgrid(np.arange(directions), angles, angles, indexing="ij"),
                    -1).reshape(-1, 3)
    i = grid[:, 0].astype(int)
    pair = np.asarray(pairs, dtype=float).reshape(-1, 2)
    a, b = np.array(ratios, dtype=float).reshape(-1, 2).T
    p_phi = np.repeat(pair[:, 0], a.size)
    ratio = np.repeat(pair[:, 1] / pair[:, 0], a.size)
    aa, bb = np.tile(a, len(pair)), np.tile(b, len(pair))
    out = []
    for regime in ("SAM", "LAM"):
        er = energy_for_period_ratio(aa, bb, ratio, regime)
        for j in np.nonzero(np.isfinite(er))[0]:
            rows = np.stack([ra[i], dec[i], np.full(i.size, er[j]), np.full(i.size, aa[j]),
                             np.full(i.size, bb[j]), np.full(i.size, p_phi[j]), grid[:, 1],
                             grid[:, 2]], axis=1)
            out.append((rows, regime, (tuple(pair[j // a.size]), (aa[j], bb[j]))))
    return out


def rank_starts(model: ConvexModel, starts, regime: str, *, max_iterations: int = 5,
                chunk: int = 64) -> np.ndarray:
    """chi2 of the best shape (rotation fixed, a few iterations) at each start's
    attitude history: the cost of a start, to choose the few worth a full fit.

    Parameters
    ----------
    model : ConvexModel
        Usually a coarse one (few facets, a low degree): only the ranking counts.
    starts : (m, 8) array
        Physical parameter rows.
    regime : str
        Their mode (for the record: the attitude does not depend on it).
    max_iterations : int
        Iterations of each shape fit.
    chunk : int
        Attitude histories computed together.

    Returns
    -------
    (m,) array

    Examples
    --------
    >>> model = example_model()
    >>> y = model.brightness_of(EXAMPLE_SHAPE, *tumbler_directions(model, EXAMPLE_STATE))
    >>> model = with_brightness(model, y)
    >>> rows = np.array([EXAMPLE_STATE, EXAMPLE_STATE])
    >>> rows[1, 6] += 0.5                                  # phi0 off by 0.5 rad
    >>> chi2 = rank_starts(model, rows, "SAM")
    >>> bool(chi2[0] < 1e-6 < chi2[1])
    True
    """
    _mode(regime)
    rows = np.atleast_2d(np.asarray(starts, dtype=float))
    chi2 = np.empty(rows.shape[0])
    for first in range(0, rows.shape[0], chunk):
        o_all, s_all = tumbler_directions(model, rows[first:first + chunk])
        for i, (o, s) in enumerate(zip(o_all, s_all)):
            fit = fit_shape_rotation(model, lambda r, o=o, s=s: (o, s),
                                     max_iterations=max_iterations)
            chi2[first + i] = fit.chi2
    return chi2


def search_tumbler(model: ConvexModel, periods=None, *, ratios=RATIO_GRID,
                   directions: int = 8, phases: int = 4, polish: int = 2, keep: int = 3,
                   coarse=(3, 2), max_iterations: int = 40,
                   timings: dict | None = None) -> list[TumblerFit]:
    """Tumbler fits from the data alone, best first.

    1. The two fundamental periods (``periods``, else :func:`attitude.photometry.
       fit_periods` of the data, one magnitude offset per lightcurve);
    2. the candidate ``(P_phi, P_psi)`` (:func:`period_pairs`) and their starts
       (:func:`tumbler_starts`), grouped by pair, mode and moment ratios;
    3. in each group the ``polish`` starts of lowest chi2 (:func:`rank_starts`, on a
       coarse Gaussian image of ``coarse = (rows, degree)``) refined by a short fit on
       that coarse image;
    4. the ``keep`` best of those fitted on the full model (:func:`fit_tumbler`).

    timings : dict, optional
        Filled with the CPU seconds (this process) of the stages: ``periods``,
        ``search`` (ranking and coarse fits) and ``refinement`` (the full fits).

    Returns
    -------
    list of TumblerFit
        Sorted by chi2; the first is the solution, the others the alternatives.

    Examples
    --------
    See ``docs/inversion.md`` (a run takes a minute or more: about two thousand starts
    are ranked).

    >>> search_tumbler.__name__
    'search_tumbler'
    """
    clock = [time.process_time()]

    def lap(name):
        clock.append(time.process_time())
        if timings is not None:
            timings[name] = clock[-1] - clock[-2]

    if periods is None:
        magnitudes = -2.5 * np.log10(model.data)
        sigma = 2.5 / np.log(10.0) * model.sigma / model.data
        periods = fit_periods(model.time, magnitudes, sigma, n_periods=2,
                              sessions=model.block).periods
    lap("periods")
    pairs = period_pairs(periods)
    rough = ConvexModel(list(model.observations), GaussianImage(*coarse), t0=model.t0)
    half = phases // 2 if phases > 1 else 1
    candidates = []
    for rows, regime, _ in _start_groups(pairs, ratios, directions, phases):
        # psi0 and psi0 + pi differ little for a nearly symmetric coarse shape
        rows = rows[rows[:, 7] < np.pi - 1e-9] if half > 1 else rows
        chi2 = rank_starts(rough, rows, regime)
        for i in np.argsort(chi2)[:polish]:
            fit = fit_tumbler(rough, rows[i], regime=regime, continuation=(),
                              max_iterations=15, homogeneity=False)
            candidates.append((fit.chi2, fit))
    candidates.sort(key=lambda c: c[0])
    lap("search")
    fits = [fit_tumbler(model, [fit.parameters[k] for k in PARAMETERS],
                        regime=fit.regime, max_iterations=max_iterations)
            for _, fit in candidates[:keep]]
    lap("refinement")
    return sorted(fits, key=lambda f: f.chi2)

"""Least-squares fits of a torque-free rotation state to observations.

The forward model is the exact solution (:class:`~attitude.fitting.parameters.RotationModel`);
``scipy.optimize.least_squares`` (trust-region reflective) minimises chi^2 over the
chosen free parameters from several starts, one per discrete ambiguity of the problem:
the guess; its mirror across the separatrix (the same energy ratio's distance from
C/B on the other side: SAM <-> LAM); the half-turn of the rotation angle psi0 + pi
(a body symmetric under a half-turn looks the same). The best start wins; the
covariance is ``(J^T J)^-1`` at the optimum, J the Jacobian of the residuals over their
sigmas.

The parameter domain is not a box (A <= B <= C, A + B >= C, 1 <= E/E0 <= C/A): outside
it the parameters are projected onto it and the distance is added as a steep penalty
residual, so that the solver sees a continuous function.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import least_squares
from scipy.special import gammaincinv

from ..foundations.errors import AttitudeError
from ..foundations.progress import Progress
from ..model.body import RigidBody
from ..model.state import AttitudeState
from .observations import LightcurveObservations, seconds_since
from .parameters import ANGLES, PARAMETERS, RotationModel, free_parameters

__all__ = ["FitResult", "fit", "Objective"]

#: Weight of the distance outside the parameter domain (per unit of parameter).
PENALTY = 1e4
#: A converged fit whose chi^2 lies more than this many standard deviations
#: (sqrt(2 dof)) above its expectation (dof) is reported as unsuccessful: a local
#: minimum or wrong uncertainties, not an answer.
CHI2_SIGMAS = 10.0
#: A fit that ran out of evaluations (``max_nfev``) at a chi^2 below this quantile of
#: the chi^2 distribution of its degrees of freedom is reported as such (status
#: ``"max_nfev at an acceptable chi2"``): statistically as good as the optimum, though
#: the solver's tolerances were not met; above it, as not converged (``"max_nfev"``).
ACCEPTABLE_CHI2_QUANTILE = 0.999
_EPS = 1e-9


def project(values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Parameter vectors (N, 8) projected onto the physical domain, and the distance moved.

    Examples
    --------
    >>> v, d = project(np.array([[0, 0, 5.0, 0.5, 0.9, 1.0, 0, 0]]))
    >>> float(v[0, 2]), float(d[0])          # E/E0 clipped to C/A = 2
    (2.0, 3.0)
    """
    v = np.array(values, dtype=float, copy=True)
    orig = v.copy()
    v[:, 1] = np.clip(v[:, 1], -np.pi / 2, np.pi / 2)
    v[:, 4] = np.clip(v[:, 4], 0.5 + _EPS, 1.0 - _EPS)                  # B/C
    v[:, 3] = np.clip(v[:, 3], 1.0 - v[:, 4] + _EPS, v[:, 4] - _EPS)    # A/C
    v[:, 2] = np.clip(v[:, 2], 1.0 + _EPS, 1.0 / v[:, 3] - _EPS)        # E/E0
    v[:, 5] = np.maximum(v[:, 5], _EPS)
    return v, np.sum(np.abs(v - orig), axis=1)


@dataclass(frozen=True)
class Objective:
    """Normalised residuals of observations for batches of parameter vectors.

    Parameters
    ----------
    observations : sequence of observation objects
    model : RotationModel
    fixed : (8,) array
        Values of the parameters that are not free.
    free : tuple of int
        Indices (into :data:`PARAMETERS`) of the free parameters.

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> body = att.RigidBody.from_principal_moments([0.6, 0.9, 1.0])
    >>> truth = att.AttitudeState("2029-04-13", Rotation.from_rotvec([0.3, -0.2, 1.0]),
    ...                           [0.05, 0.1, 1.0])
    >>> t = np.linspace(0.0, 20.0, 40)
    >>> q = att.propagate(body, truth, t).dataset["quaternion"].values
    >>> res = att.fit([att.AttitudeObservations(t, q, "0.001 deg")], body, truth,
    ...               free=["phi0", "psi0"])
    >>> objective = res.objective
    >>> x = np.array([res.parameters[name] for name in res.free])
    >>> r = objective.residuals(x)          # 40 quaternions x 3 axes + the domain penalty
    >>> r.shape, bool(np.abs(r).max() < 1e-6)        # exact data: residuals ~ 0 at the truth
    ((1, 121), True)
    >>> objective.jacobian(x).shape
    (121, 2)
    """

    observations: tuple
    model: RotationModel
    fixed: np.ndarray
    free: tuple
    times: np.ndarray = field(init=False, repr=False)
    slices: tuple = field(init=False, repr=False)
    needs_periods: bool = field(init=False, repr=False)

    def __post_init__(self):
        spans, t_all, start = [], [], 0
        for obs in self.observations:
            t = seconds_since(self.model.epoch, obs.times) if np.size(obs.times) else \
                np.zeros(0)
            delay = getattr(obs, "delay", None)
            if delay is not None:
                t = t - delay                       # light time: emission epochs
            spans.append(slice(start, start + t.size))
            t_all.append(t)
            start += t.size
        object.__setattr__(self, "times", np.concatenate(t_all) if t_all else np.zeros(0))
        object.__setattr__(self, "slices", tuple(spans))
        # period observations have residuals but no epochs: the model's periods are
        # computed only when one is present
        object.__setattr__(self, "needs_periods", any(
            o.n_residuals and not np.size(o.times) for o in self.observations))

    def full(self, x: np.ndarray) -> np.ndarray:
        """Free values (N, k) -> full parameter vectors (N, 8)."""
        x = np.atleast_2d(x)
        v = np.repeat(self.fixed[None], x.shape[0], axis=0)
        v[:, list(self.free)] = x
        return v

    def jacobian(self, x: np.ndarray) -> np.ndarray:
        """(m, k) central-difference Jacobian at one point: all 2k parameter vectors
        propagated as one batch (steps of eps^(1/3) relative, at least 1e-8 absolute;
        truncation and round-off errors ~eps^(2/3), 4e-11 relative).

        The batch costs about what one evaluation costs: the exact solution is
        vectorised over bodies."""
        x = np.asarray(x, dtype=float)
        h = np.maximum(np.finfo(float).eps ** (1 / 3) * np.abs(x), 1e-8)
        step = np.diag(h)
        r = self.residuals(np.vstack([x + step, x - step]))
        k = x.size
        return ((r[:k] - r[k:]) / (2 * h[:, None])).T

    def residuals(self, x: np.ndarray) -> np.ndarray:
        """(N, m) normalised residuals, the last column the domain penalty."""
        v, distance = project(self.full(x))
        if self.times.size:
            q, w = self.model.evaluate(v, self.times)
        else:
            q = w = np.zeros((v.shape[0], 0, 4))
        periods = self.model.periods(v) if self.needs_periods else {}
        parts = [obs.residuals(q[:, s], w[:, s], periods)
                 for obs, s in zip(self.observations, self.slices)]
        parts.append(PENALTY * distance[:, None])
        out = np.concatenate(parts, axis=1)
        return np.where(np.isfinite(out), out, 1e6)


@dataclass(frozen=True)
class FitResult:
    """The outcome of :func:`fit`.

    Attributes
    ----------
    success, message : bool, str
        From the solver, for the best start; ``success`` is also False when the solver
        stopped at a chi^2 more than :data:`CHI2_SIGMAS` standard deviations above its
        expectation (a local minimum: the message says so), and when it ran out of
        evaluations (``max_nfev``), whatever the chi^2.
    status : str
        What the solver's stop means: ``"converged"``; ``"local minimum"`` (converged
        at an improbable chi^2, above); ``"max_nfev at an acceptable chi2"`` (out of
        evaluations at a chi^2 below the :data:`ACCEPTABLE_CHI2_QUANTILE` quantile of
        its distribution: as good a fit as the data allow, not yet converged: raise
        ``max_nfev``); ``"max_nfev"`` (out of evaluations at a higher chi^2);
        ``"failed"`` (any other stop of the solver).
    body, state : RigidBody, AttitudeState
        The fitted body (moments in the guess body's axes) and state at the epoch.
    regime : str
        ``"SAM"`` or ``"LAM"`` (:func:`attitude.diagnose`).
    margin : float
        Distance of E/E0 from the separatrix C/B in units of its 1-sigma (how sure the
        regime is; inf when neither is free).
    parameters, uncertainties : dict
        Every parameter (fixed ones with uncertainty 0), SI and radians.
    covariance : (k, k) array
        Of the free parameters, in the order of ``free``.
    free : tuple of str
    residuals : (m,) array
        Normalised residuals at the optimum (without the penalty term).
    chi2 : float
    dof : int
        Residuals minus free parameters (and minus the lightcurve offsets).
    alternatives : tuple of (chi2, regime)
        The optimum reached from every start (the guess, its mirror across the
        separatrix, psi0 + pi, ...), best first: a second regime with a chi2 close to
        the best one is an ambiguity the data do not resolve.

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> body = att.RigidBody.from_principal_moments([0.6, 0.9, 1.0])
    >>> truth = att.AttitudeState("2029-04-13", Rotation.from_rotvec([0.3, -0.2, 1.0]),
    ...                           [0.05, 0.1, 1.0])
    >>> t = np.linspace(0.0, 20.0, 40)
    >>> q = att.propagate(body, truth, t).dataset["quaternion"].values
    >>> res = att.fit([att.AttitudeObservations(t, q, "0.001 deg")], body, truth,
    ...               free=["phi0", "psi0"])
    >>> res.success, res.status, res.regime, res.free, res.dof
    (True, 'converged', 'SAM', ('phi0', 'psi0'), 118)
    >>> bool(res.chi2 < 1e-6)                             # noiseless data
    True
    >>> res.uncertainties["energy_ratio"]                 # fixed: no uncertainty
    0.0
    """

    success: bool
    message: str
    status: str
    body: RigidBody
    state: AttitudeState
    regime: str
    margin: float
    parameters: dict
    uncertainties: dict
    covariance: np.ndarray
    free: tuple
    residuals: np.ndarray
    chi2: float
    dof: int
    alternatives: tuple
    objective: Objective = field(repr=False)

    def summary(self) -> str:
        """A table of the parameters with their 1-sigma.

        See :func:`fit` for an example.
        """
        rows = [f"regime {self.regime} ({self.margin:.1f} sigma from the separatrix), "
                f"chi2 = {self.chi2:.3g} for {self.dof} degrees of freedom"]
        for name in PARAMETERS:
            value, sigma = self.parameters[name], self.uncertainties[name]
            unit = "deg" if name in ANGLES else ("s" if name == "precession_period" else "")
            scale = np.degrees(1.0) if name in ANGLES else 1.0
            mark = "" if name in self.free else "  (fixed)"
            rows.append(f"  {name:22s} {value * scale:14.8g} +- {sigma * scale:.3g} {unit}"
                        f"{mark}")
        return "\n".join(rows)


    def lightcurve_offsets(self) -> tuple:
        """The magnitude offset of every session of every lightcurve, with its 1-sigma.

        The offsets were profiled out of the fit (the weighted mean residual of each
        session, :class:`~attitude.fitting.LightcurveObservations`); their variance is
        that of a weighted mean, ``1 / sum(w)``, plus what the uncertainty of the
        rotation parameters carries into it, ``g^T C g`` (``g`` the derivative of the
        offset by the free parameters, central differences as for the Jacobian; the
        two are uncorrelated: the fit sees only the residuals with the session means
        removed).

        Returns
        -------
        tuple of dict
            One per lightcurve, in the order of the observations: ``session`` (labels),
            ``offset`` and ``sigma`` (mag), arrays in the order of the labels.

        Examples
        --------
        >>> import numpy as np, attitude as att
        >>> from scipy.spatial.transform import Rotation
        >>> body = att.RigidBody.from_principal_moments([0.6, 0.9, 1.0])
        >>> truth = att.AttitudeState("2029-04-13", Rotation.from_rotvec([0.3, -0.2, 1.0]),
        ...                           [0.05, 0.1, 1.0])
        >>> shape = att.Polyhedron.ellipsoid_from_moments(body.principal_moments,
        ...                                               subdivisions=1)
        >>> geom = att.Geometry(sun=[1.0, 0, 0], observer=[np.cos(0.4), np.sin(0.4), 0.2])
        >>> t = np.linspace(0.0, 60.0, 120)
        >>> q = att.propagate(body, truth, t).dataset["quaternion"].values
        >>> night = (t > 30.0).astype(int)                   # two sessions
        >>> clean = att.LightcurveObservations(t, np.zeros(t.size), 0.01, geom, shape)
        >>> mag = clean.model_magnitudes(q[None])[0] + np.where(night, 12.3, 11.8)
        >>> obs = att.LightcurveObservations(t, mag, 0.01, geom, shape, sessions=night)
        >>> res = att.fit(obs, body, truth, free=["phi0", "psi0"], multistart=False)
        >>> res.dof                                # 120 magnitudes - 2 angles - 2 offsets
        116
        >>> (lc,) = res.lightcurve_offsets()
        >>> lc["session"].tolist(), lc["offset"].round(6).tolist()
        ([0, 1], [11.8, 12.3])
        >>> bool(np.all(lc["sigma"] < 0.01))
        True
        """
        obj = self.objective
        values = np.array([self.parameters[n] for n in PARAMETERS])
        x = values[list(obj.free)]
        h = np.maximum(np.finfo(float).eps ** (1 / 3) * np.abs(x), 1e-8)
        k = x.size
        xs = np.vstack([x[None], x + np.diag(h), x - np.diag(h)])
        v, _ = project(obj.full(xs))
        q, _ = obj.model.evaluate(v, obj.times)
        out = []
        for o, s in zip(obj.observations, obj.slices):
            if not isinstance(o, LightcurveObservations):
                continue
            b = o.offsets(q[:, s])                                   # (1 + 2k, S)
            g = (b[1:k + 1] - b[k + 1:]) / (2 * h[:, None])          # (k, S)
            var = 1.0 / o.session_weight + np.einsum("ks,kl,ls->s", g, self.covariance, g)
            out.append({"session": o.session_labels, "offset": b[0],
                        "sigma": np.sqrt(var)})
        return tuple(out)


def _starts(p0: np.ndarray, free: tuple) -> list[np.ndarray]:
    """The guess and its discrete alternatives (mirror across the separatrix, psi0 + pi)."""
    out = [p0]
    i_er, i_psi = PARAMETERS.index("energy_ratio"), PARAMETERS.index("psi0")
    if i_er in free:
        mirror = p0.copy()
        sep = 1.0 / p0[4]
        mirror[i_er] = np.clip(2 * sep - p0[i_er], 1.0 + 1e-6, 1.0 / p0[3] - 1e-6)
        out.append(mirror)
    if i_psi in free:
        for base in list(out):
            turned = base.copy()
            turned[i_psi] = (base[i_psi] + np.pi) % (2 * np.pi)
            out.append(turned)
    return out


def fit(observations, body: RigidBody, state: AttitudeState, *, free=None, starts=None,
        multistart: bool = True, **solver) -> FitResult:
    """Fit the torque-free rotation state (and moment ratios) to observations.

    Parameters
    ----------
    observations : observation or sequence of observations
        :class:`~attitude.fitting.AttitudeObservations`,
        :class:`~attitude.fitting.AngularVelocityObservations`,
        :class:`~attitude.fitting.PeriodObservations`,
        :class:`~attitude.fitting.LightcurveObservations`, in any mix.
    body, state : RigidBody, AttitudeState
        The first guess; its epoch is the epoch of the fitted state, its principal axes
        (in the body frame) and its largest moment C are kept.
    free : sequence of str, optional
        Names from :data:`~attitude.fitting.PARAMETERS` to fit; default all eight.
    starts : sequence of dict, optional
        Extra starting points (parameter name -> value) besides the automatic ones.
    multistart : bool
        Also start from the guess's discrete alternatives (default); ``False`` starts
        from the guess (and ``starts``) only, when the guess is known to be close.
    **solver
        Passed to ``scipy.optimize.least_squares`` (default ``x_scale="jac"``,
        ``xtol=ftol=gtol=1e-8``: a relative change of chi^2 below 1e-8 is far below
        its statistical spread; ``max_nfev=500`` per start).

    Returns
    -------
    FitResult

    Raises
    ------
    AttitudeError
        On an unknown parameter name, no observations, or more free parameters than
        residuals.

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> body = att.RigidBody.from_principal_moments([0.6, 0.9, 1.0])
    >>> truth = att.AttitudeState("2029-04-13", Rotation.from_rotvec([0.3, -0.2, 1.0]),
    ...                           [0.05, 0.1, 1.0])
    >>> t = np.linspace(0.0, 20.0, 40)
    >>> q = att.propagate(body, truth, t).dataset["quaternion"].values
    >>> guess = att.AttitudeState(truth.epoch, truth.attitude, [0.06, 0.09, 1.01])
    >>> res = att.fit([att.AttitudeObservations(t, q, "0.001 deg")], body, guess)
    >>> res.regime, bool(np.allclose(res.state.omega_body, truth.omega_body, atol=1e-8))
    ('SAM', True)
    """
    if not isinstance(observations, (list, tuple)):
        observations = [observations]
    observations = tuple(observations)
    if not observations:
        raise AttitudeError("give at least one set of observations", key="observations")
    p0_dict, model = free_parameters(body, state)
    names = PARAMETERS if free is None else tuple(free)
    unknown = [n for n in names if n not in PARAMETERS]
    if unknown or not names:
        raise AttitudeError(f"unknown parameter(s) {unknown}; use names from "
                            f"{', '.join(PARAMETERS)}", key="free")
    idx = tuple(sorted({PARAMETERS.index(n) for n in names}))
    n_res = sum(o.n_residuals for o in observations)
    if n_res < len(idx):
        raise AttitudeError(f"{len(idx)} free parameters but only {n_res} residuals: fix "
                            f"some parameters (free=...) or add observations", key="free")
    p0 = np.array([p0_dict[k] for k in PARAMETERS])
    objective = Objective(observations, model, p0, idx)
    candidates = _starts(p0, idx) if multistart else [p0]
    for extra in starts or ():
        c = p0.copy()
        for k, v in extra.items():
            c[PARAMETERS.index(k)] = v
        candidates.append(c)
    options = dict(x_scale="jac", xtol=1e-8, ftol=1e-8, gtol=1e-8, method="trf",
                   max_nfev=500)
    options.update(solver)
    solutions = []
    with Progress(len(candidates), "fit (least squares)", unit="starts") as bar, \
            bar.ticking():                 # shown by the command line (not --quiet)
        for c in candidates:
            solutions.append(least_squares(lambda x: objective.residuals(x)[0],
                                           c[list(idx)], jac=objective.jacobian, **options))
            bar.update()
    best = min(solutions, key=lambda sol: sol.cost)
    alternatives = tuple(sorted(
        (2 * float(sol.cost), str(objective.model.periods(
            project(objective.full(sol.x))[0])["regime"][0])) for sol in solutions))
    return _result(best, objective, alternatives)


def _result(sol, objective: Objective, alternatives: tuple) -> FitResult:
    values, _ = project(objective.full(sol.x))
    values = values[0]
    jac = sol.jac[:-1]                                       # without the penalty row
    covariance = np.linalg.pinv(jac.T @ jac)
    sig = np.sqrt(np.clip(np.diag(covariance), 0.0, None))
    names = tuple(PARAMETERS[i] for i in objective.free)
    parameters = dict(zip(PARAMETERS, map(float, values)))
    for k in ANGLES[:1] + ANGLES[2:]:
        parameters[k] %= 2 * np.pi
    uncertainties = dict.fromkeys(PARAMETERS, 0.0)
    uncertainties.update(zip(names, map(float, sig)))
    body, state = objective.model.body_and_state(values)
    periods = objective.model.periods(values[None])
    regime = str(periods["regime"][0])
    # E/E0 - C/B and its 1-sigma from the covariance (gradient in (E/E0, B/C))
    grad = np.zeros(len(names))
    for name, g in (("energy_ratio", 1.0), ("ratio_b", 1.0 / values[4] ** 2)):
        if name in names:
            grad[names.index(name)] = g
    s = float(np.sqrt(grad @ covariance @ grad))
    gap = abs(values[2] - 1.0 / values[4])
    margin = gap / s if s > 0 else np.inf
    res = sol.fun[:-1]
    nuisance = sum(getattr(o, "n_nuisance", 0) for o in objective.observations)
    chi2, dof = float(res @ res), int(res.size - len(names) - nuisance)
    status, message = stop_status(sol, chi2, dof)
    return FitResult(status == "converged", message, status, body, state, regime,
                     float(margin), parameters, uncertainties, covariance, names, res, chi2,
                     dof, alternatives, objective)


def acceptable_chi2(dof: int, quantile: float = ACCEPTABLE_CHI2_QUANTILE) -> float:
    """The ``quantile`` of the chi^2 distribution with ``dof`` degrees of freedom.

    Examples
    --------
    >>> round(acceptable_chi2(291), 1)                # 291 + about 3.1 sqrt(2 * 291)
    371.3
    """
    return float(2.0 * gammaincinv(0.5 * dof, quantile))


def stop_status(sol, chi2: float, dof: int) -> tuple[str, str]:
    """The status of a fit (:class:`FitResult`) and its message, from the solver's stop
    (``scipy.optimize.least_squares``'s ``status``, ``nfev``, ``message``) and the
    chi^2 it stopped at."""
    where = f"chi2 = {chi2:.6g} for {dof} degrees of freedom"
    if sol.status == 0:                              # least_squares: max_nfev reached
        if dof > 0 and chi2 <= acceptable_chi2(dof):
            return "max_nfev at an acceptable chi2", (
                f"max_nfev reached at an acceptable chi2: the solver stopped after "
                f"{sol.nfev} evaluations ({sol.message}) at {where}, below the "
                f"{ACCEPTABLE_CHI2_QUANTILE:.1%} quantile of its distribution "
                f"({acceptable_chi2(dof):.6g}): the state fits the data, but the solver's "
                "tolerances were not met; raise max_nfev to converge")
        return "max_nfev", (f"not converged: the solver stopped ({sol.message}) at {where}; "
                            "raise max_nfev, or start closer (starts=...)")
    if not sol.success:
        return "failed", str(sol.message)
    if dof > 0 and chi2 > dof + CHI2_SIGMAS * np.sqrt(2.0 * dof):
        return "local minimum", (
            f"the solver stopped ({sol.message}) at {where}, "
            f"{(chi2 - dof) / np.sqrt(2.0 * dof):.0f} sigma above its expectation: a local "
            "minimum, or uncertainties that are too small; try other starts (starts=...) "
            "or check the sigmas")
    return "converged", str(sol.message)

"""Posterior sampling of a fitted rotation state with emcee (the ``fitting`` extra).

The likelihood is ``exp(-chi^2 / 2)`` of the same normalised residuals as the least-squares
fit; the prior is uniform over the physical domain of the free parameters (outside it the
log-probability is ``-inf``).  emcee's affine-invariant ensemble runs with
``vectorize=True``: the walkers of one step are propagated as one batch by the exact
solution, so a step costs one vectorised call, not one per walker.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import xarray as xr

from ..foundations.errors import MissingDependencyError
from ..foundations.progress import Progress
from .leastsq import FitResult, Objective, project
from .parameters import PARAMETERS

__all__ = ["Posterior", "sample_posterior"]


@dataclass(frozen=True)
class Posterior:
    """Samples of the posterior of a fit.

    Attributes
    ----------
    samples : xarray.Dataset
        One variable per free parameter and ``regime`` (str), dims ``(step, walker)``,
        the burn-in removed.
    autocorrelation_time : dict
        emcee's integrated autocorrelation time per free parameter, in steps (NaN where
        the chain is too short to estimate it).
    acceptance_fraction : float
        Mean over walkers.

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
    >>> post = sample_posterior(res, n_walkers=8, n_steps=60, rng=1)
    >>> dict(post.samples.sizes), sorted(post.samples.data_vars)    # burn-in: 15 steps
    ({'step': 45, 'walker': 8}, ['phi0', 'psi0', 'regime'])
    >>> low, median, high = post.intervals(0.95)["psi0"]
    >>> bool(low < res.parameters["psi0"] < high)
    True
    """

    samples: xr.Dataset
    autocorrelation_time: dict
    acceptance_fraction: float

    def intervals(self, level: float = 0.95) -> dict:
        """Central credible intervals: ``{name: (low, median, high)}``.

        Examples
        --------
        >>> import xarray as xr, numpy as np
        >>> s = xr.Dataset({"ratio_a": (("step", "walker"), np.arange(100.0).reshape(10, 10))})
        >>> Posterior(s, {}, 0.3).intervals(0.5)["ratio_a"]
        (24.75, 49.5, 74.25)
        """
        lo, hi = 50 * (1 - level), 50 * (1 + level)
        out = {}
        for name, var in self.samples.data_vars.items():
            if var.dtype.kind == "f":
                x = var.values.ravel()
                out[name] = tuple(float(v) for v in np.percentile(x, [lo, 50, hi]))
        return out

    @property
    def regime_fractions(self) -> dict:
        """Fraction of the samples in each regime (how sure are we that it is SAM?)."""
        names, counts = np.unique(self.samples["regime"].values.ravel(), return_counts=True)
        return {str(k): float(c / counts.sum()) for k, c in zip(names, counts)}


def sample_posterior(result: FitResult, observations=None, *, n_walkers: int = 32,
                     n_steps: int = 1000, burn: int | None = None, rng=None,
                     scatter: float = 1e-3, progress: bool = False) -> Posterior:
    """Sample the posterior around a least-squares fit with emcee.

    Parameters
    ----------
    result : FitResult
        The fit to start from; its free parameters are sampled.
    observations : sequence, optional
        Default: those of the fit.
    n_walkers, n_steps : int
        Ensemble size (>= 2 x free parameters) and steps per walker.
    burn : int, optional
        Steps dropped at the start (default a quarter).
    rng : int or numpy Generator, optional
        Seed of the walkers' start and of emcee's moves.
    scatter : float
        Walkers start in a Gaussian ball of ``scatter`` times the fit's 1-sigma (or of
        ``scatter`` relative where the 1-sigma is zero).
    progress : bool
        Report the steps on stderr (:mod:`attitude.foundations.progress`).

    Returns
    -------
    Posterior

    Raises
    ------
    MissingDependencyError
        Without emcee: ``pip install "attitude-dynamics[fitting]"``.

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
    >>> post = sample_posterior(res, n_walkers=8, n_steps=60, rng=1)
    >>> regimes = set(post.samples.regime.values.ravel().tolist())
    >>> bool(0.0 < post.acceptance_fraction < 1.0), regimes
    (True, {'SAM'})
    >>> offset = float(post.samples.psi0.median()) - res.parameters["psi0"]
    >>> bool(abs(offset) < res.uncertainties["psi0"])   # centred on the fit, within 1 sigma
    True
    """
    try:
        import emcee  # optional dependency (the fitting extra)
    except ImportError:
        raise MissingDependencyError("posterior sampling needs emcee: pip install "
                                     "\"attitude-dynamics[fitting]\"") from None
    objective = result.objective
    if observations is not None:
        objective = Objective(tuple(observations), objective.model, objective.fixed,
                              objective.free)
    k = len(objective.free)
    if n_walkers < 2 * k:
        n_walkers = 2 * k + 2
    generator = np.random.default_rng(rng)
    center = np.array([result.parameters[PARAMETERS[i]] for i in objective.free])
    sigma = np.array([result.uncertainties[PARAMETERS[i]] for i in objective.free])
    width = np.where(sigma > 0, scatter * sigma, scatter * np.maximum(abs(center), 1e-3))
    start = center + width * generator.standard_normal((n_walkers, k))

    def log_prob(x):
        x = np.atleast_2d(x)
        _, outside = project(objective.full(x))
        r = objective.residuals(x)[:, :-1]
        lp = -0.5 * np.sum(r * r, axis=1)
        return np.where(outside > 0, -np.inf, lp)

    sampler = emcee.EnsembleSampler(n_walkers, k, log_prob, vectorize=True)
    sampler.random_state = np.random.RandomState(  # emcee's moves draw from their own
        int(generator.integers(2**31))).get_state()   # legacy generator: seed it
    # run_mcmc's loop, with attitude's progress report instead of emcee's tqdm bar
    with Progress(n_steps, "posterior (MCMC)", unit="steps", show=progress) as bar:
        for _ in sampler.sample(start, iterations=n_steps):
            bar.update()
    burn = n_steps // 4 if burn is None else int(burn)
    chain = sampler.get_chain(discard=burn)                     # (step, walker, k)
    names = [PARAMETERS[i] for i in objective.free]
    data = {n: (("step", "walker"), chain[..., j]) for j, n in enumerate(names)}
    flat = chain.reshape(-1, k)
    regimes = objective.model.periods(project(objective.full(flat))[0])["regime"]
    data["regime"] = (("step", "walker"), np.asarray(regimes).reshape(chain.shape[:2]))
    try:
        tau = sampler.get_autocorr_time(discard=burn, quiet=True)
    except Exception:  # emcee raises when the chain is far too short
        tau = np.full(k, np.nan)
    return Posterior(xr.Dataset(data), dict(zip(names, map(float, tau))),
                     float(np.mean(sampler.acceptance_fraction)))

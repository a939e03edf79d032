"""Figures of a fit: the normalised residuals of each set of observations, and the
pairwise distributions of a posterior (a corner plot drawn with matplotlib alone).
"""

from __future__ import annotations

import numpy as np

from ..foundations.figures import agg_figure
from .leastsq import FitResult
from .parameters import ANGLES
from .posterior import Posterior

__all__ = ["residual_figure", "corner_figure"]


def residual_figure(result: FitResult):
    """The normalised residuals (residual / sigma) of each observation set against its
    index, with the +-1 and +-3 sigma bands.

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> body = att.RigidBody.from_principal_moments([0.6, 0.9, 1.0])
    >>> truth = att.AttitudeState("2029-04-13", Rotation.identity(), [0.05, 0.1, 1.0])
    >>> t = np.linspace(0.0, 10.0, 20)
    >>> q = att.propagate(body, truth, t).dataset["quaternion"].values
    >>> res = att.fit(att.AttitudeObservations(t, q, "0.01 deg"), body, truth,
    ...               free=["energy_ratio", "precession_period"], multistart=False)
    >>> len(residual_figure(res).axes)
    1
    """
    obs = result.objective.observations
    fig = agg_figure(figsize=(8, 2.4 * len(obs)), layout="constrained")
    start = 0
    for k, o in enumerate(obs):
        ax = fig.add_subplot(len(obs), 1, k + 1)
        r = result.residuals[start:start + o.n_residuals]
        start += o.n_residuals
        ax.plot(np.arange(r.size), r, ".", ms=3)
        for level, style in ((1, ":"), (3, "--")):
            for sign in (1, -1):
                ax.axhline(sign * level, color="0.5", lw=0.7, ls=style)
        ax.set_ylabel("residual / sigma")
        ax.set_title(f"{type(o).__name__}: rms {np.sqrt(np.mean(r * r)):.2f}",
                     fontsize="small")
    fig.axes[-1].set_xlabel("residual index")
    return fig


def corner_figure(posterior: Posterior):
    """Pairwise scatter plots and histograms of the posterior samples of the free
    parameters (angles in degrees).

    Examples
    --------
    >>> import numpy as np, xarray as xr
    >>> rng = np.random.default_rng(0)
    >>> s = xr.Dataset({k: (("step", "walker"), rng.normal(size=(50, 8)))
    ...                 for k in ("energy_ratio", "ratio_a")})
    >>> len(corner_figure(Posterior(s, {}, 0.3)).axes)      # 2 x 2, upper triangle empty
    3
    """
    names = [n for n, v in posterior.samples.data_vars.items() if v.dtype.kind == "f"]
    k = len(names)
    fig = agg_figure(figsize=(2.2 * k + 1, 2.2 * k + 1), layout="constrained")
    values = {n: posterior.samples[n].values.ravel() * (np.degrees(1.0) if n in ANGLES
                                                         else 1.0) for n in names}
    for i, yi in enumerate(names):
        for j, xj in enumerate(names[:i + 1]):
            ax = fig.add_subplot(k, k, i * k + j + 1)
            if i == j:
                ax.hist(values[xj], bins=30, color="tab:blue", histtype="step")
                ax.set_yticks([])
            else:
                ax.plot(values[xj], values[yi], ".", ms=1, alpha=0.3)
                if j == 0:
                    ax.set_ylabel(yi, fontsize="small")
            if i == k - 1:
                ax.set_xlabel(xj, fontsize="small")
    return fig

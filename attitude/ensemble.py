"""Ensembles: populations of bodies and states, propagated and summarised together.

The user's namespace for populations (``att.ensemble.regime_fractions(cloud)``,
``att.ensemble.local_cluster(2)``): it gathers what lives in the modules that own each
idea, and nothing inside the package imports it.

- :class:`~attitude.model.population.Ensemble`: the population container (arrays along
  ``body``), built from arrays, bodies, tables (:mod:`attitude.model.tables`) or a Monte
  Carlo draw (:mod:`attitude.model.sampling`, :data:`MODELS`);
- :func:`propagate_ensemble` and the ``status`` values: the chunked, optionally dask,
  propagation engine (:mod:`attitude.propagation.batch`); :func:`local_cluster`
  (:mod:`attitude.propagation.cluster`);
- the statistics of a population (:mod:`attitude.analysis.statistics`): :func:`diagnose_ensemble`,
  :func:`classify_ensemble`, :func:`regime_fractions`, :func:`period_quantiles`,
  :func:`attitude_spread`, :func:`spread_quantiles`.

Examples
--------
>>> import astropy.units as u, attitude as att
>>> cloud = att.Ensemble.sample(
...     50, rng=1, epoch="2029-04-13", frame="ECLIPJ2000",
...     mean={"angular_momentum_ra": 250 * u.deg, "angular_momentum_dec": -75 * u.deg,
...           "energy_ratio": 1.024, "ratio_a": 0.61, "ratio_b": 0.965,
...           "precession_period": 27.38 * u.h},
...     sigma={"energy_ratio": 0.013 / 3})
>>> att.ensemble.regime_fractions(cloud)
{'SAM': 1.0}
"""

from __future__ import annotations

from .analysis.statistics import (
    attitude_spread,
    classify_ensemble,
    diagnose_ensemble,
    period_quantiles,
    regime_fractions,
    spread_quantiles,
)
from .foundations.errors import InvalidBodiesWarning
from .model.population import Ensemble
from .model.sampling import MODELS, spin_state, tumbling_state
from .propagation.batch import STATUS_FAILED, STATUS_INVALID, STATUS_OK, propagate_ensemble
from .propagation.cluster import local_cluster

__all__ = [
    "Ensemble",
    "MODELS",
    "InvalidBodiesWarning",
    "STATUS_OK",
    "STATUS_INVALID",
    "STATUS_FAILED",
    "tumbling_state",
    "spin_state",
    "diagnose_ensemble",
    "classify_ensemble",
    "regime_fractions",
    "period_quantiles",
    "attitude_spread",
    "spread_quantiles",
    "propagate_ensemble",
    "local_cluster",
]

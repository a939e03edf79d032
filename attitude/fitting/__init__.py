"""Fitting: rotation states and moment ratios from observations, with uncertainties.

The rotation-state studies this toolkit serves run backwards, from observed attitudes,
rates, periods or lightcurves to the state and its uncertainties (Pravec et al. 2014 for
Apophis).  The forward model is the exact torque-free solution, evaluated for many
parameter vectors in one vectorised call:

- :mod:`~attitude.fitting.parameters` -- Pravec's parameterisation and the forward model;
- :mod:`~attitude.fitting.observations` -- attitudes, rates, periods and lightcurves, each
  with its uncertainties;
- :mod:`~attitude.fitting.leastsq` -- :func:`fit`: least squares with multi-start over
  the discrete ambiguities, covariance, regime and its margin;
- :mod:`~attitude.fitting.posterior` -- :func:`sample_posterior`: MCMC with emcee (the
  ``fitting`` extra), all walkers propagated as one batch;
- :mod:`~attitude.fitting.synthetic` -- closed loops on synthetic data: random hidden
  states, noisy observations of them, perturbed first guesses (the tests and
  ``benchmarks/fitting_coverage.py`` draw their cases with it).
"""

from .leastsq import FitResult, fit
from .observations import (
    AngularVelocityObservations,
    AttitudeObservations,
    LightcurveObservations,
    PeriodObservations,
)
from .parameters import PARAMETERS, RotationModel, free_parameters
from .posterior import Posterior, sample_posterior

__all__ = [
    "fit",
    "FitResult",
    "sample_posterior",
    "Posterior",
    "AttitudeObservations",
    "AngularVelocityObservations",
    "PeriodObservations",
    "LightcurveObservations",
    "PARAMETERS",
    "RotationModel",
    "free_parameters",
]

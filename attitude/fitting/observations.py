"""Observations of a rotation, each with its uncertainties, as immutable value objects.

Every kind gives the residuals of a batch of model rotations, normalised by its
uncertainties (so that the sum of squares is chi^2):

- :class:`AttitudeObservations` -- measured attitudes (quaternions) with an angular
  1-sigma per axis: three residuals per sample, the rotation vector from the measured to
  the modelled attitude over sigma;
- :class:`AngularVelocityObservations` -- measured body rates with a 1-sigma;
- :class:`PeriodObservations` -- periods with their 1-sigma, under the period keys of
  :func:`attitude.diagnose` (``precession`` P_phi, ``rotation`` P_psi, ``polhode``, ``spin``);
- :class:`LightcurveObservations` (photometry's, the one type of a lightcurve with its
  geometry, which the inversion reads too) -- magnitudes with their 1-sigma, the Sun/observer
  geometry, a shape and a scattering law: the model magnitude is the shape's brightness
  (:func:`attitude.photometry.facet_brightness`) in the modelled attitude, plus one
  fitted offset per observing session (the absolute magnitude and the nightly zero
  points are not part of the rotation state; they are profiled out).

A fit may mix them (:func:`attitude.fitting.fit`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..foundations import quaternion as quat
from ..foundations.errors import AttitudeError
from ..foundations.quantities import to_si
from ..model.regimes import PERIOD_KEYS
from ..photometry.observations import LightcurveObservations, sample_times, seconds_since

__all__ = ["AttitudeObservations", "AngularVelocityObservations", "PeriodObservations",
           "LightcurveObservations", "seconds_since"]


def _si(value, unit: str, key: str):
    """The quantity reader, its error keyed by ``key``."""
    return to_si(value, unit, key=key, finite=False, error=AttitudeError)


def _sigma(value, unit: str, key: str) -> float:
    s = _si(value, unit, key)
    if np.ndim(s) != 0 or not (np.isfinite(s) and s > 0):
        raise AttitudeError(f"must be one finite, positive uncertainty in {unit}, got "
                            f"{value!r}", key=key)
    return float(s)


@dataclass(frozen=True)
class AttitudeObservations:
    """Measured attitudes: body -> inertial quaternions (scalar-last) at ``times``.

    Parameters
    ----------
    times : astropy Time array, or seconds since the fit's epoch
    quaternions : (n, 4) array
        Body -> inertial, scalar-last (normalised here; the sign is irrelevant).
    sigma : float (rad), Quantity or str (``"0.01 deg"``)
        Angular 1-sigma per axis.

    Examples
    --------
    >>> import numpy as np
    >>> obs = AttitudeObservations([0.0, 10.0], [[0, 0, 0, 1], [0, 0, 0, 1]], "1 deg")
    >>> obs.n_residuals, round(float(np.degrees(obs.sigma)), 12)
    (6, 1.0)
    """

    times: object
    quaternions: np.ndarray
    sigma: float

    def __post_init__(self):
        q = np.asarray(self.quaternions, dtype=float)
        if q.ndim != 2 or q.shape[1] != 4 or not np.all(np.isfinite(q)):
            raise AttitudeError(f"expected finite quaternions of shape (n, 4), got shape "
                                f"{q.shape}", key="quaternions")
        norm = np.linalg.norm(q, axis=1, keepdims=True)
        if np.any(norm == 0):
            raise AttitudeError("a quaternion is zero", key="quaternions")
        object.__setattr__(self, "quaternions", q / norm)
        object.__setattr__(self, "times", sample_times(self.times, q.shape[0], "times"))
        object.__setattr__(self, "sigma", _sigma(self.sigma, "rad", "sigma"))

    @property
    def n_residuals(self) -> int:
        """Number of residuals (three per sample)."""
        return 3 * self.quaternions.shape[0]

    def residuals(self, q: np.ndarray, w: np.ndarray, periods: dict) -> np.ndarray:
        """(N, 3 n) rotation vectors from measured to modelled attitudes, over sigma."""
        d = quat.multiply(quat.conjugate(self.quaternions)[None], q)
        d = d * np.where(d[..., 3:] < 0, -1.0, 1.0)
        v = d[..., :3]
        s = np.linalg.norm(v, axis=-1, keepdims=True)
        angle = 2.0 * np.arctan2(s, d[..., 3:])
        scale = np.where(s > 1e-300, angle / np.where(s > 1e-300, s, 1.0), 2.0)
        return (v * scale).reshape(q.shape[0], -1) / self.sigma


@dataclass(frozen=True)
class AngularVelocityObservations:
    """Measured body rates (rad/s, body frame) at ``times``, with a 1-sigma per axis.

    Examples
    --------
    >>> obs = AngularVelocityObservations([0.0], [[0.0, 0.0, 0.1]], "1e-4 rad/s")
    >>> obs.n_residuals
    3
    """

    times: object
    omega: np.ndarray
    sigma: float

    def __post_init__(self):
        w = np.asarray(_si(self.omega, "rad/s", "omega"), dtype=float)
        if w.ndim != 2 or w.shape[1] != 3 or not np.all(np.isfinite(w)):
            raise AttitudeError(f"expected finite rates of shape (n, 3), got shape "
                                f"{w.shape}", key="omega")
        object.__setattr__(self, "omega", w)
        object.__setattr__(self, "times", sample_times(self.times, w.shape[0], "times"))
        object.__setattr__(self, "sigma", _sigma(self.sigma, "rad/s", "sigma"))

    @property
    def n_residuals(self) -> int:
        """Number of residuals (three per sample)."""
        return 3 * self.omega.shape[0]

    def residuals(self, q: np.ndarray, w: np.ndarray, periods: dict) -> np.ndarray:
        """(N, 3 n) rate differences over sigma."""
        return (w - self.omega[None]).reshape(w.shape[0], -1) / self.sigma


@dataclass(frozen=True)
class PeriodObservations:
    """Measured periods and their 1-sigma, by period key.

    Parameters
    ----------
    **periods : (value, sigma) pairs
        Keys of :data:`attitude.model.regimes.PERIOD_KEYS` (``precession``, ``rotation``,
        ``polhode``, ``spin``); values in seconds, Quantities or strings (``"27.38 h"``).

    Examples
    --------
    >>> obs = PeriodObservations(precession=("27.38 h", "0.07 h"), rotation=("263 h", "6 h"))
    >>> obs.periods["precession"]
    (98568.0, 252.0)
    """

    periods: dict

    def __init__(self, **periods):
        if not periods:
            raise AttitudeError("give at least one period, e.g. precession=('27.38 h', "
                                "'0.07 h')", key="periods")
        out = {}
        for key, pair in periods.items():
            if key not in PERIOD_KEYS:
                raise AttitudeError(f"unknown period key; use one of "
                                    f"{', '.join(PERIOD_KEYS)}", key=key)
            if not (isinstance(pair, (tuple, list)) and len(pair) == 2):
                raise AttitudeError("expected a (value, sigma) pair", key=key)
            value = _sigma(pair[0], "s", key)
            out[key] = (value, _sigma(pair[1], "s", f"{key}.sigma"))
        object.__setattr__(self, "periods", out)

    times = np.zeros(0)

    @property
    def n_residuals(self) -> int:
        """Number of residuals (one per period)."""
        return len(self.periods)

    def residuals(self, q: np.ndarray, w: np.ndarray, periods: dict) -> np.ndarray:
        """(N, k) period differences over sigma (NaN where the model has no such period)."""
        return np.stack([(periods[k] - v) / s for k, (v, s) in self.periods.items()],
                        axis=-1)

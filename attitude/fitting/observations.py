"""Observations of a rotation, each with its uncertainties, as immutable value objects.

Every kind gives the residuals of a batch of model rotations, normalised by its
uncertainties (so that the sum of squares is chi^2):

- :class:`AttitudeObservations` -- measured attitudes (quaternions) with an angular
  1-sigma per axis: three residuals per sample, the rotation vector from the measured to
  the modelled attitude over sigma;
- :class:`AngularVelocityObservations` -- measured body rates with a 1-sigma;
- :class:`PeriodObservations` -- periods with their 1-sigma, under the period keys of
  :func:`attitude.diagnose` (``precession`` P_phi, ``rotation`` P_psi, ``polhode``, ``spin``);
- :class:`LightcurveObservations` -- magnitudes with their 1-sigma, the Sun/observer
  geometry, a shape and a scattering law: the model magnitude is the shape's brightness
  (:func:`attitude.photometry.facet_brightness`) in the modelled attitude, plus one
  fitted offset per observing session (the absolute magnitude and the nightly zero
  points are not part of the rotation state; they are profiled out).

A fit may mix them (:func:`attitude.fitting.fit`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from astropy.time import Time

from ..foundations import quaternion as quat
from ..foundations.errors import AttitudeError
from ..foundations.quantities import to_si
from ..model.regimes import PERIOD_KEYS
from ..photometry.brightness import facet_brightness
from ..photometry.geometry import Geometry

__all__ = ["AttitudeObservations", "AngularVelocityObservations", "PeriodObservations",
           "LightcurveObservations", "seconds_since"]


def seconds_since(epoch: Time, times) -> np.ndarray:
    """Observation times as seconds since ``epoch``: an astropy Time array (converted
    with the epoch's scale) or plain seconds already counted from it.

    Examples
    --------
    >>> from astropy.time import Time
    >>> e = Time("2029-04-13T00:00:00", scale="tdb")
    >>> seconds_since(e, Time(["2029-04-13T00:01:00"], scale="tdb"))
    array([60.])
    """
    if isinstance(times, Time):
        return np.atleast_1d((times - epoch).to_value("s"))
    return np.atleast_1d(to_si(times, "s", name="times", error=AttitudeError))


def _si(value, unit: str, key: str):
    """The quantity reader, its error keyed by ``key``."""
    return to_si(value, unit, key=key, finite=False, error=AttitudeError)


def _sigma(value, unit: str, key: str) -> float:
    s = _si(value, unit, key)
    if np.ndim(s) != 0 or not (np.isfinite(s) and s > 0):
        raise AttitudeError(f"must be one finite, positive uncertainty in {unit}, got "
                            f"{value!r}", key=key)
    return float(s)


def _times(times, n_expected: int | None, key: str):
    if isinstance(times, Time):
        t = times.reshape(-1)
    else:
        t = np.atleast_1d(_si(times, "s", key))
        if not np.all(np.isfinite(t)):
            raise AttitudeError("times must be finite", key=key)
    if t.size == 0 or (n_expected is not None and t.size != n_expected):
        raise AttitudeError(f"expected {n_expected} times (one per sample), got {t.size}",
                            key=key)
    return t


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
        object.__setattr__(self, "times", _times(self.times, q.shape[0], "times"))
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
        object.__setattr__(self, "times", _times(self.times, w.shape[0], "times"))
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


@dataclass(frozen=True)
class LightcurveObservations:
    """Measured magnitudes of a body of known shape, with their 1-sigma and geometry.

    Parameters
    ----------
    times : astropy Time array, or seconds since the fit's epoch
        Observation (reception) times; the attitude is modelled at ``times -
        geometry.light_time`` when the geometry carries light times.
    magnitudes : (n,) array
    sigma : float or (n,) array
        1-sigma of each magnitude, mag.
    geometry : attitude.photometry.Geometry
        Sun and observer directions (inertial frame of the fit), constant or per epoch.
    shape : attitude.Polyhedron
        The body's shape in the body frame of the fit.
    law : str or scattering law
        As in :func:`attitude.photometry.dataset` (default ``"ls-lambert"``).
    sessions : (n,) array, optional
        Session label of each magnitude (the ``session`` variable of
        :func:`attitude.photometry.read_lightcurve`: an ALCDEF block, a night): each
        session gets its own magnitude offset.  Default: one session.

    Attributes
    ----------
    session_labels : (S,) array
        The distinct session labels, sorted (``[0]`` for one session).
    session_index : (n,) int array
        The session of each magnitude, as an index into ``session_labels``.
    session_weight : (S,) array
        ``sum(1/sigma^2)`` of each session (the inverse variance of its offset at fixed
        rotation parameters).

    Notes
    -----
    The model magnitude is ``-2.5 log10(flux) + offset_s`` with one offset per session
    ``s``.  Differential magnitudes of different nights have independent zero points
    (comparison stars, extinction, filters), so the offsets are unknown; they enter the
    model linearly, and for fixed rotation parameters the least-squares offset of a
    session is the weighted mean residual of its magnitudes,
    ``offset_s = sum_i w_i (m_i - model_i) / sum_i w_i`` (``w = 1/sigma^2``, ``i`` in
    ``s``).  The residuals are evaluated with these offsets (they are *profiled out*,
    the variable projection of Golub & Pereyra 1973), so the solver sees only the
    rotation parameters:

    - chi^2 at the optimum is the joint minimum over rotation and offsets, and the
      offsets are counted in the degrees of freedom (:attr:`n_nuisance`, one per
      session);
    - the Jacobian of the profiled residuals is the rotation Jacobian with its
      session means removed, so ``(J^T J)^-1`` is the covariance of the rotation
      parameters *marginalised* over the offsets (the Schur complement of the joint
      normal matrix), not the smaller one at fixed offsets;
    - the posterior (:func:`attitude.fitting.sample_posterior`) of the profiled chi^2 is
      the posterior marginalised over offsets with flat priors (the Gaussian integral
      over a linear parameter is a constant);
    - :meth:`offsets` gives the offsets of a model; with their 1-sigma,
      :meth:`attitude.fitting.FitResult.lightcurve_offsets`.

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> shape = att.Polyhedron.ellipsoid(2.0, 1.2, 1.0, subdivisions=2)
    >>> geom = att.Geometry(sun=[1.0, 0, 0], observer=[np.cos(0.3), np.sin(0.3), 0])
    >>> obs = LightcurveObservations([0.0, 60.0], [15.0, 15.2], 0.01, geom, shape)
    >>> obs.n_residuals, obs.n_nuisance
    (2, 1)
    >>> two = LightcurveObservations([0.0, 60.0, 86400.0], [15.0, 15.2, 14.1], 0.01, geom,
    ...                              shape, sessions=["night 1", "night 1", "night 2"])
    >>> two.n_nuisance, two.session_labels.tolist()
    (2, ['night 1', 'night 2'])
    """

    times: object
    magnitudes: np.ndarray
    sigma: object
    geometry: Geometry
    shape: object
    law: object = "ls-lambert"
    delay: np.ndarray = None
    sessions: object = None

    def __post_init__(self):
        m = np.asarray(self.magnitudes, dtype=float)
        if m.ndim != 1 or m.size == 0 or not np.all(np.isfinite(m)):
            raise AttitudeError(f"expected a non-empty 1-D array of finite magnitudes, got "
                                f"shape {m.shape}", key="magnitudes")
        object.__setattr__(self, "magnitudes", m)
        object.__setattr__(self, "times", _times(self.times, m.size, "times"))
        sig = np.asarray(self.sigma, dtype=float)
        if sig.shape not in ((), m.shape) or not np.all(np.isfinite(sig) & (sig > 0)):
            raise AttitudeError(f"expected one or {m.size} finite, positive magnitude "
                                f"uncertainties", key="sigma")
        object.__setattr__(self, "sigma", np.broadcast_to(sig, m.shape).copy())
        if not isinstance(self.geometry, Geometry):
            raise AttitudeError("expected an attitude.photometry.Geometry", key="geometry")
        sun, observer = self.geometry.broadcast(m.size)
        object.__setattr__(self, "_sun", sun)
        object.__setattr__(self, "_observer", observer)
        lt = self.geometry.light_time
        object.__setattr__(self, "delay", np.zeros(m.size) if lt is None else
                           np.broadcast_to(np.asarray(lt, dtype=float), m.shape).copy())
        if self.sessions is None:
            labels, index = np.zeros(1, dtype=int), np.zeros(m.size, dtype=int)
        else:
            s = np.asarray(self.sessions)
            if s.shape != m.shape:
                raise AttitudeError(f"expected one session label per magnitude ({m.size}), "
                                    f"got shape {s.shape}", key="sessions")
            labels, index = np.unique(s, return_inverse=True)
        object.__setattr__(self, "sessions", None if self.sessions is None else
                           np.asarray(self.sessions))
        object.__setattr__(self, "session_labels", labels)
        object.__setattr__(self, "session_index", index.reshape(-1))
        weight = 1.0 / self.sigma**2
        object.__setattr__(self, "_weight", weight)
        object.__setattr__(self, "session_weight",
                           np.bincount(index.reshape(-1), weight, minlength=labels.size))

    @property
    def n_residuals(self) -> int:
        """Number of residuals (one per magnitude)."""
        return self.magnitudes.size

    @property
    def n_nuisance(self) -> int:
        """Number of fitted offsets (one per session), counted in the degrees of freedom."""
        return int(self.session_labels.size)

    def model_magnitudes(self, q: np.ndarray) -> np.ndarray:
        """(N, n) magnitudes (without the offset) of the attitudes ``q`` (N, n, 4)."""
        inv = quat.conjugate(q)
        sun_b = quat.rotate(inv, self._sun[None])
        obs_b = quat.rotate(inv, self._observer[None])
        flux, _ = facet_brightness(self.shape, sun_b.reshape(-1, 3), obs_b.reshape(-1, 3),
                                   self.law)
        with np.errstate(divide="ignore", invalid="ignore"):
            return -2.5 * np.log10(flux.reshape(q.shape[:-1]))

    def _offsets(self, model: np.ndarray) -> np.ndarray:
        """(N, S) least-squares offsets of the model magnitudes (N, n), per session."""
        weighted = (self.magnitudes - model) * self._weight
        n_sessions = self.session_labels.size
        flat = self.session_index[None] + n_sessions * np.arange(model.shape[0])[:, None]
        sums = np.bincount(flat.ravel(), weighted.ravel(),
                           minlength=n_sessions * model.shape[0])
        return sums.reshape(model.shape[0], n_sessions) / self.session_weight

    def offsets(self, q: np.ndarray) -> np.ndarray:
        """(N, S) magnitude offsets per session (order of :attr:`session_labels`) that
        minimise chi^2 for the attitudes ``q`` (N, n, 4): the weighted mean residuals.

        Examples
        --------
        >>> import numpy as np, attitude as att
        >>> shape = att.Polyhedron.ellipsoid(2.0, 1.2, 1.0, subdivisions=1)
        >>> geom = att.Geometry(sun=[1.0, 0, 0], observer=[np.cos(0.3), np.sin(0.3), 0])
        >>> q = np.tile([0.0, 0.0, 0.0, 1.0], (1, 3, 1))          # fixed attitude
        >>> clean = LightcurveObservations([0.0, 1.0, 2.0], [0.0] * 3, 0.01, geom, shape)
        >>> m = clean.model_magnitudes(q)[0]
        >>> obs = LightcurveObservations([0.0, 1.0, 2.0], m + [3.0, 3.0, 5.5], 0.01, geom,
        ...                              shape, sessions=[1, 1, 2])
        >>> obs.offsets(q).round(12).tolist()
        [[3.0, 5.5]]
        """
        return self._offsets(self.model_magnitudes(q))

    def residuals(self, q: np.ndarray, w: np.ndarray, periods: dict) -> np.ndarray:
        """(N, n) magnitude residuals over sigma, the best offset of each session
        removed per model."""
        model = self.model_magnitudes(q)
        offset = self._offsets(model)
        return (model + offset[:, self.session_index] - self.magnitudes) / self.sigma

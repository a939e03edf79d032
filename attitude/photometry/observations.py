"""Observed lightcurves with their geometry: the one type that fitting and inversion read.

:class:`LightcurveObservations` carries measured magnitudes, their 1-sigma, the epochs
of the points and the Sun/observer :class:`~attitude.photometry.Geometry` of each point,
with what the two consumers add:

- a **fit** of a rotation state (:func:`attitude.fitting.fit`) needs the body's shape
  and a scattering law (``shape``, ``law``): the model magnitude is the shape's
  brightness in the modelled attitude plus one fitted offset per session;
- an **inversion** (:func:`attitude.invert`) fits the shape itself, and needs to know
  whether a lightcurve is relative or ``calibrated`` and where it came from (``name``,
  the file and line quoted by its errors).

The times are those of the observer (reception); when the geometry carries light times
(:meth:`Geometry.from_orbit`), the body is modelled at ``times - light_time``
(:attr:`LightcurveObservations.time`, seconds of TDB at the body since ``epoch``).

:func:`attitude.photometry.read_lightcurve` with ``geometry=`` and
:func:`attitude.read_damit_lightcurves` return lists of them, one per session.
"""

from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np
from astropy.time import Time

from attitude.foundations import quaternion as quat
from attitude.foundations.errors import AttitudeError
from attitude.foundations.quantities import to_si
from attitude.photometry.brightness import facet_brightness
from attitude.photometry.geometry import Geometry

__all__ = ["LightcurveObservations", "seconds_since", "MAGNITUDE_PER_LN"]

#: ``2.5 / ln 10``: d(magnitude) / d(ln flux), the factor between a magnitude's 1-sigma
#: and the relative 1-sigma of the flux.
MAGNITUDE_PER_LN = 2.5 / np.log(10.0)


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


def sample_times(times, n_expected: int | None, key: str):
    """Time array or finite seconds, of the expected length (``n_expected`` None: any);
    the samples' times of every observations type (photometry and fitting)."""
    if isinstance(times, Time):
        t = times.reshape(-1)
    else:
        t = np.atleast_1d(to_si(times, "s", key=key, finite=False, error=AttitudeError))
        if not np.all(np.isfinite(t)):
            raise AttitudeError("times must be finite", key=key)
    if t.size == 0 or (n_expected is not None and t.size != n_expected):
        raise AttitudeError(f"expected {n_expected} times (one per sample), got {t.size}",
                            key=key)
    return t


@dataclass(frozen=True)
class LightcurveObservations:
    """Measured magnitudes with their 1-sigma, epochs and Sun/observer geometry.

    Parameters
    ----------
    times : astropy Time array, or seconds since the fit's epoch
        Observation (reception) times; the body is modelled at ``times -
        geometry.light_time`` when the geometry carries light times.
    magnitudes : (n,) array
    sigma : float or (n,) array
        1-sigma of each magnitude, mag.
    geometry : attitude.photometry.Geometry
        Sun and observer directions (inertial frame of the fit), constant or per epoch.
    shape : attitude.Polyhedron, optional
        The body's shape in the body frame of a fit (:func:`attitude.fitting.fit`
        needs it; an inversion fits its own: :meth:`with_shape` adds one later).
    law : str or scattering law
        As in :func:`attitude.photometry.dataset` (default ``"ls-lambert"``).
    sessions : (n,) array, optional
        Session label of each magnitude (the ``session`` variable of
        :func:`attitude.photometry.read_lightcurve`: an ALCDEF block, a night): each
        session gets its own magnitude offset.  Default: one session.
    epoch : astropy Time, optional
        The reference of :attr:`time` (default: the first of ``times`` when they are a
        Time array).  Kept in TDB.
    calibrated : bool
        True when the magnitudes are reduced to unit distances and comparable between
        lightcurves (an inversion then fits their level); False (default): relative.
    name : str
        Where the data came from (file and line), for the messages of errors.

    Attributes
    ----------
    session_labels : (S,) array
        The distinct session labels, sorted (``[0]`` for one session).
    session_index : (n,) int array
        The session of each magnitude, as an index into ``session_labels``.
    session_weight : (S,) array
        ``sum(1/sigma^2)`` of each session (the inverse variance of its offset at fixed
        rotation parameters).
    magnitude_sigma : (n,) array
        ``sigma``, mag, per point.

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

    An inversion reads the same data as intensities, :attr:`brightness` ``=
    10**(-0.4 m)`` with :attr:`brightness_sigma` ``= brightness * sigma / (2.5 / ln
    10)``, at the body times :attr:`time`.

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
    >>> [len(s) for s in two.split_sessions()]
    [2, 1]
    """

    times: object
    magnitudes: np.ndarray
    sigma: object
    geometry: Geometry
    shape: object = None
    law: object = "ls-lambert"
    delay: np.ndarray = None
    sessions: object = None
    epoch: Time | None = None
    calibrated: bool = False
    name: str = "lightcurve"

    def __post_init__(self):
        where = {"key": "magnitudes"}
        m = np.asarray(self.magnitudes, dtype=float)
        if m.ndim != 1 or m.size == 0 or not np.all(np.isfinite(m)):
            bad = np.flatnonzero(~np.isfinite(m.ravel())) if m.size else []
            raise AttitudeError(f"{self.name}: expected a non-empty 1-D array of finite "
                                f"magnitudes, got shape {m.shape}"
                                + (f" (point {int(bad[0])} is {m.ravel()[bad[0]]})"
                                   if len(bad) else ""), **where)
        object.__setattr__(self, "magnitudes", m)
        object.__setattr__(self, "times", sample_times(self.times, m.size, "times"))
        sig = np.asarray(self.sigma, dtype=float)
        if sig.shape not in ((), m.shape) or not np.all(np.isfinite(sig) & (sig > 0)):
            raise AttitudeError(f"{self.name}: expected one or {m.size} finite, positive "
                                "magnitude uncertainties", key="sigma")
        object.__setattr__(self, "sigma", np.broadcast_to(sig, m.shape).copy())
        object.__setattr__(self, "magnitude_sigma", self.sigma)
        if not isinstance(self.geometry, Geometry):
            raise AttitudeError("expected an attitude.photometry.Geometry", key="geometry")
        try:
            sun, observer = self.geometry.broadcast(m.size)
        except AttitudeError as err:
            raise AttitudeError(f"{self.name}: {err.reason}", key="geometry") from None
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
        weight = 1.0 / self.magnitude_sigma**2
        object.__setattr__(self, "_weight", weight)
        object.__setattr__(self, "session_weight",
                           np.bincount(index.reshape(-1), weight, minlength=labels.size))
        epoch = self.epoch
        if epoch is None and isinstance(self.times, Time):
            epoch = self.times[0]
        object.__setattr__(self, "epoch", None if epoch is None else Time(epoch).tdb)
        object.__setattr__(self, "calibrated", bool(self.calibrated))

    # ------------------------------------------------------------------ the data
    def __len__(self) -> int:
        return self.magnitudes.size

    @property
    def n_residuals(self) -> int:
        """Number of residuals (one per magnitude)."""
        return self.magnitudes.size

    @property
    def n_nuisance(self) -> int:
        """Number of fitted offsets (one per session), counted in the degrees of freedom."""
        return int(self.session_labels.size)

    @property
    def time(self) -> np.ndarray:
        """Seconds of TDB at the body (light time removed) since :attr:`epoch`.

        Raises
        ------
        AttitudeError
            For times given as seconds without an ``epoch``.
        """
        if isinstance(self.times, Time):
            return seconds_since(self.epoch, self.times.tdb) - self.delay
        if self.epoch is None:
            raise AttitudeError(f"{self.name}: the times are seconds without an epoch: "
                                "give epoch= (an astropy Time)", key="epoch")
        return np.asarray(self.times, dtype=float) - self.delay

    @property
    def brightness(self) -> np.ndarray:
        """Intensities, ``10**(-0.4 m)``."""
        return 10.0 ** (-0.4 * self.magnitudes)

    @property
    def brightness_sigma(self) -> np.ndarray:
        """1-sigma of :attr:`brightness` (same units), ``brightness * sigma / (2.5/ln 10)``."""
        return self.brightness * self.magnitude_sigma / MAGNITUDE_PER_LN

    def sun_and_observer(self) -> tuple[np.ndarray, np.ndarray]:
        """Unit vectors from the body toward the Sun and the observer, ``(n, 3)`` each.

        Examples
        --------
        >>> import numpy as np
        >>> from attitude.photometry import Geometry
        >>> obs = LightcurveObservations([0.0, 60.0], [1.0, 1.1], 0.01,
        ...                              Geometry(sun=[2, 0, 0], observer=[0, 3, 0]))
        >>> s, o = obs.sun_and_observer()
        >>> s.tolist(), o.shape
        ([[1.0, 0.0, 0.0], [1.0, 0.0, 0.0]], (2, 3))
        """
        return self._sun, self._observer

    def take(self, index, name: str | None = None) -> LightcurveObservations:
        """The observations of the points ``index`` (an integer or boolean array).

        Examples
        --------
        >>> from attitude.photometry import Geometry
        >>> obs = LightcurveObservations([0.0, 60.0, 120.0], [1.0, 1.1, 1.2], 0.01,
        ...                              Geometry(sun=[2, 0, 0], observer=[0, 3, 0]))
        >>> obs.take([0, 2]).magnitudes.tolist()
        [1.0, 1.2]
        """
        index = np.arange(len(self))[np.asarray(index)]
        return self._rebuild(times=self.times[index], magnitudes=self.magnitudes[index],
                             sigma=self.magnitude_sigma[index],
                             geometry=self.geometry.take(index),
                             sessions=None if self.sessions is None else self.sessions[index],
                             name=self.name if name is None else name)

    def _rebuild(self, **changes) -> LightcurveObservations:
        """A new :class:`LightcurveObservations` (never a subclass) of these fields with
        ``changes``; ``sigma`` in magnitudes and the delay recomputed."""
        values = {f.name: getattr(self, f.name) for f in fields(LightcurveObservations)}
        values |= {"sigma": self.magnitude_sigma, "delay": None} | changes
        return LightcurveObservations(**values)

    def split_sessions(self) -> list[LightcurveObservations]:
        """One observations object per session (in the order of :attr:`session_labels`),
        each named ``"<name>, session <label>"`` when there is more than one."""
        if self.session_labels.size == 1:
            return [self]
        return [self.take(self.session_index == k, name=f"{self.name}, session {label}")
                for k, label in enumerate(self.session_labels)]

    def with_shape(self, shape, law="ls-lambert") -> LightcurveObservations:
        """The same observations with a shape and a scattering law, ready for a fit.

        Examples
        --------
        >>> import attitude as att
        >>> obs = LightcurveObservations([0.0], [1.0], 0.01,
        ...                              att.Geometry(sun=[1, 0, 0], observer=[1, 0.1, 0]))
        >>> obs.with_shape(att.Polyhedron.ellipsoid(2, 1, 1)).shape is not None
        True
        """
        return self._rebuild(shape=shape, law=law)

    # ------------------------------------------------------------------ the model (fits)
    def model_magnitudes(self, q: np.ndarray) -> np.ndarray:
        """(N, n) magnitudes (without the offset) of the attitudes ``q`` (N, n, 4)."""
        if self.shape is None:
            raise AttitudeError(f"{self.name}: a fit needs the body's shape: "
                                "observations.with_shape(shape)", key="shape")
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
        return (model + offset[:, self.session_index] - self.magnitudes) / self.magnitude_sigma

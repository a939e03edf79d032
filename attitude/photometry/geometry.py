"""Sun and observer directions seen from the body: the illumination geometry.

A lightcurve needs, at every epoch, the unit vectors from the body toward the Sun
and toward the observer, in the inertial frame of the attitude ephemeris.
:class:`Geometry` holds them (constant or one per epoch), with the heliocentric and
observer distances and the light time when they are known.
:meth:`Geometry.from_orbit` computes them from the target's heliocentric
:class:`~attitude.model.orbit.KeplerOrbit` and an observer: the Earth (astropy's built-in
ephemeris) or any object with ``position(t)`` (another orbit, a tabulated path).

Conventions: times are seconds since the epoch of the ephemeris, at the *body*
(light leaves the body at ``t`` and reaches the observer at ``t + light_time``);
distances in metres; the phase angle is the Sun-body-observer angle.
"""

from __future__ import annotations

from dataclasses import dataclass

import astropy.units as u
import numpy as np
from astropy.time import Time, TimeDelta

from attitude.foundations.constants import AU, OBLIQUITY_J2000, SPEED_OF_LIGHT
from attitude.foundations.errors import PhotometryError
from attitude.model.orbit import as_path

__all__ = ["Geometry", "OrbitGeometry", "reduced_magnitude", "phase_angle", "AU", "SPEED_OF_LIGHT"]

_EQUATORIAL = {"ICRF", "GCRF", "EME2000", "J2000"}
_ECLIPTIC = {"ECLIPJ2000", "ECLIPTIC_J2000"}
# A phase angle within this of 180 deg means the observer looks at the unlit side only.
_ANTIPARALLEL_TOL = 1e-9


def _unit_vectors(value, name: str) -> tuple[np.ndarray, np.ndarray]:
    """Unit vectors and norms of a (3,) or (n, 3) array; a zero vector is an error."""
    try:
        vec = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise PhotometryError(f"must be a vector (3,) or an array (n_time, 3), got {value!r}",
                              key=name) from None
    if vec.ndim not in (1, 2) or vec.shape[-1] != 3:
        raise PhotometryError(f"must have shape (3,) or (n_time, 3), got {vec.shape}", key=name)
    if not np.isfinite(vec).all():
        raise PhotometryError("has non-finite components", key=name)
    norm = np.linalg.norm(vec, axis=-1)
    if np.any(norm == 0.0):
        first = int(np.flatnonzero(np.atleast_1d(norm) == 0.0)[0])
        raise PhotometryError(f"is a zero vector (epoch index {first}): give the direction "
                              "from the body toward the source", key=name)
    return vec / norm[..., None], norm


def phase_angle(sun, observer) -> np.ndarray:
    """Sun-body-observer angle, rad, from the two direction vectors (any length).

    ``atan2(|s x o|, s . o)``, accurate at small and large angles alike.

    Examples
    --------
    >>> from attitude.photometry.geometry import phase_angle
    >>> float(np.rad2deg(phase_angle([1, 0, 0], [1, 1, 0])))
    45.0
    """
    s = np.asarray(sun, dtype=float)
    o = np.asarray(observer, dtype=float)
    return np.arctan2(np.linalg.norm(np.cross(s, o), axis=-1), np.einsum("...i,...i", s, o))


def reduced_magnitude(magnitude, sun_distance, observer_distance):
    """The magnitude at unit heliocentric and observer distances.

    ``m_red = m - 5 log10(r Delta / au^2)``, the form asteroid observers tabulate
    (``H(alpha)`` before the phase correction).

    Parameters
    ----------
    magnitude : array_like
        Apparent magnitudes.
    sun_distance, observer_distance : array_like or Quantity
        ``r`` and ``Delta``; floats are metres.

    Examples
    --------
    >>> from attitude.photometry.geometry import reduced_magnitude, AU
    >>> round(float(reduced_magnitude(15.0, 2 * AU, 1 * AU)), 6)
    13.49485
    """
    r = u.Quantity(sun_distance, u.m).to_value(u.m) if isinstance(sun_distance, u.Quantity) \
        else np.asarray(sun_distance, dtype=float)
    d = u.Quantity(observer_distance, u.m).to_value(u.m) \
        if isinstance(observer_distance, u.Quantity) else np.asarray(observer_distance, float)
    return np.asarray(magnitude, dtype=float) - 5.0 * np.log10(r * d / AU**2)


@dataclass(frozen=True, eq=False)
class Geometry:
    """Directions from the body toward the Sun and the observer, inertial frame.

    Parameters
    ----------
    sun, observer : array_like, shape (3,) or (n_time, 3)
        Vectors from the body toward the Sun and toward the observer, in the inertial
        frame of the ephemeris; any length (they are normalised).  A constant vector
        applies to every epoch.
    sun_distance, observer_distance : array_like, optional
        Heliocentric distance ``r`` and observer distance ``Delta``, m (scalars or per
        epoch).  Default: the lengths of the given vectors when both are longer than
        1 m, else unknown (``None``).
    light_time : array_like, optional
        Body -> observer light time, s (per epoch or scalar).
    frame : str, optional
        Inertial frame label, checked against the ephemeris's when given.

    Raises
    ------
    PhotometryError
        On a zero, non-finite or wrongly shaped vector, or when the observer is exactly
        opposite the Sun (phase angle 180 deg: only the unlit side is seen).

    Examples
    --------
    >>> import numpy as np
    >>> from attitude.photometry import Geometry
    >>> geom = Geometry(sun=[1, 0, 0], observer=[np.cos(0.5), np.sin(0.5), 0])
    >>> round(float(geom.phase_angle), 12)
    0.5
    """

    sun: np.ndarray
    observer: np.ndarray
    sun_distance: np.ndarray | None = None
    observer_distance: np.ndarray | None = None
    light_time: np.ndarray | None = None
    frame: str | None = None

    def __post_init__(self):
        sun, r = _unit_vectors(self.sun, "sun")
        obs, d = _unit_vectors(self.observer, "observer")
        if sun.ndim == 2 and obs.ndim == 2 and len(sun) != len(obs):
            raise PhotometryError(f"sun has {len(sun)} epochs but observer has {len(obs)}",
                                  key="observer")
        alpha = phase_angle(sun, obs)
        bad = np.atleast_1d(alpha) > np.pi - _ANTIPARALLEL_TOL
        if bad.any():
            raise PhotometryError(
                f"the observer is opposite the Sun (phase angle 180 deg, epoch index "
                f"{int(np.flatnonzero(bad)[0])}): only the unlit side is seen and the "
                "magnitude is infinite; check the sign of the vectors (body -> Sun, "
                "body -> observer)", key="sun")
        if self.sun_distance is None and self.observer_distance is None \
                and np.min(r) > 1.0 and np.min(d) > 1.0:
            object.__setattr__(self, "sun_distance", r)
            object.__setattr__(self, "observer_distance", d)
        for key in ("sun_distance", "observer_distance", "light_time"):
            value = getattr(self, key)
            if value is not None:
                arr = np.asarray(value, dtype=float)
                if not np.isfinite(arr).all() or (key != "light_time" and np.any(arr <= 0)):
                    raise PhotometryError(f"must be finite and positive, got {value!r}", key=key)
                object.__setattr__(self, key, arr)
        object.__setattr__(self, "sun", sun)
        object.__setattr__(self, "observer", obs)

    # ------------------------------------------------------------------ derived
    @property
    def phase_angle(self) -> np.ndarray:
        """Sun-body-observer angle, rad (scalar or per epoch)."""
        return phase_angle(self.sun, self.observer)

    @property
    def n_time(self) -> int | None:
        """Number of epochs, or None for a constant geometry."""
        n = [len(v) for v in (self.sun, self.observer) if v.ndim == 2]
        return n[0] if n else None

    def broadcast(self, n_time: int) -> tuple[np.ndarray, np.ndarray]:
        """``(sun, observer)`` as (n_time, 3) arrays.

        Raises
        ------
        PhotometryError
            If the geometry has a different number of epochs.

        Examples
        --------
        >>> from attitude.photometry import Geometry
        >>> Geometry(sun=[1, 0, 0], observer=[0, 1, 0]).broadcast(2)[0]
        array([[1., 0., 0.],
               [1., 0., 0.]])
        """
        if self.n_time not in (None, n_time):
            raise PhotometryError(f"the geometry has {self.n_time} epochs but the ephemeris "
                                  f"has {n_time}; give one Sun/observer vector per epoch",
                                  key="geometry")
        return (np.broadcast_to(self.sun, (n_time, 3)).copy(),
                np.broadcast_to(self.observer, (n_time, 3)).copy())

    def take(self, index) -> Geometry:
        """The geometry of the epochs ``index`` (a constant geometry is kept as it is).

        Examples
        --------
        >>> from attitude.photometry import Geometry
        >>> g = Geometry(sun=[[1, 0, 0], [0, 1, 0], [0, 0, 1]], observer=[1, 1, 1])
        >>> g.take([2]).sun.tolist(), g.take([2]).observer.tolist()
        ([[0.0, 0.0, 1.0]], [0.5773502691896258, 0.5773502691896258, 0.5773502691896258])
        """
        n = self.n_time
        if n is None:
            return self
        index = np.arange(n)[np.asarray(index)]

        def pick(value, ndim=1):
            if value is None:
                return None
            arr = np.asarray(value)
            return arr[index] if arr.ndim == ndim and arr.shape[0] == n else arr

        return Geometry(sun=pick(self.sun, 2), observer=pick(self.observer, 2),
                        sun_distance=pick(self.sun_distance),
                        observer_distance=pick(self.observer_distance),
                        light_time=pick(self.light_time), frame=self.frame)

    # ------------------------------------------------------------------ constructors
    @classmethod
    def from_orbit(cls, orbit, times=None, observer="earth", *, epoch: Time | None = None,
                   frame: str = "ECLIPJ2000", light_time: bool = True
                   ) -> Geometry | OrbitGeometry:
        """Sun and observer directions from the target's heliocentric orbit.

        Without ``times``, the recipe for the epochs of a file: an
        :class:`OrbitGeometry`, which :func:`attitude.read_lightcurve` (``geometry=``)
        evaluates at the file's epochs, taken as the observer's (reception) times.

        Parameters
        ----------
        orbit : KeplerOrbit or path
            The target's heliocentric orbit (``mu`` of the Sun), or any object with
            ``position(t)`` (m, heliocentric, inertial ``frame``).
        times : array_like or astropy Time, optional
            Seconds since `epoch` at the body (emission times), or an astropy Time
            array (then `epoch` defaults to its first element).  None: return the
            :class:`OrbitGeometry` recipe (then `epoch` is required: the epoch of the
            orbit's ``t = 0``).
        observer : "earth", "sun" or path, optional
            The observer: ``"earth"`` (geocentre, astropy's built-in ephemeris), or an
            object with ``position(t)`` giving the observer's heliocentric position (m).
        epoch : astropy Time, optional
            The epoch of ``t = 0``; required for ``observer="earth"``.
        frame : str, optional
            The inertial frame of the orbit and of the result: an equatorial
            (``ICRF``, ``EME2000``, ...) or the J2000 ecliptic (``ECLIPJ2000``, the
            default, as asteroid elements are given).
        light_time : bool, optional
            Correct for the light time: the observer is taken where it is when the
            light emitted at ``t`` arrives (``t + Delta/c``, solved by fixed-point
            iteration). Default True.

        Returns
        -------
        Geometry
            Per-epoch vectors with ``sun_distance``, ``observer_distance`` and
            ``light_time``.

        Raises
        ------
        PhotometryError
            On an unknown observer or frame, or a missing epoch.

        Examples
        --------
        >>> from astropy.time import Time
        >>> from attitude.model.orbit import KeplerOrbit
        >>> from attitude.photometry import Geometry
        >>> orbit = KeplerOrbit.from_elements(mu="1.32712440018e20 m3/s2", a="0.9224 AU",
        ...                                   e=0.1914, i="3.34 deg")
        >>> geom = Geometry.from_orbit(orbit, [0.0, 86400.0], "earth",
        ...                            epoch=Time("2029-03-01", scale="tdb"))
        >>> geom.sun.shape, bool((geom.light_time > 0).all())
        ((2, 3), True)
        """
        if times is None:
            return OrbitGeometry(orbit, observer, epoch, frame, light_time)
        if isinstance(times, Time):
            epoch = times[0] if epoch is None and times.ndim else (epoch or times)
            times = np.atleast_1d((times - epoch).sec)
        t = np.atleast_1d(np.asarray(times, dtype=float))
        target = as_path(orbit)
        r_target = np.asarray(target.position(t), dtype=float).reshape(len(t), 3)
        observe = _observer_path(observer, epoch, frame)
        tau = np.zeros_like(t)
        for _ in range(4 if light_time else 1):   # contraction by |v|/c ~ 1e-4 per step
            r_obs = observe(t + tau)
            delta = r_obs - r_target
            tau = np.linalg.norm(delta, axis=1) / SPEED_OF_LIGHT if light_time else tau
        return cls(sun=-r_target, observer=delta,
                   sun_distance=np.linalg.norm(r_target, axis=1),
                   observer_distance=np.linalg.norm(delta, axis=1),
                   light_time=tau if light_time else None, frame=frame)


@dataclass(frozen=True, eq=False)
class OrbitGeometry:
    """The geometry of a body on a heliocentric orbit, for epochs given later.

    What :meth:`Geometry.from_orbit` returns without ``times``;
    :func:`attitude.read_lightcurve` (``geometry=``) calls :meth:`at` with the epochs of
    the file.

    Parameters
    ----------
    orbit : KeplerOrbit or path
        The target's heliocentric orbit (its ``t = 0`` is ``epoch``).
    observer : "earth", "sun" or path
        As in :meth:`Geometry.from_orbit`.
    epoch : astropy Time
        The epoch of the orbit's ``t = 0`` (the epoch of its mean anomaly); any scale,
        used in TDB.
    frame : str
        The inertial frame of the orbit (default ``ECLIPJ2000``).
    light_time : bool
        Correct for the light time (default True).

    Raises
    ------
    PhotometryError
        Without an epoch (an astropy Time).

    Examples
    --------
    >>> from astropy.time import Time
    >>> from attitude.model.orbit import KeplerOrbit
    >>> from attitude.photometry import Geometry
    >>> orbit = KeplerOrbit.from_elements(mu="1.32712440018e20 m3/s2", a="2.2 AU", e=0.1,
    ...                                   i="5 deg")
    >>> recipe = Geometry.from_orbit(orbit, observer="earth",
    ...                              epoch=Time("2026-01-01", scale="tdb"))
    >>> geom = recipe.at(Time(["2026-01-10T00:00:00", "2026-01-10T06:00:00"], scale="utc"))
    >>> geom.sun.shape, bool((geom.light_time > 0).all())
    ((2, 3), True)
    """

    orbit: object
    observer: object = "earth"
    epoch: Time | None = None
    frame: str = "ECLIPJ2000"
    light_time: bool = True

    def __post_init__(self):
        if not isinstance(self.epoch, Time) or self.epoch.ndim:
            raise PhotometryError("the orbit's geometry needs the epoch of its t = 0 (one "
                                  "astropy Time, e.g. Time('2026-01-01', scale='tdb'))",
                                  key="epoch")
        object.__setattr__(self, "epoch", self.epoch.tdb)

    def at(self, times: Time) -> Geometry:
        """The geometry at the observer's epochs ``times`` (reception times).

        The body is where the light that reaches the observer at ``times`` left it:
        ``t_body = t - Delta/c``, with ``Delta`` the distance between the observer at
        ``t`` and the body at ``t_body`` (solved by fixed-point iteration, a contraction
        by ``|v|/c``).  The Sun is taken at the body's epoch (the Sun's own motion over a
        light time is below the orbit's accuracy).

        Parameters
        ----------
        times : astropy Time
            The epochs at the observer, any scale (UTC for observed lightcurves).

        Returns
        -------
        Geometry
            Per epoch, with ``light_time`` (the body epochs are ``times - light_time``).

        Raises
        ------
        PhotometryError
            If ``times`` is not an astropy Time.
        """
        if not isinstance(times, Time):
            raise PhotometryError("the epochs at the observer must be an astropy Time (a "
                                  "scale explicit: UTC for observed lightcurves)", key="times")
        t = np.atleast_1d((times.tdb - self.epoch).to_value(u.s))
        target = as_path(self.orbit)
        observe = _observer_path(self.observer, self.epoch, self.frame)
        r_obs = observe(t)
        tau = np.zeros_like(t)
        for _ in range(4 if self.light_time else 1):   # contraction ~1e-4 per step
            r_target = np.asarray(target.position(t - tau), dtype=float).reshape(len(t), 3)
            delta = r_obs - r_target
            if self.light_time:
                tau = np.linalg.norm(delta, axis=1) / SPEED_OF_LIGHT
        return Geometry(sun=-r_target, observer=delta,
                        sun_distance=np.linalg.norm(r_target, axis=1),
                        observer_distance=np.linalg.norm(delta, axis=1),
                        light_time=tau if self.light_time else None, frame=self.frame)


def _observer_path(observer, epoch, frame):
    if isinstance(observer, str):
        name = observer.lower()
        if name == "sun":
            return lambda t: np.zeros((len(t), 3))
        if name != "earth":
            raise PhotometryError(f"unknown observer {observer!r}: use 'earth', 'sun' or an "
                                  "object with position(t) (heliocentric, m)", key="observer")
        if epoch is None:
            raise PhotometryError("observer='earth' needs the epoch (an astropy Time) of "
                                  "t = 0", key="epoch")
        if frame not in _EQUATORIAL | _ECLIPTIC:
            raise PhotometryError(f"frame {frame!r} is not supported for the Earth's "
                                  f"position: use one of {sorted(_EQUATORIAL | _ECLIPTIC)}",
                                  key="frame")
        return lambda t: _earth_heliocentric(epoch, t, frame)
    path = as_path(observer)
    return lambda t: np.asarray(path.position(t), dtype=float).reshape(len(t), 3)


def _earth_heliocentric(epoch: Time, t: np.ndarray, frame: str) -> np.ndarray:
    """Heliocentric position of the geocentre, m, from astropy's built-in ephemeris."""
    from astropy.coordinates import get_body_barycentric  # costly import: only when used

    when = epoch + TimeDelta(t, format="sec")
    r = (get_body_barycentric("earth", when) - get_body_barycentric("sun", when))
    xyz = r.xyz.to_value(u.m).T                 # ICRS axes
    if frame in _ECLIPTIC:
        ce, se = np.cos(OBLIQUITY_J2000), np.sin(OBLIQUITY_J2000)
        x, y, z = xyz.T
        xyz = np.stack([x, ce * y + se * z, -se * y + ce * z], axis=1)
    return xyz

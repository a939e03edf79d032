"""The International Geomagnetic Reference Field along an orbit, in inertial axes.

IGRF-14 (Alken et al. 2025) is evaluated by the ``ppigrf`` package in geocentric
spherical coordinates of the Earth-fixed frame; :class:`IGRF` moves the orbit's inertial
positions into that frame (astropy, :mod:`attitude.environment.frames`), asks ``ppigrf``
for the field, and turns the field back into the inertial axes of the run.  The field
along the orbit does not depend on the attitude, so it is tabulated once (default every
20 s) and interpolated by cubic splines.  The IGRF coefficients are linear in time
between their five-yearly epochs, so each one-day segment evaluates the field at both
of its ends and interpolates linearly between them: exact inside a five-year interval.
"""

from __future__ import annotations

import numpy as np
from astropy.time import Time, TimeDelta

from ..foundations.errors import MissingDependencyError, OrbitError, TorqueConfigError
from ..foundations.quantities import to_time
from ..model.orbit import as_path
from .frames import check_frame, inertial_to_earth_fixed
from .tabulation import TimeTable

__all__ = ["IGRF", "IGRF_VALIDITY", "spherical_to_cartesian"]

#: The time span of the IGRF-14 coefficients (definitive and predicted); TT, since UTC
#: is not defined ahead of the leap-second table.
IGRF_VALIDITY = (Time("1900-01-01T00:00:00", scale="tt"),
                 Time("2030-01-01T00:00:00", scale="tt"))


def spherical_to_cartesian(position: np.ndarray, b_r, b_theta, b_phi) -> np.ndarray:
    """Field components along (r, theta south, phi east) at ``position`` -> Cartesian.

    Examples
    --------
    >>> spherical_to_cartesian(np.array([[7e6, 0.0, 0.0]]), [1.0], [0.0], [0.0])
    array([[1., 0., 0.]])
    """
    x, y, z = np.moveaxis(np.asarray(position, dtype=float), -1, 0)
    rho = np.hypot(x, y)
    r = np.hypot(rho, z)
    st, ct = rho / r, z / r
    cp = np.where(rho > 0, x / np.where(rho > 0, rho, 1.0), 1.0)
    sp = np.where(rho > 0, y / np.where(rho > 0, rho, 1.0), 0.0)
    r_hat = np.stack([st * cp, st * sp, ct], axis=-1)
    t_hat = np.stack([ct * cp, ct * sp, -st], axis=-1)
    p_hat = np.stack([-sp, cp, np.zeros_like(cp)], axis=-1)
    return (np.asarray(b_r)[..., None] * r_hat + np.asarray(b_theta)[..., None] * t_hat
            + np.asarray(b_phi)[..., None] * p_hat)


class IGRF:
    """The IGRF-14 geomagnetic field along an orbit, inertial components, tesla.

    A drop-in for :class:`attitude.model.torques.TiltedDipoleField`: ``field(t)`` gives the
    field at the body at ``t`` seconds after the epoch, shape ``t.shape + (3,)``.

    Parameters
    ----------
    orbit : TLEOrbit, KeplerOrbit, path or callable
        Position of the body relative to the Earth's centre, in ``frame``, m.
    epoch : astropy Time, optional
        Time ``t = 0``; default ``orbit.epoch`` (a :class:`TLEOrbit` has one).
    frame : str, optional
        Inertial frame of the orbit's positions; default ``orbit.frame``, else ``"GCRF"``.
    spacing : float
        Node spacing of the tabulation, s.
    max_degree : int
        Highest spherical-harmonic degree (1 is the centred dipole, 13 the full model).

    Raises
    ------
    OrbitError
        If the epoch is missing, or a requested time lies outside the coefficients'
        span :data:`IGRF_VALIDITY` (1900-2030).
    MissingDependencyError
        If ``ppigrf`` is absent (the ``environment`` extra).

    Examples
    --------
    >>> from astropy.time import Time
    >>> from attitude.model.orbit import KeplerOrbit
    >>> leo = KeplerOrbit.from_elements(mu=3.986004418e14, a="6871 km", i="51.6 deg")
    >>> field = IGRF(leo, epoch=Time("2024-03-01T00:00:00", scale="utc"))
    >>> b = field(0.0)
    >>> 1e-5 < float(np.linalg.norm(b)) < 6e-5       # tesla: 10-60 microtesla in LEO
    True
    """

    def __init__(self, orbit, *, epoch=None, frame: str | None = None,
                 spacing: float = 20.0, max_degree: int = 13):
        try:
            import ppigrf  # optional dependency (the environment extra)
        except ImportError:
            raise MissingDependencyError(
                "the IGRF field needs the ppigrf package: pip install "
                "\"attitude-dynamics[environment]\"") from None
        self._igrf_gc = ppigrf.igrf_gc
        self.orbit = as_path(orbit)
        epoch = getattr(orbit, "epoch", None) if epoch is None else epoch
        if epoch is None:
            raise OrbitError("the IGRF field needs the epoch of t = 0: pass epoch= (an "
                             "astropy Time) or an orbit that carries one (TLEOrbit)",
                             key="epoch")
        self.epoch = to_time(epoch, key="epoch", error=TorqueConfigError)
        self.frame = check_frame(frame if frame is not None
                                 else getattr(orbit, "frame", "GCRF"))
        if not (isinstance(max_degree, (int, np.integer)) and 1 <= max_degree <= 13):
            raise OrbitError(f"must be an integer from 1 to 13, got {max_degree!r}",
                             key="max_degree")
        self.max_degree = int(max_degree)
        self._table = TimeTable(self._evaluate, spacing=spacing, segment=4320 * spacing)

    def _check_span(self, times: Time, t: np.ndarray) -> None:
        lo, hi = IGRF_VALIDITY
        tt = times.tt.jd                        # compared in TT: UTC has no 1900
        outside = (tt < lo.jd) | (tt > hi.jd)
        if np.any(outside):
            i = int(np.flatnonzero(outside)[0])
            raise OrbitError(f"t = {t[i]:.0f} s ({times[i].utc.isot} UTC) lies outside "
                             f"IGRF-14's span {lo.isot[:10]} to {hi.isot[:10]}; "
                             f"use a TiltedDipoleField for other epochs", key="epoch")

    def _evaluate(self, t: np.ndarray) -> np.ndarray:
        times = (self.epoch + TimeDelta(t, format="sec")).utc
        self._check_span(times, t)
        m = inertial_to_earth_fixed(times, self.frame)
        r_ef = np.einsum("nij,nj->ni", m, self.orbit.position(t))
        x, y, z = r_ef.T
        r = np.sqrt(x * x + y * y + z * z)
        theta = np.degrees(np.arccos(z / r))
        phi = np.degrees(np.arctan2(y, x))
        ends = times[[0, -1]]
        b_r, b_t, b_p = self._igrf_gc(r / 1e3, theta, phi, list(ends.datetime),
                                      max_degree=self.max_degree)
        # linear in time between the two ends of the segment (exact inside an IGRF epoch)
        span = (ends[1] - ends[0]).to_value("s")
        w = ((times - ends[0]).to_value("s") / span)[None, :]
        weights = np.concatenate([1 - w, w])
        b_ef = spherical_to_cartesian(r_ef, *(np.sum(weights * np.asarray(b), axis=0)
                                              for b in (b_r, b_t, b_p)))
        return np.einsum("nji,nj->ni", m, b_ef) * 1e-9

    def compiled_parameters(self, t_span=None) -> tuple[str, dict] | None:
        """``("piecewise_cubic", {breakpoints, coefficients})``: the tabulated field over
        ``t_span = (t0, t1)`` (s) for a compiled kernel, or None without a span.

        Examples
        --------
        >>> from astropy.time import Time
        >>> from attitude.model.orbit import KeplerOrbit
        >>> leo = KeplerOrbit.from_elements(mu=3.986004418e14, a="6871 km", i="51.6 deg")
        >>> field = IGRF(leo, epoch=Time("2024-03-01T00:00:00", scale="utc"), max_degree=1)
        >>> field.compiled_parameters((0.0, 60.0))[0]
        'piecewise_cubic'
        """
        return self._table.compiled_parameters(t_span)

    def __call__(self, t) -> np.ndarray:
        """Field at the body at ``t`` (s after the epoch), inertial, T, ``t.shape + (3,)``."""
        return self._table(t)

    def __repr__(self) -> str:
        return (f"IGRF(degree {self.max_degree}, epoch {self.epoch.utc.isot} UTC, "
                f"frame {self.frame!r})")

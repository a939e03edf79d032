"""NRLMSIS 2.1 (through ``pymsis``): the density of the upper atmosphere with the time, the
place and the solar and geomagnetic activity.

:class:`MSISAtmosphere` has the interface of
:class:`~attitude.environment.drag.ExponentialAtmosphere` (``density(altitude)``, also
as a call), at a place and time that default to the equator, longitude 0 and the
model's epoch, and adds what the exponential table lacks: the density along an orbit
(:meth:`MSISAtmosphere.along`), where the latitude, longitude and local time of each
point come from the orbit's inertial position rotated into the Earth-fixed frame
(astropy).  The density along the orbit does not depend on the attitude, so it is
tabulated (log-density every 20 s, cubic splines) and interpolated.

The solar and geomagnetic indices are constants given by the user: F10.7 of the day
before, its 81-day mean, and the daily Ap (all seven Ap slots of NRLMSIS set to it).
Real indices change from day to day and through a storm by factors of several; for a
run longer than a few days, or a past epoch, take them from the space-weather record
(the density scales roughly with them; NRLMSIS's own table lookup needs a download and
is not used).

``pymsis`` is the ``msis`` extra (``pip install "attitude-dynamics[msis]"``). Its wrapper
is MIT-licensed; the NRLMSIS 2.x Fortran source it compiles is the U.S. Naval Research
Laboratory's, distributed under NRL's own licence, which does not allow commercial use
without NRL's agreement.

References
----------
.. [1] J. T. Emmert et al., NRLMSIS 2.0: A whole-atmosphere empirical model of
   temperature and neutral species densities, Earth Space Sci. 8 (2021), e2020EA001321.
.. [2] G. Lucas, pymsis, https://swxtrec.github.io/pymsis/
"""

from __future__ import annotations

import numpy as np
from astropy import units as u
from astropy.time import Time, TimeDelta

from ..foundations.errors import MissingDependencyError, TorqueConfigError
from ..foundations.quantities import to_si, to_time
from ..model.orbit import as_path
from .frames import check_frame, inertial_to_earth_fixed
from .tabulation import TimeTable

__all__ = ["MSISAtmosphere", "MSIS_VERSIONS"]

#: Versions of the model that ``pymsis`` offers: 0 is NRLMSISE-00.
MSIS_VERSIONS = (0, 2.0, 2.1)


def _pymsis():
    try:
        import pymsis  # optional dependency (the msis extra), compiled Fortran
    except ImportError:
        raise MissingDependencyError(
            "the NRLMSIS density needs the pymsis package: pip install "
            "\"attitude-dynamics[msis]\"", key="atmosphere") from None
    return pymsis


class MSISAtmosphere:
    """The NRLMSIS density of the atmosphere, with constant solar and geomagnetic indices.

    Parameters
    ----------
    f107 : float
        F10.7 solar radio flux of the previous day, sfu (10^-22 W m^-2 Hz^-1).
    f107a : float
        Its 81-day mean centred on the day, sfu.
    ap : float
        Daily geomagnetic Ap index.
    epoch : astropy Time, optional
        Time ``t = 0`` of :meth:`along`, and the time of :meth:`density` when it is not
        given.
    version : {2.1, 2.0, 0}
        NRLMSIS 2.1 (default), 2.0, or NRLMSISE-00.

    Raises
    ------
    TorqueConfigError
        Naming the index that is not a positive finite number (``ap`` may be 0).
    MissingDependencyError
        If ``pymsis`` is absent (the ``msis`` extra).

    Examples
    --------
    >>> from astropy.time import Time
    >>> atm = MSISAtmosphere(f107=150.0, f107a=150.0, ap=15.0,
    ...                      epoch=Time("2016-10-01T12:00:00", scale="utc"))
    >>> rho = atm(400e3)                   # kg/m^3, equator, longitude 0, at the epoch
    >>> 1e-12 < float(rho) < 1e-11
    True
    """

    def __init__(self, f107, f107a, ap, *, epoch=None, version: float = 2.1):
        self._calculate = _pymsis().calculate
        for key, value, low in (("f107", f107, "positive"), ("f107a", f107a, "positive"),
                                ("ap", ap, "nonnegative")):
            x = to_si(value, "", key=key, shape=(), error=TorqueConfigError)
            if not (np.isfinite(x) and (x > 0 if low == "positive" else x >= 0)):
                raise TorqueConfigError(f"must be a {low} finite number, got {value!r}",
                                        key=key)
            setattr(self, key, float(x))
        if version not in MSIS_VERSIONS:
            raise TorqueConfigError(f"expected one of {MSIS_VERSIONS}, got {version!r}",
                                    key="version")
        self.version = version
        self.epoch = None if epoch is None else to_time(epoch, key="epoch",
                                                                   error=TorqueConfigError)

    def at(self, times, latitude, longitude, altitude) -> np.ndarray:
        """Density (kg/m^3) at geodetic ``latitude``, ``longitude`` (rad, WGS 84) and
        ``altitude`` (m above the WGS 84 ellipsoid) at ``times`` (astropy Time), all
        broadcast to one shape: one ``pymsis.calculate`` call, point by point.

        Examples
        --------
        >>> from astropy.time import Time
        >>> atm = MSISAtmosphere(150.0, 150.0, 15.0)
        >>> rho = atm.at(Time(["2016-10-01T00:00:00", "2016-10-01T12:00:00"]), 0.0, 0.0,
        ...              400e3)
        >>> bool(rho[1] > rho[0])                 # noon is denser than midnight
        True
        """
        times = Time(times)
        shape = np.broadcast_shapes(times.shape, np.shape(latitude), np.shape(longitude),
                                    np.shape(altitude))
        dates = np.broadcast_to(times.utc.datetime64, shape).reshape(-1)
        lat, lon, alt = (np.broadcast_to(np.asarray(x, dtype=float), shape).reshape(-1)
                         for x in (latitude, longitude, altitude))
        n = dates.size
        out = self._calculate(dates, np.degrees(lon), np.degrees(lat), alt / 1e3,
                              f107s=np.full(n, self.f107), f107as=np.full(n, self.f107a),
                              aps=np.full((n, 7), self.ap), version=self.version)
        rho = np.asarray(out, dtype=float).reshape(n, -1)[:, 0]   # Variable.MASS_DENSITY
        return rho.reshape(shape)

    def density(self, altitude, *, latitude=0.0, longitude=0.0, time=None) -> np.ndarray:
        """Density at ``altitude`` (m), kg/m^3, as ``ExponentialAtmosphere.density``;
        at geodetic ``latitude`` and ``longitude`` (rad; default the equator at
        Greenwich, where the geodetic altitude is the altitude above the equatorial
        sphere) and ``time`` (default the epoch).

        Examples
        --------
        >>> from astropy.time import Time
        >>> atm = MSISAtmosphere(150.0, 150.0, 15.0)
        >>> rho = atm.density([300e3, 500e3], time=Time("2016-10-01T12:00:00"))
        >>> bool(rho[0] > 10 * rho[1])
        True
        """
        time = self.epoch if time is None else Time(time)
        if time is None:
            raise TorqueConfigError("NRLMSIS needs a time: pass time= or build the model "
                                    "with epoch=", key="time")
        return self.at(time, latitude, longitude, np.asarray(altitude, dtype=float))

    def __call__(self, altitude) -> np.ndarray:
        return self.density(altitude)

    def along(self, orbit, *, epoch=None, frame: str = "GCRF", spacing: float = 20.0):
        """The density along ``orbit`` as a function of ``t`` (s after ``epoch``, default
        the model's): positions (``frame``, m) rotated into the Earth-fixed frame,
        their geodetic coordinates (WGS 84) given to NRLMSIS; tabulated every ``spacing``
        seconds (the log-density, cubic splines) one day at a time.

        Examples
        --------
        >>> from astropy.time import Time
        >>> from attitude.model.orbit import KeplerOrbit
        >>> leo = KeplerOrbit.from_elements(mu=3.986004418e14, a="6778 km", i="51.6 deg")
        >>> atm = MSISAtmosphere(150.0, 150.0, 15.0)
        >>> rho = atm.along(leo, epoch=Time("2016-10-01T00:00:00", scale="utc"))
        >>> values = rho(np.linspace(0.0, leo.period, 50))
        >>> bool(values.max() > 1.5 * values.min())     # day side against night side
        True
        """
        epoch = self.epoch if epoch is None else to_time(epoch, key="epoch",
                                                                    error=TorqueConfigError)
        if epoch is None:
            raise TorqueConfigError("the density along an orbit needs the epoch of t = 0",
                                    key="epoch")
        path, frame = as_path(orbit), check_frame(frame)
        from astropy.coordinates import EarthLocation  # costly (~1 s to import): used here

        def evaluate(t):
            times = epoch + TimeDelta(t, format="sec")
            r_ef = np.einsum("nij,nj->ni", inertial_to_earth_fixed(times, frame),
                             np.asarray(path.position(t), dtype=float))
            lon, lat, height = EarthLocation.from_geocentric(*r_ef.T, unit=u.m).to_geodetic(
                "WGS84")
            rho = self.at(times, lat.to_value(u.rad), lon.to_value(u.rad),
                          height.to_value(u.m))
            return np.log(rho)[:, None]

        table = TimeTable(evaluate, spacing=spacing, segment=4320 * spacing)

        def density_at(t):
            return np.exp(table(t)[..., 0])

        return density_at

    def __repr__(self) -> str:
        return (f"MSISAtmosphere(f107={self.f107:g}, f107a={self.f107a:g}, ap={self.ap:g}, "
                f"version={self.version})")

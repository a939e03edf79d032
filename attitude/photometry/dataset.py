"""The lightcurve dataset: synthetic or observed brightness against time.

========================  ==============  ============================================
variable                  dims            meaning
========================  ==============  ============================================
``time`` (coordinate)     time            s since the ``epoch`` attribute (body time)
``flux``                  time            relative flux (units "1"), synthetic curves
``magnitude``             time            mag: ``-2.5 log10 flux`` (synthetic: reduced to
                                          unit distances) or as observed
``magnitude_error``       time            mag, observed curves
``session``               time            int: observing session (ALCDEF block)
``phase_angle``           time            rad
``sun_distance``          time            m, when known
``observer_distance``     time            m, when known
``light_time``            time            s, body -> observer, when known
``facet_flux``            time, face      per-facet flux (optional)
========================  ==============  ============================================

Global attributes: ``epoch`` (ISO 8601), ``time_scale``, ``frame``, ``law``,
``Conventions``, ``title``, ``history``, ``source``.
"""

from __future__ import annotations

from datetime import UTC, datetime
from os import PathLike
from pathlib import Path

import numpy as np
import xarray as xr
from astropy.time import Time

from attitude.foundations.errors import LightcurveFormatError
from attitude.foundations.quantities import to_time
from attitude.model.ephemeris import file_encoding, write_atomically
from attitude.version import __version__

__all__ = ["Lightcurve"]

_ATTRS = {
    "flux": {"units": "1", "long_name": "disk-integrated flux relative to the projected "
             "area of the volume-equivalent sphere (geometric albedo at zero phase)"},
    "magnitude": {"units": "mag", "long_name": "magnitude"},
    "magnitude_error": {"units": "mag", "long_name": "magnitude uncertainty (1 sigma)"},
    "session": {"long_name": "observing session index"},
    "phase_angle": {"units": "rad", "long_name": "Sun-body-observer angle"},
    "sun_distance": {"units": "m", "long_name": "heliocentric distance of the body"},
    "observer_distance": {"units": "m", "long_name": "body-observer distance"},
    "light_time": {"units": "s", "long_name": "light time from the body to the observer"},
    "facet_flux": {"units": "1", "long_name": "relative flux of each facet"},
}


class Lightcurve:
    """A lightcurve: a thin wrapper around an ``xarray.Dataset`` (schema above).

    Examples
    --------
    >>> import numpy as np
    >>> from astropy.time import Time
    >>> from attitude.photometry import Lightcurve
    >>> lc = Lightcurve.from_arrays([0.0, 60.0], flux=[1.0, 0.1],
    ...                             epoch=Time("2030-01-01", scale="tdb"))
    >>> lc.dataset.magnitude.values
    array([-0. ,  2.5])
    """

    def __init__(self, dataset: xr.Dataset):
        if not isinstance(dataset, xr.Dataset) or "time" not in dataset.coords \
                or "magnitude" not in dataset or "epoch" not in dataset.attrs:
            raise LightcurveFormatError("not a lightcurve: expected a dataset with a time "
                                        "coordinate, a magnitude variable and an epoch "
                                        "attribute")
        self._dataset = dataset

    @classmethod
    def from_arrays(cls, time, flux=None, *, magnitude=None, magnitude_error=None,
                    session=None, phase_angle=None, epoch: Time | str, frame: str = "",
                    law: str = "", sun_distance=None, observer_distance=None,
                    light_time=None, facet_flux=None, title: str = "lightcurve",
                    source: str = "", attrs: dict | None = None) -> Lightcurve:
        """Build the dataset from arrays (flux or magnitude, or both).

        Parameters
        ----------
        time : array_like, shape (n,)
            Seconds since `epoch`.
        flux, magnitude, magnitude_error, phase_angle : array_like, optional
            Per epoch (scalars broadcast).  ``magnitude`` defaults to ``-2.5 log10 flux``.
        sun_distance, observer_distance, light_time : array_like, optional
            m, m, s; per epoch or scalars.
        session : array_like of int, optional
        facet_flux : array_like, shape (n, n_faces), optional
        epoch : astropy Time or str
            The time of ``time = 0``, with its scale; an ISO 8601 string is read by
            :func:`attitude.foundations.quantities.to_time` in its default scale, TDB (as
            ``AttitudeState`` reads it).  Observed times in UTC come as a ``Time`` with
            ``scale="utc"`` (what :func:`attitude.read_lightcurve` builds).
        frame, law, title, source : str
        attrs : dict, optional
            More global attributes.
        """
        time = np.asarray(time, dtype=float)
        n = time.shape
        data = {}
        if flux is not None:
            flux = np.asarray(flux, dtype=float)
            data["flux"] = flux
            if magnitude is None:
                with np.errstate(divide="ignore"):
                    magnitude = -2.5 * np.log10(flux)
        if magnitude is None:
            raise LightcurveFormatError("a lightcurve needs a flux or a magnitude")
        data["magnitude"] = magnitude
        for key, value in (("magnitude_error", magnitude_error), ("session", session),
                           ("phase_angle", phase_angle), ("sun_distance", sun_distance),
                           ("observer_distance", observer_distance),
                           ("light_time", light_time)):
            if value is not None:
                data[key] = value
        variables = {}
        for key, value in data.items():
            arr = np.broadcast_to(np.asarray(value, dtype=int if key == "session"
                                             else float), n).copy()
            variables[key] = xr.Variable(("time",), arr, _ATTRS[key])
        if facet_flux is not None:
            variables["facet_flux"] = xr.Variable(("time", "face"), np.asarray(facet_flux),
                                                  _ATTRS["facet_flux"])
        epoch = to_time(epoch, key="epoch", error=LightcurveFormatError, precision=None)
        stamp = datetime.now(UTC).strftime("%Y-%m-%dT%H:%M:%SZ")
        ds_attrs = {"epoch": _isot(epoch), "time_scale": epoch.scale.upper(), "frame": frame,
                    "law": law, "Conventions": "CF-1.10", "title": title,
                    "history": f"{stamp} created by attitude {__version__}",
                    "source": source or f"attitude {__version__}"}
        ds_attrs.update(attrs or {})
        time_var = xr.Variable(("time",), time, {
            "units": "s", "long_name": "time elapsed since the reference epoch (at the "
            "body: add light_time for the observer's clock)",
            "reference_epoch": ds_attrs["epoch"], "time_scale": ds_attrs["time_scale"]})
        return cls(xr.Dataset(variables, coords={"time": time_var}, attrs=ds_attrs))

    # ------------------------------------------------------------------ views
    @property
    def dataset(self) -> xr.Dataset:
        """The lightcurve as an ``xarray.Dataset``."""
        return self._dataset

    @property
    def time(self) -> np.ndarray:
        """Seconds since :attr:`epoch`."""
        return np.asarray(self._dataset.time.values, dtype=float)

    @property
    def magnitude(self) -> np.ndarray:
        """Magnitudes, mag."""
        return np.asarray(self._dataset.magnitude.values, dtype=float)

    @property
    def epoch(self) -> Time:
        """The astropy Time of ``time = 0`` (the ``epoch`` attribute in ``time_scale``;
        without one, :func:`attitude.foundations.quantities.to_time`'s default, TDB)."""
        attrs = self._dataset.attrs
        return to_time(attrs["epoch"], scale=attrs.get("time_scale"), key="epoch",
                       error=LightcurveFormatError, precision=None)

    def __len__(self) -> int:
        return self._dataset.sizes["time"]

    def __repr__(self) -> str:
        return f"<Lightcurve {len(self)} epochs since {self._dataset.attrs['epoch']}>"

    def amplitude(self) -> float:
        """Peak-to-peak amplitude of the magnitude, mag (per session for observed
        curves: the largest session range).

        Examples
        --------
        >>> from astropy.time import Time
        >>> from attitude.photometry import Lightcurve
        >>> Lightcurve.from_arrays([0, 1, 2], magnitude=[1.0, 1.5, 1.2],
        ...                        epoch=Time("2030-01-01")).amplitude()
        0.5
        """
        m = self._dataset.magnitude
        if "session" in self._dataset:
            return float(max(float(np.ptp(g.values)) for _, g in
                             m.groupby(self._dataset.session)))
        return float(np.ptp(m.values))

    # ------------------------------------------------------------------ files
    def to_netcdf(self, path: str | PathLike) -> Path:
        """Write a netCDF-4 file atomically (temporary file, then rename); returns the
        path."""
        path = Path(path)
        ds = self._dataset
        encoding = file_encoding(ds)
        return write_atomically(path, lambda tmp: ds.to_netcdf(
            tmp, engine="netcdf4", format="NETCDF4", encoding=encoding))

    @classmethod
    def from_netcdf(cls, path: str | PathLike) -> Lightcurve:
        """Read a lightcurve written by :meth:`to_netcdf`.

        Raises
        ------
        LightcurveFormatError
            If the file is missing, unreadable, or not a lightcurve.
        """
        path = Path(path)
        if not path.is_file():
            raise LightcurveFormatError("no such file", path=str(path))
        try:
            with xr.open_dataset(path, engine="netcdf4", decode_times=False,
                                 decode_timedelta=False) as ds:
                ds = ds.load()
        except (OSError, ValueError, RuntimeError) as exc:  # RuntimeError: netCDF4 on a
            # damaged HDF5 block ("NetCDF: HDF error"), met when the data are read
            raise LightcurveFormatError(f"not a readable netCDF file ({exc})",
                                        path=str(path)) from None
        try:
            return cls(ds)
        except LightcurveFormatError as err:
            raise LightcurveFormatError(err.reason, path=str(path)) from None


def _isot(epoch: Time) -> str:
    t = epoch.copy()
    t.precision = 9
    return t.isot

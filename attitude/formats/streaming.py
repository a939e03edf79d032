"""Streaming netCDF output for long ephemerides: blocks appended along an unlimited
``time`` dimension, so 1e8 epochs never sit in memory at once.

:class:`EphemerisWriter` writes the same file as :meth:`Ephemeris.to_netcdf` (same schema,
attributes, CF layout, chunked zlib variables), block by block, into a temporary file in
the destination folder that is renamed onto the destination when the writer closes
normally; on an exception the temporary file is removed and an existing destination is
left untouched.  :func:`propagate_to_netcdf` drives it with the exact torque-free solution,
whose cost is O(1) per epoch, so blocks are independent and the streamed data equal a
one-shot :func:`attitude.propagate` bit for bit.

Examples
--------
>>> import numpy as np, attitude as att, tempfile, pathlib
>>> from scipy.spatial.transform import Rotation
>>> from attitude.formats.streaming import UniformTimes, propagate_to_netcdf
>>> body = att.RigidBody.from_principal_moments([1.0, 2.0, 3.0])
>>> state = att.AttitudeState("2030-01-01", Rotation.identity(), [0.1, 0.02, 0.3])
>>> out = pathlib.Path(tempfile.mkdtemp()) / "long.nc"
>>> path = propagate_to_netcdf(body, state, UniformTimes(0.0, 10.0, 2500), out, block=1000)
>>> len(att.Ephemeris.from_netcdf(path))
2500
"""

from __future__ import annotations

import os
import tempfile
from os import PathLike
from pathlib import Path

import netCDF4
import numpy as np
from astropy.time import Time

from ..body import RigidBody
from ..ephemeris import (
    CHUNK_TIME,
    Ephemeris,
    file_encoding,
)
from ..errors import EphemerisFormatError
from ..propagation.propagator import propagate

__all__ = ["EphemerisWriter", "UniformTimes", "propagate_to_netcdf"]

_DATA = ("quaternion", "angular_velocity", "angular_momentum", "kinetic_energy")


class UniformTimes:
    """``count`` times ``start + step * i`` (seconds since the epoch), generated lazily
    block by block: the same float64 values as ``start + step * np.arange(count)``."""

    def __init__(self, start: float, step: float, count: int):
        self.start, self.step, self.count = float(start), float(step), int(count)
        if self.count < 0 or not (np.isfinite(self.start) and np.isfinite(self.step)):
            raise ValueError("UniformTimes: need finite start and step and count >= 0")

    def __len__(self) -> int:
        return self.count

    def __getitem__(self, index: slice) -> np.ndarray:
        if not isinstance(index, slice):
            raise TypeError("UniformTimes supports slices only")
        i0, i1, _ = index.indices(self.count)
        return self.start + self.step * np.arange(i0, i1, dtype=float)


class EphemerisWriter:
    """Append blocks of a single-body ephemeris to a netCDF file.

    Use as a context manager::

        with EphemerisWriter("out.nc", body=body, epoch=state.epoch, frame="ICRF") as w:
            for block in blocks:
                w.append(block)          # an Ephemeris, or w.append_arrays(t, q, w)

    Parameters
    ----------
    path : destination; written only when the writer closes without an exception
    body : RigidBody
    epoch : astropy Time, the reference epoch of ``time``
    frame : inertial frame label
    title, source, extra_attrs : global attributes, as for :meth:`Ephemeris.from_arrays`
    chunk : samples per chunk along ``time`` in the file
    """

    def __init__(self, path: str | PathLike, *, body: RigidBody, epoch: Time,
                 frame: str = "ICRF", title: str = "attitude ephemeris", source: str = "",
                 extra_attrs: dict | None = None, chunk: int = CHUNK_TIME):
        if not isinstance(body, RigidBody):
            raise TypeError("EphemerisWriter writes a single-body ephemeris: body must be a "
                            "RigidBody")
        self.path = Path(path)
        self.body, self.epoch, self.frame = body, epoch, frame
        self._template_args = {"title": title, "source": source,
                               "extra_attrs": extra_attrs}
        self.chunk = int(chunk)
        self._nc: netCDF4.Dataset | None = None
        self._tmp: str | None = None
        self._n = 0
        self._last = -np.inf

    # --- lifecycle --------------------------------------------------------------------
    def open(self) -> EphemerisWriter:
        if self._tmp is not None:
            raise RuntimeError("EphemerisWriter is already open")
        template = Ephemeris.from_arrays(
            np.empty(0), np.empty((0, 4)), np.empty((0, 3)), body=self.body,
            epoch=self.epoch, frame=self.frame, **self._template_args)
        self._epoch_attr = template.dataset.attrs["epoch"]
        ds = template.dataset
        self.path.parent.mkdir(parents=True, exist_ok=True)
        fd, self._tmp = tempfile.mkstemp(prefix=f".{self.path.name}.", suffix=".tmp",
                                         dir=self.path.parent)
        os.close(fd)
        try:
            ds.to_netcdf(self._tmp, engine="netcdf4", format="NETCDF4",
                         encoding=file_encoding(ds, time_chunk=self.chunk),
                         unlimited_dims=("time",))
            self._nc = netCDF4.Dataset(self._tmp, "a")
            self._nc.set_auto_maskandscale(False)
        except BaseException:
            self.abort()
            raise
        return self

    def __enter__(self) -> EphemerisWriter:
        return self.open()

    def __exit__(self, exc_type, exc, tb) -> None:
        if exc_type is None:
            self.close()
        else:
            self.abort()

    def close(self) -> Path:
        """Finish the file and rename it onto :attr:`path`."""
        if self._tmp is None:
            raise RuntimeError("EphemerisWriter is not open")
        try:
            self._nc.close()
            self._nc = None
            with open(self._tmp, "rb+") as fh:
                os.fsync(fh.fileno())
            os.replace(self._tmp, self.path)
            self._tmp = None
        except BaseException:
            self.abort()
            raise
        return self.path

    def abort(self) -> None:
        """Drop the temporary file; :attr:`path` is left as it was."""
        if self._nc is not None:
            try:
                self._nc.close()
            except Exception:  # noqa: BLE001 - the file is discarded anyway
                pass
            self._nc = None
        if self._tmp is not None and os.path.exists(self._tmp):
            os.unlink(self._tmp)
        self._tmp = None

    def __len__(self) -> int:
        return self._n

    # --- data -------------------------------------------------------------------------
    def append(self, eph: Ephemeris) -> None:
        """Append a block; it must share the writer's epoch, frame and body."""
        ds = eph.dataset
        if eph.is_batch:
            raise EphemerisFormatError("EphemerisWriter: batch ephemerides are not supported")
        if ds.attrs["epoch"] != self._epoch_attr or eph.time_scale != self.epoch.scale.upper():
            raise EphemerisFormatError(
                f"block epoch {ds.attrs['epoch']} {eph.time_scale} differs from the file's "
                f"{self._epoch_attr} {self.epoch.scale.upper()}")
        if eph.frame != self.frame:
            raise EphemerisFormatError(f"block frame {eph.frame} differs from the file's "
                                       f"{self.frame}")
        if "inertia" in ds.attrs and not np.array_equal(
                np.asarray(ds.attrs["inertia"]), self.body.inertia.ravel()):
            raise EphemerisFormatError("block inertia differs from the file's body")
        self._write({name: ds[name].values for name in ("time", *_DATA)})

    def append_arrays(self, time, quaternion, angular_velocity) -> None:
        """Append samples given as arrays (derived variables are computed here)."""
        self.append(Ephemeris.from_arrays(time, quaternion, angular_velocity, body=self.body,
                                          epoch=self.epoch, frame=self.frame))

    def _write(self, arrays: dict[str, np.ndarray]) -> None:
        if self._nc is None:
            raise RuntimeError("EphemerisWriter is not open (use it as a context manager)")
        t = arrays["time"]
        k = len(t)
        if k == 0:
            return
        if not (t[0] > self._last and np.all(np.diff(t) > 0)):
            raise EphemerisFormatError(
                f"time must increase strictly across blocks (block starts at {t[0]!r} s "
                f"after {self._last!r} s)")
        n = self._n
        for name, values in arrays.items():
            self._nc[name][n:n + k, ...] = values
        self._n, self._last = n + k, t[-1]


def propagate_to_netcdf(body: RigidBody, state, times, path: str | PathLike, *,
                        block: int = 100_000, title: str | None = None,
                        source: str | None = None, chunk: int = CHUNK_TIME) -> Path:
    """Propagate with the exact torque-free solution and stream the ephemeris to ``path``.

    ``times`` (seconds since ``state.epoch``) is anything with ``len()`` and slicing: a
    numpy array (or ``np.memmap``), a Quantity, an astropy ``Time`` array, or
    :class:`UniformTimes` (generated block by block, nothing of size ``len(times)`` in
    memory).  :func:`attitude.propagate` is called on ``block`` samples at a time and each
    block is appended; the file appears at ``path`` only when complete.
    """
    if not isinstance(body, RigidBody):
        raise TypeError("propagate_to_netcdf streams a single body: body must be a RigidBody")
    block = int(block)
    if block < 1:
        raise ValueError(f"block must be >= 1, got {block}")
    n = len(times)
    writer = None
    try:
        for i0 in range(0, max(n, 1), block):
            eph = propagate(body, state, times[i0:i0 + block], method="exact")
            if writer is None:
                attrs = eph.dataset.attrs
                writer = EphemerisWriter(
                    path, body=body, epoch=state.epoch, frame=state.frame,
                    title=title if title is not None else attrs["title"],
                    source=source if source is not None else attrs["source"], chunk=chunk)
                writer.open()
            writer.append(eph)
    except BaseException:
        if writer is not None:
            writer.abort()
        raise
    return writer.close()

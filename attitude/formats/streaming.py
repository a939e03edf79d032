"""Streaming netCDF output for long ephemerides: blocks appended along an unlimited
``time`` dimension, so 1e8 epochs never sit in memory at once.

:class:`EphemerisWriter` writes the same file as :meth:`Ephemeris.to_netcdf` (same schema,
attributes, CF layout, chunked zlib variables), block by block, for one body (dims
``time, ...``) or a batch (dims ``body, time, ...``), into a temporary file that
:class:`~attitude.model.ephemeris.AtomicFiles` renames onto the destination when the writer
closes normally; on an exception the temporary file is removed and an existing
destination is left untouched.

:func:`propagate_to_netcdf` drives it block by block in time:

- without torques, with the exact torque-free solution, whose cost is O(1) per epoch and
  independent of the other epochs, so the streamed data equal a one-shot
  :func:`attitude.propagate` (the same arithmetic on each epoch);
- with torques, with the splitting integrator
  (:func:`attitude.propagation.splitting.integrate_splitting`), restarted at the last
  epoch of each block from the state it reached there.  The longest step is fixed once
  for the whole run (:func:`~attitude.propagation.splitting.choose_step` at the initial
  state, or ``step=``) and every interval between consecutive output times is cut into
  the same equal steps as in one in-memory run, so the blocks change no step: the
  streamed run differs from ``attitude.propagate(..., step=step)`` only by the rounding
  of the state carried across each block boundary (a few ulps, then propagated by the
  dynamics like any other rounding error).

Memory is a few blocks of 7 float64 per body and epoch, whatever the number of epochs
(docs/formats.md has the measured peak and throughput, ``benchmarks/streaming.py``).

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

import math
from collections.abc import Sequence
from os import PathLike
from pathlib import Path

import netCDF4
import numpy as np
from astropy.time import Time

from ..foundations.errors import EphemerisFormatError, InvalidStateError, WriterError
from ..model.body import RigidBody
from ..model.ephemeris import CHUNK_TIME, AtomicFiles, Ephemeris, file_encoding
from ..model.population import check_batch
from ..model.state import AttitudeState
from ..propagation.propagator import elapsed_seconds, propagate
from ..propagation.splitting import choose_step, integrate_splitting

__all__ = ["EphemerisWriter", "UniformTimes", "propagate_to_netcdf"]

_DATA = ("quaternion", "angular_velocity", "angular_momentum", "kinetic_energy")
#: Samples (bodies x epochs) per block when ``block`` is not given.
_BLOCK_SAMPLES = 100_000


class UniformTimes:
    """``count`` times ``start + step * i`` (seconds since the epoch), generated lazily
    block by block: the same float64 values as ``start + step * np.arange(count)``.

    Parameters
    ----------
    start, step : float
        First time and spacing, s.
    count : int
        Number of times (>= 0).

    Examples
    --------
    >>> times = UniformTimes(0.0, 0.5, 10**9)      # nothing of that size in memory
    >>> len(times), times[3:6].tolist()
    (1000000000, [1.5, 2.0, 2.5])
    """

    def __init__(self, start: float, step: float, count: int):
        try:
            self.start, self.step, self.count = float(start), float(step), int(count)
        except (TypeError, ValueError):
            self.count = -1
        if (self.count < 0 or self.count != count
                or not (np.isfinite(self.start) and np.isfinite(self.step))):
            raise InvalidStateError(f"UniformTimes({start!r}, {step!r}, {count!r}): need a "
                                    "finite start and step and count >= 0", key="times")

    def __len__(self) -> int:
        return self.count

    def __getitem__(self, index: slice) -> np.ndarray:
        if not isinstance(index, slice):
            raise InvalidStateError(f"UniformTimes supports slices only, got "
                                    f"{type(index).__name__}", key="times")
        i0, i1, _ = index.indices(self.count)
        return self.start + self.step * np.arange(i0, i1, dtype=float)


class EphemerisWriter:
    """Append blocks of an ephemeris, one body or a batch, to a netCDF file.

    Use as a context manager; the file appears at ``path`` only when the ``with`` block
    ends without an exception.

    Parameters
    ----------
    path : str or path-like
        Destination, written when the writer closes without an exception.
    body : RigidBody, or a sequence of RigidBody for a batch
        A batch file has dims ``(body, time, ...)`` and per-body ``inertia``.
    epoch : astropy.time.Time
        Reference epoch of ``time``.
    frame : str
        Inertial frame label.
    title, source, extra_attrs
        Global attributes, as for :meth:`Ephemeris.from_arrays`.
    chunk : int
        Samples per netCDF chunk along ``time``.

    Examples
    --------
    >>> import numpy as np, attitude as att, tempfile, pathlib
    >>> from scipy.spatial.transform import Rotation
    >>> bodies = [att.RigidBody.from_principal_moments(m) for m in ([1, 2, 3], [2, 3, 4])]
    >>> states = [att.AttitudeState("2030-01-01", Rotation.identity(), [0.1, 0.0, 0.3])] * 2
    >>> out = pathlib.Path(tempfile.mkdtemp()) / "batch.nc"
    >>> with EphemerisWriter(out, body=bodies, epoch=states[0].epoch) as w:
    ...     for start in (0.0, 10.0):
    ...         w.append(att.propagate(bodies, states, start + np.arange(10.0)))
    >>> att.Ephemeris.from_netcdf(out).dataset.quaternion.shape
    (2, 20, 4)
    """

    def __init__(self, path: str | PathLike, *, body, epoch: Time,
                 frame: str = "ICRF", title: str = "attitude ephemeris", source: str = "",
                 extra_attrs: dict | None = None, chunk: int = CHUNK_TIME):
        self.batch = not isinstance(body, RigidBody)
        bodies = [body] if not self.batch else list(body)
        if not bodies or not all(isinstance(b, RigidBody) for b in bodies):
            raise EphemerisFormatError("EphemerisWriter: body must be a RigidBody or a "
                                       "non-empty sequence of RigidBody", key="body")
        self.path = Path(path)
        self.body, self.epoch, self.frame = body, epoch, frame
        self._inertia = np.stack([b.inertia.ravel() for b in bodies])
        self._template_args = {"title": title, "source": source,
                               "extra_attrs": extra_attrs}
        self.chunk = int(chunk)
        self._nc: netCDF4.Dataset | None = None
        self._files: AtomicFiles | None = None
        self._n = 0
        self._last = -np.inf

    # --- lifecycle --------------------------------------------------------------------
    def open(self) -> EphemerisWriter:
        """Create the temporary file with the schema and no samples."""
        if self._files is not None:
            raise WriterError("EphemerisWriter is already open")
        lead = (len(self._inertia), 0) if self.batch else (0,)
        template = Ephemeris.from_arrays(
            np.empty(0), np.empty((*lead, 4)), np.empty((*lead, 3)), body=self.body,
            epoch=self.epoch, frame=self.frame, **self._template_args)
        self._epoch_attr = template.dataset.attrs["epoch"]
        ds = template.dataset
        self._files = AtomicFiles(self.path).open()
        try:
            tmp = self._files[self.path]
            ds.to_netcdf(tmp, engine="netcdf4", format="NETCDF4",
                         encoding=file_encoding(ds, time_chunk=self.chunk),
                         unlimited_dims=("time",))
            self._nc = netCDF4.Dataset(tmp, "a")
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
        if self._files is None:
            raise WriterError("EphemerisWriter is not open")
        try:
            self._nc.close()
            self._nc = None
            self._files.commit()
            self._files = None
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
        if self._files is not None:
            self._files.discard()
            self._files = None

    def __len__(self) -> int:
        return self._n

    # --- data -------------------------------------------------------------------------
    def append(self, eph: Ephemeris) -> None:
        """Append a block; it must share the writer's epoch, frame and bodies."""
        if self._nc is None:
            raise WriterError("EphemerisWriter is not open (use it as a context manager)")
        ds = eph.dataset
        if eph.is_batch != self.batch:
            raise EphemerisFormatError(
                f"EphemerisWriter: a {'batch' if eph.is_batch else 'single-body'} block for "
                f"a {'batch' if self.batch else 'single-body'} file")
        if ds.attrs["epoch"] != self._epoch_attr or eph.time_scale != self.epoch.scale.upper():
            raise EphemerisFormatError(
                f"block epoch {ds.attrs['epoch']} {eph.time_scale} differs from the file's "
                f"{self._epoch_attr} {self.epoch.scale.upper()}")
        if eph.frame != self.frame:
            raise EphemerisFormatError(f"block frame {eph.frame} differs from the file's "
                                       f"{self.frame}")
        inertia = (np.asarray(ds["inertia"].values) if self.batch else
                   np.asarray(ds.attrs["inertia"])[None] if "inertia" in ds.attrs else None)
        if inertia is not None and not np.array_equal(inertia.reshape(-1, 9), self._inertia):
            raise EphemerisFormatError("block inertia differs from the file's bodies")
        self._write({name: ds[name].values for name in ("time", *_DATA)})

    def append_arrays(self, time, quaternion, angular_velocity) -> None:
        """Append samples given as arrays, ``([N,] T, 4)`` quaternions body -> inertial
        and ``([N,] T, 3)`` body rates (rad/s); the derived variables are computed
        here."""
        self.append(Ephemeris.from_arrays(time, quaternion, angular_velocity, body=self.body,
                                          epoch=self.epoch, frame=self.frame))

    def _write(self, arrays: dict[str, np.ndarray]) -> None:
        if self._nc is None:
            raise WriterError("EphemerisWriter is not open (use it as a context manager)")
        t = arrays["time"]
        k = len(t)
        if k == 0:
            return
        if not (t[0] > self._last and np.all(np.diff(t) > 0)):
            raise EphemerisFormatError(
                f"time must increase strictly across blocks (block starts at {t[0]!r} s "
                f"after {self._last!r} s)")
        n = self._n
        window = slice(n, n + k)
        self._nc["time"][window] = t
        for name in _DATA:
            self._nc[name][(slice(None), window) if self.batch else window] = arrays[name]
        self._n, self._last = n + k, t[-1]


def propagate_to_netcdf(body, state, times, path: str | PathLike, *,
                        torques: Sequence | None = None, method: str | None = None,
                        step: float | None = None, order: int | None = None,
                        block: int | None = None, title: str | None = None,
                        source: str | None = None, chunk: int = CHUNK_TIME) -> Path:
    """Propagate one body or a batch and stream the ephemeris to ``path`` block by block.

    Parameters
    ----------
    body : RigidBody, or a sequence of RigidBody (a batch)
    state : AttitudeState, or a sequence of them (one per body, one epoch and frame)
    times : sequence of times since ``state.epoch``
        Anything with ``len()`` and slicing: a numpy array (or ``np.memmap``), a
        Quantity, an astropy ``Time`` array, or :class:`UniformTimes` (generated block by
        block: nothing of size ``len(times)`` in memory).  Strictly increasing; with
        torques also ``>= 0`` (the integration runs forward from the state).
    path : str or path-like
        The netCDF file; it appears only when complete.
    torques : sequence of torque models, optional
        As for :func:`attitude.propagate`.
    method : {"exact", "splitting"}, optional
        Default ``"exact"`` without torques, ``"splitting"`` with.  The DOP853
        reference adapts its steps to the block boundaries and is not streamed.
    step : float, optional
        Longest step of the splitting integrator, s; default
        :func:`~attitude.propagation.splitting.choose_step` at the initial state, fixed
        for the whole run.
    order : {2, 4, 6}, optional
        Order of the splitting integrator (default 4).
    block : int, optional
        Epochs per block (default: about 1e5 samples, ``1e5 // bodies`` epochs).
        Memory grows with ``block x bodies``, not with ``len(times)``.
    title, source : str, optional
        Global attributes (default: those of :func:`attitude.propagate`).
    chunk : int
        Samples per netCDF chunk along ``time``.

    Returns
    -------
    Path

    Raises
    ------
    InvalidStateError
        Bad times, block, method or states.

    Examples
    --------
    A batch of two bodies under a constant torque, streamed 50 epochs at a time:

    >>> import numpy as np, attitude as att, tempfile, pathlib
    >>> from scipy.spatial.transform import Rotation
    >>> from attitude.model.torques import ConstantTorque
    >>> bodies = [att.RigidBody.from_principal_moments(m) for m in ([1, 2, 3], [2, 3, 4])]
    >>> states = [att.AttitudeState("2030-01-01", Rotation.identity(), [0.1, 0.0, 0.3])] * 2
    >>> out = pathlib.Path(tempfile.mkdtemp()) / "torqued.nc"
    >>> path = propagate_to_netcdf(bodies, states, UniformTimes(0.0, 1.0, 120), out,
    ...                            torques=[ConstantTorque([0.0, 1e-4, 0.0])], step=0.5,
    ...                            block=50)
    >>> att.Ephemeris.from_netcdf(path).dataset.angular_velocity.dims
    ('body', 'time', 'axis')
    """
    batch = not isinstance(body, RigidBody)
    if batch:
        bodies, states = check_batch(body, state)
        first = states[0]
    elif isinstance(state, AttitudeState):
        bodies, states, first = body, state, state
    else:
        raise InvalidStateError(f"expected an AttitudeState for one RigidBody, got "
                                f"{type(state).__name__}", key="state")
    torques = list(torques or [])
    given, method = method, _stream_method(method, torques)
    n_bodies = len(bodies) if batch else 1
    if block is None:
        block = max(1, _BLOCK_SAMPLES // n_bodies)
    elif not isinstance(block, (int, np.integer)):
        raise InvalidStateError(f"block must be a whole number of epochs, got {block!r}",
                                key="block")
    if block < 1:
        raise InvalidStateError(f"block must be >= 1 epoch, got {block}", key="block")
    if method == "exact":
        blocks = _exact_blocks(bodies, states, times, block, given)
    else:
        blocks = _splitting_blocks(bodies, states, times, block, torques, step,
                                   4 if order is None else order)
    writer = None
    try:
        for eph in blocks:
            if writer is None:
                attrs = eph.dataset.attrs
                writer = EphemerisWriter(
                    path, body=bodies, epoch=first.epoch, frame=first.frame,
                    title=title if title is not None else attrs["title"],
                    source=source if source is not None else attrs["source"], chunk=chunk,
                    extra_attrs={k: attrs[k] for k in ("method", "method_reason")
                                 if k in attrs})
                writer.open()
            writer.append(eph)
            eph = None              # free the block before the next one is computed
    except BaseException:
        if writer is not None:
            writer.abort()
        raise
    return writer.close()


def _stream_method(method, torques) -> str:
    if method is None:
        return "splitting" if torques else "exact"
    if method == "exact" and torques:
        raise InvalidStateError("method='exact' is the torque-free solution: drop torques= "
                                "or use method='splitting'", key="method")
    if method not in ("exact", "splitting"):
        raise InvalidStateError(
            f"method={method!r}: a stream runs 'exact' (no torques) or 'splitting' (the "
            "DOP853 reference adapts its steps to each block; run it with att.propagate "
            "and stream its blocks with EphemerisWriter)", key="method")
    return method


def _exact_blocks(bodies, states, times, block: int, given=None):
    """An Ephemeris per block: :func:`attitude.propagate` with the closed form (``given``:
    the method the caller named, ``"exact"`` or None, so that the file says why)."""
    for i0 in range(0, max(len(times), 1), block):
        yield propagate(bodies, states, times[i0:i0 + block], method=given)


def _splitting_blocks(bodies, states, times, block: int, torques, step, order):
    """An Ephemeris per block: the splitting integrator restarted at the last point of
    the step grid that the previous block reached, with the state there, so that the
    blocks take the steps of one run."""
    single = isinstance(bodies, RigidBody)
    first = states if single else states[0]
    q = np.stack([s.attitude.as_quat() for s in ([states] if single else states)])
    w = np.stack([s.omega_body for s in ([states] if single else states)])
    if step is None:
        step = choose_step(bodies, q, w, torques, order=order)
    elif not (isinstance(step, (int, float, np.floating)) and step > 0):
        raise InvalidStateError(f"step must be a positive number of seconds, got {step!r}",
                                key="step")
    step = float(step) if math.isfinite(step) else None    # inf: no torque, exact flow
    name = bodies.name if single else "batch"
    title = f"attitude ephemeris{': ' + name if name else ''}"
    source = (f"attitude.formats.streaming.propagate_to_netcdf, method=splitting (splitting "
              f"integrator: exact free flow and torque kicks, order {order}, step {step!r} "
              f"s, streamed {block} epochs at a time)")
    t_last = 0.0
    for i0 in range(0, max(len(times), 1), block):
        t = elapsed_seconds(times[i0:i0 + block], first.epoch)
        if i0 == 0 and t.size and t[0] < 0:
            raise InvalidStateError(
                f"a stream with torques runs forward from the state's epoch; the "
                f"first time is {t[0]!r} s (give times >= 0)", key="times")
        # the run's step grid goes on across blocks: each block also asks for the last
        # grid time it reaches and the next block restarts there (outputs inside steps
        # do not change the trajectory, so the blocks take the steps of one run)
        grid = t_last
        if t.size and step is not None and t[-1] > t_last:
            grid = t_last + math.floor((t[-1] - t_last) / step) * step
        run_t = np.append(t, grid) if grid > t_last else t
        qs, ws = integrate_splitting(bodies, q[0] if single else q, w[0] if single else w,
                                     run_t, torques=torques, step=step, order=order,
                                     t0=t_last)
        if run_t.size > t.size:
            q, w, t_last = qs[..., -1, :], ws[..., -1, :], float(grid)
            qs, ws = qs[..., :-1, :], ws[..., :-1, :]
            if single:
                q, w = q[None], w[None]
        yield Ephemeris.from_arrays(t, qs, ws, body=bodies, epoch=first.epoch,
                                    frame=first.frame, title=title, source=source)

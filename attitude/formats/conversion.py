"""The engine of ``attitude convert IN OUT``: an attitude ephemeris from one file format
to another, netCDF (``.nc``) and CCSDS AEM (``.aem`` KVN, ``.xml`` XML), and from SPICE
C-kernels (``.bc``, :func:`attitude.formats.spice_read.read_ck`).  C-kernels are written
by :func:`attitude.formats.spice.convert_to_ck`.
"""

from __future__ import annotations

from os import PathLike
from pathlib import Path

from ..foundations.errors import EphemerisFormatError
from ..model.ephemeris import Ephemeris
from .aem_read import read_aem
from .aem_write import write_aem
from .spice_read import is_ck, read_ck

__all__ = ["convert"]

_READ_OPTIONS = ("body", "segment", "angular_velocity")
#: Options of :func:`read_ck` (``body`` too).
_CK_OPTIONS = ("sclk", "lsk", "frame", "instrument", "start", "stop", "step", "kernels")


def convert(in_path: str | PathLike, out_path: str | PathLike, **options) -> Path:
    """Convert between netCDF (``.nc``) and CCSDS AEM (``.aem`` KVN, ``.xml`` XML), or
    read a SPICE C-kernel (``.bc``) into either.

    The input format is taken from the suffix for ``.nc``, from the suffix ``.bc`` or
    the DAF/CK content for a C-kernel, and from the content otherwise (KVN or XML AEM);
    the output format from the suffix.  ``member`` picks one body of a batch or binary
    file (its index or name: :meth:`Ephemeris.member`).  ``body``, ``segment`` and
    ``angular_velocity`` go
    to :func:`read_aem`; for a CK, ``body``, ``sclk``, ``lsk``, ``frame``,
    ``instrument``, ``start``, ``stop``, ``step`` and ``kernels`` go to :func:`read_ck`;
    every other option to :func:`write_aem` (``object_name``, ``object_id``,
    ``ref_frame_a``, ``ref_frame_b``, ``attitude_type``, ``time_system``, ...).  This is
    ``attitude convert IN OUT``.

    Returns
    -------
    Path
        The output file.

    Examples
    --------
    >>> import tempfile, pathlib, numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> body = att.RigidBody.from_principal_moments([0.61, 0.965, 1.0])
    >>> state = att.AttitudeState("2024-04-13", Rotation.identity(), [0.02, 0.0, 0.1])
    >>> eph = att.propagate(body, state, np.arange(0.0, 600.0, 60.0))
    >>> folder = pathlib.Path(tempfile.mkdtemp())
    >>> nc = eph.to_netcdf(folder / "tumbler.nc")
    >>> aem = convert(nc, folder / "tumbler.aem", object_name="TUMBLER")
    >>> aem.read_text().splitlines()[0]
    'CCSDS_AEM_VERS = 2.0'
    >>> back = read_aem(aem)                      # the quaternions survive the round trip
    >>> bool(np.all((back.rotation * eph.rotation.inv()).magnitude() < 1e-12))
    True
    """
    in_path, out_path = Path(in_path), Path(out_path)
    member = options.pop("member", None)
    if is_ck(in_path):
        ck_opts = {k: options.pop(k) for k in _CK_OPTIONS + ("body",) if k in options}
        eph = read_ck(in_path, **ck_opts)
        return _write(_member(eph, member), out_path, options)
    misplaced = [k for k in _CK_OPTIONS if k in options]
    if misplaced:
        raise EphemerisFormatError(f"{', '.join(misplaced)}: options for reading a SPICE "
                                   f"C-kernel (.bc), not {in_path.name}")
    read_opts = {k: options.pop(k) for k in _READ_OPTIONS if k in options}
    if in_path.suffix.lower() == ".nc":
        if read_opts:
            raise EphemerisFormatError(
                f"{', '.join(read_opts)}: options for reading an AEM, not a netCDF file")
        eph = Ephemeris.from_netcdf(in_path)
    else:
        eph = read_aem(in_path, **read_opts)
    return _write(_member(eph, member), out_path, options)


def _member(eph: Ephemeris, member) -> Ephemeris:
    """Body ``member`` of a batch (index or name), or ``eph`` itself."""
    if member is None:
        return eph
    if not eph.is_batch:
        raise EphemerisFormatError(f"body {member!r}: the file holds one body; omit --body")
    return eph.member(member)


def _write(eph: Ephemeris, out_path: Path, options: dict) -> Path:
    """``eph`` as netCDF or AEM, by the suffix of ``out_path``."""
    suffix = out_path.suffix.lower()
    if suffix == ".nc":
        if options:
            raise EphemerisFormatError(
                f"{', '.join(options)}: options for writing an AEM, not a netCDF file")
        return eph.to_netcdf(out_path)
    if suffix in (".aem", ".kvn", ".xml"):
        return write_aem(eph, out_path, **options)
    if suffix == ".bc":
        raise EphemerisFormatError(
            f"{out_path}: a SPICE C-kernel is written from .nc or .aem/.xml "
            "(attitude.formats.spice.convert_to_ck), not converted from another .bc")
    raise EphemerisFormatError(
        f"{out_path}: unknown output format {suffix!r}: use .nc (netCDF), .aem (CCSDS AEM, "
        "KVN), .xml (CCSDS AEM, XML) or .bc (SPICE C-kernel, from .nc/.aem/.xml)")

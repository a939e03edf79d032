"""Reading SPICE C-kernels (``.bc``) for ``attitude convert MISSION.bc OUT``:
:func:`read_ck` finds the kernels a CK needs beside it (those :func:`write_ck` writes:
``STEM.tsc``, ``STEM.tf``, ``STEM.tls``) and reads it with
:meth:`attitude.Ephemeris.from_spice`, where the sampling itself lives
(:mod:`attitude.model.spice_ck`).  Needs spiceypy (``pip install
'attitude-dynamics[spice]'``).
"""

from __future__ import annotations

from collections.abc import Sequence
from os import PathLike
from pathlib import Path

from ..foundations.errors import EphemerisFormatError
from ..model.body import RigidBody
from ..model.ephemeris import Ephemeris

__all__ = ["read_ck", "is_ck"]

#: Suffixes of the companion kernels :func:`attitude.formats.spice.write_ck` writes.
COMPANIONS = {"sclk": ".tsc", "lsk": ".tls", "fk": ".tf"}


def is_ck(path: str | PathLike) -> bool:
    """Whether ``path`` is a SPICE C-kernel: the suffix ``.bc``, or a binary DAF/CK file
    whatever its name.

    Examples
    --------
    >>> is_ck("mission.bc"), is_ck("mission.nc")
    (True, False)
    """
    path = Path(path)
    if path.suffix.lower() == ".bc":
        return True
    try:
        with open(path, "rb") as fh:
            return fh.read(8).startswith(b"DAF/CK")
    except OSError:
        return False


def read_ck(path: str | PathLike, *, sclk: str | PathLike | None = None,
            lsk: str | PathLike | None = None, frame: str | None = None,
            instrument: int | str | None = None, start=None, stop=None, step=None,
            kernels: Sequence[str | PathLike] = (),
            body: RigidBody | None = None) -> Ephemeris:
    """Read a CK with the kernels it needs: those given, else those beside it with its
    stem (``STEM.tsc`` SCLK, ``STEM.tls`` LSK, ``STEM.tf`` frame kernel, as
    :func:`attitude.formats.spice.write_ck` writes them), else (LSK only) the default of
    :meth:`attitude.Ephemeris.from_spice`.  ``frame`` defaults to ``J2000``; the other
    arguments are those of :meth:`~attitude.Ephemeris.from_spice`.

    Raises
    ------
    EphemerisFormatError
        The message names the missing piece: the SCLK kernel (``--sclk``), a sample
        outside the coverage (``--start``/``--stop``), an unknown frame (``--frame``,
        ``--kernel``) or structure (``--instrument``).

    Examples
    --------
    >>> import tempfile, pathlib, numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> from attitude.formats.spice import write_ck
    >>> body = att.RigidBody.from_principal_moments([0.61, 0.965, 1.0])
    >>> state = att.AttitudeState("2024-04-13", Rotation.identity(), [0.02, 0.0, 0.1])
    >>> eph = att.propagate(body, state, np.arange(0.0, 600.0, 60.0))
    >>> files = write_ck(eph, pathlib.Path(tempfile.mkdtemp()) / "tumbler.bc")
    >>> back = read_ck(files.ck, instrument="SC_BODY_1", body=body)   # FK found beside
    >>> len(back), back.dataset.attrs["body_frame"], back.dataset.attrs["inertia_known"]
    (10, 'SC_BODY_1', 1)
    """
    path = Path(path)
    if not path.is_file():
        raise EphemerisFormatError(f"{path}: no such file")
    beside = {key: path.with_suffix(suffix) for key, suffix in COMPANIONS.items()}
    beside = {key: p for key, p in beside.items() if p.is_file()}
    if sclk is None:
        sclk = beside.get("sclk")
    if lsk is None:
        lsk = beside.get("lsk")
    extra = list(kernels)
    if "fk" in beside and beside["fk"] not in [Path(k) for k in extra]:
        extra.insert(0, beside["fk"])
    try:
        return Ephemeris.from_spice(path, sclk, lsk, frame or "J2000", start, stop, step,
                                    instrument=instrument, kernels=extra, body=body)
    except EphemerisFormatError as exc:
        if exc.key == "sclk" and sclk is None:
            raise EphemerisFormatError(
                f"{exc.reason} (none beside it as {path.with_suffix('.tsc').name})",
                key=exc.key, path=exc.path) from None
        raise

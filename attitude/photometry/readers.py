"""Observed lightcurves in: ALCDEF and CSV files -> the lightcurve dataset.

ALCDEF (Asteroid Lightcurve Data Exchange Format, Warner et al.; the Minor Planet
Center's ALCDEF database) is plain text made of sessions: a metadata block
``STARTMETADATA`` ... ``ENDMETADATA`` of ``KEY=VALUE`` lines (``OBJECTNUMBER``,
``OBJECTNAME``, ``SESSIONDATE``, ``SESSIONTIME``, ``DELIMITER`` = ``PIPE`` or ``TAB``,
``DIFFERMAGS``, ``LTCAPP``, ``LTCDAYS``, ``LTCTYPE``, ``REDUCEDMAGS``, ``UCORMAG``,
``MAGBAND``, ``FILTER``, ``PHASE``, ...), then data lines ``DATA=JD|MAG|MAGERR`` (an
optional fourth field, the airmass, is read and ignored) and ``ENDDATA``.  JDs are UTC.

What the reader does with the metadata:

* **sessions**: each block is a session (``session`` variable); differential
  magnitudes of different sessions have independent zero points, and
  :func:`~attitude.photometry.periods.fit_periods` takes ``sessions=`` to fit one
  offset each.
* **light time**: when a block says no light-time correction was applied
  (``LTCAPP=NONE``) and gives ``LTCDAYS``, the times are corrected to the asteroid
  (``JD - LTCDAYS``); blocks already corrected are kept; blocks with neither are kept
  and listed in the ``light_time_uncorrected_sessions`` attribute.
* **reduced magnitudes**: with ``reduce=True``, ``UCORMAG`` (the reduction to unit
  distances given by the observer) is added to blocks with ``REDUCEDMAGS=NONE``.

CSV: a header row naming the columns: time as ``jd`` (UTC), ``mjd`` (UTC) or ``time``
(ISO 8601, UTC); magnitude as ``mag`` or ``magnitude``; optional ``mag_err`` /
``magerr`` / ``magnitude_error`` / ``sigma`` and ``session``.  Lines starting with
``#`` are comments.

Every malformed file is a :class:`~attitude.foundations.errors.LightcurveFormatError` naming the
file and the line.

References
----------
.. [1] B. D. Warner, A. W. Harris, P. Pravec et al., "Asteroid Lightcurve Data Exchange
   Format (ALCDEF) Definition and Standards", v2.2.7 (2019).
"""

from __future__ import annotations

import csv
import re
import warnings
from pathlib import Path

import numpy as np
from astropy.time import Time, TimeDelta

from attitude.foundations.errors import LightcurveFormatError
from attitude.photometry.dataset import Lightcurve
from attitude.photometry.geometry import Geometry, OrbitGeometry
from attitude.photometry.observations import LightcurveObservations

__all__ = ["read_lightcurve", "read_alcdef", "read_csv", "observations_of"]

_DELIMITERS = {"PIPE": "|", "TAB": "\t"}
#: Julian dates a lightcurve may hold: 1582-10-15 (the Gregorian calendar) to 3000-01-01;
#: anything else is a damaged field (a JD of 1e-320 would reach astropy as year -4712).
_JD_RANGE = (2299160.5, 2816787.5)
_JD_OFFSET = {"jd": 0.0, "mjd": 2400000.5}
_TRUE = {"TRUE", "T", "YES", "Y"}


def read_lightcurve(path, *, format: str | None = None, geometry=None, sigma=None,
                    calibrated: bool = False, **options):
    """Read a lightcurve: ALCDEF, CSV or the package's own netCDF.

    Parameters
    ----------
    path : str or path-like
    format : {"alcdef", "csv", "netcdf"}, optional
        Default: from the suffix (``.nc`` netCDF, ``.csv`` CSV) or the content (a
        ``STARTMETADATA`` line: ALCDEF).
    geometry : OrbitGeometry, Geometry or callable, optional
        The Sun and observer of every point: :meth:`Geometry.from_orbit` without times
        (evaluated at the file's epochs, read as the observer's: an ALCDEF session
        already light-time corrected gets its ``LTCDAYS`` back), a :class:`Geometry`
        (constant, or one direction per point of the file), or a function of the
        observer's epochs (astropy Time) returning a Geometry.  With it, the result
        is a list of :class:`~attitude.photometry.observations.LightcurveObservations`,
        one per session, for :func:`attitude.invert` or :func:`attitude.fitting.fit`.
    sigma : float, optional
        With ``geometry``: the 1-sigma (mag) of points the file gives none for.
    calibrated : bool, optional
        With ``geometry``: the magnitudes are reduced to unit distances and comparable
        between sessions (default False: relative lightcurves).
    **options
        Passed to :func:`read_alcdef` or :func:`read_csv`.

    Returns
    -------
    Lightcurve, or list of LightcurveObservations
        Without ``geometry``: ``time`` (s since ``lc.epoch``), ``magnitude``,
        ``magnitude_error``, ``session``.  With it: one observations object per session,
        named ``"<file>: session k (line j)"``, sharing one epoch (the file's first
        point, TDB); their ``times`` are the observer's (UTC), their ``time`` the body's.

    Raises
    ------
    LightcurveFormatError
        Unreadable or malformed file (the message names the line), or an unknown format;
        with ``geometry``: a point without an uncertainty (and no ``sigma``), a geometry
        of another length than the file, a session corrected for light time whose
        ``LTCDAYS`` is unknown.

    Examples
    --------
    >>> import os, tempfile
    >>> from attitude.photometry import read_lightcurve
    >>> text = "jd,mag,mag_err\\n2460000.5,14.21,0.01\\n2460000.51,14.35,0.01\\n"
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     path = os.path.join(tmp, "lc.csv")
    ...     with open(path, "w") as f:
    ...         _ = f.write(text)
    ...     lc = read_lightcurve(path)
    >>> lc.time.round(3).tolist(), lc.epoch.isot
    ([0.0, 864.0], '2023-02-25T00:00:00.000')
    """
    path = Path(path)
    kind = (format or "").lower() or _sniff(path)
    if geometry is not None and kind == "alcdef":
        options = {"light_time": "observer"} | options
    if kind == "netcdf":
        lc = Lightcurve.from_netcdf(path)
    elif kind == "csv":
        lc = read_csv(path, **options)
    elif kind == "alcdef":
        lc = read_alcdef(path, **options)
    else:
        lc = None
    if lc is not None:
        return lc if geometry is None else observations_of(
            lc, geometry, path=path, sigma=sigma, calibrated=calibrated)
    raise LightcurveFormatError(f"unknown lightcurve format {format!r}: use 'alcdef', 'csv' "
                                "or 'netcdf'", path=str(path))


def _sniff(path: Path) -> str:
    suffix = path.suffix.lower()
    if suffix in (".nc", ".nc4", ".netcdf"):
        return "netcdf"
    if suffix == ".csv":
        return "csv"
    text = _read_text(path)
    if any(line.strip().upper() == "STARTMETADATA" for line in text.splitlines()[:200]):
        return "alcdef"
    raise LightcurveFormatError("cannot tell the format: no STARTMETADATA line (ALCDEF) and "
                                "not a .csv or .nc file; pass format=", path=str(path))


def _read_text(path: Path) -> str:
    try:
        return path.read_text(encoding="utf-8", errors="replace")
    except OSError as exc:
        raise LightcurveFormatError(f"cannot read the file ({exc.strerror or exc})",
                                    path=str(path)) from None


def read_alcdef(path, *, reduce: bool = False, light_time: bool = True) -> Lightcurve:
    """Read an ALCDEF file (all its sessions) into the lightcurve dataset.

    Parameters
    ----------
    path : str or path-like
    reduce : bool, optional
        Add ``UCORMAG`` to the magnitudes of sessions with ``REDUCEDMAGS=NONE``.
    light_time : bool or "observer", optional
        Subtract ``LTCDAYS`` from the JDs of sessions with ``LTCAPP=NONE`` (times at
        the asteroid).  Default True.  ``"observer"``: the times at the observer
        instead (``LTCDAYS`` added back to sessions already corrected), for a
        geometry that corrects the light time itself (:func:`read_lightcurve` with
        ``geometry=``).

    Returns
    -------
    Lightcurve
        Attributes ``object`` (number and name), ``sessions`` (one line of metadata per
        session), ``light_time_uncorrected_sessions``.

    Raises
    ------
    LightcurveFormatError
        Naming the line: a data line outside a block or with a bad field, a metadata
        line without ``=``, an unknown delimiter, a block without ``ENDMETADATA`` or
        ``ENDDATA``, a file without data.

    Examples
    --------
    >>> import os, tempfile
    >>> from attitude.photometry.readers import read_alcdef
    >>> text = '''STARTMETADATA
    ... OBJECTNUMBER=99942
    ... OBJECTNAME=Apophis
    ... DELIMITER=PIPE
    ... LTCAPP=NONE
    ... LTCDAYS=0.001
    ... ENDMETADATA
    ... DATA=2456318.5|15.51|0.02
    ... DATA=2456318.6|15.62|0.02
    ... ENDDATA
    ... '''
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     path = os.path.join(tmp, "apophis.alcdef")
    ...     with open(path, "w") as f:
    ...         _ = f.write(text)
    ...     lc = read_alcdef(path)
    >>> lc.dataset.attrs["object"], lc.time.round(1).tolist()
    ('99942 Apophis', [0.0, 8640.0])
    """
    path = Path(path)
    where = str(path)
    jd, mag, err, session = [], [], [], []
    sessions, uncorrected, objects = [], [], []
    state, meta, block_start, delim = "outside", {}, 0, "|"
    block_jd = []

    def fail(lineno, message):
        return LightcurveFormatError(message, key=f"line {lineno}", path=where)

    lines = _read_text(path).splitlines()
    for lineno, raw in enumerate(lines, start=1):
        line = raw.strip()
        if not line:
            continue
        upper = line.upper()
        if upper == "STARTMETADATA":
            if state != "outside":
                raise fail(lineno, f"STARTMETADATA inside the block started on line "
                                   f"{block_start}: close it with ENDMETADATA/ENDDATA first")
            state, meta, block_start, block_jd = "metadata", {}, lineno, []
        elif upper == "ENDMETADATA":
            if state != "metadata":
                raise fail(lineno, "ENDMETADATA without STARTMETADATA")
            name = meta.get("DELIMITER", "PIPE").upper()
            if name not in _DELIMITERS:
                raise fail(lineno, f"DELIMITER={meta['DELIMITER']} is unknown: the standard "
                                   "allows PIPE or TAB")
            delim = _DELIMITERS[name]
            state = "data"
        elif upper == "ENDDATA":
            if state != "data":
                raise fail(lineno, "ENDDATA without a metadata block before it")
            if not block_jd:
                raise fail(lineno, f"the session started on line {block_start} has no "
                                   "DATA lines")
            k = len(sessions)
            ucor, ltc = _session_corrections(meta, lineno, fail)
            applied = meta.get("LTCAPP", "NONE").upper() not in ("NONE", "")
            shift = 0.0
            if light_time == "observer":
                if applied and ltc is None:
                    raise fail(lineno, f"the session started on line {block_start} says "
                                       f"LTCAPP={meta['LTCAPP']} without LTCDAYS: its times "
                                       "at the observer cannot be recovered for the "
                                       "geometry; give LTCDAYS (or LTCAPP=NONE)")
                shift = -ltc if applied else 0.0
            elif light_time and not applied:
                if ltc is not None:
                    shift = ltc
                else:
                    uncorrected.append(k)
            elif not applied:
                uncorrected.append(k)
            add = ucor if (reduce and ucor is not None
                           and meta.get("REDUCEDMAGS", "NONE").upper() == "NONE") else 0.0
            for j, m, e in block_jd:
                jd.append(j - shift)
                mag.append(m + add)
                err.append(e)
                session.append(k)
            sessions.append(_session_line(k, meta, block_start))
            obj = " ".join(x for x in (meta.get("OBJECTNUMBER", ""),
                                       meta.get("OBJECTNAME", "")) if x).strip()
            if obj and obj not in objects:
                objects.append(obj)
            state = "outside"
        elif upper.startswith("DATA="):
            if state != "data":
                raise fail(lineno, "DATA line outside a session: it must follow ENDMETADATA")
            fields = line[5:].split(delim)
            if len(fields) < 2 or len(fields) > 4:
                raise fail(lineno, f"expected DATA=JD{delim}MAG[{delim}MAGERR[{delim}AIRMASS]]"
                                   f", got {line!r}")
            try:
                values = [float(x) for x in fields[:3]]
            except ValueError:
                raise fail(lineno, f"not a number in {line!r}") from None
            if not np.isfinite(values).all():
                raise fail(lineno, f"non-finite value in {line!r}")
            problem = _date_problem(values[0], "jd")
            if problem:
                raise fail(lineno, problem)
            if len(values) == 2 or values[2] <= 0:
                values = values[:2] + [np.nan]
            block_jd.append(tuple(values))
        elif state == "metadata":
            if "=" not in line:
                raise fail(lineno, f"expected KEY=VALUE in the metadata block, got {line!r}")
            key, value = line.split("=", 1)
            meta[key.strip().upper()] = value.strip()
        elif state == "data":
            raise fail(lineno, f"expected DATA=... or ENDDATA, got {line!r}")
        else:
            raise fail(lineno, f"text outside a session block: {line!r} (a session starts "
                               "with STARTMETADATA)")
    if state != "outside":
        raise LightcurveFormatError(
            f"the session started on line {block_start} is not closed "
            f"({'ENDMETADATA' if state == 'metadata' else 'ENDDATA'} missing at the end of "
            "the file)", key=f"line {len(lines)}", path=where)
    if not jd:
        raise LightcurveFormatError("no session (STARTMETADATA ... ENDDATA) in the file",
                                    path=where)
    return _build(np.array(jd), np.array(mag), np.array(err), np.array(session),
                  title=f"lightcurve of {', '.join(objects) or 'unknown object'}",
                  source=f"ALCDEF file {path.name}",
                  attrs={"object": ", ".join(objects), "sessions": "\n".join(sessions),
                         "light_time_uncorrected_sessions": np.array(uncorrected, dtype=int),
                         "format": "ALCDEF"})


def _session_corrections(meta, lineno, fail):
    out = []
    for key in ("UCORMAG", "LTCDAYS"):
        value = meta.get(key)
        if value in (None, "") or value.upper() == "NONE":
            out.append(None)
            continue
        try:
            out.append(float(value))
        except ValueError:
            raise fail(lineno, f"{key}={value} in this session's metadata is not a number") \
                from None
    return tuple(out)


def _session_line(k, meta, block_start):
    keys = ("SESSIONDATE", "SESSIONTIME", "FILTER", "MAGBAND", "DIFFERMAGS", "LTCAPP",
            "REDUCEDMAGS", "PHASE", "MPCCODE")
    items = "; ".join(f"{key}={meta[key]}" for key in keys if key in meta)
    return f"session {k} (line {block_start}): {items}"


def read_csv(path, *, time_scale: str = "utc") -> Lightcurve:
    """Read a CSV lightcurve (header row, see the module notes).

    Parameters
    ----------
    path : str or path-like
    time_scale : str, optional
        The scale of the times (default ``"utc"``).

    Raises
    ------
    LightcurveFormatError
        Naming the line: no header, no time or magnitude column, a bad value, a row
        with the wrong number of fields.

    Examples
    --------
    >>> import os, tempfile
    >>> from attitude.photometry.readers import read_csv
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     path = os.path.join(tmp, "lc.csv")
    ...     with open(path, "w") as f:
    ...         _ = f.write("mjd,mag,session\\n60000.0,12.0,1\\n60000.5,12.4,2\\n")
    ...     lc = read_csv(path)
    >>> lc.dataset.session.values.tolist(), lc.time.tolist()   # the file's session numbers
    ([1, 2], [0.0, 43200.0])
    """
    path = Path(path)
    where = str(path)
    rows = [(k, line) for k, line in enumerate(_read_text(path).splitlines(), start=1)
            if line.strip() and not line.lstrip().startswith("#")]
    if not rows:
        raise LightcurveFormatError("empty file: expected a header row and data rows",
                                    path=where)
    header_line, header = rows[0]
    names = [c.strip().lower() for c in next(csv.reader([header]))]

    def column(options, required, what):
        for name in options:
            if name in names:
                return names.index(name), name
        if required:
            raise LightcurveFormatError(
                f"no {what} column in the header {names}: name it one of {list(options)}",
                key=f"line {header_line}", path=where)
        return None, None

    i_time, time_kind = column(("jd", "mjd", "time"), True, "time")
    i_mag, _ = column(("mag", "magnitude"), True, "magnitude")
    i_err, _ = column(("mag_err", "magerr", "magnitude_error", "sigma"), False, "")
    i_ses, _ = column(("session",), False, "")
    times, mag, err, ses = [], [], [], []
    for lineno, line in rows[1:]:
        fields = next(csv.reader([line]))
        if len(fields) != len(names):
            raise LightcurveFormatError(f"expected {len(names)} fields ({', '.join(names)}), "
                                        f"got {len(fields)}: {line!r}", key=f"line {lineno}",
                                        path=where)
        def fail(message, lineno=lineno):
            return LightcurveFormatError(message, key=f"line {lineno}", path=where)

        try:
            times.append(fields[i_time].strip() if time_kind == "time"
                         else float(fields[i_time]))
            mag.append(float(fields[i_mag]))
            err.append(float(fields[i_err]) if i_err is not None else np.nan)
            ses.append(fields[i_ses].strip() if i_ses is not None else "0")
        except ValueError:
            raise fail(f"not a number in {line!r}") from None
        if not (np.isfinite(mag[-1]) and (time_kind == "time" or np.isfinite(times[-1]))):
            raise fail(f"non-finite value in {line!r}")
        problem = None if time_kind == "time" else _date_problem(times[-1], time_kind)
        if problem:
            raise fail(problem)
    if not mag:
        raise LightcurveFormatError("no data rows after the header", path=where)
    try:
        with warnings.catch_warnings():     # a year outside UTC: refused just below
            warnings.filterwarnings("ignore", message="ERFA function")
            when = Time(times, format="isot" if time_kind == "time" else time_kind,
                        scale=time_scale)
    except ValueError as exc:
        raise LightcurveFormatError(f"cannot read the {time_kind} column ({exc})",
                                    path=where) from None
    if time_kind == "time":
        for (lineno, _), text, jd in zip(rows[1:], times, when.jd1 + when.jd2):
            problem = _date_problem(jd, "time", text)
            if problem:
                raise LightcurveFormatError(problem, key=f"line {lineno}", path=where)
    try:                      # the file's session numbers, kept (1, 2, 3 stay 1, 2, 3)
        session = np.array([int(s) for s in ses])
    except ValueError:        # labels that are not integers: numbered in sorted order
        _, session = np.unique(np.array(ses), return_inverse=True)
    return _build(when, np.array(mag), np.array(err), session,
                  title="observed lightcurve", source=f"CSV file {path.name}",
                  attrs={"format": "CSV"})


def _date_problem(value: float, kind: str, text: str = "") -> str | None:
    """Why ``value`` (of the column ``kind``: ``jd``, ``mjd``, or ``time`` given as a JD,
    written ``text``) is not a date within :data:`_JD_RANGE`; None if it is."""
    lo, hi = _JD_RANGE
    if lo <= value + _JD_OFFSET.get(kind, 0.0) <= hi:
        return None
    fix = {"jd": "give the Julian date (UTC), e.g. 2460000.5",
           "mjd": "give the modified Julian date (UTC), e.g. 60000.0",
           "time": "give an ISO 8601 date (UTC), e.g. 2023-02-25T00:00:00"}[kind]
    shown = f"{kind} {text!r}" if kind == "time" else f"{kind} {value!r}"
    return f"{shown} is not a date between 1582 and 3000: {fix}"


def _build(when, mag, err, session, *, title, source, attrs):
    """Sorted by time; ``time`` from astropy's two-double differences (no JD rounding)."""
    if not isinstance(when, Time):
        when = Time(np.asarray(when, dtype=float), format="jd", scale="utc")
    order = np.argsort(when.jd, kind="stable")
    when, mag, err, session = when[order], mag[order], err[order], session[order]
    epoch = when[0]
    time = (when - epoch).sec
    return Lightcurve.from_arrays(time, magnitude=mag, magnitude_error=err,
                                  session=session, epoch=epoch, title=title, source=source,
                                  attrs=attrs)


def observations_of(lc: Lightcurve, geometry, *, path=None, sigma=None,
                    calibrated: bool = False) -> list[LightcurveObservations]:
    """A read lightcurve with its geometry: one observations object per session.

    Parameters
    ----------
    lc : Lightcurve
        Observed magnitudes with ``magnitude_error`` and ``session`` (as read), the
        times those of the observer.
    geometry : OrbitGeometry, Geometry or callable
        As in :func:`read_lightcurve`.
    path : path, optional
        The file, for the names and the errors.
    sigma : float, optional
        The 1-sigma (mag) of points without one.
    calibrated : bool
        Magnitudes reduced to unit distances (default False: relative).

    Raises
    ------
    LightcurveFormatError
        Naming the file and the session's line: a point without an uncertainty and no
        ``sigma``, a geometry of another length than the file.

    Examples
    --------
    >>> import numpy as np
    >>> from astropy.time import Time
    >>> from attitude.photometry import Geometry, Lightcurve
    >>> lc = Lightcurve.from_arrays([0.0, 60.0, 86400.0], magnitude=[15.0, 15.1, 15.3],
    ...                             magnitude_error=0.01, session=[0, 0, 1],
    ...                             epoch=Time("2026-01-01", scale="utc"))
    >>> obs = observations_of(lc, Geometry(sun=[1, 0, 0], observer=[1, 0.2, 0]))
    >>> [len(o) for o in obs], obs[1].time.round(3).tolist()     # TDB seconds at the body
    ([2, 1], [86400.0])
    """
    where = None if path is None else str(path)
    label = Path(path).name if path is not None else "lightcurve"
    ds = lc.dataset
    n = len(lc)
    times = lc.epoch + TimeDelta(lc.time, format="sec")
    err = np.asarray(ds["magnitude_error"].values, dtype=float) \
        if "magnitude_error" in ds else np.full(n, np.nan)
    session = np.asarray(ds["session"].values) if "session" in ds else np.zeros(n, int)
    lines = _session_lines(ds.attrs.get("sessions", ""))
    missing = ~(np.isfinite(err) & (err > 0))
    if missing.any():
        if sigma is None:
            k = session[np.flatnonzero(missing)[0]]
            raise LightcurveFormatError(
                f"{int(missing.sum())} point(s) without a magnitude uncertainty, the first "
                f"in session {k}: give them one (MAGERR, a mag_err column) or sigma= (the "
                "scenario's [inversion] sigma)", key=_where(k, lines), path=where)
        err = np.where(missing, float(sigma), err)
    if isinstance(geometry, OrbitGeometry):
        geom = geometry.at(times)
    elif isinstance(geometry, Geometry):
        geom = geometry
    elif callable(geometry):
        geom = geometry(times)
    else:
        raise LightcurveFormatError(f"geometry must be Geometry.from_orbit(...), a Geometry "
                                    f"or a function of the epochs, got {geometry!r}",
                                    path=where, key="geometry")
    if geom.n_time not in (None, n):
        raise LightcurveFormatError(f"the geometry has {geom.n_time} directions for the "
                                    f"file's {n} points: give one per point (or a "
                                    "constant one)", path=where, key="geometry")
    epoch = times[0].tdb
    out = []
    for k in np.unique(session):
        pick = np.flatnonzero(session == k)
        name = f"{label}: session {k}" + (f" (line {lines[k]})" if k in lines else "")
        out.append(LightcurveObservations(times[pick], lc.magnitude[pick], err[pick],
                                          geom.take(pick), epoch=epoch,
                                          calibrated=calibrated, name=name))
    return out


def _session_lines(text: str) -> dict:
    """``{session: line}`` from the ``sessions`` attribute of an ALCDEF read."""
    return {int(k): int(line) for k, line in
            re.findall(r"^session (\d+) \(line (\d+)\)", text, flags=re.MULTILINE)}


def _where(k, lines) -> str:
    return f"line {lines[k]}" if k in lines else f"session {k}"

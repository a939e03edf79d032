"""Reading a CCSDS AEM into an :class:`~attitude.Ephemeris`: :func:`read_aem` (KVN or XML,
version 1.0 or 2.0, detected from the content), the selection and concatenation of the
segments, their time order, and the attributes that keep the AEM header and metadata.
Import it from :mod:`attitude.formats.aem` (the module notes there give the conventions).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from os import PathLike
from pathlib import Path

import numpy as np
from astropy.time import Time, TimeDelta

from ..foundations.errors import EphemerisFormatError
from ..model.body import RigidBody
from ..model.ephemeris import Ephemeris
from .aem_kinematics import estimate_omega, rotation_and_rates
from .aem_kvn import parse_kvn
from .aem_message import Epochs, Message, Segment, error_at, parse_times, warn_at
from .aem_xml import parse_xml

__all__ = ["read_aem"]


# --- message -> states -------------------------------------------------------------------
def _load(path: Path) -> Message:
    where = str(path)
    if not path.is_file():
        raise EphemerisFormatError(f"{path}: no such file")
    data = path.read_bytes()
    if data.startswith(b"\xef\xbb\xbf"):
        data = data[3:]
    if data.lstrip()[:1] == b"<":
        return parse_xml(data, where)
    try:
        text = data.decode("ascii")
    except UnicodeDecodeError as exc:
        line = data[:exc.start].count(b"\n") + 1
        raise error_at(where, line, "KVN", "non-ASCII character: a KVN AEM holds printable "
                     "ASCII only (6.6.3)") from None
    return parse_kvn(text, where)


# --- reading ------------------------------------------------------------------------
def read_aem(path: str | PathLike, *, body: RigidBody | None = None,
             segment: int | Sequence[int] | None = None,
             angular_velocity: str = "file") -> Ephemeris:
    """Read a CCSDS Attitude Ephemeris Message (KVN or XML, version 1.0 or 2.0).

    Parameters
    ----------
    path : str or path-like
        The AEM; KVN or XML is detected from the content, not the suffix.
    body : RigidBody, optional
        The body's mass properties (an AEM has none).  Without it the ephemeris carries
        ``inertia_known = 0``, no ``inertia`` attribute, and NaN angular momentum and
        kinetic energy.
    segment : int or sequence of int, optional
        Segment(s) to read (0-based, in file order).  By default all segments are
        concatenated; they must share frames and time system, and time must not go
        backwards from one to the next.  The ``aem_segment`` variable records the
        segment of each sample (do not interpolate across a change, 4.2.4.8.3).
    angular_velocity : {"file", "estimate"}
        Where the file gives no rates (``QUATERNION``, ``EULER_ANGLE``, the ambiguous
        version-1 ``.../RATE`` types): NaN (``"file"``), or estimated from neighbouring
        attitudes within each segment (``"estimate"``, second order in the step).

    Returns
    -------
    Ephemeris
        Quaternions body -> inertial (scalar last), body rates in rad/s, ``time`` in
        seconds since the first epoch, ``time_scale`` from ``TIME_SYSTEM`` and ``frame``
        the inertial frame.  Attributes keep the AEM metadata (``aem_object_name``,
        ``aem_object_id``, ``body_frame``, ``aem_time_system``, ...).

    Raises
    ------
    EphemerisFormatError
        For a malformed file; the message names the line and the keyword.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from attitude.formats.aem import read_aem
    >>> text = '''CCSDS_AEM_VERS = 2.0
    ... CREATION_DATE = 2024-01-01T00:00:00
    ... ORIGINATOR = EXAMPLE
    ... META_START
    ... OBJECT_NAME = SAT
    ... OBJECT_ID = 2024-001A
    ... REF_FRAME_A = EME2000
    ... REF_FRAME_B = SC_BODY_1
    ... TIME_SYSTEM = UTC
    ... START_TIME = 2024-01-01T00:00:00
    ... STOP_TIME = 2024-01-01T00:01:00
    ... ATTITUDE_TYPE = QUATERNION/ANGVEL
    ... ANGVEL_FRAME = SC_BODY_1
    ... META_STOP
    ... DATA_START
    ... 2024-01-01T00:00:00 0.0 0.0 0.0 1.0 0.0 0.0 1.0
    ... 2024-01-01T00:01:00 0.0 0.0 0.5 0.8660254037844386 0.0 0.0 1.0
    ... DATA_STOP
    ... '''
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "example.aem"
    >>> _ = path.write_text(text)
    >>> eph = read_aem(path)
    >>> eph.frame, eph.time_scale, eph.time.tolist()
    ('EME2000', 'UTC', [0.0, 60.0])
    >>> eph.dataset.angular_velocity.values[0].round(6).tolist()   # rad/s
    [0.0, 0.0, 0.017453]
    """
    if angular_velocity not in ("file", "estimate"):
        raise EphemerisFormatError(
            f"angular_velocity={angular_velocity!r}: use 'file' (NaN where the file has no "
            "rates) or 'estimate' (from neighbouring attitudes)", key="angular_velocity")
    path = Path(path)
    msg = _load(path)
    chosen = [msg.segments[k] for k in _chosen_segments(msg, segment)]
    for seg in chosen[1:]:
        _check_same_frames(seg, chosen[0], msg.where)
    parts = _segment_samples(chosen, [_chosen_index(msg, seg) for seg in chosen],
                             msg.where, angular_velocity)
    ds = _aem_ephemeris(msg, chosen[0], parts, body, path.name).dataset
    ds["aem_segment"] = ("time", np.concatenate([p.index for p in parts]), {
        "long_name": "index of the CCSDS AEM segment of each sample (no interpolation "
                     "across a change of segment)", "units": "1"})
    if body is None:
        _mark_unknown_mass_properties(ds)
    return Ephemeris(ds)


def _chosen_segments(msg: Message, segment) -> list[int]:
    """Indices of the segments ``segment=`` selects (all by default)."""
    everything = list(range(len(msg.segments)))
    if segment is None:
        return everything
    wanted = [segment] if isinstance(segment, (int, np.integer)) else list(segment)
    try:
        chosen = [everything[int(k)] for k in wanted]
    except IndexError:
        raise EphemerisFormatError(
            f"{msg.where}: segment={segment!r}, but the file has {len(msg.segments)} "
            "segment(s) (numbered from 0)", key="segment") from None
    if not chosen:
        raise EphemerisFormatError(f"{msg.where}: segment=[] selects no data", key="segment")
    return chosen


def _chosen_index(msg: Message, seg: Segment) -> int:
    return next(k for k, s in enumerate(msg.segments) if s is seg)


def _check_same_frames(seg: Segment, first: Segment, where: str) -> None:
    """Segments are concatenated only when they share frames and time system."""
    spec = seg.spec
    for attr, what in (("inertial", "inertial frame"), ("body_frame", "body frame"),
                       ("time_system", "TIME_SYSTEM")):
        if getattr(spec, attr) != getattr(first.spec, attr):
            key = ("TIME_SYSTEM" if attr == "time_system" else
                   "REF_FRAME_A" if (attr == "inertial") == spec.inertial_is_a
                   else "REF_FRAME_B")
            raise error_at(where, seg.meta.line(key), key,
                         f"{what} {getattr(spec, attr)} differs from "
                         f"{getattr(first.spec, attr)} in the segment at line "
                         f"{first.meta.start}: segments are concatenated only when they "
                         "share frames and time system; read them one at a time with "
                         "segment=")


@dataclass
class _Samples:
    """The samples of one segment: seconds since the first epoch of the file, body ->
    inertial quaternions, body rates (rad/s), where the rates come from."""

    seconds: np.ndarray
    quaternion: np.ndarray
    omega: np.ndarray
    index: np.ndarray               # the segment number of each sample
    rates: str                      # "file", "estimate" or "none"
    attitude_type: str
    epoch: Time                     # the first time tag of the file (9 decimals)


def _segment_samples(segments: list[Segment], numbers: list[int], where: str,
                     angular_velocity: str) -> list[_Samples]:
    """Times, attitudes and rates of each segment, with the checks of time order within
    a segment and from one segment to the next."""
    out: list[_Samples] = []
    whole0 = frac0 = epoch = previous = None
    for seg, k in zip(segments, numbers):
        spec = seg.spec
        ep = parse_times(seg.epochs, seg.lines, spec, where)
        if whole0 is None:
            whole0, frac0 = ep.whole[0], float("0." + ep.digits[0][:9]) if ep.digits[0] else 0.0
            # the epoch: the first time tag, its fraction cut to 9 decimals
            epoch = whole0 + TimeDelta(frac0, format="sec")
        sec = ep.seconds_since(whole0, frac0)
        _check_increasing(seg, sec, where)
        if previous is not None and sec[0] < previous[0]:
            raise error_at(where, seg.lines[0], "EPOCH",
                         f"time goes backwards: this segment starts at {seg.epochs[0]}, before "
                         f"the previous one ends ({previous[1]}, line {previous[2]}); read the "
                         "segments one at a time with segment=")
        previous = (sec[-1], seg.epochs[-1], seg.lines[-1])
        _check_span(seg, ep, where)
        q, w, has_rates = rotation_and_rates(seg, where)
        if spec.attitude_type.endswith("/RATE"):
            warn_at(where, seg.meta.line("ATTITUDE_TYPE"), "ATTITUDE_TYPE",
                  f"{spec.attitude_type}: the version 1.0 rate items are ambiguous (angular "
                  "velocity or Euler angle rates) and are not used")
        rates = "file" if has_rates else "estimate" if angular_velocity == "estimate" else "none"
        out.append(_Samples(sec, q, w, np.full(len(sec), k, dtype=np.int32), rates,
                            spec.attitude_type, epoch))
    for part in out:
        if part.rates == "estimate":
            part.omega = estimate_omega(part.quaternion, part.seconds)
    return out


def _check_increasing(seg: Segment, sec: np.ndarray, where: str) -> None:
    dt = np.diff(sec)
    back = np.flatnonzero(~(dt > 0))
    if back.size:
        i = back[0] + 1
        what = "repeats" if dt[i - 1] == 0 else "goes back from"
        raise error_at(where, seg.lines[i], "EPOCH",
                     f"time {what} the previous data line (line {seg.lines[i - 1]}, "
                     f"{seg.epochs[i - 1]} -> {seg.epochs[i]}): epochs must increase "
                     "within a segment (4.2.4.8.1)")


_RATE_SOURCES = {"file": "from the AEM data lines",
                 "estimate": "estimated from neighbouring attitudes (finite differences)",
                 "none": "not in the AEM (NaN)"}


def _aem_attrs(msg: Message, first: Segment, parts: list[_Samples],
               body: RigidBody | None) -> dict:
    """Global attributes that keep the AEM header and metadata."""
    attrs = {
        "aem_version": msg.version,
        "aem_form": msg.form,
        "aem_object_name": first.meta.get("OBJECT_NAME"),
        "aem_object_id": first.meta.get("OBJECT_ID"),
        "aem_originator": msg.header.get("ORIGINATOR"),
        "aem_creation_date": msg.header.get("CREATION_DATE"),
        "aem_time_system": first.spec.time_system,
        "aem_attitude_type": ", ".join(dict.fromkeys(p.attitude_type for p in parts)),
        "body_frame": first.spec.body_frame,
        "inertia_known": int(body is not None),
        "angular_velocity_source": "; ".join(
            _RATE_SOURCES[s] for s in dict.fromkeys(p.rates for p in parts)),
    }
    if first.meta.get("CENTER_NAME"):
        attrs["aem_center_name"] = first.meta.get("CENTER_NAME")
    if msg.header.get("MESSAGE_ID"):
        attrs["aem_message_id"] = msg.header.get("MESSAGE_ID")
    comments = msg.header.comments + first.meta.comments
    if comments:
        attrs["comment"] = "\n".join(c.strip() for c in comments)
    return attrs


def _aem_ephemeris(msg: Message, first: Segment, parts: list[_Samples],
                   body: RigidBody | None, file_name: str) -> Ephemeris:
    attrs = _aem_attrs(msg, first, parts, body)
    name = first.meta.get("OBJECT_NAME")
    return Ephemeris.from_arrays(
        np.concatenate([p.seconds for p in parts]),
        np.concatenate([p.quaternion for p in parts]),
        np.concatenate([p.omega for p in parts]),
        body=body if body is not None else _PLACEHOLDER,
        epoch=parts[0].epoch, frame=first.spec.inertial,
        title=f"attitude ephemeris of {name} (CCSDS AEM)",
        source=(f"CCSDS AEM {msg.version} ({msg.form}) {file_name}, ORIGINATOR "
                f"{attrs['aem_originator']}, CREATION_DATE {attrs['aem_creation_date']}"),
        extra_attrs=attrs)


def _mark_unknown_mass_properties(ds) -> None:
    """No body given: no inertia attributes, NaN angular momentum and energy."""
    for key in ("inertia", "principal_moments"):
        ds.attrs.pop(key, None)
    note = "unknown: the AEM carries no mass properties (read_aem(..., body=...))"
    for name in ("angular_momentum", "kinetic_energy"):
        ds[name].values[:] = np.nan
        ds[name].attrs["comment"] = note


_PLACEHOLDER = RigidBody.from_principal_moments([1.0, 1.0, 1.0])


def _check_span(seg: Segment, ep: Epochs, where: str) -> None:
    """Warn when data fall outside START_TIME .. STOP_TIME (by more than 1 microsecond)."""
    for key, idx, sign in (("START_TIME", 0, 1.0), ("STOP_TIME", -1, -1.0)):
        bound = parse_times([seg.meta.get(key)], [seg.meta.line(key)], seg.spec, where, key)
        bound_minus_sample = bound.seconds_since(ep.whole[idx], ep.frac[idx])[0]
        gap = -sign * bound_minus_sample          # >= 0 when the bound covers the data
        if gap < -1e-6:
            warn_at(where, seg.meta.line(key), key,
                  f"{seg.meta.get(key)} does not cover the data (epoch {seg.epochs[idx]} at "
                  f"line {seg.lines[idx]})")



"""Writing an :class:`~attitude.Ephemeris` as a CCSDS AEM version 2.0: :func:`write_aem`
(KVN or XML) and the checks of its options (frames, time system, attitude type, text
values).  Import it from :mod:`attitude.formats.aem` (the module notes there give the
conventions).
"""

from __future__ import annotations

from collections.abc import Sequence
from datetime import UTC, datetime
from os import PathLike
from pathlib import Path

import numpy as np
from astropy.time import Time, TimeDelta

from ..foundations.errors import EphemerisFormatError
from ..model.ephemeris import Ephemeris, write_atomically
from ..model.state import INERTIAL_FRAMES, format_epoch
from .aem_kinematics import state_values
from .aem_kvn import write_kvn
from .aem_message import (
    AEM_TIME_SYSTEMS,
    AEM_WRITE_TYPES,
    INERTIAL_LABELS,
    Output,
    euler_sequence,
    norm_text,
)
from .aem_xml import write_xml

__all__ = ["write_aem"]

_SYNONYMS = ({"J2000", "EME2000"},)


def _text(value, keyword: str) -> str:
    """A KVN/XML text value: printable ASCII, one line, all upper case unless all lower
    case (6.8.6)."""
    s = " ".join(str(value).split())
    if not s:
        raise EphemerisFormatError(f"{keyword}: an empty value is not allowed")
    if not s.isascii() or not s.isprintable():
        raise EphemerisFormatError(f"{keyword} = {s!r}: only printable ASCII is allowed")
    if len(s) > 200:
        raise EphemerisFormatError(f"{keyword} = {s[:40]!r}...: longer than 200 characters")
    return s if s.islower() else s.upper()


def _write_form(path: Path, form: str | None) -> str:
    if form is None:
        suffix = path.suffix.lower()
        if suffix == ".xml":
            return "xml"
        if suffix in (".aem", ".kvn", ".txt"):
            return "kvn"
        raise EphemerisFormatError(
            f"{path}: cannot tell the AEM form from the suffix {suffix!r}: use .aem (KVN) or "
            ".xml, or pass form='kvn' or form='xml'")
    form = form.lower()
    if form not in ("kvn", "xml"):
        raise EphemerisFormatError(f"form={form!r}: use 'kvn' or 'xml'")
    return form


def _frames(eph: Ephemeris, ref_frame_a, ref_frame_b) -> tuple[str, str]:
    label = eph.frame.strip().upper()
    frame_a = label if ref_frame_a is None else norm_text(_text(ref_frame_a, "REF_FRAME_A"))
    if frame_a not in INERTIAL_LABELS:
        raise EphemerisFormatError(
            f"REF_FRAME_A = {frame_a}: attitude writes the rotation from the inertial frame "
            f"(REF_FRAME_A) to the body frame (REF_FRAME_B); REF_FRAME_A must be one of "
            f"{', '.join(INERTIAL_FRAMES)}")
    if frame_a != label and label != "INERTIAL" and not any(
            {frame_a, label} <= s for s in _SYNONYMS):
        raise EphemerisFormatError(
            f"REF_FRAME_A = {frame_a} would relabel a {label} ephemeris without rotating it; "
            "attitude never converts frames silently (only the generic label INERTIAL can be "
            "renamed, and J2000 <-> EME2000)")
    default_b = eph.dataset.attrs.get("body_frame", "SC_BODY_1")
    frame_b = norm_text(_text(ref_frame_b if ref_frame_b is not None else default_b,
                               "REF_FRAME_B"))
    if frame_b in INERTIAL_LABELS:
        raise EphemerisFormatError(
            f"REF_FRAME_B = {frame_b}: the body frame must not be an inertial frame label "
            "(use SC_BODY_1, INSTRUMENT_A, ...)")
    return frame_a, frame_b


def _write_times(eph: Ephemeris, time_system: str | None) -> tuple[str, Time]:
    """The TIME_SYSTEM to write and the sample epochs as a Time whose calendar strings
    are the epochs of that system."""
    scale = eph.time_scale.lower()
    if time_system is None:
        prior = str(eph.dataset.attrs.get("aem_time_system", ""))
        ok = AEM_TIME_SYSTEMS.get(prior, ("",))[0] == scale
        time_system = prior if ok else scale.upper()
    ts = norm_text(str(time_system))
    if ts not in AEM_TIME_SYSTEMS:
        raise EphemerisFormatError(
            f"TIME_SYSTEM = {time_system!r}: use one of {', '.join(AEM_TIME_SYSTEMS)}")
    target, offset = AEM_TIME_SYSTEMS[ts]
    times = eph.times
    if target != scale:
        if "ut1" in (target, scale):
            raise EphemerisFormatError(
                f"TIME_SYSTEM = {ts}: converting {scale.upper()} to {target.upper()} needs "
                "Earth orientation data (UT1 - UTC); keep the ephemeris time scale")
        times = getattr(times, target)
    if offset:
        times = times - TimeDelta(offset, format="sec")
    return ts, times


def write_aem(ephemeris: Ephemeris, path: str | PathLike, *, form: str | None = None,
              attitude_type: str | None = None, euler_rot_seq: str = "ZXZ",
              angvel_frame: str = "REF_FRAME_B", object_name: str | None = None,
              object_id: str | None = None, center_name: str | None = None,
              ref_frame_a: str | None = None, ref_frame_b: str | None = None,
              originator: str = "attitude", message_id: str | None = None,
              time_system: str | None = None, comments: Sequence[str] = (),
              interpolation_method: str | None = None,
              interpolation_degree: int | None = None) -> Path:
    """Write an ephemeris as a CCSDS AEM version 2.0 (KVN or XML), atomically.

    The quaternion written is the rotation from ``REF_FRAME_A`` (the inertial frame)
    to ``REF_FRAME_B`` (the body frame), scalar ``QC`` last: the same four numbers as
    our body -> inertial quaternion (see the module notes).

    Parameters
    ----------
    ephemeris : Ephemeris
        A single-body ephemeris.  An ``aem_segment`` variable (from :func:`read_aem`)
        splits the output into the same segments.
    path : str or path-like
        Output file; replaced atomically.
    form : {"kvn", "xml"}, optional
        Default from the suffix: ``.xml`` -> XML, ``.aem`` (or ``.kvn``, ``.txt``) -> KVN.
    attitude_type : str, optional
        One of :data:`AEM_WRITE_TYPES`.  Default ``QUATERNION/ANGVEL``, or ``QUATERNION``
        when the ephemeris has no angular velocity (NaN).
    euler_rot_seq : str
        Rotation sequence for the Euler types (``ZXZ``, ``XYZ``, ...; ``313`` accepted).
    angvel_frame : str
        Frame of the angular velocity components: ``REF_FRAME_B`` (the body frame,
        default) or ``REF_FRAME_A`` (the inertial frame); the frame name is written.
    object_name, object_id, center_name : str, optional
        Default from the ephemeris attributes (``aem_object_name``, ``body_name``), else
        ``UNKNOWN``.  Mixed-case text is written in upper case (6.8.6).
    ref_frame_a : str, optional
        The inertial frame's name; default the ephemeris frame.  Only synonyms
        (J2000/EME2000) or a rename of the generic ``INERTIAL`` label are allowed.
    ref_frame_b : str, optional
        The body frame's name, default ``body_frame`` attribute or ``SC_BODY_1``.
    originator, message_id : str
        Header values.
    time_system : str, optional
        ``TIME_SYSTEM``; default the ephemeris time scale (or the ``aem_time_system``
        it was read with).  Epochs are converted with astropy (not to/from UT1).
    comments : sequence of str
        Header ``COMMENT`` lines.
    interpolation_method, interpolation_degree : optional
        Recommended interpolation (both or neither).

    Returns
    -------
    Path

    Examples
    --------
    >>> import numpy as np, tempfile, pathlib
    >>> import attitude as att
    >>> from astropy.time import Time
    >>> from attitude.formats.aem import write_aem, read_aem
    >>> body = att.RigidBody.from_principal_moments([1.0, 2.0, 3.0])
    >>> q = [[0.0, 0.0, np.sqrt(0.5), np.sqrt(0.5)]]      # body x along inertial y
    >>> w = [[0.0, 0.0, np.radians(1.0)]]                  # 1 deg/s about body z
    >>> eph = att.Ephemeris.from_arrays([0.0], q, w, body=body, frame="ICRF",
    ...                                 epoch=Time("2030-01-01T00:00:00", scale="tdb"))
    >>> out = write_aem(eph, pathlib.Path(tempfile.mkdtemp()) / "eph.aem", object_name="demo")
    >>> print(out.read_text().splitlines()[-2])
    2030-01-01T00:00:00.000000000 0.0 0.0 7.071067811865476e-01 7.071067811865476e-01 0.0 0.0 1.0
    >>> back = read_aem(out, body=body)
    >>> float(abs(back.dataset.quaternion.values - eph.dataset.quaternion.values).max())
    0.0
    """
    eph = _single_ephemeris(ephemeris)
    path = Path(path)
    form = _write_form(path, form)
    ds = eph.dataset
    q = np.asarray(ds["quaternion"].values, dtype=float)
    w = np.asarray(ds["angular_velocity"].values, dtype=float)
    kind = _write_kind(attitude_type, eph, q, w)
    seq = euler_sequence(euler_rot_seq) if kind.startswith("EULER") else None
    frame_a, frame_b = _frames(eph, ref_frame_a, ref_frame_b)
    angvel_in_a = _angvel_in_a(angvel_frame, frame_a, frame_b)
    ts, times = _write_times(eph, time_system)
    if (interpolation_method is None) != (interpolation_degree is None):
        raise EphemerisFormatError(
            "give interpolation_method and interpolation_degree together (4.2.3)")
    attrs = ds.attrs
    object_name = _text(object_name or attrs.get("aem_object_name") or attrs.get("body_name")
                        or "UNKNOWN", "OBJECT_NAME")
    object_id = _text(object_id or attrs.get("aem_object_id") or "UNKNOWN", "OBJECT_ID")
    center = center_name or attrs.get("aem_center_name")
    header = [("CREATION_DATE", datetime.now(UTC).strftime("%Y-%m-%dT%H:%M:%S")),
              ("ORIGINATOR", _text(originator, "ORIGINATOR"))]
    if message_id is not None:
        header.append(("MESSAGE_ID", _text(message_id, "MESSAGE_ID")))
    common = [("OBJECT_NAME", object_name), ("OBJECT_ID", object_id)]
    if center:
        common.append(("CENTER_NAME", _text(center, "CENTER_NAME")))
    common += [("REF_FRAME_A", frame_a), ("REF_FRAME_B", frame_b), ("TIME_SYSTEM", ts)]
    tail = [("ATTITUDE_TYPE", kind)]
    if seq:
        tail.append(("EULER_ROT_SEQ", seq))
    if kind.endswith("/ANGVEL"):
        tail.append(("ANGVEL_FRAME", frame_a if angvel_in_a else frame_b))
    if interpolation_method is not None:
        tail += [("INTERPOLATION_METHOD", _text(interpolation_method, "INTERPOLATION_METHOD")),
                 ("INTERPOLATION_DEGREE", _degree(interpolation_degree))]
    out = Output(
        kind=kind, header_comments=[_text_comment(c) for c in comments], header=header,
        provenance=(f"attitude: quaternion = rotation from REF_FRAME_A ({frame_a}) to "
                    f"REF_FRAME_B ({frame_b}), scalar QC last"),
        segments=[(common + [("START_TIME", format_epoch(times[a])),
                             ("STOP_TIME", format_epoch(times[b - 1]))] + tail, a, b)
                  for a, b in _segment_bounds(eph)],
        times=times, values=state_values(kind, q, w, seq, angvel_in_a))
    writer = write_kvn if form == "kvn" else write_xml
    return write_atomically(path, lambda tmp: writer(tmp, out))


def _degree(value) -> str:
    """INTERPOLATION_DEGREE as text: a non-negative integer."""
    try:
        degree = int(value)
    except (TypeError, ValueError):
        degree = -1
    if degree < 0 or degree != value:
        raise EphemerisFormatError(f"interpolation_degree={value!r}: give a non-negative "
                                   "integer", key="INTERPOLATION_DEGREE")
    return str(degree)


def _single_ephemeris(ephemeris) -> Ephemeris:
    """The ephemeris, if it is one body with samples."""
    if not isinstance(ephemeris, Ephemeris):
        raise EphemerisFormatError(
            f"expected an attitude.Ephemeris, got {type(ephemeris).__name__}")
    if ephemeris.is_batch:
        raise EphemerisFormatError(
            f"a batch ephemeris holds {ephemeris.dataset.sizes['body']} bodies and an AEM one "
            "object: write one at a time (eph.member(k) or eph.member(\"secondary\"); "
            "attitude convert --body NAME|INDEX)")
    if len(ephemeris) == 0:
        raise EphemerisFormatError("the ephemeris has no samples")
    return ephemeris


def _write_kind(attitude_type: str | None, eph: Ephemeris, q: np.ndarray,
                w: np.ndarray) -> str:
    """The ATTITUDE_TYPE to write, checked against the data it needs."""
    if attitude_type is None:
        kind = "QUATERNION/ANGVEL" if np.all(np.isfinite(w)) else "QUATERNION"
    else:
        kind = norm_text(attitude_type).replace("_/_", "/")
        if kind not in AEM_WRITE_TYPES:
            raise EphemerisFormatError(
                f"attitude_type={attitude_type!r}: write one of {', '.join(AEM_WRITE_TYPES)}")
    if not np.all(np.isfinite(q)):
        raise EphemerisFormatError("the ephemeris has non-finite quaternions")
    if kind not in ("QUATERNION", "EULER_ANGLE") and not np.all(np.isfinite(w)):
        i = int(np.flatnonzero(~np.all(np.isfinite(w), axis=1))[0])
        raise EphemerisFormatError(
            f"ATTITUDE_TYPE = {kind} needs the angular velocity, which is NaN at sample {i} "
            "(t = {:.9g} s): write attitude_type='QUATERNION' or 'EULER_ANGLE', or estimate "
            "the rates first".format(eph.time[i]))
    return kind


def _angvel_in_a(angvel_frame: str, frame_a: str, frame_b: str) -> bool:
    """Whether the ``angvel_frame=`` option names REF_FRAME_A (else REF_FRAME_B)."""
    which = norm_text(str(angvel_frame))
    if which in ("REF_FRAME_A", "A", frame_a):
        return True
    if which in ("REF_FRAME_B", "B", frame_b):
        return False
    raise EphemerisFormatError(
        f"angvel_frame={angvel_frame!r}: use REF_FRAME_A ({frame_a}) or REF_FRAME_B "
        f"({frame_b})")


def _segment_bounds(eph: Ephemeris) -> list[tuple[int, int]]:
    """``(start, stop)`` sample ranges of the segments: runs of equal ``aem_segment``,
    each with strictly increasing time."""
    ds = eph.dataset
    seg = (np.asarray(ds["aem_segment"].values) if "aem_segment" in ds
           else np.zeros(len(eph), dtype=int))
    cuts = np.flatnonzero(np.diff(seg) != 0) + 1
    bounds = list(zip(np.concatenate([[0], cuts]), np.concatenate([cuts, [len(eph)]])))
    for a, b in bounds:
        back = np.flatnonzero(~(np.diff(eph.time[a:b]) > 0))
        if back.size:
            raise EphemerisFormatError(
                f"time does not increase at sample {a + back[0] + 1} (t = "
                f"{eph.time[a + back[0] + 1]:.9g} s): an AEM segment needs increasing epochs")
    return bounds


def _text_comment(value) -> str:
    s = " ".join(str(value).split())
    if not s.isascii() or not s.isprintable() or len(s) > 240:
        raise EphemerisFormatError(
            f"COMMENT {s[:40]!r}: a comment is one line of printable ASCII, at most 240 "
            "characters")
    return s



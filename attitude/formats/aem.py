"""CCSDS Attitude Ephemeris Messages (AEM): read and write, KVN and XML forms.

The Attitude Ephemeris Message is the attitude-history exchange format of the CCSDS
Attitude Data Messages standard (CCSDS 504.0-B-2, January 2024, section 4; XML in
section 7).  :func:`write_aem` writes version 2.0; :func:`read_aem` reads versions 1.0
(CCSDS 504.0-B-1) and 2.0, in either form (detected from the content).

Conventions (CCSDS 504.0-B-2 annex F, and how they meet ours)
--------------------------------------------------------------
* **Quaternion.** The AEM quaternion "from frame A to frame B" is the rotation that
  carries the basis vectors of A onto those of B; the coordinates transform as
  ``X_B = M_BA X_A`` with ``M_BA`` the *transpose* of the rotation matrix of
  ``(Q1, Q2, Q3, QC)``, i.e. ``X_A = R(q) X_B`` (annex F2).  With A the inertial frame
  and B the body frame that is exactly our attitude quaternion, which maps body-frame
  vectors into the inertial frame (``v_inertial = R(q) v_body``): the components are
  written unchanged, ``Q1 Q2 Q3 QC = x y z w`` (version 2 puts the scalar ``QC`` last).
  :func:`write_aem` always writes ``REF_FRAME_A`` = the inertial frame and
  ``REF_FRAME_B`` = the body frame.  :func:`read_aem` accepts either order (it inverts
  the rotation when ``REF_FRAME_A`` is the body frame) and, for version 1 files, the
  ``QUATERNION_TYPE = FIRST | LAST`` and ``ATTITUDE_DIR = A2B | B2A`` choices.
* **Euler angles** (annex F3): three successive *intrinsic* rotations carrying A onto
  B, in the order of ``EULER_ROT_SEQ`` (``ZXZ``; version 1 spelled it ``313``), in
  degrees.  In scipy terms ``R(q) = Rotation.from_euler("ZXZ", angles, degrees=True)``
  (upper case = intrinsic).
* **Angular velocity** (annex F4): the angular velocity of B relative to A, in deg/s,
  with components in the frame named by ``ANGVEL_FRAME`` (A or B).  Ours is the body
  rate relative to inertial space in body components, rad/s: written with
  ``ANGVEL_FRAME`` = the body frame (``REF_FRAME_B``) unless asked otherwise.
  ``.../DERIVATIVE`` types carry time derivatives of the quaternion (1/s) or of the
  Euler angles (deg/s) instead, converted exactly (``q_dot = q omega / 2``).
* **Time**: ``TIME_SYSTEM`` maps to an astropy scale (:data:`AEM_TIME_SYSTEMS`); GPS,
  Galileo (GST) and BeiDou (BDT) time are stored as TAI (``TAI = GPS + 19 s``,
  ``TAI = BDT + 33 s``).  Epochs are written with 9 decimals of seconds from astropy's
  two-double representation (``epoch + TimeDelta``), so they are exact to 0.5 ns.
* **Numbers** are written with the shortest decimal that reads back to the same
  double, capped at the 16 significant digits the standard allows (6.8.4): a quaternion
  component comes back within 5e-17.

What is checked on reading (each failure raises :class:`~attitude.EphemerisFormatError`
naming the file, the line and the keyword): the version line and version (1.0 or 2.0;
version-1 keywords in a version-2 file), every mandatory header and metadata keyword,
unknown or repeated keywords, ``ATTITUDE_TYPE`` (and the keywords each type needs:
``EULER_ROT_SEQ``, ``ANGVEL_FRAME``, ``QUATERNION_TYPE``, ``ATTITUDE_DIR``),
``TIME_SYSTEM``, the frames (exactly one of ``REF_FRAME_A``/``REF_FRAME_B`` must be an
inertial frame of :data:`attitude.INERTIAL_FRAMES`), malformed epochs and numbers,
data lines with the wrong number of fields, non-finite values, quaternions whose norm
is off by more than :data:`AEM_QUATERNION_NORM_TOL`, time not increasing within a
segment or going backwards between segments, and XML units attributes that differ
from the standard's units.

An AEM carries no mass properties.  :func:`read_aem` takes the body as ``body=``;
without it the ephemeris has no ``inertia`` attribute, ``inertia_known = 0``, and its
``angular_momentum`` and ``kinetic_energy`` are NaN (unknown) rather than computed for
an invented body.
"""

from __future__ import annotations

import re
import warnings
import xml.parsers.expat
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from datetime import UTC, datetime
from os import PathLike
from pathlib import Path
from xml.sax.saxutils import escape, quoteattr

import numpy as np
from astropy.time import Time, TimeDelta
from scipy.spatial.transform import Rotation

from ..foundations import quaternion as quat
from ..foundations.errors import AttitudeWarning, EphemerisFormatError
from ..model.body import RigidBody
from ..model.ephemeris import Ephemeris, write_atomically
from ..model.state import INERTIAL_FRAMES, format_epoch

__all__ = [
    "read_aem",
    "write_aem",
    "convert",
    "CCSDS_AEM_VERS",
    "AEM_ATTITUDE_TYPES",
    "AEM_WRITE_TYPES",
    "AEM_TIME_SYSTEMS",
    "AEM_QUATERNION_NORM_TOL",
]

#: Version written by :func:`write_aem` (CCSDS 504.0-B-2).
CCSDS_AEM_VERS = "2.0"

#: A quaternion read from a file must have ``| |q| - 1 | <=`` this; it is then
#: normalised.  Files print quaternions with as few as 5 decimals (the standard's own
#: examples are off by up to 3.4e-6), so the test only catches corrupt or misaligned data.
AEM_QUATERNION_NORM_TOL = 1e-5

#: ``TIME_SYSTEM`` -> (astropy scale, seconds added to a file time to get that scale).
#: Other SANA time systems (MET, MRT, SCLK, GMST, ...) need mission data and are refused.
AEM_TIME_SYSTEMS = {
    "UTC": ("utc", 0.0),
    "TAI": ("tai", 0.0),
    "TT": ("tt", 0.0),
    "TDB": ("tdb", 0.0),
    "TCB": ("tcb", 0.0),
    "TCG": ("tcg", 0.0),
    "UT1": ("ut1", 0.0),
    "GPS": ("tai", 19.0),      # TAI = GPS + 19 s
    "GST": ("tai", 19.0),      # Galileo system time, aligned with GPS time
    "BDT": ("tai", 33.0),      # BeiDou time: TAI = BDT + 33 s
}

_Q = ("Q1", "Q2", "Q3", "QC")
_QDOT = ("Q1_DOT", "Q2_DOT", "Q3_DOT", "QC_DOT")
_ANGVEL = ("ANGVEL_X", "ANGVEL_Y", "ANGVEL_Z")
_ANG = ("ANGLE_1", "ANGLE_2", "ANGLE_3")
_ANGDOT = ("ANGLE_1_DOT", "ANGLE_2_DOT", "ANGLE_3_DOT")
_RATE = ("RATE_1", "RATE_2", "RATE_3")          # version-1 rates (ambiguous, not used)
_SPIN = ("SPIN_ALPHA", "SPIN_DELTA", "SPIN_ANGLE", "SPIN_ANGLE_VEL")

#: ATTITUDE_TYPE -> data items after the epoch, in the order of table 4-4 (version 2;
#: version 1 with ``QUATERNION_TYPE = LAST``).
_FIELDS = {
    "QUATERNION": _Q,
    "QUATERNION/DERIVATIVE": _Q + _QDOT,
    "QUATERNION/ANGVEL": _Q + _ANGVEL,
    "QUATERNION/RATE": _Q + _RATE,
    "EULER_ANGLE": _ANG,
    "EULER_ANGLE/DERIVATIVE": _ANG + _ANGDOT,
    "EULER_ANGLE/ANGVEL": _ANG + _ANGVEL,
    "EULER_ANGLE/RATE": _ANG + _RATE,
    "SPIN": _SPIN,
    "SPIN/NUTATION": _SPIN + ("NUTATION", "NUTATION_PER", "NUTATION_PHASE"),
    "SPIN/NUTATION_MOM": _SPIN + ("MOMENTUM_ALPHA", "MOMENTUM_DELTA", "NUTATION_VEL"),
}

_TYPES = {
    "1.0": ("QUATERNION", "QUATERNION/DERIVATIVE", "QUATERNION/RATE", "EULER_ANGLE",
            "EULER_ANGLE/RATE", "SPIN", "SPIN/NUTATION"),
    "2.0": ("QUATERNION", "QUATERNION/DERIVATIVE", "QUATERNION/ANGVEL", "EULER_ANGLE",
            "EULER_ANGLE/DERIVATIVE", "EULER_ANGLE/ANGVEL", "SPIN", "SPIN/NUTATION",
            "SPIN/NUTATION_MOM"),
}

#: Attitude types :func:`read_aem` understands (version 2 names; version 1 adds
#: ``QUATERNION/RATE`` and ``EULER_ANGLE/RATE``, whose rates are not used).
AEM_ATTITUDE_TYPES = _TYPES["2.0"]

#: Attitude types :func:`write_aem` writes (exact conversions of our state).
AEM_WRITE_TYPES = ("QUATERNION", "QUATERNION/DERIVATIVE", "QUATERNION/ANGVEL",
                   "EULER_ANGLE", "EULER_ANGLE/DERIVATIVE", "EULER_ANGLE/ANGVEL")

# <attitudeState> child element of each type (table 7-5; version 1 names as well).
_XML_TAGS = {
    "QUATERNION": ("quaternionEphemeris", "quaternionState"),
    "QUATERNION/DERIVATIVE": ("quaternionDerivative",),
    "QUATERNION/ANGVEL": ("quaternionAngVel",),
    "QUATERNION/RATE": ("quaternionEulerRate",),
    "EULER_ANGLE": ("eulerAngle",),
    "EULER_ANGLE/DERIVATIVE": ("eulerAngleDerivative",),
    "EULER_ANGLE/ANGVEL": ("eulerAngleAngVel",),
    "EULER_ANGLE/RATE": ("eulerAngleRate",),
    "SPIN": ("spin",),
    "SPIN/NUTATION": ("spinNutation",),
    "SPIN/NUTATION_MOM": ("spinNutationMom",),
}

# Units of the data items (4.2.4.6); XML files may carry them as attributes.
_UNITS = {**dict.fromkeys(_QDOT, "1/s"), **dict.fromkeys(_ANG, "deg"),
          **dict.fromkeys(_ANGDOT + _ANGVEL + _RATE, "deg/s"),
          "SPIN_ALPHA": "deg", "SPIN_DELTA": "deg", "SPIN_ANGLE": "deg",
          "SPIN_ANGLE_VEL": "deg/s", "NUTATION": "deg", "NUTATION_PER": "s",
          "NUTATION_PHASE": "deg", "MOMENTUM_ALPHA": "deg", "MOMENTUM_DELTA": "deg",
          "NUTATION_VEL": "deg/s"}

_HEADER_KEYS = {
    "1.0": ("COMMENT", "CREATION_DATE", "ORIGINATOR"),
    "2.0": ("COMMENT", "CLASSIFICATION", "CREATION_DATE", "ORIGINATOR", "MESSAGE_ID"),
}
_HEADER_MANDATORY = ("CREATION_DATE", "ORIGINATOR")
_META_KEYS = {
    "1.0": ("COMMENT", "OBJECT_NAME", "OBJECT_ID", "CENTER_NAME", "REF_FRAME_A",
            "REF_FRAME_B", "ATTITUDE_DIR", "TIME_SYSTEM", "START_TIME", "USEABLE_START_TIME",
            "USEABLE_STOP_TIME", "STOP_TIME", "ATTITUDE_TYPE", "QUATERNION_TYPE",
            "EULER_ROT_SEQ", "RATE_FRAME", "INTERPOLATION_METHOD", "INTERPOLATION_DEGREE"),
    "2.0": ("COMMENT", "OBJECT_NAME", "OBJECT_ID", "CENTER_NAME", "REF_FRAME_A",
            "REF_FRAME_B", "TIME_SYSTEM", "START_TIME", "USEABLE_START_TIME",
            "USEABLE_STOP_TIME", "STOP_TIME", "ATTITUDE_TYPE", "EULER_ROT_SEQ",
            "ANGVEL_FRAME", "INTERPOLATION_METHOD", "INTERPOLATION_DEGREE"),
}
_META_MANDATORY = {
    "1.0": ("OBJECT_NAME", "OBJECT_ID", "REF_FRAME_A", "REF_FRAME_B", "ATTITUDE_DIR",
            "TIME_SYSTEM", "START_TIME", "STOP_TIME", "ATTITUDE_TYPE"),
    "2.0": ("OBJECT_NAME", "OBJECT_ID", "REF_FRAME_A", "REF_FRAME_B", "TIME_SYSTEM",
            "START_TIME", "STOP_TIME", "ATTITUDE_TYPE"),
}
_VERSION_ONLY = {  # keyword -> the only version that has it
    "ATTITUDE_DIR": "1.0", "QUATERNION_TYPE": "1.0", "RATE_FRAME": "1.0",
    "ANGVEL_FRAME": "2.0", "CLASSIFICATION": "2.0", "MESSAGE_ID": "2.0",
}

_EPOCH_RE = re.compile(
    r"^(\d{4})-(?:(\d{2})-(\d{2})|(\d{3}))T(\d{2}):(\d{2}):(\d{2}(?:\.\d*)?)Z?$")
_KVN_RE = re.compile(r"^([A-Za-z][A-Za-z0-9_]*)\s*=\s*(.*?)\s*$")
_DIGIT_AXES = {"1": "X", "2": "Y", "3": "Z"}
_AXIS = {"X": np.array([1.0, 0.0, 0.0]), "Y": np.array([0.0, 1.0, 0.0]),
         "Z": np.array([0.0, 0.0, 1.0])}
_INERTIAL = frozenset(INERTIAL_FRAMES)
_SYNONYMS = ({"J2000", "EME2000"},)
_CHUNK = 20_000                 # data lines formatted at a time when writing


# --- errors -------------------------------------------------------------------------
def _error(where: str, line: int | None, keyword: str, message: str) -> EphemerisFormatError:
    """``"<file>, line <n>: <KEYWORD>: <message>"`` in the one error shape
    (``key`` the keyword); ``path`` is the file and ``line`` its line (``keyword`` is
    ``key`` under its AEM name)."""
    loc = f"{where}, line {line}" if line else where
    err = EphemerisFormatError(message, key=keyword, path=loc or None)
    err.path, err.line, err.keyword = where or None, line, keyword
    return err


def _warn(where: str, line: int | None, keyword: str, message: str) -> None:
    loc = f"{where}, line {line}" if line else where
    warnings.warn(f"{loc}: {keyword}: {message}", AttitudeWarning, stacklevel=3)


# --- parsed message -----------------------------------------------------------------
@dataclass
class _Block:
    """Keyword = value pairs of a header or metadata block, with their line numbers."""

    where: str
    start: int
    items: dict[str, tuple[str, int]] = field(default_factory=dict)
    comments: list[str] = field(default_factory=list)
    stop: int = 0

    def add(self, key: str, value: str, line: int, allowed: Sequence[str], version: str,
            section: str) -> None:
        if key == "COMMENT":
            self.comments.append(value)
            return
        if key not in allowed:
            other = _VERSION_ONLY.get(key)
            if other and other != version:
                hint = {"1.0": "a version 2.0 file always places the scalar last and gives "
                               "the rotation from REF_FRAME_A to REF_FRAME_B; write "
                               "CCSDS_AEM_VERS = 1.0 if the file follows version 1",
                        "2.0": "write CCSDS_AEM_VERS = 2.0 if the file follows version 2"}
                raise _error(self.where, line, key,
                             f"is an AEM version {other} keyword, not allowed in a version "
                             f"{version} {section} ({hint[other]})")
            raise _error(self.where, line, key,
                         f"is not an AEM version {version} {section} keyword; allowed: "
                         f"{', '.join(k for k in allowed if k != 'COMMENT')}")
        if key in self.items:
            raise _error(self.where, line, key,
                         f"appears twice in the {section} (first at line {self.items[key][1]})")
        if not value:
            raise _error(self.where, line, key, "has no value")
        self.items[key] = (value, line)

    def get(self, key: str, default: str | None = None) -> str | None:
        return self.items[key][0] if key in self.items else default

    def line(self, key: str) -> int:
        return self.items[key][1] if key in self.items else self.start


@dataclass(frozen=True)
class _Spec:
    """Validated metadata of one segment."""

    attitude_type: str
    fields: tuple[str, ...]         # data items in the order of the KVN data line
    euler_seq: str | None           # "ZXZ" (scipy intrinsic)
    inertial: str                   # our frame label
    body_frame: str
    inertial_is_a: bool
    a2b: bool                       # the data give the rotation from A to B
    angvel_in_a: bool               # ANGVEL components in REF_FRAME_A
    time_system: str
    scale: str
    offset: float


@dataclass
class _Segment:
    meta: _Block
    spec: _Spec
    data_line: int
    lines: list[int]
    epochs: list[str]
    values: np.ndarray              # (n, len(_FIELDS[type])) in canonical order


@dataclass
class _Message:
    where: str
    form: str
    version: str
    header: _Block
    segments: list[_Segment]


def _norm_text(value: str) -> str:
    """Text value as compared: upper case, blanks and underscores equivalent (6.8.8)."""
    return re.sub(r"[\s_]+", "_", value.strip()).upper()


def _version(where: str, line: int, value: str) -> str:
    try:
        v = float(value)
    except ValueError:
        v = None
    if v == 1.0 or v == 2.0:
        return f"{v:.1f}"
    raise _error(where, line, "CCSDS_AEM_VERS",
                 f"version {value!r} is not supported: this reader handles AEM versions 1.0 "
                 "(CCSDS 504.0-B-1) and 2.0 (CCSDS 504.0-B-2)")


def _euler_seq(value: str, where: str = "", line: int | None = None) -> str:
    seq = value.strip().upper()
    if re.fullmatch(r"[123]{3}", seq):
        seq = "".join(_DIGIT_AXES[c] for c in seq)
    if not re.fullmatch(r"[XYZ]{3}", seq) or seq[0] == seq[1] or seq[1] == seq[2]:
        raise _error(where, line, "EULER_ROT_SEQ",
                     f"{value!r} is not a rotation sequence: give three axes with no axis "
                     "repeated twice in a row, such as ZXZ or XYZ (version 1: 313, 123)")
    return seq


def _spec(version: str, meta: _Block) -> _Spec:
    """Check a metadata block and work out how to read its data."""
    for key in _META_MANDATORY[version]:
        if key not in meta.items:
            raise _error(meta.where, meta.stop or meta.start, key,
                         f"mandatory keyword missing from the metadata block that starts at "
                         f"line {meta.start}")
    att_type = _attitude_type(version, meta)
    frame_a, frame_b, a_inertial = _ref_frames(meta)
    inertial, body_frame = (frame_a, frame_b) if a_inertial else (frame_b, frame_a)
    a2b, fields = _direction_and_fields(version, meta, att_type)
    euler_seq = None
    if att_type.startswith("EULER"):
        _require(meta, "EULER_ROT_SEQ", f"mandatory for ATTITUDE_TYPE = {att_type}: the "
                 "angles mean nothing without their rotation sequence")
        euler_seq = _euler_seq(meta.get("EULER_ROT_SEQ"), meta.where,
                               meta.line("EULER_ROT_SEQ"))
    angvel_in_a = att_type.endswith("/ANGVEL") and _angvel_frame_is_a(meta, att_type,
                                                                       frame_a, frame_b)
    time_system = _norm_text(meta.get("TIME_SYSTEM"))
    if time_system not in AEM_TIME_SYSTEMS:
        raise _error(meta.where, meta.line("TIME_SYSTEM"), "TIME_SYSTEM",
                     f"{meta.get('TIME_SYSTEM')!r} is not supported: use one of "
                     f"{', '.join(AEM_TIME_SYSTEMS)} (mission, spacecraft-clock and sidereal "
                     "time systems need mission data to become a time scale)")
    scale, offset = AEM_TIME_SYSTEMS[time_system]
    return _Spec(att_type, fields, euler_seq, inertial, body_frame, a_inertial, a2b,
                 angvel_in_a, time_system, scale, offset)


def _require(meta: _Block, key: str, message: str) -> None:
    """A keyword that the other keywords make mandatory."""
    if key not in meta.items:
        raise _error(meta.where, meta.stop or meta.start, key, message)


def _attitude_type(version: str, meta: _Block) -> str:
    """``ATTITUDE_TYPE``, normalised, one of the version's types."""
    raw_type = meta.get("ATTITUDE_TYPE")
    att_type = _norm_text(raw_type).replace("_/_", "/")
    if att_type in _TYPES[version]:
        return att_type
    if version == "2.0" and att_type in _TYPES["1.0"]:
        hint = (f"{att_type} is an AEM version 1.0 type (replaced in version 2.0 by "
                f"{att_type.replace('RATE', 'ANGVEL')} and .../DERIVATIVE)")
    elif version == "1.0" and att_type in _TYPES["2.0"]:
        hint = f"{att_type} exists only in AEM version 2.0"
    else:
        hint = f"use one of {', '.join(_TYPES[version])}"
    raise _error(meta.where, meta.line("ATTITUDE_TYPE"), "ATTITUDE_TYPE",
                 f"{raw_type!r} is not an AEM version {version} attitude type: {hint}")


def _ref_frames(meta: _Block) -> tuple[str, str, bool]:
    """``REF_FRAME_A``, ``REF_FRAME_B`` and whether A is the inertial one: exactly one of
    them must be an inertial frame (ours), the other is the body frame."""
    frame_a = _norm_text(meta.get("REF_FRAME_A"))
    frame_b = _norm_text(meta.get("REF_FRAME_B"))
    a_inertial, b_inertial = frame_a in _INERTIAL, frame_b in _INERTIAL
    if a_inertial == b_inertial:
        what = "both" if a_inertial else "neither"
        raise _error(meta.where, meta.line("REF_FRAME_A"), "REF_FRAME_A",
                     f"REF_FRAME_A = {frame_a} and REF_FRAME_B = {frame_b}: {what} of them is "
                     f"an inertial frame ({', '.join(INERTIAL_FRAMES)}); an attitude ephemeris "
                     "holds the rotation between an inertial frame and the body frame "
                     "(local orbital or Earth-fixed frames need an orbit or Earth model)")
    return frame_a, frame_b, a_inertial


def _direction_and_fields(version: str, meta: _Block, att_type: str
                          ) -> tuple[bool, tuple[str, ...]]:
    """Whether the data rotate A to B, and the data items in file order (version 1
    chooses both: ``ATTITUDE_DIR``, ``QUATERNION_TYPE``; version 2 fixes them)."""
    fields = _FIELDS[att_type]
    if version != "1.0":
        return True, fields
    direction = _norm_text(meta.get("ATTITUDE_DIR"))
    if direction not in ("A2B", "B2A"):
        raise _error(meta.where, meta.line("ATTITUDE_DIR"), "ATTITUDE_DIR",
                     f"{meta.get('ATTITUDE_DIR')!r} must be A2B or B2A")
    if att_type.startswith("QUATERNION"):
        _require(meta, "QUATERNION_TYPE", f"mandatory for ATTITUDE_TYPE = {att_type} in AEM "
                 "version 1.0 (FIRST or LAST: where the scalar QC stands)")
        qtype = _norm_text(meta.get("QUATERNION_TYPE"))
        if qtype not in ("FIRST", "LAST"):
            raise _error(meta.where, meta.line("QUATERNION_TYPE"), "QUATERNION_TYPE",
                         f"{meta.get('QUATERNION_TYPE')!r} must be FIRST or LAST")
        if qtype == "FIRST":
            rest = fields[4:]
            if rest == _QDOT:
                rest = ("QC_DOT", "Q1_DOT", "Q2_DOT", "Q3_DOT")
            fields = ("QC", "Q1", "Q2", "Q3") + rest
    return direction == "A2B", fields


def _angvel_frame_is_a(meta: _Block, att_type: str, frame_a: str, frame_b: str) -> bool:
    """Whether ``ANGVEL_FRAME`` names REF_FRAME_A (else REF_FRAME_B; no third frame)."""
    _require(meta, "ANGVEL_FRAME", f"mandatory for ATTITUDE_TYPE = {att_type}: the frame of "
             "the angular velocity components")
    value = _norm_text(meta.get("ANGVEL_FRAME"))
    if value in ("REF_FRAME_A", frame_a):
        return True
    if value in ("REF_FRAME_B", frame_b):
        return False
    raise _error(meta.where, meta.line("ANGVEL_FRAME"), "ANGVEL_FRAME",
                 f"{meta.get('ANGVEL_FRAME')!r} must be REF_FRAME_A ({frame_a}) or "
                 f"REF_FRAME_B ({frame_b}); components in a third frame cannot be "
                 "converted without its orientation")


# --- header and metadata blocks (both forms) -------------------------------------------
def _block(where: str, version: str, section: str, start: int,
           entries: Sequence[tuple[str, str, int]]) -> _Block:
    """A header or metadata block from its ``(keyword, value, line)`` entries: every
    keyword checked against the ``section`` of ``version``, none repeated or empty."""
    allowed = (_HEADER_KEYS if section == "header" else _META_KEYS)[version]
    block = _Block(where, start)
    for key, value, line in entries:
        block.add(key, value, line, allowed, version, section)
    return block


def _header(where: str, version: str, start: int, entries: Sequence[tuple[str, str, int]],
            *, end: int, context: str) -> _Block:
    """The message header, with its mandatory keywords (missing: an error at line
    ``end``, explained by ``context``)."""
    header = _block(where, version, "header", start, entries)
    for key in _HEADER_MANDATORY:
        if key not in header.items:
            raise _error(where, end, key, f"mandatory header keyword missing {context}")
    return header


def _metadata(where: str, version: str, start: int, entries: Sequence[tuple[str, str, int]],
              stop: int = 0) -> tuple[_Block, _Spec]:
    """A segment's metadata block and how to read its data (:func:`_spec`)."""
    meta = _block(where, version, "metadata", start, entries)
    meta.stop = stop
    return meta, _spec(version, meta)


# --- KVN ----------------------------------------------------------------------------
def _is_comment(s: str) -> bool:
    return s.startswith("COMMENT") and (len(s) == 7 or s[7].isspace())


def _kvn_pair(where: str, i: int, s: str) -> tuple[str, str]:
    """``(KEYWORD, value)`` of a KVN line (``COMMENT`` takes the rest of the line)."""
    if _is_comment(s):
        return "COMMENT", s[8:]
    m = _KVN_RE.match(s)
    if not m:
        raise _error(where, i, s.split()[0][:40],
                     "expected 'KEYWORD = value' (or a block delimiter)")
    return m.group(1).upper(), m.group(2)


def _kvn_version(first: tuple[int, str] | None, where: str) -> str:
    """The version from the first non-blank line, which must be ``CCSDS_AEM_VERS``."""
    if first is None:
        raise _error(where, None, "CCSDS_AEM_VERS", "the file is empty")
    i, s = first
    m = _KVN_RE.match(s)
    if not m or m.group(1).upper() != "CCSDS_AEM_VERS":
        other = re.match(r"CCSDS_([A-Z]{3})_VERS", s)
        found = (f"this is a CCSDS {other.group(1)} message, not an attitude ephemeris "
                 "message" if other else f"found {s[:40]!r}")
        raise _error(where, i, "CCSDS_AEM_VERS",
                     f"the first non-blank line must be 'CCSDS_AEM_VERS = 2.0': {found}")
    return _version(where, i, m.group(2))


class _KvnReader:
    """The KVN structure, line by line: header, then segments of a metadata block
    (``META_START`` ... ``META_STOP``) and a data block (``DATA_START`` ...
    ``DATA_STOP``).  ``state`` is where the reader is: ``header``, ``meta``,
    ``after_meta`` (between ``META_STOP`` and ``DATA_START``), ``data`` or ``body``
    (between segments)."""

    def __init__(self, where: str, version: str, start: int):
        self.where, self.version, self.start = where, version, start
        self.state = "header"
        self.entries: list[tuple[str, str, int]] = []   # of the open header/metadata
        self.header: _Block | None = None
        self.meta_start = self.data_start = 0
        self.meta: _Block | None = None
        self.spec: _Spec | None = None
        self.rows: list[tuple[int, list[str]]] = []
        self.segments: list[_Segment] = []

    def feed(self, i: int, s: str) -> None:
        if self.state == "data":
            self._data_line(i, s)
            return
        delimiter = {"META_START": self._meta_start, "META_STOP": self._meta_stop,
                     "DATA_START": self._data_start, "DATA_STOP": self._data_stop}.get(s)
        if delimiter is not None:
            delimiter(i)
        else:
            self._keyword(i, s)

    def _meta_start(self, i: int) -> None:
        if self.state == "header":
            self.header = _header(self.where, self.version, self.start, self.entries, end=i,
                                  context="(the header ends at this META_START)")
            self.header.stop = i
        elif self.state != "body":
            raise _error(self.where, i, "META_START",
                         f"unexpected: the metadata block that starts at line "
                         f"{self.meta_start} has no DATA_START/DATA_STOP")
        self.state, self.meta_start, self.entries = "meta", i, []

    def _meta_stop(self, i: int) -> None:
        if self.state != "meta":
            raise _error(self.where, i, "META_STOP", "without a META_START")
        self.meta, self.spec = _metadata(self.where, self.version, self.meta_start,
                                         self.entries, stop=i)
        self.state = "after_meta"

    def _data_start(self, i: int) -> None:
        if self.state != "after_meta":
            raise _error(self.where, i, "DATA_START", "must follow a metadata block "
                         "(META_START ... META_STOP)")
        self.state, self.data_start, self.rows = "data", i, []

    def _data_stop(self, i: int) -> None:
        raise _error(self.where, i, "DATA_STOP", "without a DATA_START")

    def _keyword(self, i: int, s: str) -> None:
        if self.state == "after_meta" and s[:1].isdigit():
            raise _error(self.where, i, "DATA_START", "data line without DATA_START: the "
                         "data of a segment sit between DATA_START and DATA_STOP (4.2.4.1)")
        key, value = _kvn_pair(self.where, i, s)
        if self.state in ("header", "meta"):
            self.entries.append((key, value, i))
        elif key != "COMMENT":
            expected = {"after_meta": "DATA_START", "body": "META_START"}[self.state]
            raise _error(self.where, i, key, f"unexpected here: expected {expected}")

    def _data_line(self, i: int, s: str) -> None:
        if s == "DATA_STOP":
            self.segments.append(_kvn_segment(self.where, self.meta, self.spec,
                                              self.data_start, self.rows))
            self.state = "body"
        elif _is_comment(s):
            return
        elif "=" in s or s in ("META_START", "META_STOP", "DATA_START"):
            raise _error(self.where, i, s.split("=")[0].strip(),
                         f"expected a data line or DATA_STOP: the data block opened by "
                         f"DATA_START at line {self.data_start} is not closed")
        else:
            self.rows.append((i, s.split()))

    def finish(self, n_lines: int) -> _Message:
        """The message, once every line is fed; errors for unclosed blocks."""
        where, state = self.where, self.state
        if state in ("header", "meta"):     # the keywords first: as if checked on the way
            _block(where, self.version, "header" if state == "header" else "metadata",
                   self.start, self.entries)
        if state == "data":
            raise _error(where, n_lines, "DATA_STOP",
                         f"missing at the end of the file (DATA_START at line "
                         f"{self.data_start})")
        if state in ("meta", "after_meta"):
            raise _error(where, n_lines, "DATA_START" if state == "after_meta" else
                         "META_STOP", f"missing at the end of the file (META_START at line "
                         f"{self.meta_start})")
        if not self.segments:
            raise _error(where, n_lines, "META_START", "the file has no segment "
                         "(META_START ... DATA_STOP): no attitude data")
        return _Message(where, "KVN", self.version, self.header, self.segments)


def _parse_kvn(text: str, where: str) -> _Message:
    lines = text.splitlines()
    it = ((i, s.strip()) for i, s in enumerate(lines, 1))
    it = ((i, s) for i, s in it if s)
    first = next(it, None)
    reader = _KvnReader(where, _kvn_version(first, where), first[0])
    for i, s in it:
        reader.feed(i, s)
    return reader.finish(len(lines))


def _kvn_segment(where: str, meta: _Block, spec: _Spec, data_start: int,
                 rows: list[tuple[int, list[str]]]) -> _Segment:
    if not rows:
        raise _error(where, data_start, "DATA_START", "the data block has no data lines")
    fields = spec.fields
    canonical = _FIELDS[spec.attitude_type]
    k = len(fields)
    values = np.empty((len(rows), k))
    lines, epochs = [], []
    for r, (i, tokens) in enumerate(rows):
        if len(tokens) != k + 1:
            raise _error(where, i, spec.attitude_type,
                         f"a data line needs {k + 1} fields (EPOCH {' '.join(fields)}), got "
                         f"{len(tokens)}")
        try:
            values[r] = [float(tok) for tok in tokens[1:]]
        except ValueError:
            for name, tok in zip(fields, tokens[1:]):
                _number(tok, where, i, name)
        lines.append(i)
        epochs.append(tokens[0])
    bad = np.argwhere(~np.isfinite(values))
    if bad.size:
        r, j = bad[0]
        _number(rows[r][1][j + 1], where, rows[r][0], fields[j])
    if fields != canonical:
        values = values[:, [fields.index(f) for f in canonical]]
    return _Segment(meta, spec, data_start, lines, epochs, values)


def _number(token: str, where: str, line: int, name: str) -> float:
    try:
        x = float(token)
    except ValueError:
        raise _error(where, line, name, f"{token!r} is not a number") from None
    if not np.isfinite(x):
        raise _error(where, line, name, f"{token!r}: NaN and infinities are not allowed "
                     "in an AEM (6.8.5)")
    return x


# --- XML ----------------------------------------------------------------------------
class _Node:
    __slots__ = ("tag", "attrib", "line", "children", "text")

    def __init__(self, tag: str, attrib: dict, line: int):
        self.tag, self.attrib, self.line = tag, attrib, line
        self.children: list[_Node] = []
        self.text = ""

    def elements(self, skip_comments: bool = True) -> list[_Node]:
        return [c for c in self.children if not (skip_comments and c.tag == "COMMENT")]


def _xml_tree(data: bytes, where: str) -> _Node:
    """Parse with expat to keep line numbers (ElementTree drops them).  DTDs (and with
    them entity expansion) are refused."""
    parser = xml.parsers.expat.ParserCreate()
    parser.SetParamEntityParsing(xml.parsers.expat.XML_PARAM_ENTITY_PARSING_NEVER)
    parser.buffer_text = True
    stack: list[_Node] = []
    roots: list[_Node] = []

    def start(tag, attrib):
        node = _Node(tag.rpartition(":")[2], attrib, parser.CurrentLineNumber)
        (stack[-1].children if stack else roots).append(node)
        stack.append(node)

    def end(tag):
        node = stack.pop()
        node.text = node.text.strip()

    def chars(s):
        if stack:
            stack[-1].text += s

    def doctype(*args):
        raise _error(where, parser.CurrentLineNumber, "DOCTYPE",
                     "document type declarations are not allowed in an AEM")

    parser.StartElementHandler = start
    parser.EndElementHandler = end
    parser.CharacterDataHandler = chars
    parser.StartDoctypeDeclHandler = doctype
    try:
        parser.Parse(data, True)
    except xml.parsers.expat.ExpatError as exc:
        raise _error(where, exc.lineno, "XML", f"not well-formed XML "
                     f"({xml.parsers.expat.ErrorString(exc.code)})") from None
    return roots[0]


def _parse_xml(data: bytes, where: str) -> _Message:
    root = _xml_tree(data, where)
    if root.tag == "ndm":
        aems = [c for c in root.children if c.tag == "aem"]
        if len(aems) != 1:
            raise _error(where, root.line, "ndm",
                         f"a combined NDM instantiation with {len(aems)} <aem> messages: "
                         "exactly one is read")
        root = aems[0]
    if root.tag != "aem":
        raise _error(where, root.line, root.tag,
                     f"the root element is <{root.tag}>, not <aem>: not an attitude "
                     "ephemeris message")
    if root.attrib.get("id") != "CCSDS_AEM_VERS":
        raise _error(where, root.line, "CCSDS_AEM_VERS",
                     "the <aem> element needs id=\"CCSDS_AEM_VERS\" (7.6.3)")
    if "version" not in root.attrib:
        raise _error(where, root.line, "CCSDS_AEM_VERS",
                     "the <aem> element has no version attribute (version=\"2.0\")")
    version = _version(where, root.line, root.attrib["version"])
    parts = {c.tag: c for c in root.children}
    for tag in ("header", "body"):
        if tag not in parts:
            raise _error(where, root.line, tag, f"the <aem> element has no <{tag}>")
    header = _header(where, version, parts["header"].line, _xml_entries(parts["header"]),
                     end=parts["header"].line, context="from <header>")
    segments = []
    for seg in parts["body"].children:
        if seg.tag != "segment":
            raise _error(where, seg.line, seg.tag, "expected <segment> in <body>")
        sparts = {c.tag: c for c in seg.children}
        for tag in ("metadata", "data"):
            if tag not in sparts:
                raise _error(where, seg.line, tag, f"the <segment> has no <{tag}>")
        meta, spec = _metadata(where, version, sparts["metadata"].line,
                               _xml_entries(sparts["metadata"]))
        segments.append(_xml_segment(where, meta, spec, sparts["data"]))
    if not segments:
        raise _error(where, parts["body"].line, "segment", "the <body> has no <segment>")
    return _Message(where, "XML", version, header, segments)


def _xml_entries(node: _Node) -> list[tuple[str, str, int]]:
    """``(keyword, value, line)`` of the child elements of ``<header>``/``<metadata>``."""
    return [(c.tag, c.text, c.line) for c in node.children]


def _xml_leaves(node: _Node) -> Iterator[_Node]:
    for c in node.children:
        if c.children:
            yield from _xml_leaves(c)
        else:
            if c.tag in ("rotation1", "rotation2", "rotation3"):   # version 1 Euler items
                kind = "ANGLE" if node.tag == "rotationAngles" else "RATE"
                c.tag = f"{kind}_{c.tag[-1]}"
            yield c


def _xml_segment(where: str, meta: _Block, spec: _Spec, data: _Node) -> _Segment:
    canonical = _FIELDS[spec.attitude_type]
    tags = _XML_TAGS[spec.attitude_type]
    states = data.elements()
    if not states:
        raise _error(where, data.line, "attitudeState", "the <data> has no <attitudeState>")
    values = np.empty((len(states), len(canonical)))
    lines, epochs = [], []
    for r, st in enumerate(states):
        if st.tag != "attitudeState":
            raise _error(where, st.line, st.tag, "expected <attitudeState> in <data>")
        inner = st.elements()
        if len(inner) != 1 or inner[0].tag not in tags:
            got = ", ".join(f"<{c.tag}>" for c in inner) or "nothing"
            raise _error(where, st.line, spec.attitude_type,
                         f"<attitudeState> must hold one <{tags[0]}>, got {got}")
        found: dict[str, _Node] = {}
        for leaf in _xml_leaves(inner[0]):
            if leaf.tag == "COMMENT":
                continue
            if leaf.tag in found:
                raise _error(where, leaf.line, leaf.tag, "appears twice in one state")
            if leaf.tag != "EPOCH" and leaf.tag not in canonical:
                raise _error(where, leaf.line, leaf.tag,
                             f"is not an item of ATTITUDE_TYPE = {spec.attitude_type} "
                             f"(EPOCH {' '.join(canonical)})")
            found[leaf.tag] = leaf
        for name in ("EPOCH",) + canonical:
            if name not in found:
                raise _error(where, inner[0].line, name,
                             f"missing from <{inner[0].tag}>")
        for j, name in enumerate(canonical):
            leaf = found[name]
            unit = leaf.attrib.get("units")
            if unit is not None and unit != _UNITS.get(name, unit):
                raise _error(where, leaf.line, name,
                             f"units={unit!r}, but the AEM unit of {name} is "
                             f"{_UNITS[name]!r} (4.2.4.6)")
            try:
                values[r, j] = float(leaf.text)
            except ValueError:
                _number(leaf.text, where, leaf.line, name)
        lines.append(found["EPOCH"].line)
        epochs.append(found["EPOCH"].text)
    bad = np.argwhere(~np.isfinite(values))
    if bad.size:
        r, j = bad[0]
        _number(str(values[r, j]), where, lines[r], canonical[j])
    return _Segment(meta, spec, data.line, lines, epochs, values)


# --- message -> states -------------------------------------------------------------------
def _load(path: Path) -> _Message:
    where = str(path)
    if not path.is_file():
        raise EphemerisFormatError(f"{path}: no such file")
    data = path.read_bytes()
    if data.startswith(b"\xef\xbb\xbf"):
        data = data[3:]
    if data.lstrip()[:1] == b"<":
        return _parse_xml(data, where)
    try:
        text = data.decode("ascii")
    except UnicodeDecodeError as exc:
        line = data[:exc.start].count(b"\n") + 1
        raise _error(where, line, "KVN", "non-ASCII character: a KVN AEM holds printable "
                     "ASCII only (6.6.3)") from None
    return _parse_kvn(text, where)


@dataclass
class _Epochs:
    """Parsed time tags, kept exact: whole seconds as an astropy Time (two-double, so
    whole-second differences come out exact after rounding) plus the decimal fraction
    of the second, read from its digits."""

    whole: Time
    frac: np.ndarray
    digits: list[str]

    def seconds_since(self, whole0: Time, frac0: float) -> np.ndarray:
        """Seconds since ``whole0 + frac0``: an integer number of seconds (leap seconds
        included in UTC) plus the difference of the fractions."""
        n = np.rint((self.whole - whole0).to_value("sec"))
        return n + (self.frac - frac0)


def _parse_times(strings: Sequence[str], lines: Sequence[int], spec: _Spec, where: str,
                 keyword: str = "EPOCH") -> _Epochs:
    """CCSDS time strings (``YYYY-MM-DDThh:mm:ss[.d*][Z]`` or ``YYYY-DDDThh:mm:ss...``,
    6.8.9) in the segment's time system."""
    cal, doy, digits = [], [], []
    for k, (s, line) in enumerate(zip(strings, lines)):
        m = _EPOCH_RE.match(s)
        if not m:
            raise _error(where, line, keyword,
                         f"{s!r} is not a CCSDS time (YYYY-MM-DDThh:mm:ss.ddd or "
                         "YYYY-DDDThh:mm:ss.ddd)")
        y, mo, d, dd, hh, mi, sec = m.groups()
        sec, _, frac = sec.partition(".")
        digits.append(frac)
        if dd is None:
            cal.append((k, f"{y}-{mo}-{d}T{hh}:{mi}:{sec}"))
        else:
            doy.append((k, f"{y}:{dd}:{hh}:{mi}:{sec}"))
    jd1 = np.empty(len(strings))
    jd2 = np.empty(len(strings))
    for group, fmt in ((cal, "isot"), (doy, "yday")):
        if not group:
            continue
        idx = [k for k, _ in group]
        try:
            t = Time([s for _, s in group], format=fmt, scale=spec.scale)
        except ValueError:
            for k, s in group:
                try:
                    Time(s, format=fmt, scale=spec.scale)
                except ValueError as exc:
                    raise _error(where, lines[k], keyword,
                                 f"{strings[k]!r} is not a valid time ({exc})") from None
            raise
        jd1[idx], jd2[idx] = t.jd1, t.jd2
    whole = Time(jd1, jd2, format="jd", scale=spec.scale)
    if spec.offset:
        whole = whole + TimeDelta(spec.offset, format="sec")
    frac = np.array([float("0." + f) if f else 0.0 for f in digits])
    return _Epochs(whole, frac, digits)


def _rotation_and_rates(seg: _Segment, where: str) -> tuple[np.ndarray, np.ndarray, bool]:
    """Body -> inertial quaternions (scalar last) and body rates (rad/s, NaN if the file
    has none) of one segment, and whether the file gave rates."""
    spec, values, lines = seg.spec, seg.values, seg.lines
    col = {name: values[:, j] for j, name in enumerate(_FIELDS[spec.attitude_type])}
    n = len(values)
    kind = spec.attitude_type
    w = np.full((n, 3), np.nan)
    has_rates = True

    # "Start" frame S and "end" frame E of the data: X_S = R X_E; w = omega of E
    # relative to S in E components (annex F).  S = A, E = B unless version 1 says B2A.
    if kind.startswith("QUATERNION"):
        q = np.stack([col[k] for k in _Q], axis=1)
        norm = np.linalg.norm(q, axis=1)
        bad = np.flatnonzero(~(np.abs(norm - 1.0) <= AEM_QUATERNION_NORM_TOL))
        if bad.size:
            i = bad[0]
            raise _error(where, lines[i], "Q1 Q2 Q3 QC",
                         f"quaternion ({', '.join(f'{x:.9g}' for x in q[i])}) has norm "
                         f"{norm[i]:.9g}, not 1 within {AEM_QUATERNION_NORM_TOL:g}: corrupt "
                         "data or wrong columns (is the scalar QC first?)")
        q = q / norm[:, None]
        rot = Rotation.from_quat(q)
        if kind == "QUATERNION/DERIVATIVE":
            qdot = np.stack([col[k] for k in _QDOT], axis=1)
            # q_dot = q (x) (omega_E, 0) / 2  =>  omega_E = 2 vec(conj(q) (x) q_dot)
            w = 2.0 * quat.multiply(quat.conjugate(q), qdot)[:, :3]
    elif kind.startswith("EULER"):
        angles = np.stack([col[k] for k in _ANG], axis=1)
        rot = Rotation.from_euler(spec.euler_seq, angles, degrees=True)
        if kind == "EULER_ANGLE/DERIVATIVE":
            rates = np.radians(np.stack([col[k] for k in _ANGDOT], axis=1))
            w = _euler_rates_to_omega(spec.euler_seq, np.radians(angles), rates)
    else:
        # Spin (annex F5): attitude = rotations Z(alpha + 90), X(90 - delta), Z(spin angle)
        # from A; body rate = spin rate about body Z plus the nutation rate about the
        # angular momentum L (F5.3: omega = phi_dot L + psi_dot z_B).
        angles = np.stack([col["SPIN_ALPHA"] + 90.0, 90.0 - col["SPIN_DELTA"],
                           col["SPIN_ANGLE"]], axis=1)
        rot = Rotation.from_euler("ZXZ", angles, degrees=True)
        w = np.zeros((n, 3))
        w[:, 2] = np.radians(col["SPIN_ANGLE_VEL"])
        if kind == "SPIN/NUTATION_MOM":
            a, d = np.radians(col["MOMENTUM_ALPHA"]), np.radians(col["MOMENTUM_DELTA"])
            L_a = np.stack([np.cos(d) * np.cos(a), np.cos(d) * np.sin(a), np.sin(d)], axis=1)
            w += np.radians(col["NUTATION_VEL"])[:, None] * rot.inv().apply(L_a)
        elif kind == "SPIN/NUTATION":
            per = col["NUTATION_PER"]
            if np.any(per == 0):
                i = int(np.flatnonzero(per == 0)[0])
                raise _error(where, lines[i], "NUTATION_PER", "a nutation period of 0 s")
            nu, ph = np.radians(col["NUTATION"]), np.radians(col["NUTATION_PHASE"])
            L_b = np.stack([np.sin(nu) * np.cos(ph), -np.sin(nu) * np.sin(ph), np.cos(nu)],
                           axis=1)
            w += np.radians(360.0 / per)[:, None] * L_b
    if kind.endswith("/ANGVEL"):
        w = np.radians(np.stack([col[k] for k in _ANGVEL], axis=1))
        if spec.angvel_in_a:
            w = rot.inv().apply(w)             # X_B = R^T X_A
    if kind.endswith("/RATE") or kind in ("QUATERNION", "EULER_ANGLE"):
        has_rates = False
        w = np.full((n, 3), np.nan)
    if not spec.a2b:                          # data were B -> A: flip to A -> B
        rot, w = rot.inv(), -rot.apply(w)
    if not spec.inertial_is_a:                # A is the body: flip to inertial -> body
        rot, w = rot.inv(), -rot.apply(w)
    return rot.as_quat(), w, has_rates


def _euler_rates_to_omega(seq: str, angles: np.ndarray, rates: np.ndarray) -> np.ndarray:
    """Body rate from intrinsic Euler angles and their rates (rad, rad/s).

    With ``R = R1(t1) R2(t2) R3(t3)``: ``omega_B = R3^T R2^T a1 t1' + R3^T a2 t2' + a3 t3'``.
    """
    M = _euler_rate_matrix(seq, angles)
    return np.einsum("nij,nj->ni", M, rates)


def _euler_rate_matrix(seq: str, angles: np.ndarray) -> np.ndarray:
    """(n, 3, 3) matrix whose columns map the three Euler angle rates to body rates."""
    a1, a2, a3 = (_AXIS[c] for c in seq)
    n = len(angles)
    R2 = Rotation.from_rotvec(a2 * angles[:, 1:2])
    R3 = Rotation.from_rotvec(a3 * angles[:, 2:3])
    c1 = R3.inv().apply(R2.inv().apply(np.tile(a1, (n, 1))))
    c2 = R3.inv().apply(np.tile(a2, (n, 1)))
    c3 = np.tile(a3, (n, 1))
    return np.stack([c1, c2, c3], axis=2)


def _estimate_omega(q: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Body rates from a quaternion sequence: relative rotations between neighbours
    (``rotvec(R_i^-1 R_i+1) / dt``), averaged with weights that make the estimate
    second-order accurate at interior points."""
    n = len(t)
    w = np.full((n, 3), np.nan)
    if n < 2:
        return w
    rot = Rotation.from_quat(q)
    d = (rot[:-1].inv() * rot[1:]).as_rotvec() / np.diff(t)[:, None]
    h = np.diff(t)[:, None]
    w[0], w[-1] = d[0], d[-1]
    w[1:-1] = (h[1:] * d[:-1] + h[:-1] * d[1:]) / (h[:-1] + h[1:])
    return w


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


def _chosen_segments(msg: _Message, segment) -> list[int]:
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


def _chosen_index(msg: _Message, seg: _Segment) -> int:
    return next(k for k, s in enumerate(msg.segments) if s is seg)


def _check_same_frames(seg: _Segment, first: _Segment, where: str) -> None:
    """Segments are concatenated only when they share frames and time system."""
    spec = seg.spec
    for attr, what in (("inertial", "inertial frame"), ("body_frame", "body frame"),
                       ("time_system", "TIME_SYSTEM")):
        if getattr(spec, attr) != getattr(first.spec, attr):
            key = ("TIME_SYSTEM" if attr == "time_system" else
                   "REF_FRAME_A" if (attr == "inertial") == spec.inertial_is_a
                   else "REF_FRAME_B")
            raise _error(where, seg.meta.line(key), key,
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


def _segment_samples(segments: list[_Segment], numbers: list[int], where: str,
                     angular_velocity: str) -> list[_Samples]:
    """Times, attitudes and rates of each segment, with the checks of time order within
    a segment and from one segment to the next."""
    out: list[_Samples] = []
    whole0 = frac0 = epoch = previous = None
    for seg, k in zip(segments, numbers):
        spec = seg.spec
        ep = _parse_times(seg.epochs, seg.lines, spec, where)
        if whole0 is None:
            whole0, frac0 = ep.whole[0], float("0." + ep.digits[0][:9]) if ep.digits[0] else 0.0
            # the epoch: the first time tag, its fraction cut to 9 decimals
            epoch = whole0 + TimeDelta(frac0, format="sec")
        sec = ep.seconds_since(whole0, frac0)
        _check_increasing(seg, sec, where)
        if previous is not None and sec[0] < previous[0]:
            raise _error(where, seg.lines[0], "EPOCH",
                         f"time goes backwards: this segment starts at {seg.epochs[0]}, before "
                         f"the previous one ends ({previous[1]}, line {previous[2]}); read the "
                         "segments one at a time with segment=")
        previous = (sec[-1], seg.epochs[-1], seg.lines[-1])
        _check_span(seg, ep, where)
        q, w, has_rates = _rotation_and_rates(seg, where)
        if spec.attitude_type.endswith("/RATE"):
            _warn(where, seg.meta.line("ATTITUDE_TYPE"), "ATTITUDE_TYPE",
                  f"{spec.attitude_type}: the version 1.0 rate items are ambiguous (angular "
                  "velocity or Euler angle rates) and are not used")
        rates = "file" if has_rates else "estimate" if angular_velocity == "estimate" else "none"
        out.append(_Samples(sec, q, w, np.full(len(sec), k, dtype=np.int32), rates,
                            spec.attitude_type, epoch))
    for part in out:
        if part.rates == "estimate":
            part.omega = _estimate_omega(part.quaternion, part.seconds)
    return out


def _check_increasing(seg: _Segment, sec: np.ndarray, where: str) -> None:
    dt = np.diff(sec)
    back = np.flatnonzero(~(dt > 0))
    if back.size:
        i = back[0] + 1
        what = "repeats" if dt[i - 1] == 0 else "goes back from"
        raise _error(where, seg.lines[i], "EPOCH",
                     f"time {what} the previous data line (line {seg.lines[i - 1]}, "
                     f"{seg.epochs[i - 1]} -> {seg.epochs[i]}): epochs must increase "
                     "within a segment (4.2.4.8.1)")


_RATE_SOURCES = {"file": "from the AEM data lines",
                 "estimate": "estimated from neighbouring attitudes (finite differences)",
                 "none": "not in the AEM (NaN)"}


def _aem_attrs(msg: _Message, first: _Segment, parts: list[_Samples],
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


def _aem_ephemeris(msg: _Message, first: _Segment, parts: list[_Samples],
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


def _check_span(seg: _Segment, ep: _Epochs, where: str) -> None:
    """Warn when data fall outside START_TIME .. STOP_TIME (by more than 1 microsecond)."""
    for key, idx, sign in (("START_TIME", 0, 1.0), ("STOP_TIME", -1, -1.0)):
        bound = _parse_times([seg.meta.get(key)], [seg.meta.line(key)], seg.spec, where, key)
        bound_minus_sample = bound.seconds_since(ep.whole[idx], ep.frac[idx])[0]
        gap = -sign * bound_minus_sample          # >= 0 when the bound covers the data
        if gap < -1e-6:
            _warn(where, seg.meta.line(key), key,
                  f"{seg.meta.get(key)} does not cover the data (epoch {seg.epochs[idx]} at "
                  f"line {seg.lines[idx]})")


# --- writing ------------------------------------------------------------------------
def _fmt(x: float) -> str:
    """Shortest decimal that reads back to ``x`` when it has at most 16 digits, else ``x``
    rounded to 16 significant digits in floating-point notation (6.8.4 allows no more):
    ``0.56748``, ``1.0e-05``, ``-2.345678901234568e-01``."""
    if x == 0.0:
        return "0.0"                      # also -0.0, which the standard does not allow
    r = repr(x)
    mant, e, exp = r.partition("e")
    if not e:
        if len(r) - (r[0] == "-") <= 17:                   # <= 16 digits and the point
            return r
    elif len(mant) - (mant[0] == "-") - ("." in mant) <= 16:
        return (mant if "." in mant else mant + ".0") + e + exp
    if abs(x) > 1e308:
        return r                          # 16 digits would round up to infinity
    mant, e, exp = f"{x:.15e}".partition("e")
    sign, mant = ("-", mant[1:]) if mant[0] == "-" else ("", mant)
    digits, power = (mant[0] + mant[2:]).rstrip("0"), int(exp)
    if 0 <= power < 15 and max(len(digits), power + 2) <= 16:     # fixed point fits
        whole, frac = digits[:power + 1].ljust(power + 1, "0"), digits[power + 1:]
        return f"{sign}{whole}.{frac or '0'}"
    if -4 <= power < 0 and len(digits) - power <= 16:
        return f"{sign}0.{'0' * (-power - 1)}{digits}"
    return f"{sign}{digits[0]}.{digits[1:] or '0'}e{exp}"


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
    frame_a = label if ref_frame_a is None else _norm_text(_text(ref_frame_a, "REF_FRAME_A"))
    if frame_a not in _INERTIAL:
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
    frame_b = _norm_text(_text(ref_frame_b if ref_frame_b is not None else default_b,
                               "REF_FRAME_B"))
    if frame_b in _INERTIAL:
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
    ts = _norm_text(str(time_system))
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


def _state_values(kind: str, q: np.ndarray, w: np.ndarray, seq: str | None,
                  angvel_in_a: bool) -> np.ndarray:
    """Data items (without the epoch) of ``kind`` for quaternions body -> inertial and
    body rates (rad/s): REF_FRAME_A is the inertial frame, REF_FRAME_B the body."""
    parts = []
    rot = Rotation.from_quat(q)
    if kind.startswith("QUATERNION"):
        parts.append(q)
        if kind == "QUATERNION/DERIVATIVE":
            parts.append(0.5 * quat.multiply(q, np.concatenate([w, np.zeros((len(w), 1))],
                                                               axis=1)))
    else:
        with warnings.catch_warnings():
            warnings.filterwarnings("ignore", message=".*[Gg]imbal lock.*")
            angles = rot.as_euler(seq, degrees=True)
        parts.append(angles)
        if kind == "EULER_ANGLE/DERIVATIVE":
            M = _euler_rate_matrix(seq, np.radians(angles))
            det = np.linalg.det(M)
            bad = np.flatnonzero(~(np.abs(det) > 1e-9))
            if bad.size:
                raise EphemerisFormatError(
                    f"EULER_ANGLE/DERIVATIVE: the {seq} sequence is in gimbal lock at sample "
                    f"{bad[0]} (angles {np.round(angles[bad[0]], 6).tolist()} deg): the angle "
                    "rates are undefined there; write EULER_ANGLE/ANGVEL or choose another "
                    "EULER_ROT_SEQ")
            parts.append(np.degrees(np.linalg.solve(M, w[..., None])[..., 0]))
    if kind.endswith("/ANGVEL"):
        parts.append(np.degrees(rot.apply(w) if angvel_in_a else w))
    return np.concatenate(parts, axis=1)


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
    seq = _euler_seq(euler_rot_seq) if kind.startswith("EULER") else None
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
    out = _Output(
        kind=kind, header_comments=[_text_comment(c) for c in comments], header=header,
        provenance=(f"attitude: quaternion = rotation from REF_FRAME_A ({frame_a}) to "
                    f"REF_FRAME_B ({frame_b}), scalar QC last"),
        segments=[(common + [("START_TIME", format_epoch(times[a])),
                             ("STOP_TIME", format_epoch(times[b - 1]))] + tail, a, b)
                  for a, b in _segment_bounds(eph)],
        times=times, values=_state_values(kind, q, w, seq, angvel_in_a))
    writer = _write_kvn if form == "kvn" else _write_xml
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
            "object: write one at a time (Ephemeris(eph.dataset.isel(body=k)))")
    if len(ephemeris) == 0:
        raise EphemerisFormatError("the ephemeris has no samples")
    return ephemeris


def _write_kind(attitude_type: str | None, eph: Ephemeris, q: np.ndarray,
                w: np.ndarray) -> str:
    """The ATTITUDE_TYPE to write, checked against the data it needs."""
    if attitude_type is None:
        kind = "QUATERNION/ANGVEL" if np.all(np.isfinite(w)) else "QUATERNION"
    else:
        kind = _norm_text(attitude_type).replace("_/_", "/")
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
    which = _norm_text(str(angvel_frame))
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


@dataclass(frozen=True)
class _Output:
    """An AEM ready to write: header, segment metadata, and the data items."""

    kind: str
    header_comments: list[str]
    header: list[tuple[str, str]]
    provenance: str                 # the COMMENT line of every metadata block
    segments: list[tuple[list[tuple[str, str]], int, int]]   # metadata, start, stop
    times: Time                     # calendar strings in the TIME_SYSTEM
    values: np.ndarray              # data items after the epoch, (n, len(fields))

    def rows(self, a: int, b: int) -> Iterator[tuple[str, list[str]]]:
        """``(epoch, items)`` text of samples ``a:b``, formatted :data:`_CHUNK` at a time."""
        for c in range(a, b, _CHUNK):
            stop = min(c + _CHUNK, b)
            epochs = np.atleast_1d(format_epoch(self.times[c:stop]))
            for epoch, vals in zip(epochs, self.values[c:stop].tolist()):
                yield str(epoch), [_fmt(v) for v in vals]


def _write_kvn(tmp: Path, out: _Output) -> None:
    with open(tmp, "w", encoding="ascii", newline="\n") as fh:
        fh.write(f"CCSDS_AEM_VERS = {CCSDS_AEM_VERS}\n")
        for c in out.header_comments:
            fh.write(f"COMMENT {c}\n")
        for key, value in out.header:
            fh.write(f"{key:<20} = {value}\n")
        for meta, a, b in out.segments:
            fh.write(f"\nMETA_START\nCOMMENT {out.provenance}\n")
            for key, value in meta:
                fh.write(f"{key:<20} = {value}\n")
            fh.write("META_STOP\n\nDATA_START\n")
            fh.writelines(f"{e} {' '.join(v)}\n" for e, v in out.rows(a, b))
            fh.write("DATA_STOP\n")


def _write_xml(tmp: Path, out: _Output) -> None:
    with open(tmp, "w", encoding="utf-8", newline="\n") as fh:
        fh.write('<?xml version="1.0" encoding="UTF-8"?>\n'
                 '<aem xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"\n'
                 '     xsi:noNamespaceSchemaLocation='
                 '"https://sanaregistry.org/r/ndmxml_unqualified/'
                 'ndmxml-4.0.0-master-4.0.xsd"\n'
                 f'     id="CCSDS_AEM_VERS" version={quoteattr(CCSDS_AEM_VERS)}>\n'
                 "  <header>\n")
        for c in out.header_comments:
            fh.write(f"    <COMMENT>{escape(c)}</COMMENT>\n")
        for key, value in out.header:
            fh.write(f"    <{key}>{escape(value)}</{key}>\n")
        fh.write("  </header>\n  <body>\n")
        for meta, a, b in out.segments:
            fh.write("  <segment>\n    <metadata>\n"
                     f"      <COMMENT>{escape(out.provenance)}</COMMENT>\n")
            for key, value in meta:
                fh.write(f"      <{key}>{escape(value)}</{key}>\n")
            fh.write("    </metadata>\n    <data>\n")
            fh.writelines(_state_xml(out.kind, e, v) for e, v in out.rows(a, b))
            fh.write("    </data>\n  </segment>\n")
        fh.write("  </body>\n</aem>\n")


def _state_xml(kind: str, epoch: str, vals: list[str]) -> str:
    """One ``<attitudeState>`` line of the XML form (table 7-5)."""
    fields = _FIELDS[kind]
    item = dict(zip(fields, vals))

    def el(name: str) -> str:
        unit = f' units="{_UNITS[name]}"' if name in _UNITS else ""
        return f"<{name}{unit}>{item[name]}</{name}>"

    body = [f"<EPOCH>{epoch}</EPOCH>"]
    if kind.startswith("QUATERNION"):
        body.append("<quaternion>" + "".join(el(k) for k in _Q) + "</quaternion>")
        if kind == "QUATERNION/DERIVATIVE":
            body.append("<quaternionDot>" + "".join(el(k) for k in _QDOT) + "</quaternionDot>")
        elif kind == "QUATERNION/ANGVEL":
            body.append("<angVel>" + "".join(el(k) for k in _ANGVEL) + "</angVel>")
    else:
        body += [el(k) for k in fields]
    tag = _XML_TAGS[kind][0]
    return f"      <attitudeState><{tag}>{''.join(body)}</{tag}></attitudeState>\n"


def _text_comment(value) -> str:
    s = " ".join(str(value).split())
    if not s.isascii() or not s.isprintable() or len(s) > 240:
        raise EphemerisFormatError(
            f"COMMENT {s[:40]!r}: a comment is one line of printable ASCII, at most 240 "
            "characters")
    return s


# --- conversion ---------------------------------------------------------------------
_READ_OPTIONS = ("body", "segment", "angular_velocity")


def convert(in_path: str | PathLike, out_path: str | PathLike, **options) -> Path:
    """Convert between netCDF (``.nc``) and CCSDS AEM (``.aem`` KVN, ``.xml`` XML).

    The input format is taken from the suffix for ``.nc`` and from the content
    otherwise (KVN or XML AEM); the output format from the suffix.  ``body``,
    ``segment`` and ``angular_velocity`` go to :func:`read_aem`, every other option to
    :func:`write_aem` (``object_name``, ``object_id``, ``ref_frame_a``, ``ref_frame_b``,
    ``attitude_type``, ``time_system``, ...).  This is ``attitude convert IN OUT``.

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
    read_opts = {k: options.pop(k) for k in _READ_OPTIONS if k in options}
    if in_path.suffix.lower() == ".nc":
        if read_opts:
            raise EphemerisFormatError(
                f"{', '.join(read_opts)}: options for reading an AEM, not a netCDF file")
        eph = Ephemeris.from_netcdf(in_path)
    else:
        eph = read_aem(in_path, **read_opts)
    suffix = out_path.suffix.lower()
    if suffix == ".nc":
        if options:
            raise EphemerisFormatError(
                f"{', '.join(options)}: options for writing an AEM, not a netCDF file")
        return eph.to_netcdf(out_path)
    if suffix in (".aem", ".kvn", ".xml"):
        return write_aem(eph, out_path, **options)
    raise EphemerisFormatError(
        f"{out_path}: unknown output format {suffix!r}: use .nc (netCDF), .aem (CCSDS AEM, "
        "KVN) or .xml (CCSDS AEM, XML)")

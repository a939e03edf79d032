"""The CCSDS Attitude Ephemeris Message as data, shared by its two encodings (KVN and XML).

What an AEM is (CCSDS 504.0-B-2, section 4; version 1: CCSDS 504.0-B-1): the keywords
of the header and of the segment metadata in each version, the attitude types and their
data items, the units, the time systems; the parsed message (:class:`Block`,
:class:`Spec`, :class:`Segment`, :class:`Message`) with the checks of its metadata, the
CCSDS time strings (:func:`parse_times`), the numbers (:func:`parse_number`) and the
message ready to write (:class:`Output`).  The encodings are :mod:`.aem_kvn` and
:mod:`.aem_xml`; the public entry points :func:`attitude.formats.aem.read_aem` and
:func:`attitude.formats.aem.write_aem`.

Every error is an :class:`~attitude.EphemerisFormatError` naming the file, the line and
the keyword (:func:`error_at`).
"""

from __future__ import annotations

import re
import warnings
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field

import numpy as np
from astropy.time import Time, TimeDelta

from ..foundations.errors import AttitudeWarning, EphemerisFormatError
from ..model.state import INERTIAL_FRAMES, format_epoch

#: The constants of the standard; the helpers below (blocks, specs, segments, number and
#: time parsing, the output writer) are the wing's internal pieces, shared by the
#: encodings and the entry points, and not public: the public names are those of
#: :mod:`attitude.formats.aem`.
__all__ = [
    "CCSDS_AEM_VERS",
    "AEM_QUATERNION_NORM_TOL",
    "AEM_TIME_SYSTEMS",
    "AEM_ATTITUDE_TYPES",
    "AEM_WRITE_TYPES",
    "Q_ITEMS",
    "QDOT_ITEMS",
    "ANGVEL_ITEMS",
    "ANGLE_ITEMS",
    "ANGDOT_ITEMS",
    "FIELDS",
    "XML_TAGS",
    "UNITS",
    "INERTIAL_LABELS",
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

Q_ITEMS = ("Q1", "Q2", "Q3", "QC")
QDOT_ITEMS = ("Q1_DOT", "Q2_DOT", "Q3_DOT", "QC_DOT")
ANGVEL_ITEMS = ("ANGVEL_X", "ANGVEL_Y", "ANGVEL_Z")
ANGLE_ITEMS = ("ANGLE_1", "ANGLE_2", "ANGLE_3")
ANGDOT_ITEMS = ("ANGLE_1_DOT", "ANGLE_2_DOT", "ANGLE_3_DOT")
_RATE = ("RATE_1", "RATE_2", "RATE_3")          # version-1 rates (ambiguous, not used)
_SPIN = ("SPIN_ALPHA", "SPIN_DELTA", "SPIN_ANGLE", "SPIN_ANGLE_VEL")

#: ATTITUDE_TYPE -> data items after the epoch, in the order of table 4-4 (version 2;
#: version 1 with ``QUATERNION_TYPE = LAST``).
FIELDS = {
    "QUATERNION": Q_ITEMS,
    "QUATERNION/DERIVATIVE": Q_ITEMS + QDOT_ITEMS,
    "QUATERNION/ANGVEL": Q_ITEMS + ANGVEL_ITEMS,
    "QUATERNION/RATE": Q_ITEMS + _RATE,
    "EULER_ANGLE": ANGLE_ITEMS,
    "EULER_ANGLE/DERIVATIVE": ANGLE_ITEMS + ANGDOT_ITEMS,
    "EULER_ANGLE/ANGVEL": ANGLE_ITEMS + ANGVEL_ITEMS,
    "EULER_ANGLE/RATE": ANGLE_ITEMS + _RATE,
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
XML_TAGS = {
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
UNITS = {**dict.fromkeys(QDOT_ITEMS, "1/s"), **dict.fromkeys(ANGLE_ITEMS, "deg"),
          **dict.fromkeys(ANGDOT_ITEMS + ANGVEL_ITEMS + _RATE, "deg/s"),
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
_DIGIT_AXES = {"1": "X", "2": "Y", "3": "Z"}
INERTIAL_LABELS = frozenset(INERTIAL_FRAMES)
_CHUNK = 20_000                 # data lines formatted at a time when writing


# --- errors -------------------------------------------------------------------------
def error_at(where: str, line: int | None, keyword: str, message: str) -> EphemerisFormatError:
    """``"<file>, line <n>: <KEYWORD>: <message>"`` in the one error shape
    (``key`` the keyword); ``path`` is the file and ``line`` its line (``keyword`` is
    ``key`` under its AEM name)."""
    loc = f"{where}, line {line}" if line else where
    err = EphemerisFormatError(message, key=keyword, path=loc or None)
    err.path, err.line, err.keyword = where or None, line, keyword
    return err


def warn_at(where: str, line: int | None, keyword: str, message: str) -> None:
    """An :class:`~attitude.AttitudeWarning` ``"<file>, line <n>: <KEYWORD>: <message>"``,
    attributed to the frame two above the function that calls this one."""
    loc = f"{where}, line {line}" if line else where
    warnings.warn(f"{loc}: {keyword}: {message}", AttitudeWarning, stacklevel=3)


# --- parsed message -----------------------------------------------------------------
@dataclass
class Block:
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
                raise error_at(self.where, line, key,
                             f"is an AEM version {other} keyword, not allowed in a version "
                             f"{version} {section} ({hint[other]})")
            raise error_at(self.where, line, key,
                         f"is not an AEM version {version} {section} keyword; allowed: "
                         f"{', '.join(k for k in allowed if k != 'COMMENT')}")
        if key in self.items:
            raise error_at(self.where, line, key,
                         f"appears twice in the {section} (first at line {self.items[key][1]})")
        if not value:
            raise error_at(self.where, line, key, "has no value")
        self.items[key] = (value, line)

    def get(self, key: str, default: str | None = None) -> str | None:
        return self.items[key][0] if key in self.items else default

    def line(self, key: str) -> int:
        return self.items[key][1] if key in self.items else self.start


@dataclass(frozen=True)
class Spec:
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
class Segment:
    """One segment as read: its metadata, how to read it, the line of its data block, and
    per data line the line number, the epoch text and the values."""

    meta: Block
    spec: Spec
    data_line: int
    lines: list[int]
    epochs: list[str]
    values: np.ndarray              # (n, len(FIELDS[type])) in canonical order


@dataclass
class Message:
    """A parsed AEM: the file, its form (KVN or XML), version, header and segments."""

    where: str
    form: str
    version: str
    header: Block
    segments: list[Segment]


def norm_text(value: str) -> str:
    """Text value as compared: upper case, blanks and underscores equivalent (6.8.8)."""
    return re.sub(r"[\s_]+", "_", value.strip()).upper()


def parse_version(where: str, line: int, value: str) -> str:
    """``CCSDS_AEM_VERS`` as ``"1.0"`` or ``"2.0"``; any other version is an error."""
    try:
        v = float(value)
    except ValueError:
        v = None
    if v == 1.0 or v == 2.0:
        return f"{v:.1f}"
    raise error_at(where, line, "CCSDS_AEM_VERS",
                 f"version {value!r} is not supported: this reader handles AEM versions 1.0 "
                 "(CCSDS 504.0-B-1) and 2.0 (CCSDS 504.0-B-2)")


def euler_sequence(value: str, where: str = "", line: int | None = None) -> str:
    """``EULER_ROT_SEQ`` as three axis letters (``ZXZ``; version 1 digits ``313``
    accepted), checked."""
    seq = value.strip().upper()
    if re.fullmatch(r"[123]{3}", seq):
        seq = "".join(_DIGIT_AXES[c] for c in seq)
    if not re.fullmatch(r"[XYZ]{3}", seq) or seq[0] == seq[1] or seq[1] == seq[2]:
        raise error_at(where, line, "EULER_ROT_SEQ",
                     f"{value!r} is not a rotation sequence: give three axes with no axis "
                     "repeated twice in a row, such as ZXZ or XYZ (version 1: 313, 123)")
    return seq


def _spec(version: str, meta: Block) -> Spec:
    """Check a metadata block and work out how to read its data."""
    for key in _META_MANDATORY[version]:
        if key not in meta.items:
            raise error_at(meta.where, meta.stop or meta.start, key,
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
        euler_seq = euler_sequence(meta.get("EULER_ROT_SEQ"), meta.where,
                               meta.line("EULER_ROT_SEQ"))
    angvel_in_a = att_type.endswith("/ANGVEL") and _angvel_frame_is_a(meta, att_type,
                                                                       frame_a, frame_b)
    time_system = norm_text(meta.get("TIME_SYSTEM"))
    if time_system not in AEM_TIME_SYSTEMS:
        raise error_at(meta.where, meta.line("TIME_SYSTEM"), "TIME_SYSTEM",
                     f"{meta.get('TIME_SYSTEM')!r} is not supported: use one of "
                     f"{', '.join(AEM_TIME_SYSTEMS)} (mission, spacecraft-clock and sidereal "
                     "time systems need mission data to become a time scale)")
    scale, offset = AEM_TIME_SYSTEMS[time_system]
    return Spec(att_type, fields, euler_seq, inertial, body_frame, a_inertial, a2b,
                 angvel_in_a, time_system, scale, offset)


def _require(meta: Block, key: str, message: str) -> None:
    """A keyword that the other keywords make mandatory."""
    if key not in meta.items:
        raise error_at(meta.where, meta.stop or meta.start, key, message)


def _attitude_type(version: str, meta: Block) -> str:
    """``ATTITUDE_TYPE``, normalised, one of the version's types."""
    raw_type = meta.get("ATTITUDE_TYPE")
    att_type = norm_text(raw_type).replace("_/_", "/")
    if att_type in _TYPES[version]:
        return att_type
    if version == "2.0" and att_type in _TYPES["1.0"]:
        hint = (f"{att_type} is an AEM version 1.0 type (replaced in version 2.0 by "
                f"{att_type.replace('RATE', 'ANGVEL')} and .../DERIVATIVE)")
    elif version == "1.0" and att_type in _TYPES["2.0"]:
        hint = f"{att_type} exists only in AEM version 2.0"
    else:
        hint = f"use one of {', '.join(_TYPES[version])}"
    raise error_at(meta.where, meta.line("ATTITUDE_TYPE"), "ATTITUDE_TYPE",
                 f"{raw_type!r} is not an AEM version {version} attitude type: {hint}")


def _ref_frames(meta: Block) -> tuple[str, str, bool]:
    """``REF_FRAME_A``, ``REF_FRAME_B`` and whether A is the inertial one: exactly one of
    them must be an inertial frame (ours), the other is the body frame."""
    frame_a = norm_text(meta.get("REF_FRAME_A"))
    frame_b = norm_text(meta.get("REF_FRAME_B"))
    a_inertial, b_inertial = frame_a in INERTIAL_LABELS, frame_b in INERTIAL_LABELS
    if a_inertial == b_inertial:
        what = "both" if a_inertial else "neither"
        raise error_at(meta.where, meta.line("REF_FRAME_A"), "REF_FRAME_A",
                     f"REF_FRAME_A = {frame_a} and REF_FRAME_B = {frame_b}: {what} of them is "
                     f"an inertial frame ({', '.join(INERTIAL_FRAMES)}); an attitude ephemeris "
                     "holds the rotation between an inertial frame and the body frame "
                     "(local orbital or Earth-fixed frames need an orbit or Earth model)")
    return frame_a, frame_b, a_inertial


def _direction_and_fields(version: str, meta: Block, att_type: str
                          ) -> tuple[bool, tuple[str, ...]]:
    """Whether the data rotate A to B, and the data items in file order (version 1
    chooses both: ``ATTITUDE_DIR``, ``QUATERNION_TYPE``; version 2 fixes them)."""
    fields = FIELDS[att_type]
    if version != "1.0":
        return True, fields
    direction = norm_text(meta.get("ATTITUDE_DIR"))
    if direction not in ("A2B", "B2A"):
        raise error_at(meta.where, meta.line("ATTITUDE_DIR"), "ATTITUDE_DIR",
                     f"{meta.get('ATTITUDE_DIR')!r} must be A2B or B2A")
    if att_type.startswith("QUATERNION"):
        _require(meta, "QUATERNION_TYPE", f"mandatory for ATTITUDE_TYPE = {att_type} in AEM "
                 "version 1.0 (FIRST or LAST: where the scalar QC stands)")
        qtype = norm_text(meta.get("QUATERNION_TYPE"))
        if qtype not in ("FIRST", "LAST"):
            raise error_at(meta.where, meta.line("QUATERNION_TYPE"), "QUATERNION_TYPE",
                         f"{meta.get('QUATERNION_TYPE')!r} must be FIRST or LAST")
        if qtype == "FIRST":
            rest = fields[4:]
            if rest == QDOT_ITEMS:
                rest = ("QC_DOT", "Q1_DOT", "Q2_DOT", "Q3_DOT")
            fields = ("QC", "Q1", "Q2", "Q3") + rest
    return direction == "A2B", fields


def _angvel_frame_is_a(meta: Block, att_type: str, frame_a: str, frame_b: str) -> bool:
    """Whether ``ANGVEL_FRAME`` names REF_FRAME_A (else REF_FRAME_B; no third frame)."""
    _require(meta, "ANGVEL_FRAME", f"mandatory for ATTITUDE_TYPE = {att_type}: the frame of "
             "the angular velocity components")
    value = norm_text(meta.get("ANGVEL_FRAME"))
    if value in ("REF_FRAME_A", frame_a):
        return True
    if value in ("REF_FRAME_B", frame_b):
        return False
    raise error_at(meta.where, meta.line("ANGVEL_FRAME"), "ANGVEL_FRAME",
                 f"{meta.get('ANGVEL_FRAME')!r} must be REF_FRAME_A ({frame_a}) or "
                 f"REF_FRAME_B ({frame_b}); components in a third frame cannot be "
                 "converted without its orientation")


# --- header and metadata blocks (both forms) -------------------------------------------
def keyword_block(where: str, version: str, section: str, start: int,
           entries: Sequence[tuple[str, str, int]]) -> Block:
    """A header or metadata block from its ``(keyword, value, line)`` entries: every
    keyword checked against the ``section`` of ``version``, none repeated or empty."""
    allowed = (_HEADER_KEYS if section == "header" else _META_KEYS)[version]
    block = Block(where, start)
    for key, value, line in entries:
        block.add(key, value, line, allowed, version, section)
    return block


def header_block(where: str, version: str, start: int, entries: Sequence[tuple[str, str, int]],
            *, end: int, context: str) -> Block:
    """The message header, with its mandatory keywords (missing: an error at line
    ``end``, explained by ``context``)."""
    header = keyword_block(where, version, "header", start, entries)
    for key in _HEADER_MANDATORY:
        if key not in header.items:
            raise error_at(where, end, key, f"mandatory header keyword missing {context}")
    return header


def metadata_block(where: str, version: str, start: int, entries: Sequence[tuple[str, str, int]],
              stop: int = 0) -> tuple[Block, Spec]:
    """A segment's metadata block and how to read its data (:func:`_spec`)."""
    meta = keyword_block(where, version, "metadata", start, entries)
    meta.stop = stop
    return meta, _spec(version, meta)



def parse_number(token: str, where: str, line: int, name: str) -> float:
    """A finite float from the text of a data item (an error naming the item otherwise)."""
    try:
        x = float(token)
    except ValueError:
        raise error_at(where, line, name, f"{token!r} is not a number") from None
    if not np.isfinite(x):
        raise error_at(where, line, name, f"{token!r}: NaN and infinities are not allowed "
                     "in an AEM (6.8.5)")
    return x



# --- CCSDS time strings ---------------------------------------------------------
@dataclass
class Epochs:
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


def parse_times(strings: Sequence[str], lines: Sequence[int], spec: Spec, where: str,
                 keyword: str = "EPOCH") -> Epochs:
    """CCSDS time strings (``YYYY-MM-DDThh:mm:ss[.d*][Z]`` or ``YYYY-DDDThh:mm:ss...``,
    6.8.9) in the segment's time system."""
    cal, doy, digits = [], [], []
    for k, (s, line) in enumerate(zip(strings, lines)):
        m = _EPOCH_RE.match(s)
        if not m:
            raise error_at(where, line, keyword,
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
                    raise error_at(where, lines[k], keyword,
                                 f"{strings[k]!r} is not a valid time ({exc})") from None
            raise
        jd1[idx], jd2[idx] = t.jd1, t.jd2
    whole = Time(jd1, jd2, format="jd", scale=spec.scale)
    if spec.offset:
        whole = whole + TimeDelta(spec.offset, format="sec")
    frac = np.array([float("0." + f) if f else 0.0 for f in digits])
    return Epochs(whole, frac, digits)

# --- the message to write -------------------------------------------------------
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


@dataclass(frozen=True)
class Output:
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



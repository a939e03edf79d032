"""The one quantity reader: numbers, strings, Quantities and ``{value, unit}`` tables in,
SI floats out; epochs in, astropy ``Time`` out.

Every number with a unit that enters ``attitude`` (scenario files, torque tables, orbits,
shape models, events, the times and steps of :func:`attitude.propagate`) goes through
:func:`to_si`, and every epoch through :func:`to_time`, so that ``"2 1/s"`` means the same
thing everywhere and a bad value gets the same keyed
:class:`~attitude.foundations.errors.QuantityError`.

Accepted forms
--------------
- a plain number, a list of numbers or a numpy array: already in the SI unit wanted;
- a string astropy parses: ``"12.5 deg/s"``, ``"30 min"``, ``"2.6 g/cm3"``,
  ``"2.3e7 kg km2"``; two extra units are known: ``rev`` (one full turn) and ``rpm``
  (revolutions per minute);
- an astropy ``Quantity``;
- a table ``{"value": ..., "unit": "..."}`` (what TOML's inline tables give), whose
  ``value`` may be a number or a (nested) list of numbers.

Cycles and radians
------------------
Angles are radians.  Where an angular quantity is wanted (an angle, an angular rate),

- ``Hz`` (and ``kHz``, ``mHz``, ...) counts **cycles**: ``1 Hz = 1 rev/s = 2 pi rad/s``,
  like ``rpm`` and ``rev/day``;
- a bare ``1/s`` (or ``s-1``, or a plain number) counts **radians**: ``"2 1/s"`` is
  ``2 rad/s``, because radians are dimensionless in SI.

So ``to_si("1 Hz", "rad/s")`` is ``2 pi`` and ``to_si("1 1/s", "rad/s")`` is ``1``.  Where no
angle is involved (``to_si("1 Hz", "1/s")``) Hz is simply 1/s.
"""

from __future__ import annotations

import calendar
import math
import re
import warnings
from collections.abc import Mapping

import erfa
import numpy as np
from astropy import units as u
from astropy.time import Time

from .errors import QuantityError

__all__ = ["to_si", "to_time", "read_unit", "rev", "rpm", "TIME_SCALES", "DEFAULT_TIME_SCALE"]

rev = u.def_unit(["rev", "revolution"], 2 * np.pi * u.rad, doc="one full turn")
rpm = u.def_unit("rpm", rev / u.min, doc="revolutions per minute")
u.add_enabled_units([rev, rpm])

#: Time scales :func:`to_time` accepts (astropy's, lower case).
TIME_SCALES = tuple(s for s in Time.SCALES if s != "local")

#: The time scale of an epoch given without one (a plain ISO 8601 string): TDB, the scale
#: of the dynamics, everywhere -- ``AttitudeState``, scenario files, ``Lightcurve``.  Where
#: times are naturally in another scale (observers' UTC in ALCDEF and CSV lightcurve files)
#: the reader builds the epoch with that scale stated.
DEFAULT_TIME_SCALE = "tdb"

_HZ = u.Hz


def _where(key) -> str:
    return f"{key}: " if key else ""


def _is_angular(unit: u.UnitBase) -> bool:
    """Whether ``unit`` involves an angle (rad to a non-zero power)."""
    try:
        d = unit.decompose(bases=[u.rad, u.m, u.s, u.kg, u.A, u.K, u.mol, u.cd])
    except u.UnitsError:
        return False
    return any(b == u.rad and p != 0 for b, p in zip(d.bases, d.powers))


def _cycles(unit: u.UnitBase) -> u.UnitBase:
    """``unit`` with every Hz (or prefixed Hz) read as cycles per second."""
    # identity, not ==: astropy finds 1/s == Hz (equivalent units), which is the point
    if unit is _HZ:
        return u.cycle / u.s
    if isinstance(unit, u.PrefixUnit) and len(unit.represents.bases) == 1 and (
            unit.represents.bases[0] is _HZ):
        return unit.represents.scale * u.cycle / u.s
    if isinstance(unit, u.CompositeUnit) and (len(unit.bases) > 1 or unit.powers[0] != 1):
        out = u.Unit(unit.scale)
        for base, power in zip(unit.bases, unit.powers):
            out = out * _cycles(base) ** power
        return out
    return unit


def read_unit(text, *, key=None, like=None, error=QuantityError) -> u.UnitBase:
    """A unit string (``"deg/s"``) as an astropy unit, checked against ``like``.

    Parameters
    ----------
    text : str or astropy unit
    key : str, optional
        The field it came from, for the error.
    like : str or astropy unit, optional
        A unit it must convert to (same dimension; Hz counts cycles as in :func:`to_si`).
    error : type
        The :class:`~attitude.foundations.errors.AttitudeError` subclass to raise.

    Examples
    --------
    >>> read_unit("deg/h", like="rad/s")
    Unit("deg / h")
    >>> read_unit("kg", key="expect.x.unit", like="s")
    Traceback (most recent call last):
    ...
    attitude.foundations.errors.QuantityError: expect.x.unit: unit 'kg' cannot be converted ...
    """
    if isinstance(text, u.UnitBase):
        unit = text
    elif isinstance(text, str) and text.strip() != "" or text == "":
        try:
            unit = u.Unit(text)
        except ValueError:
            raise error(f"unknown unit {text!r}; write an astropy unit such as 'deg/s' or "
                        "'kg m2'", key=key) from None
    else:
        raise error(f"expected a unit string such as 'deg/s', got {text!r}", key=key)
    if like is not None:
        target = u.Unit(like)
        if _is_angular(target):
            unit_c = _cycles(unit)
        else:
            unit_c = unit
        if not unit_c.is_equivalent(target, equivalencies=_equivalencies(target)):
            raise error(f"unit '{text}' cannot be converted to '{_u(target)}' ({_not(target)})",
                        key=key)
    return unit


def _equivalencies(target: u.UnitBase) -> list:
    return u.dimensionless_angles() if target.physical_type != "dimensionless" else []


def _kind(unit: u.UnitBase) -> str:
    """``"a time"``, ``"an angular speed"``, ... for messages."""
    kind = str(unit.physical_type)
    if kind == "dimensionless" and unit.scale == 1:
        return "a pure number"
    if kind == "unknown":
        return f"in {unit}"
    kind = kind.split("/")[0]
    return ("an " if kind[0] in "aeiou" else "a ") + kind


def _u(unit) -> str:
    """A unit for messages: ``"1"`` for a pure number."""
    return str(unit) or "1"


def _not(unit: u.UnitBase) -> str:
    """``"not a time unit"``, ``"not a pure number"``, ... for messages."""
    kind = _kind(unit)
    if kind.startswith("in "):
        return f"not a unit of {unit}"
    return f"not {kind}" + ("" if kind == "a pure number" else " unit")


def _hint(unit: u.UnitBase) -> str:
    return f"1.5 {unit}" if str(unit) else "1.5"


def _from_table(value: Mapping, target: u.UnitBase, key, error) -> u.Quantity:
    extra = [k for k in value if k not in ("value", "unit")]
    if extra:
        raise error(f"unknown key {extra[0]!r} in a quantity table; write "
                    f"{{ value = ..., unit = \"{target}\" }}",
                    key=f"{key}.{extra[0]}" if key else str(extra[0]))
    if "value" not in value or "unit" not in value:
        missing = "value" if "value" not in value else "unit"
        raise error(f"a quantity table needs both 'value' and 'unit' (no {missing!r}); "
                    f"write {{ value = ..., unit = \"{target}\" }}", key=key)
    unit = read_unit(value["unit"], key=key, error=error)
    return _numbers(value["value"], key, error, target) * unit


def _numbers(value, key, error, target) -> np.ndarray:
    if isinstance(value, (bool, np.bool_)) or value is None or isinstance(value, (
            str, Mapping)):
        raise error(f"expected a quantity (numbers in {_u(target)}, a string such as "
                    f"'{_hint(target)}' or {{ value, unit }}), got {value!r}", key=key)
    try:
        out = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise error(f"expected numbers (in {_u(target)}), got {value!r}; a vector is "
                    "a list of numbers of equal length", key=key) from None
    if isinstance(value, (list, tuple)) and any(isinstance(x, (bool, np.bool_))
                                                for x in np.ravel(np.asarray(value, object))):
        raise error(f"expected numbers, got {value!r}", key=key)
    return out


def _shape_text(shape) -> str:
    if shape == ():
        return "a single number"
    if len(shape) == 1:
        return f"{shape[0]} number" + ("" if shape[0] == 1 else "s")
    return "x".join(map(str, shape)) + " numbers (nested lists)"


def to_si(value, unit, *, key: str | None = None, shape=None, positive: bool = False,
          nonnegative: bool = False, finite: bool = True, bounds=None,
          error: type = QuantityError, name: str | None = None):
    """Read a quantity and return it as float(s) in ``unit``.

    Parameters
    ----------
    value : float, array-like, str, astropy Quantity or mapping
        A number or numbers already in ``unit``; a string astropy parses
        (``"12.5 deg/s"``); a Quantity; or ``{"value": ..., "unit": "..."}``.
    unit : str or astropy unit
        The (SI) unit wanted: ``"s"``, ``"rad/s"``, ``"kg m2"``, ``""`` for a pure number.
        Hz counts cycles where an angle is wanted (module docstring).
    key : str, optional
        The field the value came from (``"propagation.step"``), named by the error.
    shape : tuple, or a tuple of tuples, optional
        The shape required: ``()`` a scalar, ``(3,)`` a 3-vector, ``((), (3, 3))`` either;
        default: any shape.
    positive, nonnegative : bool
        Require every value ``> 0`` (``>= 0``).
    finite : bool
        Require every value finite (default True).
    bounds : (low, high), optional
        Require ``low <= value <= high`` (in ``unit``; ``None`` for an open side).
    error : type
        The :class:`~attitude.foundations.errors.AttitudeError` subclass raised (default
        :class:`~attitude.foundations.errors.QuantityError`); constructed as ``error(message,
        key=key)``.
    name : str, optional
        Older spelling of ``key``.

    Returns
    -------
    float or ndarray
        A float for a scalar, else a new float64 array.

    Raises
    ------
    QuantityError
        (or ``error``) naming ``key``, the unit or shape wanted and how to write it.

    Examples
    --------
    >>> to_si("30 min", "s"), to_si({"value": [1, 2], "unit": "km"}, "m")
    (1800.0, array([1000., 2000.]))
    >>> to_si("1 Hz", "rad/s") / (2 * 3.141592653589793), to_si("2 1/s", "rad/s")
    (1.0, 2.0)
    >>> to_si("2.6 g/cm3", "kg/m3")
    2600.0
    >>> to_si([1, 2, 3], "s", key="propagation.duration", shape=())
    Traceback (most recent call last):
    ...
    attitude.foundations.errors.QuantityError: propagation.duration: expected a single ...
    >>> to_si("-1 s", "s", key="propagation.step", positive=True)
    Traceback (most recent call last):
    ...
    attitude.foundations.errors.QuantityError: propagation.step: must be positive, got -1 s
    """
    key = key if key is not None else name
    target = u.Unit(unit)
    if isinstance(value, (u.Quantity, Mapping, str)):
        out = _converted(_as_quantity(value, target, key, error), target, key, error)
    else:                     # numbers are already in ``unit``: no conversion to do
        out = _numbers(value, key, error, target)
    out = np.array(out, dtype=float)
    _check(out, target, key, error, shape=shape, positive=positive,
           nonnegative=nonnegative, finite=finite, bounds=bounds)
    return float(out) if out.ndim == 0 else out


def _as_quantity(value, target, key, error) -> u.Quantity:
    """A Quantity, a ``{value, unit}`` table or a string as a Quantity."""
    if isinstance(value, u.Quantity):
        return value
    if isinstance(value, Mapping):
        return _from_table(value, target, key, error)
    try:
        return u.Quantity(value)
    except (ValueError, TypeError):
        raise error(f"cannot parse {value!r} as a quantity; write a number and a unit "
                    f"such as '{_hint(target)}'", key=key) from None


def _converted(q: u.Quantity, target, key, error):
    """The value of ``q`` in ``target`` (cycles count as 2 pi where an angle is wanted)."""
    source = _cycles(q.unit) if _is_angular(target) else q.unit
    try:
        return (q.value * source).to_value(target, equivalencies=_equivalencies(target))
    except u.UnitConversionError:
        raise error(f"unit '{q.unit}' cannot be converted to '{_u(target)}' ({_not(target)}); "
                    f"write e.g. '{_hint(target)}'", key=key) from None


def _check(out, target, key, error, *, shape, positive, nonnegative, finite, bounds):
    if shape is not None:
        shapes = shape if (len(shape) and isinstance(shape[0], tuple)) else (shape,)
        if tuple(out.shape) not in shapes:
            got = _shape_text(out.shape) if out.ndim else "a single number"
            if out.size == 0:
                got = "an empty list"
            want = " or ".join(f"{_shape_text(s)} (shape {s})" for s in shapes)
            raise error(f"expected {want} in {_u(target)}, got {got} (shape {out.shape})",
                        key=key)
    if out.size == 0:
        raise error(f"expected at least one number (in {_u(target)}), got an empty list",
                    key=key)
    if finite and not np.all(np.isfinite(out)):
        raise error(f"every value must be finite, got {_show(out, target)}", key=key)
    if positive and not np.all(out > 0):
        raise error(f"must be positive, got {_show(out, target)}", key=key)
    if nonnegative and not np.all(out >= 0):
        raise error(f"must be non-negative, got {_show(out, target)}", key=key)
    if bounds is not None:
        low, high = bounds
        if (low is not None and not np.all(out >= low)) or (
                high is not None and not np.all(out <= high)):
            lo = "-inf" if low is None else f"{low:g}"
            hi = "inf" if high is None else f"{high:g}"
            raise error(f"must be within [{lo}, {hi}] {target}".rstrip()
                        + f", got {_show(out, target)}", key=key)


def _show(out: np.ndarray, target) -> str:
    text = f"{float(out):g}" if out.ndim == 0 else str(out.tolist())
    return f"{text} {target}".rstrip()


_ISO_DATE = re.compile(r"^\s*([+-]?\d{4,})-(\d{1,2})-(\d{1,2})(?:[T ](\d{1,2}):(\d{1,2})"
                       r"(?::(\d{1,2})(?:\.\d*)?)?)?")


def _date_problem(text: str) -> str | None:
    """Why an ISO date-time names no instant (``"2023-02-30"``: 28 days), or None."""
    m = _ISO_DATE.match(text)
    if m is None:
        return None
    year, month, day = (int(m.group(i)) for i in (1, 2, 3))
    if not 1 <= month <= 12:
        return f"month {month} does not exist"
    days = calendar.monthrange(year, month)[1] if 1 <= year <= 9999 else 31
    if not 1 <= day <= days:
        return (f"day {day} does not exist: {calendar.month_name[month]} {year} has "
                f"{days} days")
    hour, minute, second = (None if m.group(i) is None else int(m.group(i))
                            for i in (4, 5, 6))
    if hour is not None and hour > 23:
        return f"hour {hour} does not exist (0..23)"
    if minute is not None and minute > 59:
        return f"minute {minute} does not exist (0..59)"
    if second is not None and second > 60:
        return f"second {second} does not exist (0..59, 60 in a leap second)"
    return None


def to_time(value, *, scale: str | None = None, key: str | None = None,
            error: type = QuantityError, precision: int | None = 9) -> Time:
    """Read an epoch: an astropy ``Time``, an ISO 8601 string, or ``{value, scale}``.

    Parameters
    ----------
    value : astropy Time, str or mapping
        ``Time`` objects are returned as they are (a scalar is required);
        ``"2029-04-13T00:00:00"`` is read in ``scale``; ``{"value": "...", "scale":
        "utc"}`` carries its own scale.
    scale : str, optional
        Time scale of a string (``"tdb"``, ``"utc"``, ...; default
        :data:`DEFAULT_TIME_SCALE`, ``"tdb"``).
    key : str, optional
        The field, named by the error.
    error : type
        The :class:`~attitude.foundations.errors.AttitudeError` subclass raised.
    precision : int or None
        Decimal places of the seconds in the time's text forms (default 9; None:
        astropy's default).

    Returns
    -------
    astropy.time.Time
        A scalar time.

    Raises
    ------
    QuantityError
        (or ``error``) naming ``key``: unparseable text, a date or time of day that does
        not exist (``2023-02-30``, ``25:00``), an unknown scale, a second 60 outside a
        leap second.

    Examples
    --------
    >>> to_time("2029-04-13T00:00:00", scale="tdb").isot
    '2029-04-13T00:00:00.000000000'
    >>> to_time({"value": "2016-12-31T23:59:60", "scale": "utc"}).scale
    'utc'
    >>> to_time("2023-02-30T00:00:00", key="state.epoch")
    Traceback (most recent call last):
    ...
    attitude.foundations.errors.QuantityError: state.epoch: '2023-02-30T00:00:00' is not a ...
    """
    if isinstance(value, Time):
        if not value.isscalar:
            raise error(f"expected one epoch, got {value.shape} times", key=key)
        return value
    if isinstance(value, Mapping):
        extra = [k for k in value if k not in ("value", "scale")]
        if extra or "value" not in value:
            raise error("an epoch table is { value = \"2029-04-13T00:00:00\", scale = "
                        "\"tdb\" }", key=f"{key}.{extra[0]}" if extra and key else key)
        if "scale" in value:
            scale = value["scale"]
        value = value["value"]
    scale = DEFAULT_TIME_SCALE if scale is None else scale
    if not isinstance(scale, str) or scale.lower() not in TIME_SCALES:
        raise error(f"{scale!r} is not a time scale; use one of {', '.join(TIME_SCALES)}",
                    key=key)
    if not isinstance(value, str):
        raise error(f"expected an ISO 8601 date string such as '2029-04-13T00:00:00', got "
                    f"{value!r}", key=key)
    problem = _date_problem(value)
    if problem is not None:
        raise error(f"{value!r} is not a date: {problem}", key=key)
    try:
        with warnings.catch_warnings():
            # "time is after end of day": a second 60 outside a leap second (the "dubious
            # year" warning of future UTC dates is not an error)
            warnings.filterwarnings("ignore", message=".*dubious year",
                                    category=erfa.ErfaWarning)
            warnings.filterwarnings("error", message=".*end of day", category=erfa.ErfaWarning)
            t = Time(value, scale=scale.lower(),
                     **({} if precision is None else {"precision": precision}))
            t.jd1    # noqa: B018  (forces the conversion, so bad seconds warn here)
            if t.scale == "utc":
                t.tai    # noqa: B018  (a second 60 outside a leap second warns)
    except erfa.ErfaWarning as w:
        raise error(f"{value!r} is not a valid time in {scale.upper()} ({w}); a second 60 "
                    "only exists in a UTC leap second", key=key) from None
    except (ValueError, TypeError):
        raise error(f"cannot parse {value!r} as a time; use ISO 8601 such as "
                    "'2029-04-13T00:00:00'", key=key) from None
    if not t.isscalar:
        raise error(f"expected one epoch, got {t.shape} times", key=key)
    if not math.isfinite(float(t.jd1)):
        raise error(f"{value!r} is not a finite time", key=key)
    return t

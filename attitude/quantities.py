"""Units at the API boundary: astropy Quantities or strings in, SI floats out.

Plain numbers are taken as SI.  Strings are parsed by astropy (``"12.5 deg/s"``,
``"2.3e7 kg km2"``), with two extra units that attitude users expect: ``rev``
(one full turn) and ``rpm`` (revolutions per minute).
"""

from __future__ import annotations

import numpy as np
from astropy import units as u

__all__ = ["to_si", "rev", "rpm"]

rev = u.def_unit(["rev", "revolution"], 2 * np.pi * u.rad, doc="one full turn")
rpm = u.def_unit("rpm", rev / u.min, doc="revolutions per minute")
u.add_enabled_units([rev, rpm])


def parse_quantity(text: str) -> u.Quantity:
    """Parse ``"12.5 deg/s"`` into a Quantity (raises ``ValueError`` / ``TypeError``)."""
    return u.Quantity(text)


def to_si(value, unit, *, name: str, error=ValueError) -> np.ndarray | float:
    """Convert ``value`` to a float (array) in ``unit``.

    Parameters
    ----------
    value : float, array-like, str or astropy Quantity
        Plain numbers are already in ``unit``; strings are parsed by astropy.
    unit : str or astropy unit
        The SI unit wanted (``"kg m2"``, ``"rad/s"``, ...).
    name : str
        Name of the quantity, for error messages.
    error : type
        Exception class raised on failure.
    """
    unit = u.Unit(unit)
    if isinstance(value, str):
        try:
            value = parse_quantity(value)
        except (ValueError, TypeError) as exc:
            raise error(f"{name}: cannot parse {value!r} as a quantity ({exc}); "
                        f"write a number and a unit such as '1.5 {unit}'") from None
    if isinstance(value, u.Quantity):
        try:
            out = value.to_value(unit, equivalencies=u.dimensionless_angles()
                                 if unit.physical_type != "dimensionless" else [])
        except u.UnitConversionError:
            raise error(f"{name}: {value} has unit '{value.unit}', which cannot be "
                        f"converted to '{unit}'") from None
    else:
        try:
            out = np.asarray(value, dtype=float)
        except (TypeError, ValueError):
            raise error(f"{name}: expected a number or a quantity in {unit}, "
                        f"got {value!r}") from None
    out = np.asarray(out, dtype=float)
    return float(out) if out.ndim == 0 else out

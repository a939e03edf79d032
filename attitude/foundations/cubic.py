"""Horner's rule for the cubic pieces of tabulated paths and fields: one source for
:class:`attitude.environment.TimeTable` (numpy) and the compiled kernels'
piecewise-cubic blocks (numba)."""

from __future__ import annotations

__all__ = ["cubic_value", "cubic_rate"]


def cubic_value(c3, c2, c1, c0, d):
    """``((c3 d + c2) d + c1) d + c0``: a cubic piece at ``d`` past its breakpoint
    (coefficients highest power first, as scipy's ``PPoly``); floats or arrays.

    Examples
    --------
    >>> cubic_value(1.0, 0.0, 0.0, 2.0, 3.0)          # d^3 + 2
    29.0
    """
    return ((c3 * d + c2) * d + c1) * d + c0


def cubic_rate(c3, c2, c1, d):
    """``(3 c3 d + 2 c2) d + c1``: the derivative of :func:`cubic_value` by ``d``.

    Examples
    --------
    >>> cubic_rate(1.0, 0.0, 0.0, 3.0)                 # 3 d^2
    27.0
    """
    return (3.0 * c3 * d + 2.0 * c2) * d + c1

"""What the commands share: the exit codes and the text of numbers, durations and
expectations (no heavy imports: :mod:`attitude.app.cli` uses it to build its parser)."""

from __future__ import annotations

import math

#: The exit codes; the formatting helpers below serve the commands only.
__all__ = ["EXIT_OK", "EXIT_EXPECTATION", "EXIT_INPUT", "EXIT_PROPAGATION"]

EXIT_OK, EXIT_EXPECTATION, EXIT_INPUT, EXIT_PROPAGATION = 0, 1, 2, 3


def format_seconds(s: float, digits: int = 10) -> str:
    for unit, size in (("d", 86400.0), ("h", 3600.0), ("min", 60.0)):
        if abs(s) >= 2 * size:
            return f"{s / size:.{digits}g} {unit}"
    return f"{s:.{digits}g} s"


def number(x) -> str:
    return f"{x:.10g}" if isinstance(x, float) else str(x)


def measured(x, tolerance: float | None = None) -> str:
    """A computed value with the digits its check can tell apart: two past the
    tolerance's (``30.54`` for 30.54029651 +/- 0.3), 6 without a tolerance, 3 to 12.

    >>> measured(30.54029651019184, 0.3054), measured(27.37999999, 0.0821)
    ('30.54', '27.38')
    >>> measured(2.5e-15), measured("SAM")
    ('2.5e-15', 'SAM')
    """
    if isinstance(x, bool) or not isinstance(x, (int, float)):
        return str(x)
    x = float(x)
    digits = 6
    if tolerance and tolerance > 0 and x != 0 and math.isfinite(x):
        digits = min(max(math.floor(math.log10(abs(x) / tolerance)) + 2, 3), 12)
    return f"{x:.{digits}g}"


def expectation_cells(e: dict) -> tuple[str, str, str, str]:
    """``(key, expected, tolerance, got)`` of one expectation, as text (units included)."""
    unit = f" {e['unit']}" if "unit" in e else ""
    if "tolerance" in e:
        expected, tolerance = f"{number(e['expected'])}{unit}", f"+/- {e['tolerance']:.3g}{unit}"
    elif e["key"] in ("regime", "resonance") or isinstance(e["expected"], str):
        # resonance: the spin-orbit wing; secondary_regime: the binary wing
        expected, tolerance = e["expected"], "exact"
    else:
        expected, tolerance = f"<= {e['expected']:.3g}", "upper bound"
    # the digits the check can tell apart: the tolerance's, or 3 for an upper bound
    scale = e.get("tolerance") or (abs(e["got"]) / 10 if isinstance(e["got"], float)
                                   and e["key"] not in ("regime", "resonance") else None)
    got = "absent" if e["got"] is None else measured(e["got"], scale) + unit
    key = e["key"] + (f" (at {e['at']})" if "at" in e else "")      # spin_period
    return key, expected, tolerance, got


def expectation_line(e: dict) -> str:
    """``ok   precession: expected 27.38 +/- 0.0821 h, got 27.38 h``."""
    key, expected, tolerance, got = expectation_cells(e)
    if "tolerance" in e:
        expected = f"{number(e['expected'])} {tolerance}"
    return f"{'ok  ' if e['ok'] else 'FAIL'} {key}: expected {expected}, got {got}"



def one_line(text: str) -> str:
    """``text`` on one line (messages quoting other tools may hold newlines)."""
    return " ".join(str(text).split())

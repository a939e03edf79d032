"""One expectation of a run: what an ``[expect]`` key of a scenario file asks for.

Every ``[expect]`` key -- the periods, the spin period and its trend, the dataset
variables, the regime fractions, the nutation range, the wings' lightcurve and libration
keys -- is read into an :class:`Expectation` and checked by :meth:`Expectation.check`.
The usual form is a value with a unit and one tolerance::

    precession = { value = 27.38, unit = "h", rel_tol = 0.01 }    # or abs_tol, in `unit`

declared once by :meth:`Expectation.table` (a :class:`~attitude.foundations.spec.Table`:
the loader's checks, the JSON Schema and the key reference come from it) and read by
:meth:`Expectation.from_table`.  Exact values (``regime = "SAM"``) and upper bounds
(``energy_rel_drift = { max = 1e-12 }``) are expectations too (:meth:`Expectation.exact`,
:meth:`Expectation.at_most`).

Examples
--------
>>> from attitude.foundations.spec import validate
>>> period = Expectation.table("period", unit="s", default_unit="s")
>>> spec = validate({"value": 27.38, "unit": "h", "rel_tol": 0.01}, period)
>>> e = Expectation.from_table("precession", spec, default_unit="s")
>>> e.unit, round(e.tolerance, 4)
('h', 0.2738)
>>> e.check(27.5)["ok"], e.check(28.0)["ok"]
(True, False)
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from .spec import Key, Table

__all__ = ["Expectation", "REL_TOL", "ABS_TOL"]

#: The two tolerances of an expectation (exactly one is given).
REL_TOL = Key("rel_tol", "number", nonnegative=True, doc="relative tolerance")
ABS_TOL = Key("abs_tol", "number", nonnegative=True, doc="absolute tolerance, in `unit`")


@dataclass(frozen=True)
class Expectation:
    """What one ``[expect]`` entry asks of a run, and the check of what the run gave.

    Parameters
    ----------
    key : str
        The entry's name in reports (``"precession"``, ``"variables.w_end"``,
        ``"nutation_range.min"``).
    value : float, tuple of float or str
        The expected value, in ``unit`` (a string for an exact match).
    unit : str, optional
        Unit of ``value``, of the value the run gives and of ``abs_tol``; None for
        dimensionless entries that state none (regime fractions).
    rel_tol, abs_tol : float, optional
        The tolerance: ``|got - value| <= rel_tol * |value|`` or ``<= abs_tol`` (one of
        them; neither for exact values and bounds).
    upper_bound : bool
        ``value`` is a largest allowed value (``got <= value``).
    reported : tuple of (str, value)
        Details shown with the outcome (``(("at", "start"),)`` for ``spin_period``).
    source : tuple of (str, value)
        Where the run's value is read from (``variable``, ``at``, ``component`` of an
        ``[expect.variables]`` entry); not part of the outcome.

    Examples
    --------
    >>> Expectation.exact("regime", "SAM").check("LAM")
    {'key': 'regime', 'expected': 'SAM', 'got': 'LAM', 'ok': False}
    >>> Expectation.at_most("energy_rel_drift", 1e-12).check(3e-14)["ok"]
    True
    >>> Expectation("polhode", 3.3108, "s", rel_tol=1e-4).check(None)["ok"]   # not measured
    False
    """

    key: str
    value: Any
    unit: str | None = None
    rel_tol: float | None = None
    abs_tol: float | None = None
    upper_bound: bool = False
    reported: tuple = ()
    source: tuple = ()

    # --- construction -------------------------------------------------------------------

    @staticmethod
    def table(name: str, *, unit: str | None = "", default_unit: str | None = None,
              with_unit: bool = True, value: Key | None = None, before: tuple = (),
              after: tuple = (), unit_doc: str = "", doc: str = "") -> Table:
        """The :class:`~attitude.foundations.spec.Table` of ``{ value, unit, rel_tol |
        abs_tol }`` (the declaration the loader validates with).

        Parameters
        ----------
        name : str
        unit : str or None
            Dimension of the ``unit`` key (``"s"``, ``"rad"``, ``""`` dimensionless);
            None: any (checked by the reader).
        default_unit : str, optional
            Documented default of ``unit``.
        with_unit : bool
            False: no ``unit`` key (dimensionless values that state none).
        value : Key, optional
            The ``value`` key (default: a required number).
        before, after : tuple of Key
            More keys, declared before ``value`` / after ``unit``.
        unit_doc, doc : str

        Examples
        --------
        >>> Expectation.table("period", unit="s", default_unit="s").names()
        ('value', 'unit', 'rel_tol', 'abs_tol')
        """
        keys = list(before)
        keys.append(value or Key("value", "number", required=True))
        if with_unit:
            keys.append(Key("unit", "unit", unit=unit, default=default_unit, doc=unit_doc))
        keys += [*after, REL_TOL, ABS_TOL]
        return Table(name, tuple(keys), exactly_one=(("rel_tol", "abs_tol"),), doc=doc)

    @classmethod
    def from_table(cls, key: str, spec, *, default_unit: str | None = None,
                   reported: tuple = (), source: tuple = ()) -> Expectation:
        """The expectation of a table checked against :meth:`table`.

        Examples
        --------
        >>> Expectation.from_table("spin", {"value": 2.0, "abs_tol": 0.1}, default_unit="s")
        Expectation(key='spin', value=2.0, unit='s', rel_tol=None, abs_tol=0.1, \
upper_bound=False, reported=(), source=())
        """
        value = spec["value"]
        value = tuple(float(v) for v in value) if isinstance(value, (list, tuple)) \
            else value
        return cls(key, value, spec.get("unit", default_unit), spec.get("rel_tol"),
                   spec.get("abs_tol"), reported=tuple(reported), source=tuple(source))

    @classmethod
    def exact(cls, key: str, value) -> Expectation:
        """An expectation met by an equal value (``regime = "SAM"``)."""
        return cls(key, value)

    @classmethod
    def at_most(cls, key: str, maximum: float) -> Expectation:
        """An expectation met by a value up to ``maximum`` (``{ max = 1e-12 }``)."""
        return cls(key, maximum, upper_bound=True)

    # --- reading ------------------------------------------------------------------------

    @property
    def tolerance(self) -> float | None:
        """The absolute tolerance, in :attr:`unit` (None for exact values and bounds)."""
        if self.rel_tol is not None:
            return self.rel_tol * abs(self.value)
        return self.abs_tol

    def option(self, name: str, default=None):
        """A detail of :attr:`reported` or :attr:`source` (``e.option("at")``)."""
        return dict(self.source + self.reported).get(name, default)

    def entry(self) -> dict:
        """The expectation as a report entry: ``key``, ``expected``, ``unit`` (when
        stated), ``tolerance`` (when there is one) and the :attr:`reported` details."""
        out = {"key": self.key, "expected": list(self.value)
               if isinstance(self.value, tuple) else self.value}
        if self.unit is not None:
            out["unit"] = self.unit
        if self.tolerance is not None:
            out["tolerance"] = self.tolerance
        out.update(self.reported)
        return out

    def __getitem__(self, name: str):
        """``e["key"]``: the fields of :meth:`entry` and :attr:`source` (entries of
        ``Scenario.expect`` were dicts)."""
        entry = self.entry()
        if name in entry:
            return entry[name]
        return dict(self.source)[name]

    # --- checking -----------------------------------------------------------------------

    def met_by(self, got) -> bool:
        """Whether ``got`` (in :attr:`unit`; None: not measured) meets the expectation."""
        if got is None:
            return False
        if self.tolerance is None and not self.upper_bound:
            return bool(got == self.value)
        if not math.isfinite(got):
            return False
        if self.upper_bound:
            return bool(got <= self.value)
        return bool(abs(got - self.value) <= self.tolerance)

    def check(self, got) -> dict:
        """The outcome: :meth:`entry` with ``got`` and ``ok``.

        Examples
        --------
        >>> e = Expectation("libration_amplitude", 1.14, "deg", abs_tol=0.1)
        >>> e.check(1.2)
        {'key': 'libration_amplitude', 'expected': 1.14, 'unit': 'deg', 'tolerance': 0.1, \
'got': 1.2, 'ok': True}
        """
        return {**self.entry(), "got": got, "ok": self.met_by(got)}

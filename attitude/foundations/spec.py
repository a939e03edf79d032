"""Declarative specs of configuration tables: one source for validation, JSON Schema and
the key reference.

A :class:`Table` lists its :class:`Key` s (name, kind, unit, shape, required, sign,
choices, documentation) and the rules that tie keys together (exactly one of, at most
one of, needs, excludes).  From it come

- :func:`validate`: the checks a loader runs before any work (unknown keys with a
  did-you-mean, missing keys, wrong types, quantities read by
  :func:`attitude.foundations.quantities.to_si` with their unit, shape and sign, epochs read by
  :func:`attitude.foundations.quantities.to_time`), each failure one keyed error, and the values
  converted to SI;
- :func:`json_schema`: the JSON Schema (draft 2020-12) that editors validate against;
- :func:`markdown`: the key reference of the documentation.

The scenario file is declared with these in :mod:`attitude.app.scenario` (``SCENARIO``); torque
tables in :mod:`attitude.model.torques` (``TORQUE_TABLES``).  A new table is a new
:class:`Table` added there.

Examples
--------
>>> from attitude.foundations.spec import Key, Table, validate
>>> prop = Table("propagation", (
...     Key("duration", "quantity", unit="s", required=True, positive=True,
...         doc="how long to propagate"),
...     Key("method", "string", choices=("exact", "splitting")),
... ))
>>> validate({"duration": "2 min"}, prop)
{'duration': 120.0}
>>> validate({"duration": [1, 2, 3]}, prop, where="propagation", path="run.toml")
Traceback (most recent call last):
...
attitude.foundations.errors.AttitudeError: run.toml: propagation.duration: expected a single ...
"""

from __future__ import annotations

import difflib
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from .errors import AttitudeError
from .quantities import DEFAULT_TIME_SCALE, read_unit, to_si, to_time

__all__ = ["Key", "Table", "KINDS", "SYNONYMS", "validate", "json_schema", "markdown"]

#: Kinds of :class:`Key` values.
KINDS = ("string", "integer", "number", "boolean", "quantity", "unit", "time", "table",
         "tables", "map", "any")


@dataclass(frozen=True)
class Key:
    """One key of a table.

    Parameters
    ----------
    name : str
    kind : str
        One of :data:`KINDS`: ``"string"`` (``choices`` to restrict it), ``"integer"``,
        ``"number"`` (a plain float, e.g. a tolerance), ``"boolean"``, ``"quantity"``
        (``unit``, ``shape``; see :func:`attitude.foundations.quantities.to_si`), ``"unit"`` (a unit
        string convertible to ``unit``), ``"time"`` (an ISO 8601 epoch; its scale is the
        sibling key ``scale_key``), ``"table"`` (a sub-table, ``table``), ``"tables"`` (an
        array of tables: ``table``, or ``variants`` chosen by the key ``discriminator``),
        ``"map"`` (a table of free names, each value a ``table``; ``choices`` restricts
        the names), ``"any"`` (checked by the loader).
    unit : str, optional
        SI unit of a quantity (``""`` a pure number), or the dimension of a unit string.
    shape : tuple or tuple of tuples, optional
        Quantity shape: ``()`` scalar (default), ``(3,)``, ``((), (3, 3))`` either,
        ``None`` any.
    required : bool
    positive, nonnegative : bool
        Sign of a quantity, integer or number.
    bounds : (low, high), optional
        Closed range of a quantity or number (``None`` an open side).
    choices : tuple, optional
        Allowed values of a string (or names of a map).
    default : optional
        Documented default (not applied by :func:`validate`).
    doc : str
        One line for the reference.
    table : Table, optional
        Sub-table of ``"table"``, ``"tables"`` and ``"map"`` keys.
    variants : tuple of Table, optional
        The tables of a ``"tables"`` key, one per value of ``discriminator`` (each
        ``Table.name`` is that value).
    discriminator : str
        The key that chooses the variant (default ``"type"``).
    nonempty : bool
        A ``"map"`` needs at least one entry.
    schema : dict, optional
        The JSON Schema of the value, for a key of kind ``"any"`` whose forms the loader
        checks itself (e.g. an array of numbers or a ``{min, max, count}`` table).
    scale_key : str
        For ``"time"`` keys: the sibling key holding the time scale (default
        ``"time_scale"``; :data:`~attitude.foundations.quantities.DEFAULT_TIME_SCALE`,
        ``"tdb"``, when absent).

    Examples
    --------
    >>> Key("step", "quantity", unit="s", positive=True).describe()
    'quantity (s), > 0'
    """

    name: str
    kind: str
    unit: str | None = None
    shape: tuple | None = ()
    required: bool = False
    positive: bool = False
    nonnegative: bool = False
    bounds: tuple | None = None
    choices: tuple | None = None
    default: Any = None
    doc: str = ""
    table: Table | None = None
    variants: tuple = ()
    discriminator: str = "type"
    scale_key: str = "time_scale"
    nonempty: bool = False
    schema: dict | None = None

    def __post_init__(self):
        if self.kind not in KINDS:
            raise ValueError(f"Key {self.name!r}: kind {self.kind!r} is not one of {KINDS}")

    def describe(self) -> str:
        """The type column of the reference: kind, unit, shape, sign."""
        kind = self.kind
        if kind == "quantity":
            shapes = _shapes(self.shape)
            text = "quantity" if shapes == [()] else "quantity " + " or ".join(
                "scalar" if s == () else "x".join(map(str, s)) if s else "array"
                for s in shapes)
            text += f" ({self.unit or '1'})"
        elif kind == "unit":
            text = f"unit (like {self.unit or '1'})"
        elif kind == "tables":
            text = "array of tables"
        elif kind == "map":
            text = "table of named tables"
        elif kind == "time":
            text = "epoch (ISO 8601)"
        else:
            text = kind
        if self.positive:
            text += ", > 0"
        if self.nonnegative:
            text += ", >= 0"
        if self.bounds is not None:
            lo, hi = self.bounds
            text += f", in [{'-inf' if lo is None else f'{lo:g}'}, " \
                    f"{'inf' if hi is None else f'{hi:g}'}]"
        if self.choices and kind == "string":
            text += ": " + ", ".join(f"`{c}`" for c in self.choices)
        return text


@dataclass(frozen=True)
class Table:
    """A table of keys and the rules between them.

    Parameters
    ----------
    name : str
        The table's name (``"propagation"``; for a variant of a ``"tables"`` key, the
        discriminator value, e.g. ``"gravity_gradient"``).
    keys : tuple of Key
    array_of_tables : bool
        Written ``[[name]]`` (documentation only: the parent key's kind says it).
    doc : str
        One paragraph for the reference.
    exactly_one : tuple of tuples of str
        Groups of keys of which exactly one is given.
    at_most_one : tuple of tuples of str
        Groups of keys of which at most one is given.
    needs : tuple of (str, tuple of str)
        ``(key, (others...))``: when ``key`` is given, so must the others be.
    excludes : tuple of (str, tuple of str)
        ``(key, (others...))``: when ``key`` is given, the others may not be.
    open : bool
        Unknown keys allowed (checked by the loader).
    title : str
        Section title of the reference (default: ``[name]``).

    Examples
    --------
    >>> t = Table("tol", (Key("rel_tol", "number"), Key("abs_tol", "number")),
    ...           exactly_one=(("rel_tol", "abs_tol"),))
    >>> validate({"rel_tol": 0.1, "abs_tol": 1.0}, t, where="expect.x")
    Traceback (most recent call last):
    ...
    attitude.foundations.errors.AttitudeError: expect.x.abs_tol: give exactly one of ...
    """

    name: str
    keys: tuple
    array_of_tables: bool = False
    doc: str = ""
    exactly_one: tuple = ()
    at_most_one: tuple = ()
    needs: tuple = ()
    excludes: tuple = ()
    open: bool = False
    title: str = ""
    by_name: dict = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        object.__setattr__(self, "by_name", {k.name: k for k in self.keys})

    def __getitem__(self, name: str) -> Key:
        return self.by_name[name]

    def __contains__(self, name) -> bool:
        return name in self.by_name

    def names(self) -> tuple[str, ...]:
        """The key names, in declaration order."""
        return tuple(self.by_name)

    def with_keys(self, *keys: Key, **changes) -> Table:
        """A copy with ``keys`` added (or replaced, by name) and fields changed: how
        another module extends a table (``SCENARIO.with_keys(Key("photometry", ...))``).

        Examples
        --------
        >>> t = Table("x", (Key("a", "integer"),)).with_keys(Key("b", "boolean"))
        >>> t.names()
        ('a', 'b')
        """
        merged = dict(self.by_name)
        merged.update({k.name: k for k in keys})
        fields = {f: getattr(self, f) for f in ("name", "array_of_tables", "doc",
                                                  "exactly_one", "at_most_one", "needs",
                                                  "excludes", "open", "title")}
        fields.update(changes)
        return Table(keys=tuple(merged.values()), **fields)


def _shapes(shape) -> list:
    if shape is None:
        return [None]
    if len(shape) and isinstance(shape[0], tuple):
        return list(shape)
    return [tuple(shape)]


# --- validation ------------------------------------------------------------------------


def _join(where: str, name) -> str:
    return f"{where}.{name}" if where else str(name)


#: Names users write for keys (lower case) -> the key meant, for did-you-mean hints.
SYNONYMS = {
    "eccentricity": "e", "inclination": "i", "semi_major_axis": "a", "semimajor_axis": "a",
    "sma": "a", "right_ascension": "raan", "node": "raan", "omega": "argp",
    "argument_of_periapsis": "argp", "argument_of_perigee": "argp", "arg_periapsis": "argp",
    "m0": "mean_anomaly", "m": "mean_anomaly", "tau": "time_constant",
    "timescale": "time_constant", "gm": "mu", "vector": "torque", "value": "torque",
    "conductivity_tensor": "magnetic_tensor", "tensor": "magnetic_tensor",
    "l": "pivot_to_com", "com": "pivot_to_com", "gravity": "g",
}


def _unknown(name, allowed, key: str, error, path) -> AttitudeError:
    allowed = [str(a) for a in allowed]
    hint = SYNONYMS.get(str(name).lower())
    if hint not in allowed:
        near = difflib.get_close_matches(str(name), allowed, n=1)
        hint = near[0] if near else None
    did = f"; did you mean '{hint}'?" if hint else ""
    return error(f"unknown key{did} (allowed keys: {', '.join(allowed) or 'none'})",
                 key=key, path=path)


def _type_name(value) -> str:
    return {dict: "a table", list: "an array", str: "a string", bool: "a boolean",
            int: "an integer", float: "a number"}.get(type(value), type(value).__name__)


def validate(doc, table: Table, *, where: str = "", path=None,
             error: type = AttitudeError) -> dict:
    """Check ``doc`` (a parsed TOML table) against ``table`` and convert its values.

    Parameters
    ----------
    doc : mapping
    table : Table
    where : str
        Key path of ``doc`` itself (``"torques[0]"``), prefixed to every key.
    path : str, optional
        The file, named by the error.
    error : type
        The :class:`~attitude.foundations.errors.AttitudeError` subclass raised, as
        ``error(message, key=..., path=...)``.

    Returns
    -------
    dict
        The keys given, with quantities as SI floats/arrays, epochs as astropy ``Time``,
        sub-tables as dicts, arrays of tables as lists of dicts (other values as given).

    Raises
    ------
    AttitudeError
        (``error``) naming the file and the key: unknown key, missing key, wrong type,
        wrong length, empty, non-finite, wrong sign, date that does not exist, unit of
        the wrong dimension, broken rule between keys.

    Examples
    --------
    >>> steps = Table("propagation", (
    ...     Key("duration", "quantity", unit="s", required=True, positive=True),
    ...     Key("step", "quantity", unit="s", positive=True),
    ... ))
    >>> validate({"duration": "1 h", "step": {"value": 30, "unit": "s"}}, steps)
    {'duration': 3600.0, 'step': 30.0}
    >>> try:
    ...     validate({"duration": "1 h", "stepp": 30}, steps, where="propagation",
    ...              path="run.toml")
    ... except AttitudeError as err:
    ...     print(err.key, "|", err.path)
    propagation.stepp | run.toml
    """
    if not isinstance(doc, Mapping):
        raise error(f"expected a table, got {_type_name(doc)} {doc!r}"[:200], key=where or None,
                    path=path)
    if not table.open:
        for name in doc:
            if name not in table:
                raise _unknown(name, table.names(), _join(where, name), error, path)
    for key in table.keys:
        if key.required and key.name not in doc:
            raise error("missing key" + (f" ({key.doc})" if key.doc else ""),
                        key=_join(where, key.name), path=path)
    _rules(doc, table, where, path, error)
    out = {}
    # epochs last: their time scale is a sibling key, checked first
    for name in sorted(doc, key=lambda n: n in table and table[n].kind == "time"):
        key = table.by_name.get(name)
        value = doc[name]
        out[name] = value if key is None else _value(value, key, doc, _join(where, name),
                                                     path, error)
    return {name: out[name] for name in doc}


def _rules(doc, table: Table, where, path, error) -> None:
    for name, others in table.excludes:
        if name in doc:
            for other in others:
                if other in doc:
                    what = _join(where, name) if where else f"[{name}]"
                    raise error(f"not with {what}", key=_join(where, other), path=path)
    for name, others in table.needs:
        if name in doc:
            for other in others:
                if other not in doc:
                    raise error(f"missing key (needed with {_join(where, name)})",
                                key=_join(where, other), path=path)
    for group in table.at_most_one:
        given = [k for k in group if k in doc]
        if len(given) > 1:
            raise error(f"give at most one of {', '.join(group)}",
                        key=_join(where, given[1]), path=path)
    for group in table.exactly_one:
        given = [k for k in group if k in doc]
        if len(given) != 1:
            raise error(f"give exactly one of {', '.join(group)} (got "
                        f"{', '.join(given) or 'none'})",
                        key=_join(where, given[1]) if len(given) > 1 else (
                            where or group[0]),
                        path=path)


def _number_checks(x: float, key: Key, where, path, error) -> None:
    if key.positive and not x > 0:
        raise error(f"must be positive, got {x!r}", key=where, path=path)
    if key.nonnegative and not x >= 0:
        raise error(f"must be non-negative, got {x!r}", key=where, path=path)
    if key.bounds is not None:
        lo, hi = key.bounds
        if (lo is not None and not x >= lo) or (hi is not None and not x <= hi):
            span = (f"within [{lo}, {hi}]" if lo is not None and hi is not None else
                    f"at least {lo}" if lo is not None else f"at most {hi}")
            raise error(f"must be {span}, got {x!r}", key=where, path=path)


def _value(value, key: Key, parent: Mapping, where: str, path, error):
    kind = key.kind
    if kind == "quantity":
        try:
            return to_si(value, key.unit or "", key=where, shape=key.shape,
                         positive=key.positive, nonnegative=key.nonnegative,
                         bounds=key.bounds, error=error)
        except AttitudeError as exc:
            raise error(exc.reason, key=exc.key, path=path) from None
    if kind == "time":
        scale = parent.get(key.scale_key, DEFAULT_TIME_SCALE)
        scale = scale if isinstance(scale, str) else DEFAULT_TIME_SCALE
        try:
            return to_time(value, scale=scale.lower(), key=where, error=error)
        except AttitudeError as exc:
            raise error(exc.reason, key=exc.key, path=path) from None
    if kind == "unit":
        try:
            read_unit(value, key=where, like=key.unit, error=error)
        except AttitudeError as exc:
            raise error(exc.reason, key=exc.key, path=path) from None
        return value
    if kind == "string":
        if not isinstance(value, str):
            raise error(f"expected a string, got {_type_name(value)} {value!r}"[:200],
                        key=where, path=path)
        if key.choices is not None and value not in key.choices:
            near = difflib.get_close_matches(value, [str(c) for c in key.choices], n=1)
            hint = f"did you mean '{near[0]}'? " if near else ""
            raise error(f"unknown {key.name} {value!r}; {hint}choose one of "
                        f"{', '.join(map(str, key.choices))}", key=where, path=path)
        return value
    if kind == "boolean":
        if not isinstance(value, bool):
            raise error(f"expected true or false, got {value!r}"[:200], key=where, path=path)
        return value
    if kind == "integer":
        if isinstance(value, bool) or not isinstance(value, int):
            raise error(f"expected an integer, got {_type_name(value)} {value!r}"[:200],
                        key=where, path=path)
        if key.choices is not None and value not in key.choices:
            raise error(f"expected one of {', '.join(map(str, key.choices))}, got {value!r}",
                        key=where, path=path)
        _number_checks(value, key, where, path, error)
        return value
    if kind == "number":
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise error(f"expected a number, got {_type_name(value)} {value!r}"[:200],
                        key=where, path=path)
        if not math.isfinite(value):
            raise error(f"must be finite, got {value!r}", key=where, path=path)
        _number_checks(float(value), key, where, path, error)
        return float(value)
    if kind == "table":
        return validate(value, key.table, where=where, path=path, error=error)
    if kind == "map":
        if not isinstance(value, Mapping):
            raise error(f"expected a table, got {_type_name(value)}", key=where, path=path)
        if key.choices is not None:
            for name in value:
                if name not in key.choices:
                    raise _unknown(name, key.choices, _join(where, name), error, path)
        if not value and key.nonempty:
            raise error("expected a non-empty table", key=where, path=path)
        return {name: validate(v, key.table, where=_join(where, name), path=path,
                               error=error) for name, v in value.items()}
    if kind == "tables":
        if not isinstance(value, list) or not all(isinstance(v, Mapping) for v in value):
            raise error(f"expected an array of tables [[{key.name}]], got "
                        f"{_type_name(value)}", key=where, path=path)
        return [_variant(v, key, f"{where}[{i}]", path, error) for i, v in enumerate(value)]
    return value


def _variant(value: Mapping, key: Key, where: str, path, error) -> dict:
    if not key.variants:
        return validate(value, key.table, where=where, path=path, error=error)
    names = [t.name for t in key.variants]
    d = key.discriminator
    if d not in value:
        raise error(f"missing key; choose one of {', '.join(names)}", key=_join(where, d),
                    path=path)
    kind = value[d]
    if not isinstance(kind, str) or kind not in names:
        near = difflib.get_close_matches(kind, names, n=1) if isinstance(kind, str) else []
        hint = f"did you mean '{near[0]}'? " if near else ""
        raise error(f"unknown {d} {kind!r}; {hint}choose one of {', '.join(names)}"[:300],
                    key=_join(where, d), path=path)
    table = key.variants[names.index(kind)]
    return validate(value, table.with_keys(Key(d, "string")) if d not in table else table,
                    where=where, path=path, error=error)


# --- JSON Schema ---------------------------------------------------------------------

_QUANTITY_DOC = ("a number (SI), a string astropy parses ('30 d', '2.3e7 kg km2'), or "
                 "{ value, unit }")


def _array(shape: tuple) -> dict:
    if not shape:
        return {"type": "number"}
    return {"type": "array", "minItems": shape[0], "maxItems": shape[0],
            "items": _array(shape[1:])}


def _quantity_schema(key: Key) -> dict:
    forms = []
    for shape in _shapes(key.shape):
        if shape is None:
            numbers = {"anyOf": [{"type": "number"}, {"type": "array"}]}
        else:
            numbers = _array(shape)
        if shape == () and (key.positive or key.nonnegative):
            numbers = dict(numbers, **({"exclusiveMinimum": 0} if key.positive
                                       else {"minimum": 0}))
        forms.append(numbers)
        if shape in ((), None):
            forms.append({"type": "string"})
        forms.append({"type": "object", "properties": {"value": numbers if shape else
                                                       {"type": "number"},
                                                       "unit": {"type": "string"}},
                      "required": ["value", "unit"], "additionalProperties": False})
    unique = []
    for f in forms:
        if f not in unique:
            unique.append(f)
    return {"anyOf": unique}


def _key_schema(key: Key) -> dict:
    kind = key.kind
    if kind == "quantity":
        out = _quantity_schema(key)
    elif kind == "string":
        out = {"enum": list(key.choices)} if key.choices else {"type": "string"}
    elif kind == "integer":
        out = {"enum": list(key.choices)} if key.choices else {"type": "integer"}
        if key.positive:
            out["minimum"] = 1
        elif key.nonnegative:
            out["minimum"] = 0
    elif kind == "number":
        out = {"type": "number"}
        if key.positive:
            out["exclusiveMinimum"] = 0
        elif key.nonnegative:
            out["minimum"] = 0
        if key.bounds is not None:
            if key.bounds[0] is not None:
                out["minimum"] = key.bounds[0]
            if key.bounds[1] is not None:
                out["maximum"] = key.bounds[1]
    elif kind == "boolean":
        out = {"type": "boolean"}
    elif kind in ("unit", "time"):
        out = {"type": "string"}
    elif kind == "table":
        out = json_schema(key.table, root=False)
    elif kind == "map":
        out = {"type": "object", "additionalProperties": json_schema(key.table, root=False)}
        if key.choices is not None:
            out["propertyNames"] = {"enum": list(key.choices)}
        if key.nonempty:
            out["minProperties"] = 1
    elif kind == "tables":
        if key.variants:
            items = {"oneOf": [json_schema(t, root=False, const=(key.discriminator, t.name))
                               for t in key.variants]}
        else:
            items = json_schema(key.table, root=False)
        out = {"type": "array", "items": items}
    else:
        out = {}
    if key.schema is not None:
        out = dict(key.schema)
    doc = key.doc
    if key.unit is not None and kind == "quantity":
        doc = (doc + "; " if doc else "") + f"in {key.unit or '1'}: {_QUANTITY_DOC}"
    if doc:
        out = {"description": doc, **out}
    return out


def json_schema(table: Table, *, root: bool = True, const=None, title: str = "",
                description: str = "") -> dict:
    """The JSON Schema (draft 2020-12) of ``table``.

    Examples
    --------
    >>> t = Table("p", (Key("step", "quantity", unit="s", required=True),))
    >>> json_schema(t, root=False)["required"]
    ['step']
    """
    props = {}
    for key in table.keys:
        props[key.name] = _key_schema(key)
    if const is not None:
        props[const[0]] = {"const": const[1]}
    out: dict = {}
    if root:
        out["$schema"] = "https://json-schema.org/draft/2020-12/schema"
        out["$id"] = "https://github.com/attitude/attitude/docs/scenario.schema.json"
        if title:
            out["title"] = title
        if description:
            out["description"] = description
    elif table.doc:
        out["description"] = table.doc
    out["type"] = "object"
    out["properties"] = props
    if not table.open:
        out["additionalProperties"] = False
    required = [k.name for k in table.keys if k.required]
    if const is not None and const[0] not in required:
        required.insert(0, const[0])
    if required:
        out["required"] = required
    rules = []
    for group in table.exactly_one:
        rules.append({"oneOf": [{"required": [k]} for k in group]})
    for group in table.at_most_one:
        rules.append({"not": {"anyOf": [{"required": [a, b]} for i, a in enumerate(group)
                                        for b in group[i + 1:]]}})
    if table.needs:
        out["dependentRequired"] = {k: list(v) for k, v in table.needs}
    if table.excludes:
        out["dependentSchemas"] = {k: {"not": {"anyOf": [{"required": [o]} for o in v]}}
                                   for k, v in table.excludes}
    if len(rules) == 1:
        out.update(rules[0])
    elif rules:
        out["allOf"] = rules
    return out


# --- markdown reference ----------------------------------------------------------------


def _rows(table: Table, prefix: str) -> list[str]:
    rows = []
    for key in table.keys:
        name = f"{prefix}{key.name}"
        req = "yes" if key.required else ""
        doc = key.doc
        if key.default is not None:
            doc = (doc + "; " if doc else "") + f"default `{key.default}`"
        rows.append(f"| `{name}` | {key.describe()} | {req} | {doc} |")
        if key.kind == "table":
            rows += _rows(key.table, f"{name}.")
        elif key.kind == "map":
            rows += _rows(key.table, f"{name}.<name>.")
        elif key.kind == "tables" and key.variants:     # nested arrays of tables
            for variant in key.variants:
                rows += _rows(variant, f"{name}[{key.discriminator}={variant.name}].")
        elif key.kind == "tables" and key.table is not None:
            rows += _rows(key.table, f"{name}[].")       # each table of the array
    return rows


def _rules_text(table: Table) -> list[str]:
    out = [f"exactly one of {', '.join(f'`{k}`' for k in g)}" for g in table.exactly_one]
    out += [f"at most one of {', '.join(f'`{k}`' for k in g)}" for g in table.at_most_one]
    out += [f"`{k}` needs {', '.join(f'`{o}`' for o in v)}" for k, v in table.needs]
    out += [f"`{k}` excludes {', '.join(f'`{o}`' for o in v)}" for k, v in table.excludes]
    return out


def markdown(table: Table, *, level: int = 3) -> str:
    """The key reference of ``table``'s sub-tables as markdown (one section each).

    Examples
    --------
    >>> t = Table("", (Key("propagation", "table", table=Table("propagation", (
    ...     Key("step", "quantity", unit="s", required=True, doc="output step"),))),))
    >>> print(markdown(t))
    ### `[propagation]`
    <BLANKLINE>
    | key | type | required | meaning |
    | --- | --- | --- | --- |
    | `step` | quantity (s) | yes | output step |
    <BLANKLINE>
    """
    sections = []
    for key in table.keys:
        if key.kind not in ("table", "tables"):
            continue
        tables = key.variants or (key.table,)
        for sub in tables:
            if key.kind == "tables":
                title = f"`[[{key.name}]]`" + (f" with `{key.discriminator} = \"{sub.name}\"`"
                                              if key.variants else "")
            else:
                title = sub.title or f"`[{key.name}]`"
            lines = [f"{'#' * level} {title}", ""]
            doc = sub.doc or key.doc
            if doc:
                lines += [doc, ""]
            lines += ["| key | type | required | meaning |", "| --- | --- | --- | --- |"]
            lines += _rows(sub, "")
            rules = _rules_text(sub)
            for k in sub.keys:
                if k.kind == "table":
                    rules += [f"in `{k.name}`: {r}" for r in _rules_text(k.table)]
                elif k.kind == "tables" and k.table is not None and not k.variants:
                    rules += [f"in each `{k.name}[]`: {r}" for r in _rules_text(k.table)]
                elif k.kind == "tables":
                    rules += [f"in each `{k.name}[{k.discriminator}={v.name}]`: {r}"
                              for v in k.variants for r in _rules_text(v)]
            if rules:
                lines += ["", "Rules: " + "; ".join(rules) + "."]
            sections.append("\n".join(lines) + "\n")
    return "\n".join(sections)

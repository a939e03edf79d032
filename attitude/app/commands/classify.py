"""``attitude classify``: the regime of the rotation in an ephemeris file."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np

from ...analysis.classification import classification_json, classify, format_classification
from ...analysis.statistics import classify_ensemble, regime_fractions
from ...formats.spice_read import is_ck
from ...foundations.errors import EphemerisFormatError, QuantityError, ScenarioError
from ...foundations.quantities import read_unit
from ...model.body import RigidBody
from ...model.ephemeris import Ephemeris
from ..scenario import load_scenario
from .common import EXIT_OK

#: Nothing public: :func:`attitude.app.cli.main` runs ``command(args)`` (the command line
#: is the interface, tested in tests/app/test_cli.py).
__all__ = []


def command(args) -> int:
    if is_ck(args.ephemeris) and Path(args.ephemeris).is_file():
        raise EphemerisFormatError(
            "a SPICE C-kernel: convert it to netCDF first (attitude convert "
            f"{args.ephemeris} OUT.nc --sclk FILE.tsc ...), then classify OUT.nc with "
            "--body SCENARIO.toml or --inertia A,B,C")
    eph = Ephemeris.from_netcdf(args.ephemeris)
    body = _given_body(args)
    if eph.is_batch:
        if body is not None:
            raise EphemerisFormatError("--body/--inertia: an ensemble file carries the "
                                       "bodies of its members")
        return _classify_batch(eph, args)
    if body is not None:
        eph = eph.with_body(body)
    elif "inertia" not in eph.dataset.attrs:
        raise EphemerisFormatError(
            "the ephemeris has no mass properties (no inertia attribute: read from a "
            "CCSDS AEM or a SPICE CK?): give the body with --body SCENARIO.toml (its "
            "[body] table) or --inertia A,B,C (principal moments, kg m2)")
    result = classify(eph)
    results = result if isinstance(result, list) else [result]
    if args.json:
        docs = [classification_json(c) for c in results]
        print(json.dumps(docs if isinstance(result, list) else docs[0], indent=2,
                         default=float))
    else:
        print("\n\n".join(format_classification(c) for c in results))
    return EXIT_OK


def _classify_batch(eph, args) -> int:
    """An ensemble file: each body classified (``attitude.ensemble.classify_ensemble``),
    one line per body and the regime fractions; bodies that cannot be classified are
    listed with the reason and do not stop the others."""
    table = classify_ensemble(eph)
    names = (eph.dataset["body_name"].values if "body_name" in eph.dataset.coords
             else [""] * table.sizes["body"])
    fractions = regime_fractions(table)
    if args.json:
        rows = [{"body": int(i), "name": str(n), "regime": str(r),
                 "confidence": None if c != c else float(c), "reason": str(why)}
                for i, n, r, c, why in zip(table.body.values, names, table.regime.values,
                                            table.confidence.values, table.reason.values)]
        print(json.dumps({"regime_fractions": fractions, "bodies": rows}, indent=2))
        return EXIT_OK
    for i, n, r, c, why in zip(table.body.values, names, table.regime.values,
                               table.confidence.values, table.reason.values):
        label = f"body {i}" + (f" ({n})" if n else "")
        print(f"{label:<24} {r}" + (f" (confidence {c:.2f})" if c == c else f": {why}"))
    print("Regimes    " + (", ".join(f"{k} {100 * v:.1f} %" for k, v in fractions.items())
                           or "none classified"))
    return EXIT_OK


def _given_body(args) -> RigidBody | None:
    """The body of ``--body SCENARIO.toml`` or ``--inertia``, or None (not both)."""
    scenario, inertia = getattr(args, "body", None), getattr(args, "inertia", None)
    if scenario is not None and inertia is not None:
        raise ScenarioError("give the body once: --body SCENARIO.toml or --inertia, not both")
    if scenario is not None:
        loaded = load_scenario(scenario)
        if loaded.ensemble is not None:
            raise ScenarioError("an [ensemble] scenario has no single [body]: use a "
                                "scenario with a [body] table, or --inertia",
                                path=scenario, key="body")
        return loaded.body
    if inertia is not None:
        return _inertia_body(inertia)
    return None


_NUMBERS = re.compile(r"^\s*\[?\s*([^,\s\]]+(?:\s*,\s*[^,\s\]]+)*)\s*\]?\s*(.*?)\s*$")


def _inertia_body(text: str) -> RigidBody:
    """The body of ``--inertia``: 3 principal moments ``"A,B,C"`` about the body x, y, z
    axes (the order matters: the ephemeris' rates are in those axes) or 9 numbers (the
    tensor, row-major), in kg m^2 unless a unit follows (``"1,2,3 kg km2"``)."""
    match = _NUMBERS.match(text)
    try:
        values = np.array([float(v) for v in match.group(1).split(",")]) if match else None
    except ValueError:
        values = None
    if values is None or values.size not in (3, 9):
        raise QuantityError(f"{text!r}: expected 3 principal moments 'A,B,C' or 9 "
                            "numbers (the tensor, row-major), kg m2 unless a unit follows "
                            "('1,2,3 kg km2')", key="--inertia")
    unit = match.group(2)
    if unit:
        values = values * read_unit(unit, key="--inertia", like="kg m2").to("kg m2")
    if values.size == 3:
        return RigidBody.from_principal_moments(values)
    return RigidBody(values.reshape(3, 3))

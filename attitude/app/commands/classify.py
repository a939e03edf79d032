"""``attitude classify``: the regime of the rotation in an ephemeris file."""

from __future__ import annotations

import json

from ...analysis.classification import classification_json, classify, format_classification
from ...analysis.statistics import classify_ensemble, regime_fractions
from ...model.ephemeris import Ephemeris
from .common import EXIT_OK

#: Nothing public: :func:`attitude.app.cli.main` runs ``command(args)`` (the command line
#: is the interface, tested in tests/app/test_cli.py).
__all__ = []


def command(args) -> int:
    eph = Ephemeris.from_netcdf(args.ephemeris)
    if eph.is_batch:
        return _classify_batch(eph, args)
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

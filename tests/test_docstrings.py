"""Every public definition of ``attitude`` has a numpydoc ``Examples`` section with a
doctest (issue 13).

Public means: listed in the module's ``__all__``, or, in a module without ``__all__``, a
name that does not start with ``_``.  Classes count once, at class level.  The doctests
themselves run with ``pytest --doctest-modules attitude/``; this test only checks that
they exist.
"""

from __future__ import annotations

import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "attitude"

#: Definitions still without a doctest, in files being changed on another branch;
#: to be emptied when those changes land.
ALLOWLIST: dict[str, set[str]] = {}


def _public_without_doctest(path: Path) -> list[str]:
    tree = ast.parse(path.read_text(encoding="utf-8"))
    names = None
    for node in tree.body:
        if isinstance(node, ast.Assign) and any(
                getattr(t, "id", None) == "__all__" for t in node.targets):
            try:
                names = set(ast.literal_eval(node.value))
            except ValueError:
                pass
    missing = []
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.ClassDef)) and not node.name.startswith("_"):
            if names is not None and node.name not in names:
                continue
            if ">>>" not in (ast.get_docstring(node) or ""):
                missing.append(node.name)
    return missing


def _missing() -> dict[str, set[str]]:
    out = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        names = _public_without_doctest(path)
        if names:
            out[path.relative_to(PACKAGE.parent).as_posix()] = set(names)
    return out


def test_every_public_definition_has_a_doctest():
    missing = _missing()
    unexpected = {f: sorted(n - ALLOWLIST.get(f, set())) for f, n in missing.items()}
    unexpected = {f: n for f, n in unexpected.items() if n}
    assert not unexpected, ("public definitions without an Examples section (>>>): "
                            f"{unexpected}")


def test_allowlist_is_not_stale():
    """An allowlisted name that has gained a doctest (or gone) must leave the list."""
    missing = _missing()
    stale = {f: sorted(n - missing.get(f, set())) for f, n in ALLOWLIST.items()}
    stale = {f: n for f, n in stale.items() if n}
    assert not stale, f"remove from ALLOWLIST (they have a doctest now): {stale}"


def test_the_check_sees_a_missing_doctest(tmp_path):
    """The scanner itself: a public function with prose only is reported, a private one
    and a name left out of ``__all__`` are not."""
    module = tmp_path / "m.py"
    module.write_text('__all__ = ["f", "g"]\n'
                      'def f():\n    """Prose only."""\n'
                      'def g():\n    """Doc.\n\n    >>> 1\n    1\n    """\n'
                      'def h():\n    """Not exported."""\n'
                      'def _p():\n    """Private."""\n')
    assert _public_without_doctest(module) == ["f"]

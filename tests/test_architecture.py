"""The package's structure (docs/architecture.md): no import cycles, no private names
reached across modules, imports inside functions only for optional or costly
dependencies, and every public name of earlier releases still importable."""

from __future__ import annotations

import argparse
import ast
import importlib
import pathlib
import warnings

import pytest

import attitude

ROOT = pathlib.Path(attitude.__file__).parent

def _modules():
    for path in sorted(ROOT.rglob("*.py")):
        rel = path.relative_to(ROOT.parent).with_suffix("")
        parts = list(rel.parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        yield ".".join(parts), path


def _resolve(module: str, node: ast.ImportFrom, is_package: bool) -> str:
    if node.level == 0:
        return node.module or ""
    base = module.split(".")
    if not is_package:
        base = base[:-1]
    base = base[: len(base) - (node.level - 1)]
    return ".".join(base + ([node.module] if node.module else []))


def _graph():
    """``{module: {imported attitude module: [(lineno, in_function, names)]}}``."""
    graph = {}
    for name, path in _modules():
        tree = ast.parse(path.read_text())
        is_package = path.name == "__init__.py"
        edges = {}
        func_lines = set()
        for node in ast.walk(tree):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                for sub in ast.walk(node):
                    if isinstance(sub, (ast.Import, ast.ImportFrom)):
                        func_lines.add(sub.lineno)
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom):
                target = _resolve(name, node, is_package)
                for alias in node.names:
                    full = f"{target}.{alias.name}"
                    dest = full if importlib.util.find_spec is not None and (
                        ROOT.parent / full.replace(".", "/")).with_suffix(".py").exists() \
                        or (ROOT.parent / full.replace(".", "/") / "__init__.py").exists() \
                        else target
                    edges.setdefault(dest, []).append(
                        (node.lineno, node.lineno in func_lines, alias.name))
            elif isinstance(node, ast.Import):
                for alias in node.names:
                    edges.setdefault(alias.name, []).append(
                        (node.lineno, node.lineno in func_lines, alias.name))
        graph[name] = edges
    for name, (table, _) in IMPORTS_BY_NAME.items():
        if table is not None:       # the modules it imports by name count as its imports
            for dest in getattr(importlib.import_module(name), table).values():
                graph[name].setdefault(dest, []).append((0, False, dest.rsplit(".", 1)[-1]))
    return graph


#: Modules allowed to import by name (``importlib.import_module``): the table of the names
#: they import (its values count as their imports in the cycle test), or None, and why.
IMPORTS_BY_NAME = {
    "attitude": (None, "the public names, each imported on first use (PEP 562); the package "
                       "namespace is outside the cycle test"),
    "attitude.deprecation": (None, "the module paths of earlier releases, forwarded to "
                                   "their new homes (deprecation.MOVED_MODULES)"),
    "attitude.app.cli": ("COMMANDS", "each command's module is imported when it runs, so "
                                     "that `attitude --help` loads no numpy (issue 25)"),
}


GRAPH = _graph()


def _internal(graph):
    mods = set(graph)
    return {m: {d for d in edges if d in mods and d != m} for m, edges in graph.items()}


def test_no_import_cycle():
    """No module imports a module that imports it back, directly or through others
    (imports inside functions count; a package counts as importing its ``__init__``'s
    imports)."""
    g = _internal(GRAPH)
    # importing a.b.c runs a/__init__ and a/b/__init__ first
    for m in list(g):
        for d in list(g[m]):
            parts = d.split(".")
            for k in range(2, len(parts)):
                parent = ".".join(parts[:k])
                if parent in g and parent != m and not m.startswith(parent + "."):
                    g[m].add(parent)
    cycles = []
    state = {}

    def visit(m, stack):
        state[m] = 1
        stack.append(m)
        for d in sorted(g[m]):
            if d == "attitude":      # the package namespace (curated re-exports)
                continue
            if state.get(d) == 1:
                cycles.append(stack[stack.index(d):] + [d])
            elif d not in state:
                visit(d, stack)
        stack.pop()
        state[m] = 2

    for m in sorted(g):
        if m not in state and m != "attitude":
            visit(m, [])
    assert not cycles, "import cycles: " + "; ".join(" -> ".join(c) for c in cycles)


def test_no_private_name_imported_across_modules():
    bad = []
    for module, edges in GRAPH.items():
        for dest, uses in edges.items():
            if not dest.startswith("attitude"):
                continue
            for lineno, _, alias in uses:
                if alias.startswith("_") and not alias.startswith("__"):
                    bad.append(f"{module}:{lineno} imports {dest}.{alias}")
            if any(p.startswith("_") and not p.startswith("__") for p in dest.split(".")):
                bad.append(f"{module} imports the private module {dest}")
    assert not bad, "\n".join(bad)


def test_imports_inside_functions_are_optional_or_costly():
    """A function-level import of the package's own modules would hide a cycle; of a
    third-party package, it is allowed only for optional or costly dependencies, with
    the reason in a comment on the import (or on the import just above it)."""
    bad = []
    for module, edges in GRAPH.items():
        path = dict(_modules())[module]
        lines = path.read_text().splitlines()
        for dest, uses in edges.items():
            for lineno, in_function, _ in uses:
                if not in_function:
                    continue
                top = dest.split(".")[0]
                here, above = lines[lineno - 1], lines[lineno - 2]
                commented = "#" in here or ("#" in above and "import" in above)
                if top == "attitude" or not commented:
                    bad.append(f"{module}:{lineno} imports {dest} inside a function"
                               + ("" if top == "attitude" else " without a comment"))
    assert not bad, "\n".join(bad)


def test_imports_by_name_only_where_declared():
    """``importlib.import_module`` (or ``__import__``) hides an import from the graph above:
    only the modules of :data:`IMPORTS_BY_NAME` use it, and there its table says what."""
    bad = []
    for module, path in _modules():
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Call) and (
                    isinstance(node.func, ast.Attribute) and node.func.attr == "import_module"
                    or isinstance(node.func, ast.Name) and node.func.id == "__import__") \
                    and module not in IMPORTS_BY_NAME:
                bad.append(f"{module}:{node.lineno} imports a module by name")
    assert not bad, "\n".join(bad)


def test_cli_commands_are_modules_with_a_command():
    from attitude.app.cli import COMMANDS, build_parser

    subparsers = next(a for a in build_parser()._actions
                      if isinstance(a, argparse._SubParsersAction))
    assert sorted(COMMANDS) == sorted(subparsers.choices)
    for name in COMMANDS.values():
        assert (ROOT.parent / name.replace(".", "/")).with_suffix(".py").is_file()
        assert callable(importlib.import_module(name).command)


#: ``attitude.__all__`` of the release before the reorganisation (every name stays).
PREVIOUS_ALL = [
    "__version__", "RigidBody", "MassProperties", "AttitudeState", "Ephemeris", "Ensemble",
    "Event", "nutation_crossing", "event_table", "KeplerOrbit", "torques", "propagate",
    "diagnose", "classify", "Classification", "INERTIAL_FRAMES", "SYMMETRY_RTOL",
    "TRIANGLE_RTOL", "AttitudeError", "InvalidInertiaError", "InvalidStateError",
    "ShapeModelError", "ScenarioError", "PropagationError", "EphemerisFormatError",
    "OrbitError", "TorqueConfigError", "DiagnosticsError", "InsufficientDataError",
    "ClassificationError", "AttitudeWarning", "NearSeparatrixWarning",
    "InvalidBodiesWarning",
]


@pytest.mark.parametrize("name", PREVIOUS_ALL)
def test_previous_public_names_still_importable(name):
    assert name in attitude.__all__
    assert getattr(attitude, name) is not None


#: Module paths the documentation used before, and a name each held.
OLD_PATHS = {
    "attitude.aem": "read_aem", "attitude.spice": "write_ck",
    "attitude.streaming": "EphemerisWriter", "attitude.splitting": "free_flow",
    "attitude.torquefree": "free_rotation", "attitude.integrate": "integrate_reference",
    "attitude.events": "nutation_crossing", "attitude.propagate": "METHODS",
}


@pytest.mark.parametrize("old, name", sorted(OLD_PATHS.items()))
def test_old_module_paths_warn_and_forward(old, name):
    module = importlib.import_module(old)
    with pytest.warns(DeprecationWarning, match=rf"{old} is deprecated; use attitude\."):
        value = getattr(module, name)
    new = attitude.deprecation.MOVED_MODULES[old]
    assert value is getattr(importlib.import_module(new), name)


def test_old_paths_do_not_shadow_functions():
    """``import attitude.propagate`` (an old module path) leaves ``att.propagate`` the
    function."""
    import attitude.propagate  # noqa: F401

    assert callable(attitude.propagate) and attitude.propagate.__module__ == \
        "attitude.propagation.propagator"


def test_still_modules_after_reorganisation():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for name in ("ensemble", "torques", "classify", "diagnostics", "scenario"):
            importlib.import_module(f"attitude.{name}")


def test_every_public_name_exists():
    missing = [n for n in attitude.__all__ if not hasattr(attitude, n)]
    assert not missing

"""The package's structure (docs/architecture.md): imports point down the layers
(foundations < model < propagation < analysis < wings < application), no import cycles,
no private names reached across modules, imports inside functions only for optional or
costly dependencies, every public name of earlier releases still importable, and the
architecture page written from (and checked against) the import graph.

``python tests/test_architecture.py`` rewrites the generated part of
docs/architecture.md."""

from __future__ import annotations

import argparse
import ast
import importlib
import json
import pathlib
import re
import sys
import warnings

import pytest

import attitude

ROOT = pathlib.Path(attitude.__file__).parent
DOC = ROOT.parent / "docs" / "architecture.md"

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
    "attitude.foundations.lazy": (None, "the public names of `attitude` and "
                                        "`attitude.formats`, each imported on first use "
                                        "(streaming would load numba); the package "
                                        "namespaces are outside the cycle test; and "
                                        "lazy.WING_METHODS: Ephemeris.animate/view run "
                                        "attitude.pictures, a wing the model layer may "
                                        "not import (imported on the first call), and "
                                        "propagate(BinarySystem) runs attitude.binary"),
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


# --- layers -------------------------------------------------------------------------

#: The layers, lowest first: a module may import its own layer and the layers below.
LAYERS = ("foundations", "model", "propagation", "analysis", "wings", "application")

#: The wings: each imports the layers below and its own modules, not another wing.
WINGS = ("formats", "photometry", "fitting", "environment", "spinorbit", "inversion", "binary",
         "pictures")

#: Wings that build on another wing, with the reason: the only imports between wings.
WING_USES = {
    # lightcurve observations are photometry's brightness model with observed geometry
    ("fitting", "photometry"),
    # inversion reads observations with photometry's geometry (Sun and observer directions)
    ("inversion", "photometry"),
    # the binary page draws the binary wing's libration angle of its ephemeris
    ("pictures", "binary"),
}

#: Top-level modules: the user's namespaces (anything may be re-exported; nothing in the
#: package imports them) and the two that import nothing and serve every layer.
NAMESPACES = ("attitude", "attitude.ensemble", "attitude.torques", "attitude.spindown",
              "attitude.__main__")
BASE_MODULES = ("attitude.version", "attitude.deprecation")


def layer_of(module: str) -> tuple[str, str | None]:
    """``(layer, wing)`` of a module of the package: ``("namespace", None)`` for the
    user's namespaces."""
    parts = module.split(".")
    if module in NAMESPACES:
        return "namespace", None
    if module in BASE_MODULES:
        return "foundations", None
    top = parts[1]
    if top in WINGS:
        return "wings", top
    if top == "app":
        return "application", None
    if top in LAYERS:
        return top, None
    raise AssertionError(f"{module} is in no layer: put it in a layer's folder "
                         f"({', '.join(LAYERS)}) or a wing ({', '.join(WINGS)})")


def layer_violations(graph: dict[str, set[str]]) -> list[str]:
    """The imports of ``graph`` (``{module: {imported module}}``, the package's own
    modules only) that break the layer rules, one line each."""
    rank = {name: i for i, name in enumerate(LAYERS)}
    bad = []
    for module, deps in sorted(graph.items()):
        mine, my_wing = layer_of(module)
        for dep in sorted(deps):
            theirs, their_wing = layer_of(dep)
            if theirs == "namespace":
                if mine != "namespace":
                    bad.append(f"{module} imports the user namespace {dep}")
                continue
            if mine == "namespace":
                continue
            if rank[theirs] > rank[mine]:
                bad.append(f"{module} ({mine}) imports {dep} ({theirs}), a higher layer")
            elif mine == theirs == "wings" and my_wing != their_wing \
                    and (my_wing, their_wing) not in WING_USES:
                bad.append(f"{module} (wing {my_wing}) imports {dep} (wing {their_wing})")
    return bad


def test_imports_point_down_the_layers():
    bad = layer_violations(_internal(GRAPH))
    assert not bad, "\n".join(bad)


def test_the_layer_rule_catches_a_bad_import():
    """A test of the test: an import upward, one across wings and one of a user
    namespace are each reported; the package's own graph with them added fails."""
    graph = {m: set(d) for m, d in _internal(GRAPH).items()}
    graph["attitude.foundations.quaternion"].add("attitude.app.cli")
    graph["attitude.formats.aem"].add("attitude.photometry.geometry")
    graph["attitude.model.body"].add("attitude.torques")
    bad = layer_violations(graph)
    assert bad == [
        "attitude.formats.aem (wing formats) imports attitude.photometry.geometry "
        "(wing photometry)",
        "attitude.foundations.quaternion (foundations) imports attitude.app.cli "
        "(application), a higher layer",
        "attitude.model.body imports the user namespace attitude.torques",
    ]


#: The longest a module may grow: one concept per module (issue 25).
MAX_MODULE_LINES = 1000


def test_no_module_over_the_line_limit():
    long = {name: n for name, path in _modules()
            if (n := len(path.read_text().splitlines())) > MAX_MODULE_LINES}
    assert not long, f"modules over {MAX_MODULE_LINES} lines (split by concept): {long}"


def test_every_module_is_in_a_layer():
    for module in GRAPH:
        layer_of(module)          # raises naming the module


# --- docs/architecture.md -----------------------------------------------------------

GENERATED_START = "<!-- BEGIN GENERATED: python tests/test_architecture.py -->"
GENERATED_END = "<!-- END GENERATED -->"


def layer_table(graph: dict[str, set[str]]) -> str:
    """The markdown table of imports between layers (rows import columns), counted as
    edges between modules, from the import graph."""
    names = LAYERS
    counts = {(a, b): 0 for a in names for b in names}
    modules = {name: 0 for name in names}
    for module, deps in graph.items():
        mine, _ = layer_of(module)
        if mine == "namespace":
            continue
        modules[mine] += 1
        for dep in deps:
            theirs, _ = layer_of(dep)
            if theirs != "namespace":
                counts[mine, theirs] += 1
    lines = ["| imports -> | modules | " + " | ".join(names) + " |",
             "| --- | ---: | " + " | ".join("---:" for _ in names) + " |"]
    for a in names:
        row = [str(counts[a, b]) if counts[a, b] else "" for b in names]
        lines.append(f"| **{a}** | {modules[a]} | " + " | ".join(row) + " |")
    return "\n".join(lines)


def generated_section() -> str:
    return (f"{GENERATED_START}\n{layer_table(_internal(GRAPH))}\n\n"
            f"Wings that build on another wing: "
            + ", ".join(f"{a} -> {b}" for a, b in sorted(WING_USES)) + f".\n{GENERATED_END}")


def test_architecture_page_matches_the_import_graph():
    """The table of imports between layers is written from the graph (regenerate with
    ``python tests/test_architecture.py``), and the layout lists every module of the
    package, and no other."""
    text = DOC.read_text()
    start, end = text.index(GENERATED_START), text.index(GENERATED_END) + len(GENERATED_END)
    assert text[start:end] == generated_section(), \
        "docs/architecture.md is stale: run python tests/test_architecture.py"
    listed = set(re.findall(r"`(attitude/[\w/]+\.py)`", text))
    actual = {str(path.relative_to(ROOT.parent)) for _, path in _modules()}
    assert listed == actual, (f"docs/architecture.md: not listed {sorted(actual - listed)}; "
                              f"listed but absent {sorted(listed - actual)}")


def write_generated_section() -> None:
    text = DOC.read_text()
    start, end = text.index(GENERATED_START), text.index(GENERATED_END) + len(GENERATED_END)
    DOC.write_text(text[:start] + generated_section() + text[end:])


# --- names of earlier releases -------------------------------------------------------

#: ``{module: [public names]}`` of the release before the layers (main at 7127c23),
#: written by importing every module of that tree.
PREVIOUS_RELEASE = json.loads(
    (pathlib.Path(__file__).parent / "data" / "previous_release_names.json").read_text())


@pytest.mark.parametrize("module", sorted(PREVIOUS_RELEASE))
def test_every_name_of_the_previous_release_still_imports(module):
    """Each module path of the previous release still imports and still offers each of
    its public names; a path that moved warns (DeprecationWarning naming the new one)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        mod = importlib.import_module(module)
        missing = [n for n in PREVIOUS_RELEASE[module] if not hasattr(mod, n)]
    assert not missing, f"{module} lost {missing}"
    moved = module in attitude.deprecation.MOVED_MODULES
    deprecations = [w for w in caught if issubclass(w.category, DeprecationWarning)
                    and str(w.message).startswith(module + " is deprecated")]
    if moved and PREVIOUS_RELEASE[module]:
        assert deprecations, f"{module} moved but does not warn"
    elif not moved:
        assert not deprecations


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


if __name__ == "__main__":
    sys.exit(write_generated_section())

"""Sphinx configuration of the ``attitude`` documentation site (MyST Markdown).

Build with ``python -m sphinx -W --keep-going -b html docs docs/_build/html``.

The pages are Markdown whose ``>>>`` examples run as doctests under pytest
(``--doctest-glob=*.md``).  Written bare, as the doctest parser wants them, such blocks
would render as nested block quotes, so ``_fence_doctests`` wraps every run of doctest
lines outside a code fence in a ``pycon`` fence when Sphinx reads a page.  The files
themselves are not changed.

This file is also collected by pytest's ``--doctest-modules`` (``docs`` is a test path):
it imports nothing beyond the standard library and the package, has no side effects
beyond putting the repository on ``sys.path``, and holds no doctests.
"""

from __future__ import annotations

import hashlib
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:  # build from a checkout without installing
    sys.path.insert(0, str(ROOT))

import attitude  # noqa: E402

project = "attitude"
author = "attitude developers"
copyright = "attitude developers"
release = attitude.__version__
version = release

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
    "sphinx.ext.viewcode",
]

# The pages are Markdown; the API pages are reStructuredText (autodoc output with
# numbered footnotes, which docutils resolves in reST documents).
source_suffix = {".md": "markdown", ".rst": "restructuredtext"}
root_doc = "index"
exclude_patterns = ["_build", "Thumbs.db", ".DS_Store", "*.json"]
# the scenario JSON Schema (docs/scenarios.md) is published next to the pages
html_extra_path = ["scenario.schema.json"]

# MyST: $...$ and $$...$$ maths, ```{math} blocks, anchors for heading links.
myst_enable_extensions = ["dollarmath", "amsmath", "colon_fence"]
myst_heading_anchors = 3

# autodoc + napoleon (numpy-style docstrings)
autodoc_member_order = "bysource"
autodoc_typehints = "description"
autodoc_default_options = {"members": True, "show-inheritance": True}
autodoc_mock_imports = ["matplotlib", "spiceypy", "dask", "distributed", "tqdm"]
napoleon_google_docstring = False
napoleon_numpy_docstring = True
napoleon_use_rtype = False
napoleon_preprocess_types = False

html_theme = "furo"
html_title = f"attitude {release}"
pygments_style = "sphinx"

_FENCE = re.compile(r"^\s*(`{3,}|~{3,})")
_PROMPT = re.compile(r"^\s*>>>( |$)")


def _fence_doctests(text: str) -> str:
    """Wrap each run of bare doctest lines (``>>>`` to the next blank line) in a fence."""
    out: list[str] = []
    fence: str | None = None  # the marker of the code fence we are in, if any
    in_doctest = False
    for line in text.split("\n"):
        if in_doctest:
            if line.strip():
                out.append(line)
                continue
            out.extend(["```", ""])
            in_doctest = False
        m = _FENCE.match(line)
        if fence is not None:
            if m and m.group(1)[0] == fence[0] and len(m.group(1)) >= len(fence):
                fence = None
        elif m:
            fence = m.group(1)
        elif _PROMPT.match(line):
            out.extend(["", "```pycon"])
            in_doctest = True
        out.append(line)
    if in_doctest:
        out.append("```")
    return "\n".join(out)


def _on_source_read(app, docname, source):
    if str(app.env.doc2path(docname)).endswith(".md"):
        source[0] = _fence_doctests(source[0])


_FOOTNOTE_DEF = re.compile(r"^(\s*)\.\. \[(\d+)\]\s?(.*)$")


def _unique_footnotes(app, what, name, obj, options, lines):
    """Make the numbered references of numpydoc docstrings build cleanly.

    Several docstrings on one page each define ``.. [1]``: every cited reference
    (``[1]_`` in the text) becomes an auto-numbered footnote with a label of its own
    docstring (what numpydoc does; napoleon does not), and a reference that the text
    does not cite becomes a plain ``[1] ...`` line, since docutils warns about
    unreferenced footnotes."""
    numbers = {m.group(2) for line in lines if (m := _FOOTNOTE_DEF.match(line))}
    if not numbers:
        return
    uid = "r" + hashlib.sha1(name.encode()).hexdigest()[:8]
    text = "\n".join(lines)
    cited = {n for n in numbers if f"[{n}]_" in text}
    out: list[str] = []
    for line in lines:
        m = _FOOTNOTE_DEF.match(line)
        if m:
            indent, n, rest = m.groups()
            if out and out[-1].strip():
                out.append("")
            if n in cited:
                out.append(f"{indent}.. [#{uid}-{n}] {rest}")
            else:
                out.append(f"{indent}| [{n}] {rest}")
            continue
        for n in cited:
            line = line.replace(f"[{n}]_", f"[#{uid}-{n}]_")
        out.append(line)
    lines[:] = out


def setup(app):
    app.connect("source-read", _on_source_read)
    app.connect("autodoc-process-docstring", _unique_footnotes)
    return {"parallel_read_safe": True, "parallel_write_safe": True}

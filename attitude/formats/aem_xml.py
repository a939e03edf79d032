"""The XML encoding of a CCSDS AEM (CCSDS 504.0-B-2, section 7): :func:`parse_xml` reads
an ``<aem>`` document (alone or as the one message of an ``<ndm>``) into a
:class:`~.aem_message.Message`, keeping line numbers for the error messages;
:func:`write_xml` writes an :class:`~.aem_message.Output`.  The public entry points are
in :mod:`.aem`.
"""

from __future__ import annotations

import xml.parsers.expat
from collections.abc import Iterator
from pathlib import Path
from xml.sax.saxutils import escape, quoteattr

import numpy as np

from .aem_message import (
    ANGVEL_ITEMS,
    CCSDS_AEM_VERS,
    FIELDS,
    Q_ITEMS,
    QDOT_ITEMS,
    UNITS,
    XML_TAGS,
    Block,
    Message,
    Output,
    Segment,
    Spec,
    error_at,
    header_block,
    metadata_block,
    parse_number,
    parse_version,
)

#: Nothing public: these functions serve aem_read and aem_write; the public names are
#: those of :mod:`attitude.formats.aem`.
__all__ = []

# --- XML ----------------------------------------------------------------------------
class _Node:
    __slots__ = ("tag", "attrib", "line", "children", "text")

    def __init__(self, tag: str, attrib: dict, line: int):
        self.tag, self.attrib, self.line = tag, attrib, line
        self.children: list[_Node] = []
        self.text = ""

    def elements(self, skip_comments: bool = True) -> list[_Node]:
        return [c for c in self.children if not (skip_comments and c.tag == "COMMENT")]


def _xml_tree(data: bytes, where: str) -> _Node:
    """Parse with expat to keep line numbers (ElementTree drops them).  DTDs (and with
    them entity expansion) are refused."""
    parser = xml.parsers.expat.ParserCreate()
    parser.SetParamEntityParsing(xml.parsers.expat.XML_PARAM_ENTITY_PARSING_NEVER)
    parser.buffer_text = True
    stack: list[_Node] = []
    roots: list[_Node] = []

    def start(tag, attrib):
        node = _Node(tag.rpartition(":")[2], attrib, parser.CurrentLineNumber)
        (stack[-1].children if stack else roots).append(node)
        stack.append(node)

    def end(tag):
        node = stack.pop()
        node.text = node.text.strip()

    def chars(s):
        if stack:
            stack[-1].text += s

    def doctype(*args):
        raise error_at(where, parser.CurrentLineNumber, "DOCTYPE",
                     "document type declarations are not allowed in an AEM")

    parser.StartElementHandler = start
    parser.EndElementHandler = end
    parser.CharacterDataHandler = chars
    parser.StartDoctypeDeclHandler = doctype
    try:
        parser.Parse(data, True)
    except xml.parsers.expat.ExpatError as exc:
        raise error_at(where, exc.lineno, "XML", f"not well-formed XML "
                     f"({xml.parsers.expat.ErrorString(exc.code)})") from None
    return roots[0]


def parse_xml(data: bytes, where: str) -> Message:
    """The :class:`~.aem_message.Message` of an XML AEM (``where``: the file, for the
    errors)."""
    root = _xml_tree(data, where)
    if root.tag == "ndm":
        aems = [c for c in root.children if c.tag == "aem"]
        if len(aems) != 1:
            raise error_at(where, root.line, "ndm",
                         f"a combined NDM instantiation with {len(aems)} <aem> messages: "
                         "exactly one is read")
        root = aems[0]
    if root.tag != "aem":
        raise error_at(where, root.line, root.tag,
                     f"the root element is <{root.tag}>, not <aem>: not an attitude "
                     "ephemeris message")
    if root.attrib.get("id") != "CCSDS_AEM_VERS":
        raise error_at(where, root.line, "CCSDS_AEM_VERS",
                     "the <aem> element needs id=\"CCSDS_AEM_VERS\" (7.6.3)")
    if "version" not in root.attrib:
        raise error_at(where, root.line, "CCSDS_AEM_VERS",
                     "the <aem> element has no version attribute (version=\"2.0\")")
    version = parse_version(where, root.line, root.attrib["version"])
    parts = {c.tag: c for c in root.children}
    for tag in ("header", "body"):
        if tag not in parts:
            raise error_at(where, root.line, tag, f"the <aem> element has no <{tag}>")
    header = header_block(where, version, parts["header"].line, _xml_entries(parts["header"]),
                     end=parts["header"].line, context="from <header>")
    segments = []
    for seg in parts["body"].children:
        if seg.tag != "segment":
            raise error_at(where, seg.line, seg.tag, "expected <segment> in <body>")
        sparts = {c.tag: c for c in seg.children}
        for tag in ("metadata", "data"):
            if tag not in sparts:
                raise error_at(where, seg.line, tag, f"the <segment> has no <{tag}>")
        meta, spec = metadata_block(where, version, sparts["metadata"].line,
                               _xml_entries(sparts["metadata"]))
        segments.append(_xml_segment(where, meta, spec, sparts["data"]))
    if not segments:
        raise error_at(where, parts["body"].line, "segment", "the <body> has no <segment>")
    return Message(where, "XML", version, header, segments)


def _xml_entries(node: _Node) -> list[tuple[str, str, int]]:
    """``(keyword, value, line)`` of the child elements of ``<header>``/``<metadata>``."""
    return [(c.tag, c.text, c.line) for c in node.children]


def _xml_leaves(node: _Node) -> Iterator[_Node]:
    for c in node.children:
        if c.children:
            yield from _xml_leaves(c)
        else:
            if c.tag in ("rotation1", "rotation2", "rotation3"):   # version 1 Euler items
                kind = "ANGLE" if node.tag == "rotationAngles" else "RATE"
                c.tag = f"{kind}_{c.tag[-1]}"
            yield c


def _xml_segment(where: str, meta: Block, spec: Spec, data: _Node) -> Segment:
    canonical = FIELDS[spec.attitude_type]
    tags = XML_TAGS[spec.attitude_type]
    states = data.elements()
    if not states:
        raise error_at(where, data.line, "attitudeState", "the <data> has no <attitudeState>")
    values = np.empty((len(states), len(canonical)))
    lines, epochs = [], []
    for r, st in enumerate(states):
        if st.tag != "attitudeState":
            raise error_at(where, st.line, st.tag, "expected <attitudeState> in <data>")
        inner = st.elements()
        if len(inner) != 1 or inner[0].tag not in tags:
            got = ", ".join(f"<{c.tag}>" for c in inner) or "nothing"
            raise error_at(where, st.line, spec.attitude_type,
                         f"<attitudeState> must hold one <{tags[0]}>, got {got}")
        found: dict[str, _Node] = {}
        for leaf in _xml_leaves(inner[0]):
            if leaf.tag == "COMMENT":
                continue
            if leaf.tag in found:
                raise error_at(where, leaf.line, leaf.tag, "appears twice in one state")
            if leaf.tag != "EPOCH" and leaf.tag not in canonical:
                raise error_at(where, leaf.line, leaf.tag,
                             f"is not an item of ATTITUDE_TYPE = {spec.attitude_type} "
                             f"(EPOCH {' '.join(canonical)})")
            found[leaf.tag] = leaf
        for name in ("EPOCH",) + canonical:
            if name not in found:
                raise error_at(where, inner[0].line, name,
                             f"missing from <{inner[0].tag}>")
        for j, name in enumerate(canonical):
            leaf = found[name]
            unit = leaf.attrib.get("units")
            if unit is not None and unit != UNITS.get(name, unit):
                raise error_at(where, leaf.line, name,
                             f"units={unit!r}, but the AEM unit of {name} is "
                             f"{UNITS[name]!r} (4.2.4.6)")
            try:
                values[r, j] = float(leaf.text)
            except ValueError:
                parse_number(leaf.text, where, leaf.line, name)
        lines.append(found["EPOCH"].line)
        epochs.append(found["EPOCH"].text)
    bad = np.argwhere(~np.isfinite(values))
    if bad.size:
        r, j = bad[0]
        parse_number(str(values[r, j]), where, lines[r], canonical[j])
    return Segment(meta, spec, data.line, lines, epochs, values)


def write_xml(tmp: Path, out: Output) -> None:
    """Write ``out`` as XML to the (temporary) file ``tmp``."""
    with open(tmp, "w", encoding="utf-8", newline="\n") as fh:
        fh.write('<?xml version="1.0" encoding="UTF-8"?>\n'
                 '<aem xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"\n'
                 '     xsi:noNamespaceSchemaLocation='
                 '"https://sanaregistry.org/r/ndmxml_unqualified/'
                 'ndmxml-4.0.0-master-4.0.xsd"\n'
                 f'     id="CCSDS_AEM_VERS" version={quoteattr(CCSDS_AEM_VERS)}>\n'
                 "  <header>\n")
        for c in out.header_comments:
            fh.write(f"    <COMMENT>{escape(c)}</COMMENT>\n")
        for key, value in out.header:
            fh.write(f"    <{key}>{escape(value)}</{key}>\n")
        fh.write("  </header>\n  <body>\n")
        for meta, a, b in out.segments:
            fh.write("  <segment>\n    <metadata>\n"
                     f"      <COMMENT>{escape(out.provenance)}</COMMENT>\n")
            for key, value in meta:
                fh.write(f"      <{key}>{escape(value)}</{key}>\n")
            fh.write("    </metadata>\n    <data>\n")
            fh.writelines(_state_xml(out.kind, e, v) for e, v in out.rows(a, b))
            fh.write("    </data>\n  </segment>\n")
        fh.write("  </body>\n</aem>\n")


def _state_xml(kind: str, epoch: str, vals: list[str]) -> str:
    """One ``<attitudeState>`` line of the XML form (table 7-5)."""
    fields = FIELDS[kind]
    item = dict(zip(fields, vals))

    def el(name: str) -> str:
        unit = f' units="{UNITS[name]}"' if name in UNITS else ""
        return f"<{name}{unit}>{item[name]}</{name}>"

    body = [f"<EPOCH>{epoch}</EPOCH>"]
    if kind.startswith("QUATERNION"):
        body.append("<quaternion>" + "".join(el(k) for k in Q_ITEMS) + "</quaternion>")
        if kind == "QUATERNION/DERIVATIVE":
            body.append("<quaternionDot>" + "".join(el(k) for k in QDOT_ITEMS) + "</quaternionDot>")
        elif kind == "QUATERNION/ANGVEL":
            body.append("<angVel>" + "".join(el(k) for k in ANGVEL_ITEMS) + "</angVel>")
    else:
        body += [el(k) for k in fields]
    tag = XML_TAGS[kind][0]
    return f"      <attitudeState><{tag}>{''.join(body)}</{tag}></attitudeState>\n"



"""The KVN (keyword = value notation) encoding of a CCSDS AEM (CCSDS 504.0-B-2, 4.2):
:func:`parse_kvn` reads the text into a :class:`~.aem_message.Message` (header, then
segments of a metadata block ``META_START`` ... ``META_STOP`` and a data block
``DATA_START`` ... ``DATA_STOP``), :func:`write_kvn` writes an
:class:`~.aem_message.Output`.  The public entry points are in :mod:`.aem`.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from .aem_message import (
    CCSDS_AEM_VERS,
    FIELDS,
    Block,
    Message,
    Output,
    Segment,
    Spec,
    error_at,
    header_block,
    keyword_block,
    metadata_block,
    parse_number,
    parse_version,
)

#: Nothing public: these functions serve aem_read and aem_write; the public names are
#: those of :mod:`attitude.formats.aem`.
__all__ = []

_KVN_RE = re.compile(r"^([A-Za-z][A-Za-z0-9_]*)\s*=\s*(.*?)\s*$")


# --- KVN ----------------------------------------------------------------------------
def _is_comment(s: str) -> bool:
    return s.startswith("COMMENT") and (len(s) == 7 or s[7].isspace())


def _kvn_pair(where: str, i: int, s: str) -> tuple[str, str]:
    """``(KEYWORD, value)`` of a KVN line (``COMMENT`` takes the rest of the line)."""
    if _is_comment(s):
        return "COMMENT", s[8:]
    m = _KVN_RE.match(s)
    if not m:
        raise error_at(where, i, s.split()[0][:40],
                     "expected 'KEYWORD = value' (or a block delimiter)")
    return m.group(1).upper(), m.group(2)


def _kvn_version(first: tuple[int, str] | None, where: str) -> str:
    """The version from the first non-blank line, which must be ``CCSDS_AEM_VERS``."""
    if first is None:
        raise error_at(where, None, "CCSDS_AEM_VERS", "the file is empty")
    i, s = first
    m = _KVN_RE.match(s)
    if not m or m.group(1).upper() != "CCSDS_AEM_VERS":
        other = re.match(r"CCSDS_([A-Z]{3})_VERS", s)
        found = (f"this is a CCSDS {other.group(1)} message, not an attitude ephemeris "
                 "message" if other else f"found {s[:40]!r}")
        raise error_at(where, i, "CCSDS_AEM_VERS",
                     f"the first non-blank line must be 'CCSDS_AEM_VERS = 2.0': {found}")
    return parse_version(where, i, m.group(2))


class _KvnReader:
    """The KVN structure, line by line: header, then segments of a metadata block
    (``META_START`` ... ``META_STOP``) and a data block (``DATA_START`` ...
    ``DATA_STOP``).  ``state`` is where the reader is: ``header``, ``meta``,
    ``after_meta`` (between ``META_STOP`` and ``DATA_START``), ``data`` or ``body``
    (between segments)."""

    def __init__(self, where: str, version: str, start: int):
        self.where, self.version, self.start = where, version, start
        self.state = "header"
        self.entries: list[tuple[str, str, int]] = []   # of the open header/metadata
        self.header: Block | None = None
        self.meta_start = self.data_start = 0
        self.meta: Block | None = None
        self.spec: Spec | None = None
        self.rows: list[tuple[int, list[str]]] = []
        self.segments: list[Segment] = []

    def feed(self, i: int, s: str) -> None:
        if self.state == "data":
            self._data_line(i, s)
            return
        delimiter = {"META_START": self._meta_start, "META_STOP": self._meta_stop,
                     "DATA_START": self._data_start, "DATA_STOP": self._data_stop}.get(s)
        if delimiter is not None:
            delimiter(i)
        else:
            self._keyword(i, s)

    def _meta_start(self, i: int) -> None:
        if self.state == "header":
            self.header = header_block(self.where, self.version, self.start, self.entries, end=i,
                                  context="(the header ends at this META_START)")
            self.header.stop = i
        elif self.state != "body":
            raise error_at(self.where, i, "META_START",
                         f"unexpected: the metadata block that starts at line "
                         f"{self.meta_start} has no DATA_START/DATA_STOP")
        self.state, self.meta_start, self.entries = "meta", i, []

    def _meta_stop(self, i: int) -> None:
        if self.state != "meta":
            raise error_at(self.where, i, "META_STOP", "without a META_START")
        self.meta, self.spec = metadata_block(self.where, self.version, self.meta_start,
                                         self.entries, stop=i)
        self.state = "after_meta"

    def _data_start(self, i: int) -> None:
        if self.state != "after_meta":
            raise error_at(self.where, i, "DATA_START", "must follow a metadata block "
                         "(META_START ... META_STOP)")
        self.state, self.data_start, self.rows = "data", i, []

    def _data_stop(self, i: int) -> None:
        raise error_at(self.where, i, "DATA_STOP", "without a DATA_START")

    def _keyword(self, i: int, s: str) -> None:
        if self.state == "after_meta" and s[:1].isdigit():
            raise error_at(self.where, i, "DATA_START", "data line without DATA_START: the "
                         "data of a segment sit between DATA_START and DATA_STOP (4.2.4.1)")
        key, value = _kvn_pair(self.where, i, s)
        if self.state in ("header", "meta"):
            self.entries.append((key, value, i))
        elif key != "COMMENT":
            expected = {"after_meta": "DATA_START", "body": "META_START"}[self.state]
            raise error_at(self.where, i, key, f"unexpected here: expected {expected}")

    def _data_line(self, i: int, s: str) -> None:
        if s == "DATA_STOP":
            self.segments.append(_kvn_segment(self.where, self.meta, self.spec,
                                              self.data_start, self.rows))
            self.state = "body"
        elif _is_comment(s):
            return
        elif "=" in s or s in ("META_START", "META_STOP", "DATA_START"):
            raise error_at(self.where, i, s.split("=")[0].strip(),
                         f"expected a data line or DATA_STOP: the data block opened by "
                         f"DATA_START at line {self.data_start} is not closed")
        else:
            self.rows.append((i, s.split()))

    def finish(self, n_lines: int) -> Message:
        """The message, once every line is fed; errors for unclosed blocks."""
        where, state = self.where, self.state
        if state in ("header", "meta"):     # the keywords first: as if checked on the way
            keyword_block(where, self.version, "header" if state == "header" else "metadata",
                   self.start, self.entries)
        if state == "data":
            raise error_at(where, n_lines, "DATA_STOP",
                         f"missing at the end of the file (DATA_START at line "
                         f"{self.data_start})")
        if state in ("meta", "after_meta"):
            raise error_at(where, n_lines, "DATA_START" if state == "after_meta" else
                         "META_STOP", f"missing at the end of the file (META_START at line "
                         f"{self.meta_start})")
        if not self.segments:
            raise error_at(where, n_lines, "META_START", "the file has no segment "
                         "(META_START ... DATA_STOP): no attitude data")
        return Message(where, "KVN", self.version, self.header, self.segments)


def parse_kvn(text: str, where: str) -> Message:
    """The :class:`~.aem_message.Message` of a KVN AEM's text (``where``: the file, for the
    errors)."""
    lines = text.splitlines()
    it = ((i, s.strip()) for i, s in enumerate(lines, 1))
    it = ((i, s) for i, s in it if s)
    first = next(it, None)
    reader = _KvnReader(where, _kvn_version(first, where), first[0])
    for i, s in it:
        reader.feed(i, s)
    return reader.finish(len(lines))


def _kvn_segment(where: str, meta: Block, spec: Spec, data_start: int,
                 rows: list[tuple[int, list[str]]]) -> Segment:
    if not rows:
        raise error_at(where, data_start, "DATA_START", "the data block has no data lines")
    fields = spec.fields
    canonical = FIELDS[spec.attitude_type]
    k = len(fields)
    values = np.empty((len(rows), k))
    lines, epochs = [], []
    for r, (i, tokens) in enumerate(rows):
        if len(tokens) != k + 1:
            raise error_at(where, i, spec.attitude_type,
                         f"a data line needs {k + 1} fields (EPOCH {' '.join(fields)}), got "
                         f"{len(tokens)}")
        try:
            values[r] = [float(tok) for tok in tokens[1:]]
        except ValueError:
            for name, tok in zip(fields, tokens[1:]):
                parse_number(tok, where, i, name)
        lines.append(i)
        epochs.append(tokens[0])
    bad = np.argwhere(~np.isfinite(values))
    if bad.size:
        r, j = bad[0]
        parse_number(rows[r][1][j + 1], where, rows[r][0], fields[j])
    if fields != canonical:
        values = values[:, [fields.index(f) for f in canonical]]
    return Segment(meta, spec, data_start, lines, epochs, values)


def write_kvn(tmp: Path, out: Output) -> None:
    """Write ``out`` as KVN to the (temporary) file ``tmp``."""
    with open(tmp, "w", encoding="ascii", newline="\n") as fh:
        fh.write(f"CCSDS_AEM_VERS = {CCSDS_AEM_VERS}\n")
        for c in out.header_comments:
            fh.write(f"COMMENT {c}\n")
        for key, value in out.header:
            fh.write(f"{key:<20} = {value}\n")
        for meta, a, b in out.segments:
            fh.write(f"\nMETA_START\nCOMMENT {out.provenance}\n")
            for key, value in meta:
                fh.write(f"{key:<20} = {value}\n")
            fh.write("META_STOP\n\nDATA_START\n")
            fh.writelines(f"{e} {' '.join(v)}\n" for e, v in out.rows(a, b))
            fh.write("DATA_STOP\n")



"""docs/binary.md's key reference is the loader's own declaration."""

from pathlib import Path

from attitude.binary.config import binary_reference

DOC = Path(__file__).resolve().parents[2] / "docs" / "binary.md"


def test_the_key_reference_is_generated_from_the_declaration():
    text = DOC.read_text(encoding="utf-8")
    begin = "<!-- BEGIN GENERATED: python -m attitude.binary.config -->\n"
    start = text.index(begin) + len(begin)
    end = text.index("<!-- END GENERATED -->", start)
    assert text[start:end] == binary_reference(), \
        "docs/binary.md is stale: python -m attitude.binary.config, pasted between the markers"

"""The summary of ``attitude run``: rich tables on a terminal when rich is installed,
else the plain-text table (pipes, files, no rich)."""

import io
import sys

import pytest

from attitude.app.commands import run as cli  # the summary of `attitude run`
from attitude.app.scenario import load_scenario, run_scenario
from tests.app.test_scenario import GOOD, write

EXPECT = """
[expect]
regime = "SAM"
precession = { value = 1.0, unit = "h", rel_tol = 0.01 }
energy_rel_drift = { max = 1e-12 }
"""


@pytest.fixture(scope="module")
def result(tmp_path_factory):
    path = write(tmp_path_factory.mktemp("summary"), GOOD + EXPECT)
    res = run_scenario(load_scenario(path), write_outputs=False)
    res.outputs.append(path.with_name("out [1].nc"))   # brackets: not rich markup
    return res


def test_plain_summary_is_an_aligned_label_value_table(result):
    lines = cli._summary(result).splitlines()
    assert [ln[:11] for ln in lines[:4]] == ["Scenario   ", "Body       ", "State      ",
                                             "Run        "]
    assert all(ln[10] == " " and ln[11] != " " for ln in lines)
    assert lines[4].startswith("Method     exact: no torques")
    assert "Motion     regime SAM" in lines[5]
    assert "Expect     ok   regime: expected SAM, got SAM" in lines
    assert any(ln.startswith("Expect     FAIL precession: expected 1 +/- 0.01 h, got ")
               for ln in lines)
    assert lines[-1].startswith("Wrote      ") and lines[-1].endswith("out [1].nc")


def test_rich_summary_renders_run_and_expectation_tables(result):
    pytest.importorskip("rich")
    from rich.console import Console

    console = Console(record=True, width=120, file=io.StringIO())
    cli._rich_summary(result, console)
    text = console.export_text()
    assert "attitude run: test body" in text
    assert "regime SAM" in text                          # the quantity/value table
    assert "out [1].nc" in text
    rows = {ln.split("│")[1].strip(): [c.strip() for c in ln.split("│")[2:-1]]
            for ln in text.splitlines() if ln.count("│") == 6}
    assert rows["regime"] == ["SAM", "exact", "SAM", "ok"]
    assert rows["precession"][:2] == ["1 h", "+/- 0.01 h"] and rows["precession"][3] == "FAIL"
    assert rows["energy_rel_drift"][:2] == ["<= 1e-12", "upper bound"]
    assert rows["energy_rel_drift"][3] == "ok"


def test_print_summary_is_plain_when_not_a_terminal(result, capsys):
    cli._print_summary(result)              # pytest's captured stdout is not a tty
    assert capsys.readouterr().out == cli._summary(result) + "\n"


def test_print_summary_is_plain_on_a_terminal_without_rich(result, capsys, monkeypatch):
    monkeypatch.setattr(sys.stdout, "isatty", lambda: True)
    monkeypatch.setitem(sys.modules, "rich.console", None)     # import fails
    cli._print_summary(result)
    assert capsys.readouterr().out == cli._summary(result) + "\n"


def test_print_summary_is_rich_on_a_terminal(result, capsys, monkeypatch):
    pytest.importorskip("rich")
    monkeypatch.setattr(sys.stdout, "isatty", lambda: True)
    cli._print_summary(result)
    out = capsys.readouterr().out
    assert "expectations" in out and "regime SAM" in out and "Expect     " not in out

"""attitude.foundations.expectation: the one reading and check of an [expect] entry
(value, unit, rel_tol | abs_tol; exact values; upper bounds), and its one declaration."""

import dataclasses

import pytest

from attitude.foundations.errors import AttitudeError
from attitude.foundations.expectation import Expectation
from attitude.foundations.spec import Key, json_schema, validate

PERIOD = Expectation.table("period", unit="s", default_unit="s")


def test_relative_and_absolute_tolerances():
    rel = Expectation.from_table("precession", validate(
        {"value": 27.38, "unit": "h", "rel_tol": 0.01}, PERIOD), default_unit="s")
    assert rel.tolerance == pytest.approx(0.2738)
    assert rel.check(27.38 + 0.27)["ok"] and not rel.check(27.38 + 0.28)["ok"]
    neg = Expectation("trend", -2.0, "ms/day", rel_tol=0.1)      # |value|
    assert neg.tolerance == pytest.approx(0.2) and neg.check(-2.15)["ok"]
    ab = Expectation.from_table("spin", {"value": 2.0, "abs_tol": 0.1}, default_unit="s")
    assert ab.unit == "s" and ab.tolerance == 0.1
    assert ab.check(2.09)["ok"] and not ab.check(2.11)["ok"]


@pytest.mark.parametrize("got", [None, float("nan"), float("inf")])
def test_missing_or_non_finite_values_fail(got):
    assert not Expectation("polhode", 3.3, "s", rel_tol=0.1).check(got)["ok"]
    assert not Expectation.at_most("energy_rel_drift", 1e-12).check(got)["ok"]


def test_exact_values_and_bounds():
    assert Expectation.exact("regime", "SAM").check("SAM") == {
        "key": "regime", "expected": "SAM", "got": "SAM", "ok": True}
    bound = Expectation.at_most("energy_rel_drift", 1e-12)
    assert bound.check(1e-12)["ok"] and not bound.check(2e-12)["ok"]
    assert "tolerance" not in bound.check(0.0)


def test_outcome_is_the_report_entry():
    e = Expectation("spin_period", 6.3, "s", rel_tol=1e-3, reported=(("at", "end"),),
                    source=(("variable", "x"),))
    assert e.check(6.3) == {"key": "spin_period", "expected": 6.3, "unit": "s",
                            "tolerance": pytest.approx(6.3e-3), "at": "end", "got": 6.3,
                            "ok": True}
    assert e["key"] == "spin_period" and e["variable"] == "x" and e.option("at") == "end"
    assert Expectation("fraction", 0.5, abs_tol=0.1).entry() == {
        "key": "fraction", "expected": 0.5, "tolerance": 0.1}       # no unit stated
    assert dataclasses.replace(e, value=7.0).check(6.3)["ok"] is False


def test_one_declaration_gives_checks_and_schema():
    with pytest.raises(AttitudeError, match="exactly one of rel_tol, abs_tol"):
        validate({"value": 1.0}, PERIOD, where="expect.spin")
    with pytest.raises(AttitudeError, match="expect.spin.unit: unit 'kg' cannot be"):
        validate({"value": 1.0, "unit": "kg", "abs_tol": 1}, PERIOD, where="expect.spin")
    schema = json_schema(PERIOD, root=False)
    assert schema["required"] == ["value"]
    assert schema["oneOf"] == [{"required": ["rel_tol"]}, {"required": ["abs_tol"]}]
    extra = Expectation.table("spin_period", after=(Key("at", "string"),))
    assert extra.names() == ("value", "unit", "at", "rel_tol", "abs_tol")
    assert "unit" not in Expectation.table("fraction", with_unit=False)

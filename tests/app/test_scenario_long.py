"""scenarios/long/: the longer versions of CI scenarios, for users.  They load and
validate, but have no [expect] table, so ``attitude check scenarios/`` (which searches
sub-folders) skips them and CI stays quick.  They are not run here."""

import json
import tomllib
from pathlib import Path

import pytest

from attitude.app.commands.check import _check_one, _check_targets
from attitude.app.scenario import load_scenario

ROOT = Path(__file__).resolve().parents[2]
LONG = sorted((ROOT / "scenarios" / "long").glob("*.toml"))


def test_there_is_a_long_hyperion():
    assert ROOT / "scenarios" / "long" / "hyperion_50_orbits.toml" in LONG


@pytest.mark.parametrize("path", LONG, ids=lambda p: p.name)
def test_long_scenario_loads_validates_and_is_skipped_by_check(path):
    assert not load_scenario(path).expect
    doc = tomllib.loads(path.read_text())
    assert "expect" not in doc
    assert f"attitude run scenarios/long/{path.name}" in path.read_text()   # says how
    jsonschema = pytest.importorskip("jsonschema")
    schema = json.loads((ROOT / "docs" / "scenario.schema.json").read_text())
    jsonschema.Draft202012Validator(schema).validate(doc)
    files, errors = _check_targets([ROOT / "scenarios"])
    assert path in files and not errors
    assert _check_one(str(path))["status"] == "skipped"


def test_long_hyperion_is_the_ci_one_run_longer():
    ci = tomllib.loads((ROOT / "scenarios" / "hyperion.toml").read_text())
    long = tomllib.loads((ROOT / "scenarios" / "long" / "hyperion_50_orbits.toml").read_text())
    for table in ("body", "state", "torques"):
        assert long[table] == ci[table], table
    assert load_scenario(ROOT / "scenarios" / "long" / "hyperion_50_orbits.toml").duration \
        > 3 * load_scenario(ROOT / "scenarios" / "hyperion.toml").duration

"""docs/scenario.schema.json (JSON Schema draft 2020-12) describes the scenario files: it is
generated from the loader's declaration (attitude.scenario_spec.SCENARIO), so the two cannot
disagree; every shipped scenario validates, typical mistakes do not."""

import json
import tomllib
from pathlib import Path

import pytest

from attitude.app.scenario import (
    CONSERVATION_KEYS,
    EXPECT_KEYS,
    SCHEMA,
    scenario_reference,
    scenario_schema,
)
from attitude.app.scenario_spec import SPIN_EXPECT_KEYS
from attitude.model.regimes import PERIOD_KEYS, REGIMES
from attitude.photometry.config import EXPECT_KEYS as LIGHTCURVE_EXPECT_KEYS
from tests.app.test_scenario import GOOD

ROOT = Path(__file__).resolve().parents[2]
SCHEMA_PATH = ROOT / "docs" / "scenario.schema.json"
SCENARIOS = sorted((ROOT / "scenarios").glob("*.toml"))
REFERENCE_START = "<!-- BEGIN GENERATED: python -m attitude.app.scenario --reference -->"
REFERENCE_END = "<!-- END GENERATED -->"


def _schema():
    return json.loads(SCHEMA_PATH.read_text())


def test_committed_schema_is_the_generated_one():
    """Regenerate with: python -m attitude.app.scenario --schema > docs/scenario.schema.json"""
    assert _schema() == scenario_schema()


def test_reference_in_the_docs_is_the_generated_one():
    """Regenerate the section between the markers of docs/scenarios.md with
    python -m attitude.app.scenario --reference"""
    text = (ROOT / "docs" / "scenarios.md").read_text()
    start = text.index(REFERENCE_START) + len(REFERENCE_START)
    end = text.index(REFERENCE_END)
    assert text[start:end].strip() == scenario_reference().strip()


def test_schema_keys_match_the_loader():
    schema = _schema()
    props = schema["properties"]
    assert set(props) == set(SCHEMA)
    for table in ("scenario", "body", "state", "propagation", "output", "ensemble",
                  "section", "photometry"):
        assert set(props[table]["properties"]) == set(SCHEMA[table]), table
    expect = props["expect"]["properties"]
    assert set(expect) == {"regime", *PERIOD_KEYS, *CONSERVATION_KEYS, "nutation_range",
                           "variables", "regime_fractions",
                           "libration_amplitude", "resonance",
                           *LIGHTCURVE_EXPECT_KEYS, *SPIN_EXPECT_KEYS} == set(EXPECT_KEYS)
    assert expect["regime"]["enum"] == list(REGIMES)


@pytest.fixture(scope="module")
def validator():
    jsonschema = pytest.importorskip("jsonschema")
    schema = _schema()
    jsonschema.Draft202012Validator.check_schema(schema)
    return jsonschema.Draft202012Validator(schema)


@pytest.mark.parametrize("path", SCENARIOS, ids=[p.name for p in SCENARIOS])
def test_every_shipped_scenario_validates(validator, path):
    doc = tomllib.loads(path.read_text())
    errors = [f"{'/'.join(map(str, e.absolute_path))}: {e.message}"
              for e in validator.iter_errors(doc)]
    assert not errors, errors


def test_the_test_scenario_validates(validator):
    validator.validate(tomllib.loads(GOOD + '\n[expect]\nregime = "SAM"\n'))


@pytest.mark.parametrize("old, new", [
    ("[state]", "[state]\nspin = 3"),                                  # unknown key
    ('step = "10 s"', ""),                                             # missing key
    ("principal_moments = [1.0, 2.0, 3.0]",                            # two body kinds
     "principal_moments = [1.0, 2.0, 3.0]\ninertia = [[1, 0, 0], [0, 2, 0], [0, 0, 3]]"),
    ("[output]", '[expect]\nregime = "tumbling"\n[output]'),           # unknown regime
    ("[output]", "[expect]\nprecession = { value = 1.0 }\n[output]"),  # no tolerance
    ("[output]", '[[torques]]\ntype = "drag"\n[output]'),              # unknown torque
    ("[0, 0, 0, 1]", "[0, 0, 1]"),                                     # quaternion length
    ("[output]", "[expect]\nnutation_range = { min = 0, max = 1 }\n[output]"),  # no abs_tol
    ("[output]", "[expect.variables]\nx = { at = \"last\", value = 1, abs_tol = 1 }\n[output]"),
    ("[state]", '[state]\nspin_axis = { ra = 1, dec = 0 }\nspin_rate = 1'),  # and omega_body
])
def test_mistakes_are_rejected(validator, old, new):
    assert old in GOOD
    assert not validator.is_valid(tomllib.loads(GOOD.replace(old, new)))

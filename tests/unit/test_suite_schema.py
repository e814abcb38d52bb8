"""The suite JSON Schema: well-formed, shipped in the package, in step with the code, and its
violations reported in a user's words at the line and column of the bad value."""

from __future__ import annotations

import json
import re
import textwrap
from dataclasses import fields
from pathlib import Path

import pytest
from jsonschema import Draft202012Validator

from fleetsim.errors import SuiteError
from fleetsim.load.suites.orders_entry import DEFAULT_ORDER_KEYS
from fleetsim.load.suites.schema import suite_schema
from fleetsim.load.suites.suite import load_suite
from fleetsim.scenario import ScenarioSettings

REPO = Path(__file__).resolve().parents[2]
SPEC = Path("/work/shared/SPEC.md")
SPEC_EXAMPLE = Path(__file__).resolve().parents[1] / "data" / "spec_example_suite.yaml"

SUITE = """\
fleetsim: 1
name: demo
vehicle_types:
  agv: {length: 1.0, width: 0.6, height: 0.4, max_speed: 1.0, acceleration: 0.5, turn_capability: curve}
defaults:
  time_step: 0.1
  stop_on: [rejection]
scenarios:
  - name: first
    dir: scenario
    tags: [smoke]
    expect:
      tasks: all
      collisions: none
  - name: second
    dir: scenario
"""
SCENARIOS = SUITE[SUITE.index("scenarios:") :]


def load_text(tmp_path: Path, text: str) -> None:
    folder = tmp_path / "scenario"
    folder.mkdir(exist_ok=True)
    for name in ("map.json", "vehicles.csv", "tasks.csv"):
        (folder / name).write_text("", encoding="utf-8")
    path = tmp_path / "demo.fleetsim.yaml"
    path.write_text(textwrap.dedent(text), encoding="utf-8")
    load_suite(path)


def test_schema_is_valid_draft_2020_12_with_id_and_title() -> None:
    schema = suite_schema()
    Draft202012Validator.check_schema(schema)
    assert schema["$schema"] == "https://json-schema.org/draft/2020-12/schema"
    assert schema["$id"] and schema["title"] and schema["description"]


def test_the_packaged_schema_is_the_repository_file() -> None:
    assert suite_schema() == json.loads((REPO / "schemas" / "suite.schema.json").read_text("utf-8"))


def test_defaults_and_scenarios_accept_exactly_the_settings_of_scenario_settings() -> None:
    schema = suite_schema()
    settings = {f.name for f in fields(ScenarioSettings)}
    # ... and the map options and planner options (merged key by key with a scenario's own), files and
    # the order keys but a scenario's own orders.csv (fleetsim.load.suites.orders_entry), and the gate.
    given = {"map_options", "planner_options", "files", "gate", *DEFAULT_ORDER_KEYS}
    assert set(schema["properties"]["defaults"]["properties"]) == settings | given
    assert settings <= set(schema["$defs"]["scenario"]["properties"])


def test_every_object_in_the_schema_refuses_unknown_keys() -> None:
    def objects(node: object) -> list[dict[str, object]]:
        if isinstance(node, dict):
            found = [node] if node.get("type") == "object" else []
            return found + [o for value in node.values() for o in objects(value)]
        return [o for value in node for o in objects(value)] if isinstance(node, list) else []

    for node in objects(suite_schema()):
        assert node.get("additionalProperties") is not True and "additionalProperties" in node, node


def test_rejection_codes_are_the_codes_of_the_checks() -> None:
    from fleetsim.planning.checks import RejectionCode

    codes = suite_schema()["$defs"]["rejection_code"]["enum"]
    # The spec's thirteen, order-invalid (VDA 5050) and the eight rules of a dispatcher's answers.
    assert len(codes) == len(set(codes)) == 22
    assert codes == [code.value for code in RejectionCode]


def test_the_spec_example_suite_is_valid() -> None:
    """SPEC §13's example suite, kept in tests/data so that no checkout skips this; where the shared
    SPEC.md is at hand, the copy must be its example as it is."""
    copy = SPEC_EXAMPLE.read_text("utf-8")
    if SPEC.exists():
        example = re.search(r"```yaml\n(.*?)```", SPEC.read_text("utf-8"), re.S)
        assert example is not None and example.group(1) == copy
    import yaml

    Draft202012Validator(suite_schema()).validate(yaml.safe_load(copy))


def test_the_example_suite_loads(tmp_path: Path) -> None:
    load_text(tmp_path, SUITE)


VIOLATIONS = [
    pytest.param(
        ("collisions: none", "collisions: some"),
        (14, 19),
        "scenarios[0].expect.collisions: 'some' is not one of 'none', 'any' or a list of segment ids",
        id="collisions-not-one-of",
    ),
    pytest.param(
        ("collisions: none", "collisions: [3, x]"),
        (14, 23),
        "scenarios[0].expect.collisions[1]: 'x' is not a whole number (it is a string)",
        id="collisions-list-item",
    ),
    pytest.param(
        ("tasks: all", "tasks: -2"),
        (13, 14),
        "scenarios[0].expect.tasks: -2 is not one of 'all' or a whole number >= 0",
        id="tasks-negative",
    ),
    pytest.param(
        ("collisions: none", "rejections: [wrong-way, bogus]"),
        (14, 31),
        "scenarios[0].expect.rejections[1]: 'bogus' is not one of 'unknown-vehicle'",
        id="unknown-rejection-code",
    ),
    pytest.param(
        ("time_step: 0.1", "time_step: 0"), (6, 14), "defaults.time_step: 0 must be > 0", id="non-positive-time-step"
    ),
    pytest.param(
        ("time_step: 0.1", "time_step: fast"),
        (6, 14),
        "defaults.time_step: 'fast' is not a number (it is a string)",
        id="string-for-number",
    ),
    pytest.param(
        ("time_step: 0.1", "tme_step: 0.1"),
        (6, 3),
        "defaults: unknown key 'tme_step'; did you mean 'time_step'?",
        id="unknown-defaults-key",
    ),
    pytest.param(
        ("    tags: [smoke]", "    tag: [smoke]"),
        (11, 5),
        "scenarios[0]: unknown key 'tag'; did you mean 'tags'?",
        id="unknown-scenario-key",
    ),
    pytest.param(
        ("stop_on: [rejection]", "stop_on: [rejection, rejection]"),
        (7, 12),
        "defaults.stop_on: lists 'rejection' more than once",
        id="repeated-stop-on",
    ),
    pytest.param(
        ("tags: [smoke]", "tags: [xfail]"),
        (11, 12),
        "scenarios[0].tags[0]: 'xfail' must not be one of pytest's built-in markers",
        id="reserved-tag",
    ),
    pytest.param(
        ("tags: [smoke]", "tags: [smoke-test]"),
        (11, 12),
        "scenarios[0].tags[0]: 'smoke-test' is not a Python identifier",
        id="tag-not-identifier",
    ),
    pytest.param(
        ("name: first", "name: my first"),
        (9, 11),
        "scenarios[0].name: 'my first' is not a name of letters",
        id="scenario-name-pattern",
    ),
    pytest.param(
        ("  agv: {", "  my agv: {"),
        (4, 3),
        "vehicle_types: 'my agv' is not a name of letters",
        id="vehicle-type-name-pattern",
    ),
    pytest.param(
        ("turn_capability: curve", "turn_capability: curve, color: [2, 0, 0]"),
        (4, 114),
        "vehicle_types.agv.color[0]: 2 must be <= 1",
        id="color-component-too-large",
    ),
    pytest.param(
        ("turn_capability: curve", "turn_capability: drift"),
        (4, 99),
        "vehicle_types.agv.turn_capability: 'drift' is not one of 'curve' or 'in_place'",
        id="unknown-turn-capability",
    ),
    pytest.param(
        (", turn_capability: curve", ""),
        (4, 8),
        "vehicle_types.agv: missing required key 'turn_capability'",
        id="vehicle-type-incomplete",
    ),
    pytest.param(("fleetsim: 1", "fleetsim: 2"), (1, 11), "fleetsim: 2 must be 1", id="unsupported-version"),
    pytest.param(("fleetsim: 1\n", ""), (1, 1), "missing required key 'fleetsim'", id="no-version"),
    pytest.param(
        ("  - name: second\n    dir: scenario\n", "  - name: second\n    map: m.json\n"),
        (15, 5),
        "scenarios[1]: give 'dir', all of 'map', 'vehicles' and 'tasks', or 'generate' ('vehicles' is missing)",
        id="neither-dir-nor-all-files",
    ),
    pytest.param(
        (
            "  - name: second\n    dir: scenario\n",
            "  - name: second\n    generate: {layout: loop}\n    dir: scenario\n",
        ),
        (15, 5),
        "scenarios[1]: 'generate' makes the scenario, so it cannot also name files ('dir')",
        id="generate-with-files",
    ),
    pytest.param(
        ("  - name: second\n    dir: scenario\n", "  - name: second\n    generate: {layout: maze}\n"),
        (16, 24),
        "scenarios[1].generate.layout: 'maze' is not one of 'warehouse', 'loop', 'corridor' or 'any'",
        id="generate-unknown-layout",
    ),
    pytest.param(
        ("  - name: second\n    dir: scenario\n", "  - dir: scenario\n"),
        (15, 5),
        "scenarios[1]: missing required key 'name'",
        id="scenario-without-name",
    ),
    pytest.param(
        (SCENARIOS, "scenarios: {name: first}\n"),
        (8, 12),
        "scenarios: {'name': 'first'} is not a list (it is a mapping)",
        id="scenarios-not-a-list",
    ),
    pytest.param((SCENARIOS, "scenarios: []\n"), (8, 12), "scenarios: must not be empty", id="no-scenarios"),
]


@pytest.mark.parametrize(("change", "line_column", "problem"), VIOLATIONS)
def test_schema_violation_is_one_error_in_plain_words_at_the_bad_value(
    tmp_path: Path, change: tuple[str, str], line_column: tuple[int, int], problem: str
) -> None:
    assert change[0] in SUITE
    with pytest.raises(SuiteError) as caught:
        load_text(tmp_path, SUITE.replace(*change, 1))
    location = caught.value.location
    assert location is not None
    assert (location.line, location.column) == line_column
    assert caught.value.problem.startswith(problem)


def test_a_mistake_repeated_in_several_scenarios_is_reported_at_its_first_occurrence(tmp_path: Path) -> None:
    text = SUITE.replace("    dir: scenario\n", "    dir: scenario\n    colour: red\n")
    with pytest.raises(SuiteError, match=r"yaml:11:5: scenarios\[0\]: unknown key 'colour'"):
        load_text(tmp_path, text)

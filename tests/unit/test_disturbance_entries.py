"""The disturbance keys of a suite entry: loaded as written, and every mistake a located error (file,
line, the bad value), never a traceback; each check narrowly not raised by a valid neighbour."""

from __future__ import annotations

from pathlib import Path

import pytest

from fleetsim.errors import SuiteError
from fleetsim.load.suites.disturbances import HuntDisturbances
from fleetsim.load.suites.scenario import load_scenario
from fleetsim.load.suites.suite import load_suite
from fleetsim.scenario import Disturbance, RandomDisturbances, Scenario

CROSSING = Path(__file__).resolve().parents[2] / "scenario_suites" / "examples" / "crossing"

HEAD = f"""\
fleetsim: 1
name: disturbed
scenarios:
  - name: crossing
    dir: {CROSSING}
"""


def load(tmp_path: Path, entry: str) -> Scenario:
    path = tmp_path / "disturbed.fleetsim.yaml"
    path.write_text(HEAD + entry, encoding="utf-8")
    suite = load_suite(path)
    return load_scenario(suite.scenarios[0], suite)


def test_declared_random_and_hunt_keys_load_as_written(tmp_path: Path) -> None:
    scenario = load(
        tmp_path,
        """\
    disturbances:
      - {vehicle: 2, at: 12.0, stop: 20}
      - {vehicle: 1, on_segment: 3, stop: 5}
      - {vehicle: 2, at: 30, slow: 0.5, for: 40}
    random_disturbances: {seed: 7, stops_per_vehicle_hour: 6, stop: [5, 30]}
    hunt_disturbances: {count: [1, 2], stop: [1, 30], examples: 20}
""",
    )
    assert scenario.disturbances == (
        Disturbance(2, "stop", 20.0, at=12.0),
        Disturbance(1, "stop", 5.0, on_segment=3),
        Disturbance(2, "slow", 40.0, at=30.0, factor=0.5),
    )
    assert scenario.disturbances[0].line == 7
    assert scenario.random_disturbances == RandomDisturbances(7, 6.0, (5.0, 30.0))
    spec = load_suite(tmp_path / "disturbed.fleetsim.yaml").scenarios[0]
    assert spec.hunt_disturbances == HuntDisturbances(count=(1, 2), stop=(1.0, 30.0), examples=20)
    assert [d.entry() for d in scenario.disturbances] == [
        {"vehicle": 2, "at": 12.0, "stop": 20.0},
        {"vehicle": 1, "on_segment": 3, "stop": 5.0},
        {"vehicle": 2, "at": 30.0, "slow": 0.5, "for": 40.0},
    ]


@pytest.mark.parametrize(
    ("item", "line", "words"),
    [
        ("{vehicle: 9, at: 1, stop: 2}", 7, ["vehicle=9 is not a vehicle of this scenario (1, 2)"]),
        ("{vehicle: 1, on_segment: 99, stop: 2}", 7, ["on_segment=99 is not a segment of the map"]),
        ("{vehicle: 1, at: -1, stop: 2}", 7, ["at", "-1", ">= 0"]),
        ("{vehicle: 1, at: 1, stop: -2}", 7, ["stop", "-2", ">= 0"]),
        ("{vehicle: 1, at: 1, slow: 0, for: 3}", 7, ["slow", "0", "> 0"]),
        ("{vehicle: 1, at: 1, slow: 1.5, for: 3}", 7, ["slow", "1.5", "<= 1"]),
        ("{vehicle: 1, at: 1, on_segment: 2, stop: 2}", 7, ["both 'at' and 'on_segment'"]),
        ("{vehicle: 1, stop: 2}", 7, ["neither 'at' nor 'on_segment'"]),
        ("{vehicle: 1, at: 1, stop: 2, slow: 0.5, for: 1}", 7, ["both 'stop' and 'slow'"]),
        ("{vehicle: 1, at: 1}", 7, ["neither 'stop' nor 'slow'"]),
        ("{vehicle: 1, at: 1, slow: 0.5}", 7, ["slow=0.5 needs for"]),
        ("{vehicle: 1, at: 1, stop: 2, colour: red}", 7, ["colour"]),
    ],
)
def test_an_invalid_disturbance_is_a_located_error(tmp_path: Path, item: str, line: int, words: list[str]) -> None:
    with pytest.raises(SuiteError) as raised:
        load(tmp_path, f"    disturbances:\n      - {{vehicle: 1, at: 0, stop: 1}}\n      - {item}\n")
    text = str(raised.value)
    assert f"disturbed.fleetsim.yaml:{line + 1}" in text, text
    assert all(word in text for word in words), text


@pytest.mark.parametrize(
    "item",
    [
        "{vehicle: 2, at: 0, stop: 0}",  # the bounds themselves are valid
        "{vehicle: 1, on_segment: 1, stop: 2}",
        "{vehicle: 1, at: 1, slow: 1, for: 3}",
        "{vehicle: 1, at: 1, slow: 0.01, for: 0}",
    ],
)
def test_a_valid_neighbour_of_each_invalid_disturbance_loads(tmp_path: Path, item: str) -> None:
    assert len(load(tmp_path, f"    disturbances:\n      - {item}\n").disturbances) == 1


@pytest.mark.parametrize(
    ("block", "words"),
    [
        (
            "random_disturbances: {seed: 1, stops_per_vehicle_hour: 6, stop: [30, 5]}",
            ["stop=[30, 5] must be [min, max]"],
        ),
        (
            "random_disturbances: {seed: 1, stops_per_vehicle_hour: -1, stop: [5, 30]}",
            ["stops_per_vehicle_hour", ">= 0"],
        ),
        ("random_disturbances: {seed: 1, stop: [5, 30]}", ["stops_per_vehicle_hour"]),
        ("hunt_disturbances: {count: [3, 1]}", ["count=[3, 1] must be [min, max]"]),
        ("hunt_disturbances: {examples: 0}", ["examples", ">= 1"]),
    ],
)
def test_invalid_random_and_hunt_blocks_are_located_errors(tmp_path: Path, block: str, words: list[str]) -> None:
    with pytest.raises(SuiteError) as raised:
        load(tmp_path, f"    {block}\n")
    text = str(raised.value)
    assert "disturbed.fleetsim.yaml:6" in text and all(word in text for word in words), text


def test_a_generated_entry_takes_hunt_but_not_declared_disturbances(tmp_path: Path) -> None:
    path = tmp_path / "g.fleetsim.yaml"
    path.write_text(
        "fleetsim: 1\nname: g\nscenarios:\n  - name: g\n    generate: {examples: 2}\n    hunt_disturbances: {count: [1, 1]}\n",
        encoding="utf-8",
    )
    assert load_suite(path).scenarios[0].hunt_disturbances == HuntDisturbances(count=(1, 1))
    path.write_text(
        "fleetsim: 1\nname: g\nscenarios:\n  - name: g\n    generate: {examples: 2}\n    disturbances: [{vehicle: 1, at: 1, stop: 1}]\n",
        encoding="utf-8",
    )
    with pytest.raises(SuiteError, match=r"g.fleetsim.yaml:6.*not known in advance"):
        load_suite(path)

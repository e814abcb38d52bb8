"""Generated suite entries under pytest: a hunt per entry, a shrunk counterexample saved and reported."""

from __future__ import annotations

import json

import pytest

SUITE = """\
fleetsim: 1
name: hunting
vehicle_types:
  agv: {length: 1.0, width: 0.6, height: 0.4, max_speed: 1.0, acceleration: 0.5, turn_capability: in_place}
defaults:
  time_limit: 120
scenarios:
  - name: random-loops
    generate: {layout: loop, size: [1, 2], vehicles: [1, 3], tasks: [1, 2], examples: 30}
"""


@pytest.fixture
def hunting(pytester: pytest.Pytester, monkeypatch: pytest.MonkeyPatch) -> pytest.Pytester:
    monkeypatch.setenv("CI", "1")  # derandomised: the same counterexample on every run
    monkeypatch.setenv("COLUMNS", "300")
    pytester.makefile(".fleetsim.yaml", hunting=SUITE)
    return pytester


def test_a_caught_planner_fails_with_the_counterexample_saved_and_a_suite_entry_to_paste(
    hunting: pytest.Pytester,
) -> None:
    result = hunting.runpytest_inprocess("--planner", "fleetsim.planners:BFSPlanner")

    result.assert_outcomes(failed=1)
    result.stdout.fnmatch_lines(
        [
            "*It is saved as fleetsim-results/hunting/random-loops/counterexample/*",
            "  - name: random-loops-counterexample",
            "    dir: fleetsim-results/hunting/random-loops/counterexample/",
        ]
    )
    folder = hunting.path / "fleetsim-results" / "hunting" / "random-loops"
    assert sorted(p.name for p in (folder / "counterexample").iterdir()) == ["map.json", "tasks.csv", "vehicles.csv"]
    assert (folder / "failure.svg").is_file() and (folder / "run.mcap").is_file()
    first = (folder / "counterexample" / "map.json").read_bytes()

    again = hunting.runpytest_inprocess("--planner", "fleetsim.planners:BFSPlanner")
    again.assert_outcomes(failed=1)
    assert (folder / "counterexample" / "map.json").read_bytes() == first, "CI runs find the same counterexample"
    assert not (hunting.path / "hunting.fleetsim.lock.json").exists(), "generated runs are not hash-gated"


def test_a_sound_planner_passes_a_generated_entry(hunting: pytest.Pytester) -> None:
    result = hunting.runpytest_inprocess("--planner", "fleetsim.planners:ReservingPlanner", "--fleetsim-update-hashes")

    result.assert_outcomes(passed=1)
    assert not (hunting.path / "fleetsim-results").exists()


def test_a_passing_generated_entry_has_a_summary_row_with_the_examples_it_ran(hunting: pytest.Pytester) -> None:
    result = hunting.runpytest_inprocess(
        "--planner", "fleetsim.planners:ReservingPlanner", "--fleetsim-metrics-json", "metrics.json"
    )

    result.assert_outcomes(passed=1)
    result.stdout.fnmatch_lines(["*= fleetsim =*", "scenario * outcome *", "random-loops (30 generated) * passed *"])
    metrics = (hunting.path / "metrics.json").read_text(encoding="utf-8")
    assert "random-loops" not in metrics, "a different scenario every time: nothing to compare with a baseline"


def test_a_failing_generated_entry_says_how_many_scenarios_ran(hunting: pytest.Pytester) -> None:
    result = hunting.runpytest_inprocess("--planner", "fleetsim.planners:BFSPlanner")

    result.assert_outcomes(failed=1)
    result.stdout.fnmatch_lines(
        [
            "Hypothesis ran * generated scenario(s) (at most 30, the entry's examples); the last failed, and * shrink run(s)*",
            "random-loops (* generated, * shrink runs) * failed *",
        ]
    )
    document = (hunting.path / "fleetsim-results" / "hunting" / "random-loops" / "result.json").read_text(
        encoding="utf-8"
    )
    recorded = json.loads(document)
    assert 1 <= recorded["generated"] <= 30 and recorded["shrink_runs"] >= 1


def test_a_generate_block_that_cannot_hold_its_vehicles_fails_at_its_suite_entry(hunting: pytest.Pytester) -> None:
    hunting.makefile(
        ".fleetsim.yaml",
        hunting=SUITE.replace("vehicles: [1, 3]", "vehicles: [9, 9]").replace("size: [1, 2]", "size: [1, 1]"),
    )
    result = hunting.runpytest_inprocess("--planner", "fleetsim.planners:ReservingPlanner")

    result.assert_outcomes(failed=1)
    assert (
        "hunting.fleetsim.yaml:8: field 'generate': scenario 'random-loops': generate.vehicles=[9, 9] needs room for 9 vehicles "
        "with non-conflicting starts, but loop layouts of size [1, 1] have room for 2"
    ) in result.stdout.str()

"""Gated runs: hashes checked against the lock, recorded twice over, refused when nondeterministic."""

from __future__ import annotations

import itertools
import json
from dataclasses import replace
from pathlib import Path

import pytest

from fleetsim import load_scenario, load_suite
from fleetsim.gating.verify import CheckedRun, in_ci, run_checked
from fleetsim.planners import BFSPlanner, ReservingPlanner
from fleetsim.planning.plans import FleetPlan
from fleetsim.recording.artifacts import artifact_folder, write_run_artifacts
from fleetsim.scenario import Scenario
from fleetsim.sim.record import RunOrigin
from fleetsim.sim.report import broken_expectation, failure_report
from fleetsim.sim.result import Pacing

SUITE = Path(__file__).resolve().parents[2] / "scenario_suites" / "examples.fleetsim.yaml"
HINT = "pytest x.fleetsim.yaml::crossing --fleetsim-update-hashes"


def crossing() -> Scenario:
    suite = load_suite(SUITE)
    return load_scenario(suite.scenarios[0], suite)


def gated(scenario: Scenario, make: object = ReservingPlanner, **options: object) -> CheckedRun:
    settings: dict[str, object] = {
        "identity": "p:Q",
        "mode": "check",
        "recorded": None,
        "record_hint": HINT,
        "planner_timeout": None,
    }
    return run_checked(scenario, make, **{**settings, **options})  # type: ignore[arg-type]


class Alternating(ReservingPlanner):
    """Waits one extra planning round on every other run: the same code, a different trace each time."""

    runs = itertools.count()

    def __init__(self) -> None:
        super().__init__()
        self._skip = next(self.runs) % 2

    def plan_routes(self, task, fleet, layout):  # type: ignore[no-untyped-def]
        if self._skip:
            self._skip -= 1
            return []
        return super().plan_routes(task, fleet, layout)


def test_update_mode_records_an_entry_that_the_check_mode_then_accepts() -> None:
    scenario = crossing()
    recorded = gated(scenario, mode="update")
    assert recorded.record is not None and recorded.result.passed
    assert recorded.record.hash == recorded.result.trace_hash and recorded.record.steps == recorded.result.steps
    checked = gated(scenario, recorded=recorded.record)
    assert checked.result.passed and checked.record is None


def test_a_missing_hash_leaves_a_passing_run_passed_and_marks_it_unrecorded() -> None:
    checked = gated(crossing())
    assert checked.result.passed and checked.result.failures == ()
    assert checked.unrecorded


def test_a_missing_hash_fails_a_passing_run_when_a_recorded_hash_is_required() -> None:
    checked = gated(crossing(), require_recorded=True)
    assert [f.kind for f in checked.result.failures] == ["hash-missing"] and checked.unrecorded
    message = checked.result.failures[0].message
    assert HINT in message and "'p:Q'" in message and "under CI a missing hash fails" in message


def test_a_recorded_hash_is_not_unrecorded() -> None:
    scenario = crossing()
    recorded = gated(scenario, mode="update")
    assert recorded.record is not None
    assert not gated(scenario, recorded=recorded.record, require_recorded=True).unrecorded


def test_a_missing_hash_is_not_added_to_a_run_that_already_failed() -> None:
    checked = gated(crossing(), BFSPlanner, require_recorded=True)
    assert "hash-missing" not in [f.kind for f in checked.result.failures]
    assert "collision" in [f.kind for f in checked.result.failures]
    assert checked.unrecorded


@pytest.mark.parametrize(
    ("value", "expected"), [("true", True), ("1", True), ("", False), ("false", False), ("0", False)]
)
def test_ci_is_set_by_any_value_but_empty_false_0_and_no(
    monkeypatch: pytest.MonkeyPatch, value: str, expected: bool
) -> None:
    monkeypatch.setenv("CI", value)
    assert in_ci() is expected


def test_a_different_hash_says_the_behaviour_changed_and_how_to_re_record() -> None:
    scenario = crossing()
    entry = gated(scenario, mode="update").record
    assert entry is not None
    edited = replace(entry, hash="0" * 64, checkpoints=("0" * 16, *entry.checkpoints[1:]))
    failure = gated(scenario, recorded=edited).result.failures[-1]
    assert failure.kind == "hash-mismatch"
    assert "between t = 0 s and t = 10 s" in failure.message and HINT in failure.message
    assert broken_expectation(failure) == "the recorded trace hash"


def test_a_nondeterministic_planner_is_refused_and_nothing_is_recorded() -> None:
    checked = gated(crossing(), Alternating, mode="update")
    assert checked.record is None
    failure = checked.result.failures[-1]
    assert failure.kind == "nondeterministic"
    assert "first divergence at step" in failure.message and len(failure.details["hashes"]) == 2
    assert "vehicle 1's plan" in failure.message and "[[" not in failure.message  # in words, not as encoded


def test_ignore_mode_neither_checks_nor_records() -> None:
    checked = gated(crossing(), mode="ignore")
    assert checked.result.passed and checked.record is None


def test_a_planner_error_run_is_not_gated_on_its_hash() -> None:
    class Raising(ReservingPlanner):
        def plan_routes(self, task, fleet, layout):  # type: ignore[no-untyped-def]
            raise ValueError("boom")

    checked = gated(crossing(), Raising, mode="update")
    assert [f.kind for f in checked.result.failures] == ["planner-error"] and checked.record is None


def test_the_failure_report_opens_with_one_line_and_lists_broken_expectations_and_artifacts(tmp_path: Path) -> None:
    result = gated(crossing(), BFSPlanner, keep_trace=True).result
    folder = artifact_folder(tmp_path, SUITE, "crossing")
    paths = write_run_artifacts(folder, result, RunOrigin(own={"nodeid": "x::crossing"}))
    result = replace(result, artifacts=paths)
    report = failure_report(result, heading="fleetsim scenario 'crossing'")
    first, second = report.splitlines()[:2]
    assert (
        first
        == "collision at t=0.20 s: COLLISION ALERT: Possible collision detected on segment '2' (+3 more alerts; 1 other failure)"
    )
    assert second == "fleetsim scenario 'crossing'"
    assert "broken: expect.collisions: none (4 times)" in report and "broken: expect.tasks" in report
    assert f"artifacts: {paths['trace']}\n           {paths['result']}" in report  # the trace first, then the result
    document = json.loads(Path(paths["result"]).read_text(encoding="utf-8"))
    assert document["nodeid"] == "x::crossing" and document["trace_hash"] == result.trace_hash
    lines = Path(paths["trace"]).read_text(encoding="utf-8").splitlines()
    assert len(lines) == result.steps + 1  # the header and one line per step


def test_artifact_folders_are_rewritten_whole_and_named_safely(tmp_path: Path) -> None:
    folder = artifact_folder(tmp_path, Path("a/b/my suite.fleetsim.yaml"), "cross/ing")
    assert folder == tmp_path / "my_suite" / "cross_ing"
    result = gated(crossing()).result  # no trace kept: no trace file
    folder.mkdir(parents=True)
    (folder / "stale.txt").write_text("old", encoding="utf-8")
    paths = write_run_artifacts(folder, result)
    assert sorted(p.name for p in folder.iterdir()) == ["result.json"] and "trace" not in paths


def test_run_checked_reports_planner_garbage_as_a_planner_error() -> None:
    class Garbage(ReservingPlanner):
        def plan_routes(self, task, fleet, layout):  # type: ignore[no-untyped-def]
            return {"plan": FleetPlan}

    result = gated(crossing(), Garbage).result
    assert result.ended == "planner-error"
    assert "plan_routes() for vehicle 1 returned {'plan':" in result.failures[0].message


def test_pacing_says_the_order_latencies_as_count_median_p90_and_max() -> None:
    document = Pacing(10.0, 0.25, 3, tuple(k / 100 for k in (5, 1, 9, 2, 7, 3, 8, 4, 6, 10))).to_dict()
    assert document == {
        "speed": 10.0,
        "lag_max": 0.25,
        "late_steps": 3,
        "order_latency": {"orders": 10, "median": 0.055, "p90": 0.09, "max": 0.1},
    }
    assert Pacing(1.0, 0.0, 0, ()).to_dict()["order_latency"] is None  # no order arrived

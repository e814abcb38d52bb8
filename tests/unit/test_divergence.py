"""Where two traces first differ, in words: vehicles, accepted plans and events of that step."""

from __future__ import annotations

import json
from typing import Any

import pytest

from fleetsim.sim.divergence import describe_event, describe_leg, first_divergence

HEADER = '{"format":"fleetsim-trace/1","vehicles":[1,2]}'
START = [[1, 1, "f", "f", 0, 0, 0, 0], [2, 5, "b", "f", 1000, 0, 18000, 0]]
PLAN = [1, [[1, "f", "f", 1, None], [2, "f", "f", 1, None], [3, "f", "f", 1, None], [4, "f", "f", 0, 1]]]


def trace(*steps: tuple[list[Any], list[Any], list[Any]]) -> list[str]:
    """A header and one line per step: (changed vehicles, accepted plans, events)."""
    return [HEADER, *(json.dumps([n, *step], separators=(",", ":")) for n, step in enumerate(steps))]


def legs(*changes: tuple[int, int, Any]) -> list[Any]:
    """PLAN with (leg, field, value) changed."""
    plan = json.loads(json.dumps(PLAN))
    for leg, field, value in changes:
        plan[1][leg][field] = value
    return plan


def test_a_plan_differing_in_one_leg_is_told_in_words() -> None:
    a = trace((START, [PLAN], []), ([], [PLAN], []))
    b = trace((START, [PLAN], []), ([], [legs((2, 3, 0))], []))
    divergence = first_divergence(a, b, 0.1)
    assert divergence is not None and (divergence.step, divergence.time) == (1, pytest.approx(0.2))
    assert str(divergence) == (
        "first divergence at step 1 (t = 0.20 s): vehicle 1's plan, leg 2 (segment 3 forward): fixed → planned"
    )


@pytest.mark.parametrize(
    ("other", "said"),
    [
        (legs((3, 2, "r")), "vehicle 1's plan, leg 3 (segment 4 forward): progress forward → progress reverse"),
        (legs((3, 4, None)), "vehicle 1's plan, leg 3 (segment 4 forward): goal of task 1 → no goal"),
        (legs((1, 0, 7)), "vehicle 1's plan, leg 1: segment 2 forward, fixed → segment 7 forward, fixed"),
        (legs((1, 1, "b"), (1, 2, "r")), "leg 1: segment 2 forward, fixed → segment 2 backward, progress reverse, fixed"),
        ([1, PLAN[1][:3]], "vehicle 1's plan, leg 3 (segment 4 forward, planned, goal of task 1) in the first trace only (4 legs → 3)"),
    ],
)  # fmt: skip
def test_each_kind_of_leg_difference_names_what_changed(other: list[Any], said: str) -> None:
    divergence = first_divergence(trace((START, [PLAN], [])), trace((START, [other], [])), 0.1)
    assert divergence is not None and said in str(divergence)
    assert "'f'" not in str(divergence) and "None" not in str(divergence)


def test_a_plan_accepted_in_one_run_only_shows_its_first_legs() -> None:
    divergence = first_divergence(trace((START, [PLAN], [])), trace((START, [], [])), 0.1)
    assert divergence is not None
    assert divergence.differences == (
        "vehicle 1's plan accepted in the first trace only (4 legs: segment 1 forward, fixed | segment 2 forward, "
        "fixed | segment 3 forward, fixed | ...)",
    )


def test_vehicle_states_are_told_in_metres_degrees_and_metres_per_second() -> None:
    moved = [[2, 5, "b", "f", 1250, 0, 17950, 500]]
    divergence = first_divergence(trace((START, [], [])), trace((START[:1] + moved, [], [])), 0.1)
    assert divergence is not None
    assert divergence.differences == (
        "vehicle 2: x 1.000 m → 1.250 m, heading 180.00° → 179.50°, speed 0.000 m/s → 0.500 m/s",
    )


def test_events_are_told_in_words_on_both_sides() -> None:
    events = [["complete", 2], ["alert", 3, [1], [2]], ["reject", "wrong-way", 1, 0], ["disturb", 2, "stop"]]
    divergence = first_divergence(trace((START, [], events)), trace((START, [], [])), 0.1)
    assert divergence is not None
    assert divergence.differences == (
        "events: task 2 completed, collision alert on segment 3 (primary 1, secondary 2), vehicle 1's plan "
        "rejected (wrong-way at leg 0), vehicle 2's stop begins → none",
    )


@pytest.mark.parametrize(
    ("event", "said"),
    [
        (["route-error", None, "no route"], "route error: no route"),
        (["route-error", 3, "no route"], "route error for vehicle 3: no route"),
        (["planner-error", 1], "planner error (vehicle 1)"),
        (["resume", 1, "slow"], "vehicle 1's slow-down ends"),
        (["interrupted", "SIGINT"], "interrupted by SIGINT"),
        (["something-new", 1], '["something-new", 1]'),  # a later version's event, as written
    ],
)
def test_every_event_kind_has_its_words(event: list[Any], said: str) -> None:
    assert describe_event(event) == said


def test_a_leg_leaves_out_what_goes_without_saying() -> None:
    assert describe_leg([3, "b", "f", 0, None]) == "segment 3 backward, planned"
    assert describe_leg([3, "b", "r", 1, 4]) == "segment 3 backward, progress reverse, fixed, goal of task 4"


def test_identical_traces_have_no_divergence_and_equal_steps_are_skipped() -> None:
    same = trace((START, [PLAN], []), ([], [], [["complete", 1]]))
    assert first_divergence(same, list(same), 0.1) is None
    later = trace((START, [PLAN], []), ([], [], [["complete", 2]]))
    divergence = first_divergence(same, later, 0.1)
    assert divergence is not None and divergence.step == 1
    assert divergence.differences == ("events: task 1 completed → task 2 completed",)  # no plan or vehicle note


def test_headers_and_lengths_that_differ_are_said_as_before() -> None:
    a = trace((START, [], []))
    assert str(first_divergence(a, ["{}", *a[1:]], 0.1)).endswith(
        "the trace headers differ (different scenario, settings or format)"
    )
    longer = trace((START, [], []), ([], [], []))
    assert first_divergence(a, longer, 0.1) is not None
    assert "one run ended after 1 steps, the other after 2" in str(first_divergence(a, longer, 0.1))

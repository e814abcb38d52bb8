"""Why a fleet is stuck: each stuck situation built on purpose, its reason codes, blockers and root causes."""

from __future__ import annotations

import json
import math
from dataclasses import replace
from pathlib import Path
from typing import Any

import pytest
from scenario_factory import make_scenario

from fleetsim.enums import Direction, Shape
from fleetsim.layout import Layout, Segment
from fleetsim.planners import BFSPlanner, GreedyPlanner, ReservingPlanner
from fleetsim.planning.plans import FleetPlan, Response, RouteError
from fleetsim.planning.snapshot import FleetSnapshot
from fleetsim.recording.artifacts import write_run_artifacts
from fleetsim.recording.picture import failure_picture
from fleetsim.scenario import Scenario, Task
from fleetsim.sim.loop import run_scenario
from fleetsim.sim.report import failure_report
from fleetsim.sim.result import RunResult


def line(count: int, length: float = 4.0) -> tuple[Segment, ...]:
    """``count`` two-way straights in a row along x, ids 1..count: a corridor with no passing place."""
    return tuple(
        Segment(i, Shape.STRAIGHT, Direction.BOTH, ((length * i, 0.0), (length * i + length, 0.0)))
        for i in range(1, count + 1)
    )


def hexagon(side: float = 4.0) -> tuple[Segment, ...]:
    """A ring of six two-way straights round a block, ids 1..6 counter-clockwise."""
    corners = [(side * math.cos(math.radians(60 * k)), side * math.sin(math.radians(60 * k))) for k in range(6)]
    return tuple(Segment(k + 1, Shape.STRAIGHT, Direction.BOTH, (corners[k], corners[(k + 1) % 6])) for k in range(6))


class NeverFixes(BFSPlanner):
    """Plans every route and never fixes a leg of it."""

    def fix_legs(self, task: Task, fleet: FleetSnapshot, layout: Layout) -> Response:
        return []


class OnlyRouteErrors:
    """Answers every request with a route error."""

    def plan_routes(self, task: Task, fleet: FleetSnapshot, layout: Layout) -> Response:
        return [RouteError(task.vehicle_id, f"no route to segment {task.goal_segment}")]

    def fix_legs(self, task: Task, fleet: FleetSnapshot, layout: Layout) -> Response:
        return []


class RouteErrorsFirst(BFSPlanner):
    """Route errors for the first second, then real routes (narrowly not 'nothing but route errors')."""

    def plan_routes(self, task: Task, fleet: FleetSnapshot, layout: Layout) -> Response:
        if fleet.time < 1.0:
            return [RouteError(task.vehicle_id, "map not ready")]
        return super().plan_routes(task, fleet, layout)


class StopsShort(BFSPlanner):
    """Routes to the segment before the goal, without a goal marker, and then adds nothing."""

    def plan_routes(self, task: Task, fleet: FleetSnapshot, layout: Layout) -> Response:
        if fleet.plans[task.vehicle_id].legs[-1].segment == task.goal_segment - 1:
            return []
        [plan] = super().plan_routes(replace(task, goal_segment=task.goal_segment - 1), fleet, layout)
        assert isinstance(plan, FleetPlan)
        legs = tuple(replace(leg, goal_for_task=None, fixed=True) for leg in plan.legs)
        return [FleetPlan(task.vehicle_id, legs)]


def findings(result: RunResult) -> dict[int, dict[str, Any]]:
    failure = next(f for f in result.failures if f.kind in ("deadlock", "timeout"))
    document = json.loads(json.dumps(failure.to_dict()))  # exactly what result.json holds
    assert [v["vehicle"] for v in document["vehicles"]] == sorted(v["vehicle"] for v in document["vehicles"])
    return {v["vehicle"]: v for v in document["vehicles"]}


def stuck_failure(result: RunResult) -> dict[str, Any]:
    failure = next(f for f in result.failures if f.kind in ("deadlock", "timeout"))
    return json.loads(json.dumps(failure.to_dict()))


# -- cycles -----------------------------------------------------------------------------------------


def test_two_vehicles_head_on_in_a_corridor_wait_for_each_other_in_a_cycle(tmp_path: Path) -> None:
    scenario = make_scenario(tmp_path, line(3), "1,1,forward,,\n2,3,backward,,\n", "1,3,\n2,1,\n", deadlock_after=3.0)
    result = run_scenario(scenario, ReservingPlanner())
    found = findings(result)
    assert {v: f["reason"] for v, f in found.items()} == {1: "waits-for", 2: "waits-for"}
    assert (found[1]["blocked_by"], found[2]["blocked_by"]) == ([2], [1])
    assert found[1]["leg"] == {"index": 1, "segment": 2, "traverse": "forward", "progress": "forward"}
    assert found[1]["contested"] == [3] and found[2]["contested"] == [1]
    document = stuck_failure(result)
    assert document["cycles"] == [[1, 2]]
    [root] = document["roots"]
    assert (root["kind"], root["vehicles"], root["cycle"], root["segments"]) == ("cycle", [1, 2], [1, 2], [1, 3])
    assert result.failures[0].message == "vehicles 1 and 2 wait for each other (1 -> 2 -> 1) over segments 1 and 3"
    assert result.deadlock is not None and result.deadlock.cycle == (1, 2)


def test_three_vehicles_round_a_block_form_one_cycle_of_three(tmp_path: Path) -> None:
    # Each stands on every other side of the ring and is sent past the vehicle ahead of it.
    scenario = make_scenario(
        tmp_path, hexagon(), "1,1,forward,,\n2,3,forward,,\n3,5,forward,,\n", "1,4,\n2,6,\n3,2,\n", deadlock_after=2.0
    )
    result = run_scenario(scenario, GreedyPlanner())
    assert result.ended == "deadlock"
    found = findings(result)
    assert {v: (f["reason"], f["blocked_by"]) for v, f in found.items()} == {
        1: ("waits-for", [2]),
        2: ("waits-for", [3]),
        3: ("waits-for", [1]),
    }
    document = stuck_failure(result)
    assert document["cycles"] == [[1, 2, 3]]
    assert [(r["kind"], r["cycle"]) for r in document["roots"]] == [("cycle", [1, 2, 3])]
    assert result.failures[0].message.startswith("vehicles 1, 2 and 3 wait for each other (1 -> 2 -> 3 -> 1)")


def test_two_vehicles_on_a_ring_with_room_between_them_do_not_deadlock(tmp_path: Path) -> None:
    # Narrowly not a cycle: with one of the three gone, each next leg is free in turn.
    scenario = make_scenario(tmp_path, hexagon(), "1,1,forward,,\n2,3,forward,,\n", "1,4,\n2,6,\n", deadlock_after=2.0)
    result = run_scenario(scenario, GreedyPlanner())
    assert (result.status, result.ended, result.diagnosis) == ("passed", "completed", None)


# -- idle blockers and chains -----------------------------------------------------------------------


def dead_end(tmp_path: Path, third: bool, idle_task: bool = False) -> Scenario:
    """A dead-end corridor 1..7; vehicle 2 parks on segment 5, vehicle 1 (on 3) and maybe 3 (on 1) need 7."""
    vehicles = "1,3,forward,,\n2,5,forward,,\n" + ("3,1,forward,,\n" if third else "")
    tasks = "1,7,\n" + ("3,7,\n" if third else "") + ("2,5,\n" if idle_task else "")
    return make_scenario(tmp_path, line(7), vehicles, tasks, deadlock_after=2.0)


def test_a_vehicle_with_no_tasks_parked_on_the_only_way_is_the_root_cause(tmp_path: Path) -> None:
    result = run_scenario(dead_end(tmp_path, third=True), GreedyPlanner())
    found = findings(result)
    assert (found[1]["reason"], found[1]["blocked_by"], found[1]["idle"], found[1]["contested"]) == (
        "blocked-by-idle",
        [2],
        [2],
        [5],
    )
    assert (found[3]["reason"], found[3]["blocked_by"], found[3]["chain"]) == ("waits-for", [1], [3, 1, 2])
    assert 2 not in found  # no pending task: not a finding, but the root cause
    [root] = stuck_failure(result)["roots"]
    assert (root["kind"], root["vehicles"], root["segments"], root["waiting"], root["behind"]) == (
        "idle",
        [2],
        [5],
        [1],
        [1, 3],
    )
    assert result.failures[0].message == (
        "vehicle 2 (no tasks left) stands on segment 5, which vehicle 1 needs; 1 more vehicle waits behind them"
    )


def test_a_blocker_that_still_has_tasks_is_waited_for_not_blamed_as_idle(tmp_path: Path) -> None:
    # Narrowly not blocked-by-idle: vehicle 2's own task is to stay where it is, so it is not idle yet...
    # ...but its task completes at once, so give it one it cannot finish: the far side of vehicle 1.
    scenario = make_scenario(tmp_path, line(7), "1,3,forward,,\n2,5,backward,,\n", "1,7,\n2,1,\n", deadlock_after=2.0)
    result = run_scenario(scenario, GreedyPlanner())
    found = findings(result)
    assert (found[1]["reason"], found[2]["reason"]) == ("waits-for", "waits-for")
    assert "idle" not in found[1]


# -- the planner's part -----------------------------------------------------------------------------


def test_a_planner_that_never_fixes_a_leg_is_reported_as_not_fixed(tmp_path: Path) -> None:
    scenario = make_scenario(tmp_path, line(5), "1,1,forward,,\n2,5,backward,,\n", "1,3,\n2,4,\n", deadlock_after=2.0)
    result = run_scenario(scenario, NeverFixes())
    found = findings(result)
    assert {v: f["reason"] for v, f in found.items()} == {1: "not-fixed", 2: "not-fixed"}
    # Each drove its start leg (fixed from the start) to its end and has stood there since.
    assert found[1]["leg"]["segment"] == 2 and found[1]["since"] == pytest.approx(result.sim_time - 2.0)
    # Vehicle 1's route (2, 3) comes near vehicle 2's next leg (4); vehicle 2's (4) stays clear of 2.
    assert "planned_near" not in found[1] and found[2]["planned_near"] == [1]
    assert found[1]["text"].endswith("is free, but the planner has not fixed it for 2.0 s")
    assert found[2]["text"].endswith("the planner has not fixed it for 2.0 s (vehicle 1 plans to drive near it)")
    document = stuck_failure(result)
    assert [(r["kind"], r["vehicles"]) for r in document["roots"]] == [("not-fixed", [1]), ("not-fixed", [2])]
    assert document["cycles"] == []


def test_the_headline_tells_one_root_cause_in_full_and_counts_the_others(tmp_path: Path) -> None:
    scenario = make_scenario(tmp_path, line(5), "1,1,forward,,\n2,5,backward,,\n", "1,3,\n2,4,\n", deadlock_after=2.0)
    message = run_scenario(scenario, NeverFixes()).failures[0].message
    assert message.startswith("vehicle 1: its next leg (segment 2) is free, but the planner has not fixed it for 2.0 s")
    assert message.endswith("; besides: 1 more vehicle whose free next leg the planner does not fix (2)")


def test_a_planner_that_fixes_the_free_leg_in_time_is_not_stuck(tmp_path: Path) -> None:
    scenario = make_scenario(tmp_path, line(5), "1,1,forward,,\n2,5,backward,,\n", "1,2,\n2,4,\n", deadlock_after=2.0)
    assert run_scenario(scenario, GreedyPlanner()).status == "passed"


def test_a_planner_that_answers_only_route_errors_says_so_in_the_headline(tmp_path: Path) -> None:
    scenario = make_scenario(tmp_path, line(3), "1,1,forward,,\n", "1,3,\n", deadlock_after=2.0)
    result = run_scenario(scenario, OnlyRouteErrors())
    found = findings(result)
    asked = len(result.route_errors)  # once a step: it drove its start leg, then stood for 2 s
    assert found[1]["reason"] == "no-route" and asked == round(result.sim_time / 0.1)
    # Stamped with the end of the step of the call (the first call is at t = 0).
    assert (found[1]["route_errors"], found[1]["since"], found[1]["message"]) == (asked, 0.1, "no route to segment 3")
    assert result.failures[0].message.startswith(
        f"the planner answered nothing but route errors ({asked}); vehicle 1: the planner finds no route"
    )
    report = failure_report(result, heading="h")
    assert f"route errors: {asked} (1 distinct message)" in report
    assert f"  {asked}x, vehicle 1, t = 0.10-{result.sim_time:.2f} s: no route to segment 3" in report


def test_route_errors_then_routes_are_counted_but_not_called_the_only_answer(tmp_path: Path) -> None:
    scenario = make_scenario(tmp_path, line(3), "1,1,forward,,\n", "1,3,\n", time_limit=1.5)
    result = run_scenario(scenario, RouteErrorsFirst())
    assert result.ended == "time-limit" and len(result.route_errors) == 10
    assert "nothing but route errors" not in result.failures[0].message
    assert findings(result)[1]["reason"] == "moving"
    assert "route errors: 10 (1 distinct message)" in failure_report(result, heading="h")


def test_a_plan_that_ends_before_the_goal_is_reported_as_no_plan(tmp_path: Path) -> None:
    scenario = make_scenario(tmp_path, line(4), "1,1,forward,,\n", "1,4,\n", deadlock_after=2.0)
    result = run_scenario(scenario, StopsShort())
    found = findings(result)
    assert (found[1]["reason"], found[1]["plan_end"], found[1]["segment"]) == ("no-plan", 3, 3)
    assert "before the goal of task 1 (segment 4), and the planner adds nothing" in result.failures[0].message


def test_a_timeout_with_vehicles_still_driving_says_how_far_they_have_to_go(tmp_path: Path) -> None:
    scenario = make_scenario(tmp_path, line(10), "1,1,forward,,\n", "1,10,\n", time_limit=5.0)
    result = run_scenario(scenario, ReservingPlanner())
    assert result.ended == "time-limit"
    [timeout] = [f for f in result.failures if f.kind == "timeout"]
    found = findings(result)
    assert found[1]["reason"] == "moving"
    # 5 s at 0.5 m/s² from rest, 1 m/s top speed: 4 m driven of the 36 m to the goal leg (segments 1..9).
    assert found[1]["remaining"] == pytest.approx(36.0 - 4.0, abs=0.05)
    assert "vehicle 1: still driving (32.0 m to its goal leg)" in timeout.message


def test_a_timeout_with_a_vehicle_standing_still_is_not_called_moving(tmp_path: Path) -> None:
    # Narrowly not moving: the same timeout, but the vehicle stood still over its last step.
    scenario = make_scenario(tmp_path, line(5), "1,1,forward,,\n2,5,backward,,\n", "1,3,\n2,4,\n", time_limit=8.0)
    result = run_scenario(scenario, NeverFixes())
    assert {f["reason"] for f in findings(result).values()} == {"not-fixed"}


# -- the report, the picture and the recording ------------------------------------------------------


def test_the_report_lists_root_causes_cycles_and_one_line_per_vehicle(tmp_path: Path) -> None:
    result = run_scenario(dead_end(tmp_path, third=True), GreedyPlanner())
    report = failure_report(result, heading="dead end").splitlines()
    assert report[0].startswith("deadlock at t=") and "vehicle 2 (no tasks left) stands on segment 5" in report[0]
    assert "    root cause: vehicle 2 (no tasks left) stands on segment 5, which vehicle 1 needs" in report
    vehicle_lines = [line for line in report if line.lstrip().startswith("vehicle ") and "(task" in line]
    assert [line.split()[1] for line in vehicle_lines] == ["1", "3"]
    assert "blocked-by-idle vehicle 2" in vehicle_lines[0] and "chain 3 -> 1 -> 2" in vehicle_lines[1]


def test_the_failure_picture_draws_who_waits_for_whom(tmp_path: Path) -> None:
    scenario = make_scenario(
        tmp_path, hexagon(), "1,1,forward,,\n2,3,forward,,\n3,5,forward,,\n", "1,4,\n2,6,\n3,2,\n", deadlock_after=2.0
    )
    result = run_scenario(scenario, GreedyPlanner())
    picture = failure_picture(scenario, result)
    assert picture is not None
    svg = picture[1]
    for source, target in ((1, 2), (2, 3), (3, 1)):
        assert f'<g class="wait-for cycle" data-from="{source}" data-to="{target}">' in svg
    assert svg.count('class="root-cause"') == 3
    assert sorted(int(s.split('"')[0]) for s in svg.split('class="contested-segment" data-segment="')[1:]) == [1, 3, 5]
    assert "red ring: root cause" in svg


def test_a_wait_outside_a_cycle_is_drawn_in_the_plain_colour(tmp_path: Path) -> None:
    scenario = dead_end(tmp_path, third=True)
    result = run_scenario(scenario, GreedyPlanner())
    picture = failure_picture(scenario, result)
    assert picture is not None
    assert '<g class="wait-for" data-from="3" data-to="1">' in picture[1]
    assert 'class="wait-for cycle"' not in picture[1]
    assert 'class="root-cause" data-vehicle="2" data-kind="idle"' in picture[1]


def test_a_collision_picture_has_no_wait_for_layer(tmp_path: Path) -> None:
    scenario = make_scenario(tmp_path / "c", line(3), "1,1,forward,,\n2,3,backward,,\n", "1,3,\n2,1,\n")
    result = run_scenario(scenario, BFSPlanner())
    picture = failure_picture(scenario, result)
    assert picture is not None and result.ended == "collision"
    assert 'class="wait-for"' not in picture[1] and "red ring" not in picture[1]


def test_the_recording_shows_the_wait_for_relations_at_the_failure_time(tmp_path: Path) -> None:
    from mcap_ros2.reader import read_ros2_messages

    scenario = make_scenario(
        tmp_path / "s",
        hexagon(),
        "1,1,forward,,\n2,3,forward,,\n3,5,forward,,\n",
        "1,4,\n2,6,\n3,2,\n",
        deadlock_after=2.0,
    )
    result = run_scenario(scenario, GreedyPlanner())
    paths = write_run_artifacts(tmp_path / "run", result, scenario=scenario)
    markers = [
        (m.log_time_ns, marker)
        for m in read_ros2_messages(paths["mcap"], topics=["/fleetsim/stuck"])
        for marker in m.ros_msg.markers
    ]
    assert {time for time, _ in markers} == {round(result.sim_time * 1e9)}
    arrows = [marker for _, marker in markers if marker.ns == "wait_for_cycle"]
    assert len(arrows) == 3 and all(marker.type == 0 and len(marker.points) == 2 for marker in arrows)
    assert sum(marker.ns == "root_cause" for _, marker in markers) == 3
    [text] = [marker.text for _, marker in markers if marker.ns == "stuck_text"]
    assert text.startswith("deadlock: vehicles 1, 2 and 3 wait for each other")
    logs = [m.ros_msg.msg for m in read_ros2_messages(paths["mcap"], topics=["/rosout"])]
    assert logs[-1] == text


def test_a_passing_run_records_nothing_on_the_stuck_topic(tmp_path: Path) -> None:
    from mcap_ros2.reader import read_ros2_messages

    scenario = make_scenario(tmp_path / "s", line(3), "1,1,forward,,\n", "1,3,\n")
    result = run_scenario(scenario, ReservingPlanner())
    paths = write_run_artifacts(tmp_path / "run", result, scenario=scenario)
    assert list(read_ros2_messages(paths["mcap"], topics=["/fleetsim/stuck"])) == []

"""The reference planners on the shipped examples and on small purpose-built layouts.

Motion is not part of planning, so these tests move vehicles in the coarsest way that respects the
rules: each round, every vehicle with a further fixed leg steps onto it (completing a task if that leg is
its goal). That is enough to show that plans are legal, that reservations hold, and whether a planner
leads every vehicle to its goals.
"""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import pytest

from fleetsim import load_scenario, load_suite
from fleetsim.enums import Direction, Progress, Shape, TurnCapability
from fleetsim.layout import Segment
from fleetsim.load.suites.scenario import load_scenario_dir
from fleetsim.load.tiled.writer import write_map
from fleetsim.planners import BFSPlanner, ReservingPlanner
from fleetsim.planning import FleetController, FleetPlan, Planner
from fleetsim.scenario import DEFAULT_VEHICLE_TYPE, Scenario, Task

SUITE = Path(__file__).resolve().parents[2] / "scenario_suites" / "examples.fleetsim.yaml"
EXAMPLES = [spec.name for spec in load_suite(SUITE).scenarios]


def example(name: str) -> Scenario:
    suite = load_suite(SUITE)
    return load_scenario(next(spec for spec in suite.scenarios if spec.name == name), suite)


def step_forward(controller: FleetController, time: float) -> None:
    """Every vehicle with a second fixed leg drives onto it; entering a goal leg completes its task."""
    for vehicle_id, plan in sorted(controller.plans.items()):
        if len(plan.legs) > 1 and plan.legs[1].fixed:
            nxt = plan.legs[1]
            controller.set_plan(FleetPlan(vehicle_id, plan.legs[1:]))
            state = controller.states[vehicle_id]
            controller.set_state(state._replace(segment=nxt.segment, traverse=nxt.traverse, progress=nxt.progress))
            if nxt.goal_for_task is not None:
                controller.tasks.complete(nxt.goal_for_task, time)


def drive(scenario: Scenario, planner: Planner, rounds: int = 200) -> tuple[FleetController, list[str], list[str]]:
    """Plan and step until every task is done; the alerts and rejections seen on the way."""
    controller = FleetController(scenario)
    alerts: list[str] = []
    rejections: list[str] = []
    for round_number in range(rounds):
        time = round_number * 0.1
        for outcome in controller.planning_round(planner, time):
            rejections += [str(r) for r in outcome.rejections]
            rejections += [str(e) for e in outcome.route_errors]
        alerts += [alert.text() for alert in controller.alerts()]
        if controller.tasks.all_done():
            break
        step_forward(controller, time)
    return controller, alerts, rejections


@pytest.mark.parametrize("name", EXAMPLES)
def test_reserving_planner_completes_every_example_without_alerts_or_rejections(name: str) -> None:
    controller, alerts, rejections = drive(example(name), ReservingPlanner())
    assert (alerts, rejections) == ([], [])
    assert controller.tasks.all_done(), f"pending: {controller.tasks.pending()}"


def test_bfs_planner_plans_collide_on_the_crossing_where_reserving_planner_plans_do_not() -> None:
    scenario = example("crossing")
    bfs, reserving = FleetController(scenario), FleetController(scenario)
    for time in (0.0, 0.1):
        bfs.planning_round(BFSPlanner(), time)
        reserving.planning_round(ReservingPlanner(), time)
    alerts = bfs.alerts()
    assert [a.segment for a in alerts] == [2, 3, 6, 7]  # the arms' inner halves, around the junction
    assert alerts[0].text() == (
        "COLLISION ALERT: Possible collision detected on segment '2'\n"
        "Primary reservations\n - vehicle_1\nSecondary reservations\n - vehicle_2"
    )
    assert reserving.alerts() == ()


def test_bfs_planner_fixes_at_most_three_legs() -> None:
    controller = FleetController(example("corridor-passing-bay"))
    planner = BFSPlanner()
    controller.planning_round(planner, 0.0)
    assert [len(p.fixed_legs) for p in controller.plans.values()] == [1, 1]
    controller.planning_round(planner, 0.1)
    assert [len(p.fixed_legs) for p in controller.plans.values()] == [3, 3]


def test_bfs_planner_ignores_the_goal_direction() -> None:
    controller = FleetController(example("mixed-shapes"))
    planner = BFSPlanner()
    # The AGV's second task has no direction; require one the BFS route does not give.
    controller.planning_round(planner, 0.0)
    tugger_plan = controller.plans[2]
    assert tugger_plan.legs[-1].goal_for_task == 1
    assert [leg.segment for leg in tugger_plan.legs] == [4, 5, 7]


def _scenario(
    tmp_path: Path, segments: tuple[Segment, ...], vehicles: str, tasks: str, capability: TurnCapability
) -> Scenario:
    write_map(tmp_path / "map.json", segments)
    (tmp_path / "vehicles.csv").write_text(
        "vehicle_id,start_segment_id,segment_orientation,progress_direction\n" + vehicles
    )
    (tmp_path / "tasks.csv").write_text("vehicle_id,goal_segment_id,goal_progress_direction\n" + tasks)
    vehicle_type = replace(DEFAULT_VEHICLE_TYPE, turn_capability=capability)
    return load_scenario_dir(tmp_path, vehicle_types={"default": vehicle_type})


def _detour_map() -> tuple[Segment, ...]:
    # From (0,0) to (12,0): one long straight (12 m, 1 leg) or three short ones bending north (3 legs,
    # 4 + 4 + 4 = 12 m plus the bends) -- no: make the direct way two legs but longer.
    return (
        Segment(1, Shape.STRAIGHT, Direction.BOTH, ((-4.0, 0.0), (0.0, 0.0))),
        Segment(2, Shape.STRAIGHT, Direction.BOTH, ((0.0, 0.0), (6.0, 9.0), (12.0, 0.0))),  # 1 leg, 21.6 m
        Segment(3, Shape.STRAIGHT, Direction.BOTH, ((0.0, 0.0), (4.0, 0.0))),
        Segment(4, Shape.STRAIGHT, Direction.BOTH, ((4.0, 0.0), (8.0, 0.0))),
        Segment(5, Shape.STRAIGHT, Direction.BOTH, ((8.0, 0.0), (12.0, 0.0))),
        Segment(6, Shape.STRAIGHT, Direction.BOTH, ((12.0, 0.0), (16.0, 0.0))),
    )


def test_bfs_takes_the_fewest_legs_and_reserving_the_shortest_length(tmp_path: Path) -> None:
    scenario = _scenario(tmp_path, _detour_map(), "1,1,forward,\n", "1,6,\n", TurnCapability.IN_PLACE)
    for planner, expected in ((BFSPlanner(), [1, 2, 6]), (ReservingPlanner(), [1, 3, 4, 5, 6])):
        controller = FleetController(scenario)
        controller.planning_round(planner, 0.0)
        assert [leg.segment for leg in controller.plans[1].legs] == expected


def test_reserving_planner_arrives_in_the_required_direction(tmp_path: Path) -> None:
    scenario = _scenario(tmp_path, _detour_map(), "1,1,forward,\n", "1,5,reverse\n", TurnCapability.IN_PLACE)
    controller = FleetController(scenario)
    controller.planning_round(ReservingPlanner(), 0.0)
    goal = controller.plans[1].legs[-1]
    assert (goal.segment, goal.progress, goal.goal_for_task) == (5, Progress.REVERSE, 1)


def test_curve_vehicle_reverses_at_a_dead_end_to_reach_a_goal_behind_it(tmp_path: Path) -> None:
    scenario = _scenario(tmp_path, _detour_map(), "1,3,forward,\n", "1,1,\n", TurnCapability.CURVE)
    controller, alerts, rejections = drive(scenario, ReservingPlanner())
    assert controller.tasks.all_done() and (alerts, rejections) == ([], [])


def test_unreachable_goal_is_a_route_error(tmp_path: Path) -> None:
    segments = (
        Segment(1, Shape.STRAIGHT, Direction.FORWARD, ((0.0, 0.0), (4.0, 0.0))),
        Segment(2, Shape.STRAIGHT, Direction.FORWARD, ((4.0, 0.0), (8.0, 0.0))),
    )
    # Loading refuses an unreachable task, so the task is put in after loading: a planner must still
    # answer a goal it cannot reach (a scenario built in Python, or a planner of its own making).
    scenario = _scenario(tmp_path, segments, "1,2,forward,\n", "", TurnCapability.IN_PLACE)
    scenario = replace(scenario, tasks=(Task(1, 1, 1),))
    for planner in (BFSPlanner(), ReservingPlanner()):
        [outcome] = FleetController(scenario).planning_round(planner, 0.0)
        [error] = outcome.route_errors
        assert error.vehicle_id == 1 and "no route from segment 2" in error.message


def test_reserving_planner_sends_the_second_vehicle_through_the_passing_bay() -> None:
    controller = FleetController(example("corridor-passing-bay"))
    controller.planning_round(ReservingPlanner(), 0.0)
    assert [leg.segment for leg in controller.plans[2].legs] == [9, 14, 13, 12, 11, 10, 3, 2, 1]


class FarSighted(ReservingPlanner):
    """Fixes as far as the way is free (no horizon), so that the rule of where to stop shows alone."""

    fix_ahead = math.inf


def test_reserving_planner_only_stops_where_no_other_plan_comes_near() -> None:
    controller = FleetController(example("corridor-passing-bay"))
    planner = FarSighted()
    controller.planning_round(planner, 0.0)
    controller.planning_round(planner, 0.1)
    # Vehicle 1 could fix up to segment 7, but 7 lies next to the bay that vehicle 2 will drive: it
    # commits up to 6 and waits there. Vehicle 2 commits into the bay's straight, clear of the corridor.
    assert [leg.segment for leg in controller.plans[1].fixed_legs] == [1, 2, 3, 4, 5, 6]
    assert [leg.segment for leg in controller.plans[2].fixed_legs] == [9, 14, 13, 12]


def test_reserving_planner_waits_while_another_vehicle_holds_the_junction() -> None:
    controller = FleetController(example("crossing"))
    planner = FarSighted()
    controller.planning_round(planner, 0.0)
    controller.planning_round(planner, 0.1)
    assert [len(plan.fixed_legs) for plan in controller.plans.values()] == [4, 1]


@pytest.mark.parametrize("fix_ahead", [0.5, 4.0, 12.0])
def test_reserving_planner_fixes_its_way_only_a_little_past_its_braking_distance(fix_ahead: float) -> None:
    """A vehicle that holds its way far ahead makes others wait for reservations it does not need yet:
    it fixes legs until the first place past its braking distance + ``fix_ahead`` where it may stop."""
    whole = example("loop-one-way")  # vehicle 1 alone: every place is one where it may stop
    scenario = replace(whole, vehicles=whole.vehicles[:1], tasks=tuple(t for t in whole.tasks if t.vehicle_id == 1))
    controller = FleetController(scenario)
    planner = type("Planner", (ReservingPlanner,), {"fix_ahead": fix_ahead})()
    controller.planning_round(planner, 0.0)
    controller.planning_round(planner, 0.1)
    lengths = {sid: segment.length for sid, segment in scenario.layout.segments.items()}
    for vehicle_id, plan in controller.plans.items():
        kind = next(vehicle.type for vehicle in scenario.vehicles if vehicle.id == vehicle_id)
        horizon = kind.max_speed**2 / (2 * kind.acceleration) + fix_ahead
        ahead = [lengths[leg.segment] for leg in plan.fixed_legs[1:]]
        assert sum(ahead[:-1]) < horizon <= sum(ahead), (vehicle_id, ahead, horizon)
        assert len(plan.fixed_legs) < len(plan.legs)  # the goal is further than the horizon


@pytest.mark.parametrize("planner_class", [BFSPlanner, ReservingPlanner])
def test_planners_are_deterministic(planner_class: type) -> None:
    runs = [drive(example("loop-one-way"), planner_class(), rounds=30)[0].plans for _ in range(2)]
    assert dict(runs[0]) == dict(runs[1])

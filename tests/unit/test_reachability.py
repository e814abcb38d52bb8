"""Where a vehicle can drive (fleetsim.layout.reachability): moves, searches, the component index."""

from __future__ import annotations

from pathlib import Path

import pytest

from fleetsim.enums import Direction, Progress, Shape, Traverse, TurnCapability
from fleetsim.layout import Layout, Segment, build_layout
from fleetsim.layout.reachability import ReachIndex, State, arrivals, goal_states, moves, next_steps, reach
from fleetsim.load import load_scenario, load_suite
from fleetsim.planners import routing

SUITE = Path(__file__).resolve().parents[2] / "scenario_suites" / "examples.fleetsim.yaml"
F, B = Traverse.FORWARD, Traverse.BACKWARD
FWD, REV = Progress.FORWARD, Progress.REVERSE


def layout_of(*segments: Segment) -> Layout:
    return build_layout(segments, vehicle_radius=0.5)


def straight(sid: int, a: tuple[float, float], b: tuple[float, float], direction: str = "both") -> Segment:
    return Segment(sid, Shape.STRAIGHT, Direction(direction), (a, b))


def every_state(layout: Layout) -> list[State]:
    return [(sid, t, p) for sid, s in layout.segments.items() for t in Traverse if s.allows(t) for p in Progress]


def example_layouts() -> list[Layout]:
    suite = load_suite(SUITE)
    return [load_scenario(spec, suite).layout for spec in suite.scenarios]


@pytest.mark.parametrize("capability", list(TurnCapability))
def test_the_component_index_answers_what_a_search_finds_from_every_state_of_the_examples(
    capability: TurnCapability,
) -> None:
    for layout in example_layouts():
        index = ReachIndex(layout, capability)
        states = every_state(layout)
        for state in states:
            assert index.entered([state], states) == reach(layout, capability, [state]).entered, state


def test_a_start_counts_as_entered_only_when_the_vehicle_can_come_back_to_it() -> None:
    dead_end = layout_of(straight(1, (0.0, 0.0), (4.0, 0.0), "forward"))
    loop = layout_of(straight(1, (0.0, 0.0), (4.0, 0.0)))  # two-way: U-turns at both ends
    for layout, back in ((dead_end, False), (loop, True)):
        index = ReachIndex(layout, TurnCapability.CURVE)
        assert ((1, F, FWD) in index.entered([(1, F, FWD)], [(1, F, FWD)])) is back
        assert ((1, F, FWD) in reach(layout, TurnCapability.CURVE, [(1, F, FWD)]).entered) is back


def test_a_vehicle_turning_in_place_may_drive_on_with_either_progress() -> None:
    layout = layout_of(straight(1, (0.0, 0.0), (4.0, 0.0), "forward"), straight(2, (4.0, 0.0), (4.0, 4.0), "forward"))
    assert set(moves(layout, TurnCapability.IN_PLACE, (1, F, FWD))) == {(2, F, FWD), (2, F, REV)}
    assert set(moves(layout, TurnCapability.CURVE, (1, F, FWD))) == set()  # a corner


def test_arrivals_keep_the_goal_progress_and_count_the_start_only_with_its_own_progress() -> None:
    starts = [(1, F, FWD)]
    entered = [(2, F, REV), (3, B, FWD)]
    assert arrivals(starts, entered, 2, None) == {(2, F, REV)}
    assert arrivals(starts, entered, 2, FWD) == frozenset()
    assert arrivals(starts, entered, 1, FWD) == {(1, F, FWD)}
    assert arrivals(starts, entered, 1, REV) == frozenset()


def test_goal_states_follow_the_segments_direction() -> None:
    layout = layout_of(straight(1, (0.0, 0.0), (4.0, 0.0), "backward"))
    assert goal_states(layout, 1) == ((1, B, FWD), (1, B, REV))


def test_the_route_searches_use_the_same_progress_rules() -> None:
    assert routing.next_steps is next_steps


def test_remembered_estimates_are_the_estimates_worked_out_afresh() -> None:
    # A step table keeps each goal's estimates; a second search to the same goal reads them, and they are
    # the very floats a search without a table works out (so routes, and hashes, stay the same).
    for layout in example_layouts():
        table = routing.StepTable(layout, TurnCapability.IN_PLACE)
        for goal in sorted(layout.segments):
            fresh = routing.straight_line_estimate(layout, goal)
            first = routing.straight_line_estimate(layout, goal, table)
            again = routing.straight_line_estimate(layout, goal, table)
            for segment, traverse, _ in every_state(layout):
                assert first(segment, traverse) == fresh(segment, traverse) == again(segment, traverse)
            assert set(table.estimates[goal]) == {(s, t) for s, t, _ in every_state(layout)}

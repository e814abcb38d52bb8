"""The joint search of a few stuck vehicles (``choreograph``) reads the layout's predecessors from the
planner's step table, worked out once for every search, and finds what it finds without one."""

from __future__ import annotations

from fleetsim.enums import Progress, Traverse, TurnCapability
from fleetsim.layout import build_layout
from fleetsim.layout.reachability import State, next_states
from fleetsim.planners.choreography import choreograph
from fleetsim.planners.routing import StepTable
from fleetsim.scenario import DEFAULT_VEHICLE_TYPE
from fleetsim.strategies.geometry import grid

LAYOUT = build_layout(grid(3), vehicle_radius=DEFAULT_VEHICLE_TYPE.swept_radius)
CAPABILITY = DEFAULT_VEHICLE_TYPE.turn_capability


def test_the_goal_taken_by_another_vehicle_is_reached_after_it_moves_aside_with_or_without_a_table() -> None:
    first, second = sorted(LAYOUT.segments)[:2]
    starts = {1: (first, Traverse.FORWARD, Progress.FORWARD), 2: (second, Traverse.FORWARD, Progress.FORWARD)}
    capabilities = {1: CAPABILITY, 2: CAPABILITY}
    alone = choreograph(LAYOUT, [1, 2], starts, capabilities, set(), (1, second, None), 5000)
    assert alone is not None and alone[-1] == (1, (second, Traverse.FORWARD, Progress.FORWARD))
    assert alone[0][0] == 2  # the vehicle on the goal moves first
    table = StepTable(LAYOUT, CAPABILITY)
    assert choreograph(LAYOUT, [1, 2], starts, capabilities, set(), (1, second, None), 5000, table) == alone
    before = table.predecessors()
    assert choreograph(LAYOUT, [1, 2], starts, capabilities, {first}, (1, second, None), 5000, table) is None
    assert table.predecessors() is before  # worked out once


def test_a_table_for_another_capability_is_not_read() -> None:
    first, second = sorted(LAYOUT.segments)[:2]
    starts = {1: (first, Traverse.FORWARD, Progress.FORWARD), 2: (second, Traverse.FORWARD, Progress.FORWARD)}
    other = TurnCapability.CURVE if CAPABILITY is not TurnCapability.CURVE else TurnCapability.IN_PLACE
    table = StepTable(LAYOUT, other)
    capabilities = {1: CAPABILITY, 2: CAPABILITY}
    assert choreograph(LAYOUT, [1, 2], starts, capabilities, set(), (1, second, None), 5000, table) == choreograph(
        LAYOUT, [1, 2], starts, capabilities, set(), (1, second, None), 5000
    )
    assert table._before is None


def test_the_predecessors_are_every_state_each_state_is_driven_on_from() -> None:
    table = StepTable(LAYOUT, CAPABILITY)
    before = table.predecessors()
    states: list[State] = [
        (segment, traverse, progress)
        for segment, item in LAYOUT.segments.items()
        for traverse in Traverse
        if item.allows(traverse)
        for progress in Progress
    ]
    pairs = {(state, following) for state in states for following in next_states(LAYOUT, CAPABILITY, state)}
    assert pairs and {(earlier, state) for state, earlier_ones in before.items() for earlier in earlier_ones} == pairs

"""Connections and the state graph (SPEC §4): which (segment, traverse) may follow which."""

from __future__ import annotations

import math
import random

import networkx as nx
import pytest

from fleetsim.enums import Direction, JointKind, Shape, Traverse
from fleetsim.layout import Connection, Segment, build_layout

F, B = Traverse.FORWARD, Traverse.BACKWARD


def between_segments(connections: tuple[Connection, ...]) -> tuple[Connection, ...]:
    """The connections from one segment onto another, leaving out each segment's U-turns."""
    return tuple(c for c in connections if c.from_segment != c.to_segment)


def _straight(sid: int, *points: tuple[float, float], direction: Direction = Direction.BOTH) -> Segment:
    return Segment(sid, Shape.STRAIGHT, direction, tuple(points))


def _junction() -> list[Segment]:
    """Segment 1 ends at (4, 0), where 5 and 9 start and 3 ends; ids deliberately out of order."""
    return [
        _straight(9, (4.0, 0.0), (4.0, 4.0)),
        _straight(5, (4.0, 0.0), (8.0, 0.0)),
        _straight(1, (0.0, 0.0), (4.0, 0.0)),
        _straight(3, (4.0, -4.0), (4.0, 0.0)),
    ]


def test_ends_within_connection_tolerance_connect() -> None:
    layout = build_layout([_straight(1, (0, 0), (4, 0)), _straight(2, (4.049, 0), (8, 0))], vehicle_radius=0.3)
    assert layout.successors(1, F) == ((1, B, JointKind.OPPOSITE), (2, F, JointKind.SAME))


def test_ends_just_beyond_connection_tolerance_do_not_connect() -> None:
    layout = build_layout([_straight(1, (0, 0), (4, 0)), _straight(2, (4.051, 0), (8, 0))], vehicle_radius=0.3)
    assert layout.successors(1, F) == ((1, B, JointKind.OPPOSITE),)  # only its own U-turn
    assert between_segments(layout.connections) == ()


def test_connection_enters_backward_through_the_last_waypoint() -> None:
    layout = build_layout([_straight(1, (0, 0), (4, 0)), _straight(2, (8, 0), (4, 0))], vehicle_radius=0.3)
    assert layout.connections == (
        Connection(1, F, 1, B, JointKind.OPPOSITE),
        Connection(1, F, 2, B, JointKind.SAME),
        Connection(1, B, 1, F, JointKind.OPPOSITE),
        Connection(2, F, 1, B, JointKind.SAME),
        Connection(2, F, 2, B, JointKind.OPPOSITE),
        Connection(2, B, 2, F, JointKind.OPPOSITE),
    )


def test_successors_are_sorted_by_segment_then_forward_first() -> None:
    layout = build_layout(_junction(), vehicle_radius=0.3)
    assert layout.successors(1, F) == (
        (1, B, JointKind.OPPOSITE),
        (3, B, JointKind.TURN_IN_PLACE),
        (5, F, JointKind.SAME),
        (9, F, JointKind.TURN_IN_PLACE),
    )


def test_predecessors_list_the_states_that_lead_into_a_state() -> None:
    layout = build_layout(_junction(), vehicle_radius=0.3)
    assert layout.predecessors(5, F) == (
        (1, F, JointKind.SAME),
        (3, F, JointKind.TURN_IN_PLACE),
        (5, B, JointKind.OPPOSITE),
        (9, B, JointKind.TURN_IN_PLACE),
    )


def test_connections_do_not_depend_on_the_order_segments_are_given() -> None:
    segments = _junction()
    expected = build_layout(segments, vehicle_radius=0.3).connections
    for seed in range(5):
        shuffled = segments[:]
        random.Random(seed).shuffle(shuffled)
        assert build_layout(shuffled, vehicle_radius=0.3).connections == expected


def test_connections_are_sorted_by_from_state_then_to_state() -> None:
    connections = build_layout(_junction(), vehicle_radius=0.3).connections
    rank = {F: 0, B: 1}
    keys = [(c.from_segment, rank[c.from_traverse], c.to_segment, rank[c.to_traverse]) for c in connections]
    assert keys == sorted(keys)
    assert len(between_segments(connections)) == 12  # four ends meet: each ordered pair of distinct ends, once
    assert len(connections) == 12 + 4 * 2  # and each two-way segment U-turns at both of its ends


def test_forward_only_segment_has_only_its_forward_state() -> None:
    layout = build_layout([_straight(1, (0, 0), (4, 0), direction=Direction.FORWARD)], vehicle_radius=0.3)
    assert list(layout.graph.nodes) == [(1, F)]


def test_backward_only_segment_has_only_its_backward_state() -> None:
    layout = build_layout([_straight(1, (0, 0), (4, 0), direction=Direction.BACKWARD)], vehicle_radius=0.3)
    assert list(layout.graph.nodes) == [(1, B)]


def test_one_way_segment_is_never_entered_the_wrong_way() -> None:
    one_way = _straight(1, (0, 0), (4, 0), direction=Direction.FORWARD)
    layout = build_layout([one_way, _straight(2, (4, 0), (8, 0))], vehicle_radius=0.3)
    assert layout.connections == (
        Connection(1, F, 2, F, JointKind.SAME),
        Connection(2, F, 2, B, JointKind.OPPOSITE),
        Connection(2, B, 2, F, JointKind.OPPOSITE),
    )
    assert layout.successors(2, B) == ((2, F, JointKind.OPPOSITE),)  # its U-turn, but not onto 1
    assert layout.successors(1, B) == ()  # a traverse the segment forbids has no successors


@pytest.mark.parametrize(
    ("first", "second"),
    [(Direction.FORWARD, Direction.BACKWARD), (Direction.BACKWARD, Direction.FORWARD)],
    ids=["heads-meet", "tails-meet"],
)
def test_touching_one_ways_with_incompatible_directions_do_not_connect(first: Direction, second: Direction) -> None:
    segments = [_straight(1, (0, 0), (4, 0), direction=first), _straight(2, (4, 0), (8, 0), direction=second)]
    layout = build_layout(segments, vehicle_radius=0.3)
    assert layout.connections == ()
    assert layout.graph.number_of_edges() == 0
    assert layout.conflicts(1) == {1, 2}  # they still conflict


def test_two_way_segment_u_turns_onto_itself_at_both_ends_as_a_cusp() -> None:
    layout = build_layout([_straight(1, (0, 0), (4, 0))], vehicle_radius=0.3)
    assert layout.connections == (
        Connection(1, F, 1, B, JointKind.OPPOSITE),  # at its last waypoint
        Connection(1, B, 1, F, JointKind.OPPOSITE),  # at its first waypoint
    )


@pytest.mark.parametrize("direction", [Direction.FORWARD, Direction.BACKWARD])
def test_one_way_segment_has_no_u_turn(direction: Direction) -> None:
    layout = build_layout([_straight(1, (0, 0), (4, 0), direction=direction)], vehicle_radius=0.3)
    assert layout.connections == ()
    assert layout.graph.number_of_edges() == 0


def test_segment_whose_ends_meet_is_a_loop_onto_itself_and_u_turns_too() -> None:
    circle = tuple((math.cos(math.radians(a)), math.sin(math.radians(a))) for a in range(0, 361, 10))
    layout = build_layout([Segment(1, Shape.CURVE, Direction.BOTH, circle)], vehicle_radius=0.3)
    assert layout.connections == (
        Connection(1, F, 1, F, JointKind.SAME),  # round the loop again
        Connection(1, F, 1, B, JointKind.OPPOSITE),  # U-turn
        Connection(1, B, 1, F, JointKind.OPPOSITE),  # U-turn
        Connection(1, B, 1, B, JointKind.SAME),  # round the loop again, backing
    )


def test_graph_has_a_node_per_allowed_state_and_edges_carry_the_joint() -> None:
    layout = build_layout(_junction(), vehicle_radius=0.3)
    assert list(layout.graph.nodes) == [(s, t) for s in (1, 3, 5, 9) for t in (F, B)]
    assert layout.graph.edges[(1, F), (5, F)]["joint"] is JointKind.SAME
    assert layout.graph.number_of_edges() == len(layout.connections)


def test_graph_is_frozen() -> None:
    layout = build_layout(_junction(), vehicle_radius=0.3)
    assert nx.is_frozen(layout.graph)
    with pytest.raises(nx.NetworkXError):
        layout.graph.add_edge((1, F), (9, B))
    with pytest.raises(nx.NetworkXError):
        layout.graph.remove_node((1, F))


def test_segments_mapping_is_read_only_and_in_ascending_id_order() -> None:
    layout = build_layout(_junction(), vehicle_radius=0.3)
    assert list(layout.segments) == [1, 3, 5, 9]
    with pytest.raises(TypeError):
        layout.segments[2] = _straight(2, (0, 0), (1, 0))  # type: ignore[index]


def test_layout_attributes_cannot_be_reassigned() -> None:
    layout = build_layout(_junction(), vehicle_radius=0.3)
    with pytest.raises(AttributeError):
        layout.vehicle_radius = 1.0  # type: ignore[misc]


def test_traverse_may_be_given_as_its_string_value() -> None:
    layout = build_layout(_junction(), vehicle_radius=0.3)
    assert layout.successors(1, "forward") == layout.successors(1, F)  # type: ignore[arg-type]

"""The map as VDA 5050 nodes and edges: site names where the map has them, stable generated ids where it
has not, and every edge of an order read back as the segment and traverse it drives."""

from __future__ import annotations

from pathlib import Path

import pytest

from fleetsim.enums import Direction, Shape, Traverse
from fleetsim.layout import Segment, build_layout
from fleetsim.load.suites.scenario import load_scenario
from fleetsim.load.suites.suite import load_suite
from fleetsim.vda5050.places import EdgeProblem, SiteGraph, site_graph

SUITES = Path(__file__).resolve().parents[2] / "scenario_suites"
F, B = Traverse.FORWARD, Traverse.BACKWARD


def _shipped(suite: str, name: str) -> SiteGraph:
    loaded = load_suite(SUITES / f"{suite}.fleetsim.yaml")
    [spec] = [s for s in loaded.scenarios if s.name == name]
    return site_graph(load_scenario(spec, loaded).layout, map_id=name)


def test_a_tiled_junction_is_one_node_named_after_its_lowest_segment_end() -> None:
    graph = _shipped("examples", "crossing")
    centre = graph.node_at(2, True)
    meeting = graph.places[centre].ends
    assert meeting == ((2, True), (3, False), (6, True), (7, False))  # four segments meet in the middle
    assert centre == "s2.last" and (graph.places[centre].x, graph.places[centre].y) == (0.0, 0.0)
    assert all(graph.node_at(sid, at_last) == centre for sid, at_last in meeting)
    assert graph.node_at(2, False) == "s1.last" != centre  # narrow: the segment's other end is another node


def test_a_tiled_edge_is_driven_either_way_by_its_nodes() -> None:
    graph = _shipped("examples", "crossing")
    first, last = graph.node_at(1, False), graph.node_at(1, True)
    assert graph.edge_id(1, F) == graph.edge_id(1, B) == "e1"
    assert graph.leg_of("e1", first, last) == (1, F)
    assert graph.leg_of("e1", last, first) == (1, B)
    assert graph.entry_node(1, B) == last and graph.exit_node(1, B) == first


def test_a_lif_map_keeps_its_node_and_edge_ids() -> None:
    graph = _shipped("sites", "packing-hall-lif")
    assert {"A", "P", "B", "Q", "S"} <= set(graph.places)
    segment, traverse = graph.leg_of("A-P", "A", "P")
    assert traverse is F and graph.edge_id(segment, F) == "A-P"
    # P-Q and Q-P are one two-way segment: each direction is its own LIF edge.
    pq, forward = graph.leg_of("P-Q", "P", "Q")
    qp, backward = graph.leg_of("Q-P", "Q", "P")
    assert pq == qp and {forward, backward} == {F, B}
    assert graph.edge_id(pq, backward) == "Q-P"


def test_a_lif_edge_named_with_its_nodes_reversed_is_refused() -> None:
    graph = _shipped("sites", "packing-hall-lif")
    with pytest.raises(EdgeProblem, match=r"edge 'A-P' joins from 'A' to 'P', not 'P' to 'A'") as caught:
        graph.leg_of("A-P", "P", "A")
    assert caught.value.reference == "endNodeId"
    with pytest.raises(KeyError, match="has no edge driven backward"):
        graph.edge_id(graph.leg_of("A-P", "A", "P")[0], B)  # a one-way LIF edge has no reverse


def test_an_rmf_map_names_nodes_by_their_vertices() -> None:
    graph = _shipped("sites", "clinic-rmf")
    assert {"lobby", "pharmacy"} <= set(graph.places)
    segment, traverse = graph.leg_of("lobby--v1", "lobby", "v1")
    assert graph.leg_of("v1--lobby", "v1", "lobby") == (segment, B if traverse is F else F)


@pytest.mark.parametrize(
    ("edge", "start", "end", "reference", "words"),
    [
        ("e99", "s1.first", "s1.last", "edgeId", "edge 'e99' is no edge of map 'crossing'"),
        ("e1", "nowhere", "s1.last", "startNodeId", "node 'nowhere' is no node of map 'crossing'"),
        ("e1", "s1.first", "nowhere", "endNodeId", "node 'nowhere' is no node of map 'crossing'"),
    ],
)
def test_unknown_edges_and_nodes_are_named(edge: str, start: str, end: str, reference: str, words: str) -> None:
    graph = _shipped("examples", "crossing")
    with pytest.raises(EdgeProblem, match=words) as caught:
        graph.leg_of(edge, start, end)
    assert caught.value.reference == reference


def test_an_edge_between_nodes_it_does_not_join_is_refused() -> None:
    graph = _shipped("examples", "crossing")
    other = next(n for n in graph.places if n not in (graph.node_at(1, False), graph.node_at(1, True)))
    with pytest.raises(EdgeProblem, match=r"edge 'e1' joins .* not ") as caught:
        graph.leg_of("e1", graph.node_at(1, False), other)
    assert caught.value.reference == "endNodeId"


def _line(sid: int, a: tuple[float, float], b: tuple[float, float], ends: tuple[str, str] | None = None) -> Segment:
    return Segment(sid, Shape.STRAIGHT, Direction.BOTH, (a, b), (f"{sid}",), ends=ends)


def test_a_name_two_places_share_names_neither() -> None:
    segments = [_line(1, (0, 0), (4, 0), ("dock", "hub")), _line(2, (4, 0), (8, 0), ("hub", "dock"))]
    graph = site_graph(build_layout(segments, vehicle_radius=0.3), map_id="m")
    assert set(graph.places) == {"s1.first", "hub", "s2.last"}  # 'dock' names two places
    assert graph.node("hub") is graph.places["hub"]


def test_a_second_name_of_one_place_is_an_alias() -> None:
    segments = [_line(1, (0, 0), (4, 0), ("a", "m1")), _line(2, (4.01, 0), (8, 0), ("m2", "b"))]
    graph = site_graph(build_layout(segments, vehicle_radius=0.3), map_id="m")
    middle = graph.places["m1"]
    assert middle.aliases == ("m2",) and graph.node("m2") is middle
    assert middle.x == pytest.approx(4.005)
    assert graph.leg_of("2", "m2", "b") == (2, F)  # an order may name the place by either


def test_node_ids_do_not_depend_on_the_order_segments_are_given_in() -> None:
    segments = [_line(3, (0, 0), (4, 0)), _line(1, (4, 0), (8, 0)), _line(2, (4, 0), (4, 4))]
    one = site_graph(build_layout(segments, vehicle_radius=0.3), map_id="m")
    other = site_graph(build_layout(reversed(segments), vehicle_radius=0.3), map_id="m")
    assert dict(one.places) == dict(other.places)
    assert one.node_at(3, True) == "s1.first"  # the junction is named after segment 1, its lowest end

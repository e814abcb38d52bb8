"""VDA 5050 orders read as route plans: base and horizon as fixed and planned legs, progress from the
edges' orientation or the map's rules, how an order joins what the vehicle has, and every wrong order
judged twice, by a VDA 5050 error of the standard's kind and by the fleetsim check with its code."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path

import pytest

from fleetsim.enums import JointKind, Progress, Traverse, TurnCapability
from fleetsim.load.suites.scenario import load_scenario
from fleetsim.load.suites.suite import load_suite
from fleetsim.planning.checks import CheckContext, Rejection, RejectionCode, check_plans
from fleetsim.planning.plans import FleetLeg, FleetPlan
from fleetsim.planning.snapshot import initial_plan
from fleetsim.scenario import Scenario
from fleetsim.vda5050.model import Edge, Header, Node, Order, VdaError
from fleetsim.vda5050.orders import NO_SEGMENT, Join, OrderStatus, Reading, join_order, read_order, vda_error
from fleetsim.vda5050.places import SiteGraph, site_graph

SUITES = Path(__file__).resolve().parents[2] / "scenario_suites"
F, B = Traverse.FORWARD, Traverse.BACKWARD
HEADER = Header(7, "2026-12-03T12:00:00.00Z", "2.0.0", "fleetsim", "1")


def _scenario(name: str) -> Scenario:
    suite = load_suite(SUITES / "examples.fleetsim.yaml")
    [spec] = [s for s in suite.scenarios if s.name == name]
    return load_scenario(spec, suite)


def _order(
    graph: SiteGraph,
    path: Sequence[tuple[int, Traverse]],
    *,
    released: int | None = None,
    order_id: str = "o1",
    update: int = 0,
    first_sequence: int = 0,
    orientations: Sequence[float | None] | None = None,
) -> Order:
    """An order driving ``path`` (segment, traverse); the first ``released`` edges (default all) are base."""
    released = len(path) if released is None else released
    node_ids = [graph.entry_node(*path[0])] + [graph.exit_node(*leg) for leg in path]
    nodes = tuple(Node(node_id, first_sequence + 2 * k, released=k <= released) for k, node_id in enumerate(node_ids))
    edges = tuple(
        Edge(
            graph.edge_id(*leg),
            first_sequence + 2 * k + 1,
            released=k < released,
            start_node_id=node_ids[k],
            end_node_id=node_ids[k + 1],
            orientation=None if orientations is None else orientations[k],
        )
        for k, leg in enumerate(path)
    )
    return Order(HEADER, order_id, update, nodes, edges)


def _judge(scenario: Scenario, plan: FleetPlan, current: FleetPlan | None = None) -> FleetPlan | Rejection:
    plans = {v.id: initial_plan(v) for v in scenario.vehicles}
    if current is not None:
        plans[current.vehicle_id] = current
    queues = {v.id: tuple(t for t in scenario.tasks if t.vehicle_id == v.id) for v in scenario.vehicles}
    types = {v.id: v.type for v in scenario.vehicles}
    [result] = check_plans([plan], CheckContext(scenario.layout, types, plans, queues))
    return result


def _read(scenario: Scenario, order: Order, vehicle: int = 1) -> Reading:
    graph = site_graph(scenario.layout, map_id=scenario.name)
    [v] = [v for v in scenario.vehicles if v.id == vehicle]
    return read_order(order, graph, scenario.layout, v.type, v.progress)


# -- reading ----------------------------------------------------------------------------------------


def test_base_and_horizon_become_fixed_and_planned_legs() -> None:
    scenario = _scenario("crossing")
    graph = site_graph(scenario.layout, map_id="crossing")
    reading = _read(scenario, _order(graph, [(1, F), (2, F), (3, F), (4, F)], released=2))
    assert [(leg.segment, leg.traverse, leg.fixed) for leg in reading.legs] == [
        (1, F, True),
        (2, F, True),
        (3, F, False),
        (4, F, False),
    ]
    assert all(leg.progress is Progress.FORWARD for leg in reading.legs)
    assert reading.problems == ()
    assert _judge(scenario, FleetPlan(1, reading.legs)) == FleetPlan(1, reading.legs)  # the checks accept it


@pytest.mark.parametrize(
    ("orientation", "kind", "progress"),
    [
        (math.pi, "TANGENTIAL", Progress.REVERSE),
        (0.1, "TANGENTIAL", Progress.FORWARD),
        (-math.pi + 0.2, None, Progress.REVERSE),  # TANGENTIAL is the default
        (math.pi, "GLOBAL", Progress.FORWARD),  # the edge runs west: facing west is nose first
        (0.0, "GLOBAL", Progress.REVERSE),
    ],
)
def test_the_orientation_says_nose_first_or_backing(orientation: float, kind: str | None, progress: Progress) -> None:
    scenario = _scenario("crossing")
    graph = site_graph(scenario.layout, map_id="crossing")
    order = _order(graph, [(2, B)])
    [edge] = order.edges
    order = Order(HEADER, "o1", 0, order.nodes, (replace(edge, orientation=orientation, orientation_type=kind),))
    [leg] = _read(scenario, order).legs
    assert leg.progress is progress


def test_without_an_orientation_a_cusp_is_crossed_as_the_map_allows() -> None:
    scenario = _scenario("mixed-shapes")
    layout = scenario.layout
    cusp = next(
        (sid, t, c)
        for sid in sorted(layout.segments)
        for t in (F, B)
        if layout.segments[sid].allows(t)
        for c in layout.continuations(TurnCapability.CURVE, sid, t, Progress.FORWARD)
        if c.joint is JointKind.OPPOSITE and c.segment != sid
    )
    sid, traverse, after = cusp
    graph = site_graph(layout, map_id="mixed")
    tugger = next(v for v in scenario.vehicles if v.type.turn_capability is TurnCapability.CURVE)
    order = _order(graph, [(sid, traverse), (after.segment, after.traverse)])
    reading = read_order(order, graph, layout, tugger.type, Progress.FORWARD)
    assert [leg.progress for leg in reading.legs] == [Progress.FORWARD, Progress.REVERSE]  # it backs on
    # Told to go on nose first over the cusp, the tugger cannot: the checks and the VDA error say so.
    forced = _order(graph, [(sid, traverse), (after.segment, after.traverse)], orientations=[0.0, 0.0])
    legs = read_order(forced, graph, layout, tugger.type, Progress.FORWARD).legs
    plans = {v.id: initial_plan(v) for v in scenario.vehicles}
    plans[tugger.id] = FleetPlan(tugger.id, (legs[0],))
    ctx = CheckContext(layout, {v.id: v.type for v in scenario.vehicles}, plans, {v.id: () for v in scenario.vehicles})
    [rejection] = check_plans([FleetPlan(tugger.id, legs)], ctx)
    assert isinstance(rejection, Rejection) and rejection.code is RejectionCode.ILLEGAL_PROGRESS_CHANGE
    error = vda_error(rejection, forced, forced.edges)
    assert error.error_type == "noRouteError" and error.error_description.startswith("illegal-progress-change: ")
    assert ("edgeId", forced.edges[1].edge_id) in [(r.reference_key, r.reference_value) for r in error.error_references]


def test_an_unknown_edge_is_a_validation_error_and_an_unknown_segment() -> None:
    scenario = _scenario("crossing")
    graph = site_graph(scenario.layout, map_id="crossing")
    good = _order(graph, [(1, F), (2, F)])
    bad = Order(HEADER, "o1", 0, good.nodes, (good.edges[0], replace(good.edges[1], edge_id="e42")))
    reading = _read(scenario, bad)
    [problem] = reading.problems
    assert (
        problem.error_type == "validationError"
        and "edge 'e42' is no edge of map 'crossing'" in problem.error_description
    )
    assert reading.legs[1].segment == NO_SEGMENT
    rejection = _judge(scenario, FleetPlan(1, reading.legs))
    assert isinstance(rejection, Rejection) and rejection.code is RejectionCode.UNKNOWN_SEGMENT
    assert vda_error(rejection, bad, reading.edges).error_type == "validationError"


def test_sequence_ids_out_of_step_are_each_named() -> None:
    scenario = _scenario("crossing")
    graph = site_graph(scenario.layout, map_id="crossing")
    good = _order(graph, [(1, F), (2, F)])
    nodes = (good.nodes[0], Node(good.nodes[1].node_id, 3, True), good.nodes[2])
    problems = _read(scenario, Order(HEADER, "o1", 0, nodes, good.edges)).problems
    words = [p.error_description for p in problems]
    assert any("has sequenceId 3, expected 2" in w for w in words), words
    assert _read(scenario, good).problems == ()  # narrow: 0, 1, 2, 3, 4 is right


def test_an_edge_between_other_nodes_than_its_neighbours_is_named() -> None:
    scenario = _scenario("crossing")
    graph = site_graph(scenario.layout, map_id="crossing")
    good = _order(graph, [(1, F), (2, F), (3, F)])
    skipped = (good.nodes[0], good.nodes[1], good.nodes[3])  # node 2 left out, the edges kept
    edges = (good.edges[0], replace(good.edges[2], sequence_id=3))
    reading = _read(scenario, Order(HEADER, "o1", 0, (*skipped[:2], Node(skipped[2].node_id, 4, True)), edges))
    assert any("but its neighbours in the order are" in p.error_description for p in reading.problems)
    rejection = _judge(scenario, FleetPlan(1, reading.legs))  # legs 1 then 3: they do not meet
    assert isinstance(rejection, Rejection) and rejection.code is RejectionCode.NOT_CONNECTED


def test_a_base_after_the_horizon_and_a_base_ending_with_an_edge_are_named() -> None:
    scenario = _scenario("crossing")
    graph = site_graph(scenario.layout, map_id="crossing")
    good = _order(graph, [(1, F), (2, F)], released=1)
    late_node = (*good.nodes[:2], Node(good.nodes[2].node_id, 4, released=True))
    problems = _read(scenario, Order(HEADER, "o1", 0, late_node, good.edges)).problems
    assert any(
        "node 's2.last' (sequenceId 4) is released after the horizon begins" in p.error_description for p in problems
    )
    open_end = (good.edges[0], replace(good.edges[1], released=True))
    problems = _read(scenario, Order(HEADER, "o1", 0, good.nodes, open_end)).problems
    assert any("is released but its end node 's2.last' is not" in p.error_description for p in problems)
    assert _read(scenario, good).problems == ()  # narrow: base, then horizon, the base ending with a node


def test_a_one_way_segment_driven_against_its_direction_is_wrong_way_and_no_route() -> None:
    scenario = _scenario("loop-one-way")
    graph = site_graph(scenario.layout, map_id="loop")
    one_way = next(sid for sid, s in sorted(scenario.layout.segments.items()) if s.direction.value == "forward")
    order = _order(graph, [(one_way, B)])
    reading = _read(scenario, order)
    plans = {v.id: initial_plan(v) for v in scenario.vehicles}
    plans[1] = FleetPlan(1, (FleetLeg(one_way, B, Progress.FORWARD, True),))  # as if it stood there
    ctx = CheckContext(scenario.layout, {v.id: v.type for v in scenario.vehicles}, plans, {1: (), 2: ()})
    [rejection] = check_plans([FleetPlan(1, reading.legs)], ctx)
    assert isinstance(rejection, Rejection) and rejection.code is RejectionCode.WRONG_WAY
    assert vda_error(rejection, order, reading.edges).error_type == "noRouteError"


# -- joining ----------------------------------------------------------------------------------------


def _join(
    scenario: Scenario,
    order: Order,
    status: OrderStatus,
    current: FleetPlan,
) -> tuple[Join, FleetPlan | None, tuple[VdaError, ...]]:
    graph = site_graph(scenario.layout, map_id=scenario.name)
    return join_order(order, _read(scenario, order), status, current, graph)


def test_a_first_order_starts_where_the_vehicle_stands() -> None:
    scenario = _scenario("crossing")
    graph = site_graph(scenario.layout, map_id="crossing")
    start = initial_plan(scenario.vehicles[0])
    join, plan, errors = _join(scenario, _order(graph, [(1, F), (2, F)]), OrderStatus(), start)
    assert join is Join.NEW and errors == ()
    assert plan is not None and _judge(scenario, plan) == plan


def test_an_order_that_starts_elsewhere_is_no_route_and_changes_the_fixed_legs() -> None:
    scenario = _scenario("crossing")
    graph = site_graph(scenario.layout, map_id="crossing")
    start = initial_plan(scenario.vehicles[0])
    order = _order(graph, [(3, F), (4, F)])
    join, plan, [error] = _join(scenario, order, OrderStatus(), start)
    assert (
        join is Join.NEW
        and error.error_type == "noRouteError"
        and "but the vehicle is on the edge from node" in error.error_description
    )
    assert plan is not None
    rejection = _judge(scenario, plan)
    assert isinstance(rejection, Rejection) and rejection.code is RejectionCode.FIXED_LEGS_CHANGED


def test_an_update_at_the_stitching_node_continues_the_base() -> None:
    scenario = _scenario("crossing")
    graph = site_graph(scenario.layout, map_id="crossing")
    current = FleetPlan(1, (FleetLeg(1, F, Progress.FORWARD, True), FleetLeg(2, F, Progress.FORWARD, True)))
    status = OrderStatus("o1", 0, graph.exit_node(2, F), 4)
    update = _order(graph, [(3, F), (4, F)], update=1, first_sequence=4, released=1)
    join, plan, errors = _join(scenario, update, status, current)
    assert join is Join.UPDATE and errors == ()
    assert plan is not None and [(leg.segment, leg.fixed) for leg in plan.legs] == [
        (1, True),
        (2, True),
        (3, True),
        (4, False),
    ]
    assert _judge(scenario, plan, current) == plan


def test_an_update_elsewhere_is_an_order_update_error_and_a_changed_base() -> None:
    scenario = _scenario("crossing")
    graph = site_graph(scenario.layout, map_id="crossing")
    current = FleetPlan(1, (FleetLeg(1, F, Progress.FORWARD, True), FleetLeg(2, F, Progress.FORWARD, True)))
    status = OrderStatus("o1", 0, graph.exit_node(2, F), 4)
    update = _order(graph, [(2, F), (3, F)], update=1, first_sequence=2)  # resends base it already has
    join, plan, [error] = _join(scenario, update, status, current)
    assert join is Join.UPDATE and error.error_type == "orderUpdateError"
    assert "not at the stitching node" in error.error_description
    assert plan is not None
    rejection = _judge(scenario, plan, current)
    assert isinstance(rejection, Rejection) and rejection.code is RejectionCode.FIXED_LEGS_CHANGED
    assert vda_error(rejection, update, update.edges).error_type == "orderUpdateError"


def test_a_resent_update_changes_nothing_and_an_older_one_is_refused() -> None:
    scenario = _scenario("crossing")
    graph = site_graph(scenario.layout, map_id="crossing")
    current = FleetPlan(1, (FleetLeg(1, F, Progress.FORWARD, True),))
    status = OrderStatus("o1", 3, graph.exit_node(1, F), 2)
    again = _order(graph, [(2, F)], update=3, first_sequence=2)
    assert _join(scenario, again, status, current) == (Join.RESENT, None, ())
    older = _order(graph, [(2, F)], update=2, first_sequence=2)
    join, plan, [error] = _join(scenario, older, status, current)
    assert join is Join.OUTDATED and plan is None and error.error_type == "orderUpdateError"
    assert "is lower than the current 3" in error.error_description


def test_a_second_order_while_base_remains_is_refused() -> None:
    scenario = _scenario("crossing")
    graph = site_graph(scenario.layout, map_id="crossing")
    current = FleetPlan(1, (FleetLeg(1, F, Progress.FORWARD, True), FleetLeg(2, F, Progress.FORWARD, True)))
    status = OrderStatus("o1", 0, graph.exit_node(2, F), 4)
    other = _order(graph, [(3, F)], order_id="o2")
    join, plan, [error] = _join(scenario, other, status, current)
    assert join is Join.NEW and error.error_type == "orderUpdateError"
    assert "still has base to drive" in error.error_description
    assert plan is not None
    rejection = _judge(scenario, plan, current)
    assert isinstance(rejection, Rejection) and rejection.code is RejectionCode.FIXED_LEGS_CHANGED


def test_a_new_order_once_the_base_is_driven_follows_on() -> None:
    scenario = _scenario("crossing")
    graph = site_graph(scenario.layout, map_id="crossing")
    current = FleetPlan(1, (FleetLeg(2, F, Progress.FORWARD, True),))  # on its last fixed leg
    status = OrderStatus("o1", 0, graph.exit_node(2, F), 4)
    join, plan, errors = _join(scenario, _order(graph, [(3, F)], order_id="o2"), status, current)
    assert join is Join.NEW and errors == ()
    assert plan is not None and [leg.segment for leg in plan.legs] == [2, 3]

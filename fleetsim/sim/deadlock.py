"""Who waits for whom when the fleet stops (SPEC §9 ★ deadlock).

A vehicle with tasks that stands at the end of its fixed legs waits for every other vehicle whose fixed
legs hold a segment that conflicts with the leg it would drive next. A cycle in that wait-for graph is a
deadlock no planner call can break without replanning.
"""

from __future__ import annotations

from collections.abc import Mapping

import networkx as nx

from fleetsim.layout.layout import Layout
from fleetsim.planning.protocol import FleetPlan
from fleetsim.planning.reservations import fixed_segments

__all__ = ["wait_for_cycle", "wait_for_graph"]


def wait_for_graph(layout: Layout, plans: Mapping[int, FleetPlan], waiting: tuple[int, ...]) -> nx.DiGraph[int]:
    """Edges ``a -> b``: vehicle ``a`` (waiting) needs a segment that vehicle ``b``'s fixed legs block."""
    holders: dict[int, set[int]] = {}
    for vehicle_id in sorted(plans):
        for segment in fixed_segments(plans[vehicle_id]):
            holders.setdefault(segment, set()).add(vehicle_id)
    graph: nx.DiGraph[int] = nx.DiGraph()
    graph.add_nodes_from(waiting)
    for vehicle_id in waiting:
        plan = plans[vehicle_id]
        following = plan.legs[len(plan.fixed_legs):]
        if not following:
            continue
        blockers: set[int] = set()
        for segment in sorted(layout.conflicts(following[0].segment)):
            blockers |= holders.get(segment, set())
        graph.add_edges_from((vehicle_id, other) for other in sorted(blockers - {vehicle_id}))
    return graph


def wait_for_cycle(graph: nx.DiGraph[int]) -> tuple[int, ...]:
    """A cycle of the wait-for graph, starting at its smallest vehicle id; empty when there is none."""
    for start in sorted(graph.nodes):
        try:
            edges = nx.find_cycle(graph, source=start)
        except nx.NetworkXNoCycle:
            continue
        cycle = [edge[0] for edge in edges]
        first = cycle.index(min(cycle))
        return tuple(cycle[first:] + cycle[:first])
    return ()

"""The immutable layout planners receive: segments, connections, state graph and conflicts (SPEC §4).

Build one with :func:`build_layout`. Everything a planner can reach is read-only: the segment mapping is a
``MappingProxyType``, the graph is ``networkx.freeze``-d and query results are tuples and frozensets.

Asking about a segment id the layout does not have raises :class:`~fleetsim.errors.LayoutError` (a
``ValueError``) naming the id, not ``KeyError``: an unknown id is a bad argument from a planner, and the
message says which id and how many segments exist.
"""

from __future__ import annotations

import math
from collections import defaultdict
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType

import networkx as nx

from fleetsim.enums import ConflictModel, JointKind, Progress, Traverse, TurnCapability
from fleetsim.errors import LayoutError
from fleetsim.layout.conflicts import conflict_sets
from fleetsim.layout.connections import Connection, find_connections
from fleetsim.layout.continuations import Continuation, Turning, capability_of, progresses_after
from fleetsim.layout.lint import LintFinding, StateGraph, lint_layout
from fleetsim.layout.segment import Segment

__all__ = ["Connection", "Layout", "Step", "build_layout"]

Step = tuple[int, Traverse, JointKind]  # (next or previous segment, its traverse, joint kind)
StepIndex = Mapping[tuple[int, Traverse], tuple[Step, ...]]


@dataclass(frozen=True, slots=True, eq=False, repr=False)
class Layout:
    """Segments, how they connect and which of them conflict; built by
    [`build_layout`][fleetsim.layout.layout.build_layout].

    Attributes:
        segments: Every [`Segment`][fleetsim.layout.segment.Segment], by id (a read-only mapping).
        connections: Every [`Connection`][fleetsim.layout.connections.Connection]: a way from one segment
            driven one way onto another, and the ``JointKind`` (``SAME``: drive on; ``OPPOSITE``: a cusp,
            the vehicle reverses its progress; ``TURN_IN_PLACE``: a corner only a vehicle that turns in
            place can take).
        connection_tolerance: Metres within which two segment ends count as meeting.
        joint_angle_tolerance: Degrees within which two ends count as tangent (a smooth joint).
        vehicle_radius: Metres, the circle swept along a segment when conflicts are computed.
        safety_margin: Metres added between two swept circles.
        conflict_model: ``SWEPT`` (swept circles, the default) or ``BBOX`` (the thesis's bounding boxes).
        source: The map file the layout came from, if any.

    Use ``continuations`` for the legs a vehicle may legally drive next (the progress rules applied),
    ``successors`` / ``predecessors`` for the connections themselves, ``joint`` for how two legs meet
    and ``conflicts`` for the segments a fixed leg reserves (its own included). Asking about a
    segment id the layout does not have raises [`LayoutError`][fleetsim.errors.LayoutError].
    """

    segments: Mapping[int, Segment]
    connections: tuple[Connection, ...]
    connection_tolerance: float
    joint_angle_tolerance: float
    vehicle_radius: float
    safety_margin: float
    conflict_model: ConflictModel
    source: Path | None
    _successors: StepIndex
    _predecessors: StepIndex
    _joints: Mapping[tuple[int, Traverse, int, Traverse], JointKind]
    _conflicts: Mapping[int, frozenset[int]]
    _graph_cache: list[StateGraph]  # empty until `graph` is first asked for

    @property
    def graph(self) -> StateGraph:
        """The frozen networkx graph over ``(segment, traverse)`` states; edges carry ``joint``.

        Built on first use: on large maps it costs more than everything else in ``build_layout``,
        and ``successors`` / ``predecessors`` answer most questions without it.
        """
        if not self._graph_cache:
            self._graph_cache.append(_state_graph(self.segments, self.connections))
        return self._graph_cache[0]

    def __repr__(self) -> str:
        where = f", source={str(self.source)!r}" if self.source is not None else ""
        return f"Layout({len(self.segments)} segments, {len(self.connections)} connections{where})"

    def _require(self, segment: int) -> None:
        if segment not in self.segments:
            where = f" of {self.source}" if self.source is not None else ""
            msg = f"segment={segment!r} is not in the layout{where} ({len(self.segments)} segments)"
            raise LayoutError(msg)

    def successors(self, segment: int, traverse: Traverse) -> tuple[Step, ...]:
        """Where a vehicle driving ``segment`` with ``traverse`` may go next, with the joint kind.

        A tuple of ``(next_segment, next_traverse, joint)``, sorted by segment id then traverse
        (``FORWARD`` first); empty for a traverse the segment does not allow. Whether a vehicle may take
        one depends on its type and progress (``JointKind``, ``TurnCapability``).
        """
        found = self._successors.get((segment, traverse))  # hot in route searches: no checks on a hit
        if found is not None:
            return found
        self._require(segment)
        return self._successors.get((segment, Traverse(traverse)), ())

    def continuations(
        self, vehicle_type: Turning | TurnCapability, segment: int, traverse: Traverse, progress: Progress
    ) -> tuple[Continuation, ...]:
        """The legs a vehicle may legally drive next after a leg on ``segment`` with ``traverse`` and
        ``progress``: each a [`Continuation`][fleetsim.layout.continuations.Continuation] ``(segment,
        traverse, progress, joint)``, in ``successors`` order, the progress kept before the progress
        flipped.

        ``vehicle_type`` is a [`VehicleType`][fleetsim.scenario.VehicleType] (``fleet.vehicles[v].type``)
        or its ``TurnCapability``. A vehicle that turns in place may take every connection with either
        progress; one that only follows curves keeps its progress at a smooth joint, flips it at a cusp
        and takes no corner. These are exactly the rules of the ``illegal-progress-change`` check: a plan
        whose every leg is a continuation of the leg before passes it.

        Examples:
            >>> from fleetsim import Progress, Traverse, TurnCapability, build_layout, load_map
            >>> layout = build_layout(load_map("scenario_suites/examples/mixed/map.json").segments, vehicle_radius=0.4)
            >>> for leg in layout.continuations(TurnCapability.CURVE, 1, Traverse.FORWARD, Progress.FORWARD):
            ...     print(leg.segment, leg.traverse.value, leg.progress.value, leg.joint.value)
            1 backward reverse opposite
            2 forward forward same
        """
        capability = capability_of(vehicle_type)
        return tuple(
            Continuation(next_segment, next_traverse, next_progress, joint)
            for next_segment, next_traverse, joint in self.successors(segment, traverse)
            for next_progress in progresses_after(capability, joint, Progress(progress))
        )

    def joint(self, segment: int, traverse: Traverse, next_segment: int, next_traverse: Traverse) -> JointKind | None:
        """The joint from driving ``segment`` with ``traverse`` into ``next_segment`` with ``next_traverse``;
        ``None`` when the one does not lead to the other (unknown segments included)."""
        return self._joints.get((segment, traverse, next_segment, next_traverse))

    def predecessors(self, segment: int, traverse: Traverse) -> tuple[Step, ...]:
        """Where a vehicle may come from to enter ``segment`` driving ``traverse``: a tuple of
        ``(previous_segment, previous_traverse, joint)``, sorted as in ``successors``."""
        found = self._predecessors.get((segment, traverse))
        if found is not None:
            return found
        self._require(segment)
        return self._predecessors.get((segment, Traverse(traverse)), ())

    def conflicts(self, segment: int) -> frozenset[int]:
        """Ids of the segments a vehicle on ``segment`` could collide with, ``segment`` itself included.

        A fixed leg on ``segment`` reserves all of them: ``segment`` as its vehicle's primary reservation,
        the others as secondary ones; another vehicle's fixed leg on any of them is a collision alert.
        """
        self._require(segment)
        return self._conflicts[segment]

    def lint(self, vehicle_length: float | None = None) -> tuple[LintFinding, ...]:
        """Warnings about the map's drawing (dangling ends, near misses, ...), as ``fleetsim validate``
        shows them.

        With ``vehicle_length`` (metres), dangling ends that close to another segment's end are
        reported as ``gap`` too.
        """
        return lint_layout(tuple(self.segments.values()), self.graph, self.connection_tolerance, vehicle_length)


def _check_setting(name: str, value: float, *, upper: float | None = None) -> float:
    value = float(value)
    if upper is None and not (math.isfinite(value) and value >= 0.0):
        msg = f"{name}={value!r} must be a finite number >= 0"
        raise LayoutError(msg)
    if upper is not None and not (0.0 < value < upper):
        msg = f"{name}={value!r} must be between 0 and {upper:g} degrees (exclusive)"
        raise LayoutError(msg)
    return value


def _check_model(model: ConflictModel | str) -> ConflictModel:
    try:
        return ConflictModel(model)
    except ValueError:
        choices = ", ".join(m.value for m in ConflictModel)
        msg = f"conflict_model={model!r} must be one of {choices}"
        raise LayoutError(msg) from None


def _sorted_segments(segments: Iterable[Segment], source: Path | None) -> dict[int, Segment]:
    by_id: dict[int, Segment] = {}
    where = f" in {source}" if source is not None else ""
    for segment in segments:
        if segment.id in by_id:
            msg = f"duplicate segment id {segment.id!r}{where}: segment ids must be unique"
            raise LayoutError(msg)
        if not all(math.isfinite(c) for point in segment.waypoints for c in point):
            msg = f"segment {segment.id!r}{where} has a non-finite waypoint: {segment.waypoints!r}"
            raise LayoutError(msg)
        by_id[segment.id] = segment
    return {sid: by_id[sid] for sid in sorted(by_id)}


def _state_graph(segments: Mapping[int, Segment], connections: tuple[Connection, ...]) -> StateGraph:
    graph: StateGraph = nx.DiGraph()
    graph.add_nodes_from((sid, t) for sid, segment in segments.items() for t in Traverse if segment.allows(t))
    graph.add_edges_from(
        ((c.from_segment, c.from_traverse), (c.to_segment, c.to_traverse), {"joint": c.joint}) for c in connections
    )
    frozen: StateGraph = nx.freeze(graph)
    return frozen


def _step_index(connections: tuple[Connection, ...]) -> tuple[StepIndex, StepIndex]:
    """Successor and predecessor tuples per ``(segment, traverse)`` state.

    ``connections`` are sorted by (from state, to state), so each tuple comes out sorted as well.
    """
    forward: defaultdict[tuple[int, Traverse], list[Step]] = defaultdict(list)
    backward: defaultdict[tuple[int, Traverse], list[Step]] = defaultdict(list)
    for c in connections:
        forward[(c.from_segment, c.from_traverse)].append((c.to_segment, c.to_traverse, c.joint))
        backward[(c.to_segment, c.to_traverse)].append((c.from_segment, c.from_traverse, c.joint))
    return (
        MappingProxyType({key: tuple(steps) for key, steps in forward.items()}),
        MappingProxyType({key: tuple(steps) for key, steps in backward.items()}),
    )


def _joint_index(connections: tuple[Connection, ...]) -> Mapping[tuple[int, Traverse, int, Traverse], JointKind]:
    """The joint kind per (from state, to state); the first connection between two states counts."""
    joints: dict[tuple[int, Traverse, int, Traverse], JointKind] = {}
    for c in connections:
        joints.setdefault((c.from_segment, c.from_traverse, c.to_segment, c.to_traverse), c.joint)
    return MappingProxyType(joints)


def build_layout(
    segments: Iterable[Segment],
    *,
    vehicle_radius: float,
    connection_tolerance: float = 0.05,
    joint_angle_tolerance: float = 30.0,
    safety_margin: float = 0.0,
    conflict_model: ConflictModel = ConflictModel.SWEPT,
    source: Path | None = None,
) -> Layout:
    """Connect the segments, build the state graph and compute conflicts.

    ``vehicle_radius`` is the largest swept radius over the scenario's vehicle types. Raises
    [`LayoutError`][fleetsim.errors.LayoutError] for duplicate segment ids or invalid settings.
    """
    radius = _check_setting("vehicle_radius", vehicle_radius)
    tolerance = _check_setting("connection_tolerance", connection_tolerance)
    angle = _check_setting("joint_angle_tolerance", joint_angle_tolerance, upper=90.0)
    margin = _check_setting("safety_margin", safety_margin)
    model = _check_model(conflict_model)
    by_id = _sorted_segments(segments, source)
    ordered = tuple(by_id.values())
    connections = find_connections(ordered, tolerance, angle)
    successors, predecessors = _step_index(connections)
    return Layout(
        segments=MappingProxyType(by_id),
        connections=connections,
        connection_tolerance=tolerance,
        joint_angle_tolerance=angle,
        vehicle_radius=radius,
        safety_margin=margin,
        conflict_model=model,
        source=source,
        _successors=successors,
        _predecessors=predecessors,
        _joints=_joint_index(connections),
        _conflicts=MappingProxyType(conflict_sets(ordered, model, radius, margin, tolerance)),
        _graph_cache=[],
    )

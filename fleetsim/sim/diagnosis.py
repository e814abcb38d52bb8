"""Why a fleet is stuck: a finding per vehicle, the wait-for graph, its cycles and root causes.

When a run ends in deadlock or at its time limit with tasks pending, every vehicle that still has a task
gets one :class:`Finding` with a stable ``reason`` code:

- ``waits-for``: its next leg is not fixed and conflicts with segments other vehicles hold (their fixed
  legs, which include the segment each stands on);
- ``blocked-by-idle``: as above, and a holder has no tasks left, so it will never move by itself;
- ``not-fixed``: its next planned leg is free, yet the planner has not fixed it;
- ``no-route``: its head task has no route and the planner answered route errors for it;
- ``no-plan``: its plan ends before the goal leg of its head task and the planner added nothing;
- ``moving`` (time limit only): it is still driving; the run needed more time.

A planner may add a ``note`` to a vehicle's finding (fleetsim's VDA 5050 vehicles tell which order the
vehicle waits for and when its master control last spoke to it): it ends the finding's line and the root
cause it is.

A vehicle that waits needs *every* holder to move (the planner cannot fix the leg while any of them holds
a conflicting segment), so every cycle of the wait-for graph is a deadlock by itself, and so is every
chain that ends at a vehicle that will not move: one with no tasks left, or one whose finding is
``not-fixed``, ``no-route`` or ``no-plan``. Those cycles and chain ends are the :class:`RootCause` s; the
headline names the one most vehicles wait behind.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any, Literal

import networkx as nx

from fleetsim.layout.layout import Layout
from fleetsim.planning.plans import FleetLeg, FleetPlan
from fleetsim.planning.snapshot import VehicleState
from fleetsim.scenario import Task

__all__ = ["Diagnosis", "Finding", "RootCause", "StuckFacts", "diagnose", "numbered"]

Reason = Literal["waits-for", "blocked-by-idle", "not-fixed", "no-route", "no-plan", "moving"]
RootKind = Literal["cycle", "idle", "not-fixed", "no-route", "no-plan", "moving"]
REASONS: tuple[Reason, ...] = ("waits-for", "blocked-by-idle", "not-fixed", "no-route", "no-plan", "moving")
_ROOT_ORDER: dict[RootKind, int] = {"cycle": 0, "idle": 1, "no-route": 2, "no-plan": 3, "not-fixed": 4, "moving": 5}
# The headline's summary of further root causes of one kind: what one, and several, are called.
_GROUPS: dict[RootKind, tuple[str, str]] = {
    "cycle": ("wait-for cycle", "wait-for cycles"),
    "idle": ("vehicle with no tasks left in the way", "vehicles with no tasks left in the way"),
    "no-route": ("vehicle without a route", "vehicles without a route"),
    "no-plan": ("vehicle whose plan ends before the goal", "vehicles whose plans end before the goal"),
    "not-fixed": (
        "vehicle whose free next leg the planner does not fix",
        "vehicles whose free next leg the planner does not fix",
    ),
    "moving": ("vehicle still driving", "vehicles still driving"),
}
# Cycles listed at most (a dense knot of waiting vehicles can hold exponentially many).
_MAX_CYCLES = 50


def numbered(ids: Sequence[int], noun: str = "vehicle") -> str:
    """``vehicle 3``, ``vehicles 3 and 5``, ``vehicles 3, 5 and 8``."""
    names = [str(i) for i in ids]
    if len(names) == 1:
        return f"{noun} {names[0]}"
    return f"{noun}s {', '.join(names[:-1])} and {names[-1]}"


def _planned_near(vehicles: Sequence[int]) -> str:
    if not vehicles:
        return ""
    return f" ({numbered(vehicles)} {'plans' if len(vehicles) == 1 else 'plan'} to drive near it)"


def _leg_text(index: int, leg: FleetLeg) -> str:
    return f"leg {index} (segment {leg.segment} {leg.traverse.value})"


@dataclass(frozen=True, slots=True)
class Finding:
    """Why one vehicle with a pending task did not finish it."""

    vehicle: int
    reason: Reason
    segment: int  # where it stands
    task: Task
    leg_index: int | None = None  # the leg it would drive next (waits-for, blocked-by-idle, not-fixed)
    leg: FleetLeg | None = None
    held: tuple[tuple[int, tuple[int, ...]], ...] = ()  # (other vehicle, its segments that conflict with the leg)
    idle: tuple[int, ...] = ()  # holders with no tasks left
    since: float | None = None  # standing since (not-fixed); first route error since its plan last changed
    standing: float | None = None  # seconds it has stood still (not-fixed)
    route_errors: int = 0
    message: str = ""  # the planner's last route error (no-route)
    remaining: float | None = None  # metres of its plan left to its goal leg (moving)
    plan_end: int | None = None  # the segment its plan ends on (no-plan)
    planned_near: tuple[int, ...] = ()  # not-fixed: vehicles whose unfixed legs come near the wanted leg
    chain: tuple[int, ...] = ()  # waits-for: the way to its root cause, itself first
    note: str = ""  # what the planner says about this vehicle's wait (a VDA 5050 master control's order)

    @property
    def blocked_by(self) -> tuple[int, ...]:
        return tuple(vehicle for vehicle, _ in self.held)

    @property
    def contested(self) -> tuple[int, ...]:
        return tuple(sorted({segment for _, segments in self.held for segment in segments}))

    def text(self) -> str:
        """One line of the report, the planner's note last."""
        return f"{self._text()}; {self.note}" if self.note else self._text()

    def _text(self) -> str:
        who = f"vehicle {self.vehicle} (task {self.task.id}, to segment {self.task.goal_segment})"
        wanted = _leg_text(self.leg_index, self.leg) if self.leg is not None and self.leg_index is not None else "leg"
        if self.reason in ("waits-for", "blocked-by-idle"):
            held = "; ".join(f"{other} holds {numbered(segments, 'segment')}" for other, segments in self.held)
            text = f"{who} {self.reason} {numbered(self.blocked_by)}: its next {wanted} conflicts with what they hold ({held})"
            if self.idle:
                text += f"; {numbered(self.idle)} {'has' if len(self.idle) == 1 else 'have'} no tasks left and will not move"
            if len(self.chain) > 2:
                text += f"; chain {' -> '.join(map(str, self.chain))}"
            return text
        if self.reason == "not-fixed":
            text = f"{who} not-fixed: its next {wanted} is free, but the planner has not fixed it for {self.standing or 0.0:.1f} s"
            return text + _planned_near(self.planned_near)
        if self.reason == "no-route":
            return f"{who} no-route: {self.route_errors} route error(s) since t = {self.since or 0.0:.2f} s, the last: {self.message}"
        if self.reason == "no-plan":
            return f"{who} no-plan: its plan ends on segment {self.plan_end}, before its goal leg, and the planner added nothing"
        return f"{who} moving: still driving, {self.remaining or 0.0:.1f} m of its plan left to its goal leg"

    def to_dict(self) -> dict[str, Any]:
        document: dict[str, Any] = {
            "vehicle": self.vehicle,
            "reason": self.reason,
            "segment": self.segment,
            "task": self.task.id,
            "goal_segment": self.task.goal_segment,
            "text": self.text(),
        }
        if self.leg is not None:
            document["leg"] = {
                "index": self.leg_index,
                "segment": self.leg.segment,
                "traverse": self.leg.traverse.value,
                "progress": self.leg.progress.value,
            }
        if self.held:
            document["blocked_by"] = list(self.blocked_by)
            document["contested"] = list(self.contested)
            document["held"] = [{"vehicle": other, "segments": list(segments)} for other, segments in self.held]
        if self.reason == "blocked-by-idle":
            document["idle"] = list(self.idle)
        if self.since is not None:
            document["since"] = round(self.since, 6)
        if self.reason == "no-route":
            document["route_errors"] = self.route_errors
            document["message"] = self.message
        if self.remaining is not None:
            document["remaining"] = round(self.remaining, 3)
        if self.plan_end is not None:
            document["plan_end"] = self.plan_end
        if self.planned_near:
            document["planned_near"] = list(self.planned_near)
        if self.chain:
            document["chain"] = list(self.chain)
        if self.note:
            document["note"] = self.note
        return document


@dataclass(frozen=True, slots=True)
class RootCause:
    """A reason vehicles wait that waiting cannot end: a cycle, or a vehicle that will not move."""

    kind: RootKind
    vehicles: tuple[int, ...]  # a cycle in its order (smallest id first), or the one vehicle
    segments: tuple[int, ...]  # where: the segments the cycle contests, the segment a vehicle stands on
    waiting: tuple[int, ...]  # vehicles that wait for it directly
    behind: tuple[int, ...]  # every vehicle whose wait ends at it, directly or through others
    detail: str  # what the vehicle's own finding says (not-fixed, no-route, no-plan, moving)
    cycle: tuple[int, ...] = ()  # a cycle through the vehicles, smallest id first (kind cycle)

    def text(self) -> str:
        """The root cause in one sentence, for the headline."""
        direct = numbered(self.waiting) if self.waiting else ""
        needs = "need" if len(self.waiting) > 1 else "needs"
        if self.kind == "cycle":
            loop = " -> ".join(map(str, (*self.cycle, self.cycle[0])))
            more = "" if len(self.cycle) == len(self.vehicles) else ", among other cycles"
            return f"{numbered(self.vehicles)} wait for each other ({loop}{more}) over {numbered(self.segments, 'segment')}"
        if self.kind == "idle":
            where = numbered(self.segments, "segment")
            return f"vehicle {self.vehicles[0]} (no tasks left) stands on {where}, which {direct} {needs}"
        text = f"vehicle {self.vehicles[0]}: {self.detail}"
        return f"{text}; {direct} {'wait' if len(self.waiting) > 1 else 'waits'} for it" if self.waiting else text

    def to_dict(self) -> dict[str, Any]:
        return {
            "kind": self.kind,
            "vehicles": list(self.vehicles),
            **({"cycle": list(self.cycle)} if self.cycle else {}),
            "segments": list(self.segments),
            "waiting": list(self.waiting),
            "behind": list(self.behind),
            "text": self.text(),
        }


@dataclass(frozen=True, slots=True)
class Diagnosis:
    """Why the vehicles with pending tasks did not finish them, at the end of a run."""

    kind: Literal["deadlock", "timeout"]
    time: float
    findings: tuple[Finding, ...]  # by vehicle id
    edges: tuple[tuple[int, int], ...]  # wait-for: (waiting vehicle, vehicle it waits for), sorted
    cycles: tuple[tuple[int, ...], ...]  # each from its smallest id; shortest first
    roots: tuple[RootCause, ...]  # most vehicles behind first
    route_errors: int  # answered over the whole run
    only_route_errors: bool  # the planner answered nothing but route errors (no plan accepted)

    @property
    def waiting(self) -> tuple[int, ...]:
        return tuple(f.vehicle for f in self.findings if f.reason != "moving")

    def headline(self) -> str:
        """The root causes in one line: the one most vehicles wait behind in full, the others counted."""
        parts = []
        if self.only_route_errors:
            parts.append(f"the planner answered nothing but route errors ({self.route_errors})")
        if self.roots:
            first = self.roots[0]
            text = first.text()
            more = len(set(first.behind) - set(first.waiting))
            if more:
                text += f"; {more} more {'vehicle waits' if more == 1 else 'vehicles wait'} behind them"
            parts.append(text)
            others = self.roots[1:]
            if others:
                groups = [
                    f"{len(roots)} {'more ' if kind == first.kind else ''}{_GROUPS[kind][len(roots) > 1]} "
                    f"({', '.join(map(str, sorted(v for r in roots for v in r.vehicles)))})"
                    for kind in _ROOT_ORDER
                    if (roots := [r for r in others if r.kind == kind])
                ]
                parts.append("besides: " + ", ".join(groups))
        return "; ".join(parts) if parts else "no vehicle has a pending task"

    def lines(self, shown: int = 40) -> list[str]:
        """The report's lines below the headline: root causes, cycles, then one line per vehicle."""
        # Root causes nobody waits for are their vehicle's own finding: listed once, below.
        lines = [f"root cause: {root.text()}" for root in self.roots if root.waiting or root.kind == "cycle"]
        lines += [f"wait-for cycle: {' -> '.join(map(str, (*cycle, cycle[0])))}" for cycle in self.cycles]
        lines += [finding.text() for finding in self.findings[:shown]]
        if len(self.findings) > shown:
            lines.append(f"... and {len(self.findings) - shown} more vehicles (all in result.json)")
        return lines

    def to_dict(self) -> dict[str, Any]:
        """The ``details`` of the deadlock or timeout failure in ``result.json``."""
        return {
            "vehicles": [f.to_dict() for f in self.findings],
            "wait_for": [list(edge) for edge in self.edges],
            "cycles": [list(cycle) for cycle in self.cycles],
            "roots": [root.to_dict() for root in self.roots],
            "route_errors": self.route_errors,
        }


@dataclass(frozen=True, slots=True)
class StuckFacts:
    """What the run knows when it ends with tasks pending."""

    kind: Literal["deadlock", "timeout"]
    time: float
    layout: Layout
    plans: Mapping[int, FleetPlan]
    states: Mapping[int, VehicleState]
    heads: Mapping[int, Task]  # the head task of every vehicle that has one
    last_moved: Mapping[int, float]  # when each vehicle last moved (absent: never)
    plan_changed: Mapping[int, float]  # when the planner last changed each vehicle's plan (absent: never)
    route_errors: Sequence[Mapping[str, Any]]  # {time, vehicle, message}, in order
    accepted_plans: int  # plans accepted over the run (any that changed something)
    notes: Mapping[int, str] = field(default_factory=dict)  # the planner's word on a vehicle's wait


def diagnose(facts: StuckFacts) -> Diagnosis:
    """A finding for every vehicle with a pending task, the wait-for graph's cycles and root causes."""
    holders = _holders(facts.plans)
    findings = {vid: _finding(facts, vid, holders) for vid in sorted(facts.heads)}
    graph: nx.DiGraph[int] = nx.DiGraph()
    graph.add_nodes_from(findings)
    for finding in findings.values():
        graph.add_edges_from((finding.vehicle, other) for other in finding.blocked_by)
    cycles = _cycles(graph)
    roots = _roots(graph, findings, cycles)
    chains = _chains(graph, roots, findings)
    ordered = tuple(
        replace(findings[vid], chain=chains[vid]) if vid in chains else findings[vid] for vid in sorted(findings)
    )
    return Diagnosis(
        kind=facts.kind,
        time=facts.time,
        findings=ordered,
        edges=tuple(sorted(graph.edges)),
        cycles=cycles,
        roots=roots,
        route_errors=len(facts.route_errors),
        only_route_errors=bool(facts.route_errors) and facts.accepted_plans == 0,
    )


def _holders(plans: Mapping[int, FleetPlan]) -> dict[int, list[int]]:
    """Segment -> vehicles whose fixed legs (the one they stand on included) hold it, in id order."""
    holders: dict[int, list[int]] = {}
    for vid in sorted(plans):
        for segment in dict.fromkeys(leg.segment for leg in plans[vid].fixed_legs):
            holders.setdefault(segment, []).append(vid)
    return holders


def _finding(facts: StuckFacts, vid: int, holders: Mapping[int, list[int]]) -> Finding:
    plan, task, state = facts.plans[vid], facts.heads[vid], facts.states[vid]
    base = Finding(vehicle=vid, reason="no-plan", segment=state.segment, task=task, note=facts.notes.get(vid, ""))
    goal_index = next((i for i, leg in enumerate(plan.legs) if leg.goal_for_task == task.id), None)
    if facts.kind == "timeout" and facts.last_moved.get(vid, -1.0) >= facts.time - 1e-9:
        return _moving(facts, base, plan, state, goal_index)
    if goal_index is None:
        changed = facts.plan_changed.get(vid, 0.0)
        errors = [e for e in facts.route_errors if e["vehicle"] == vid and e["time"] >= changed - 1e-9]
        if errors:
            return replace(
                base,
                reason="no-route",
                since=errors[0]["time"],
                route_errors=len(errors),
                message=str(errors[-1]["message"]),
            )
        return replace(base, plan_end=plan.legs[-1].segment)
    index = len(plan.fixed_legs)
    if index >= len(plan.legs):
        return replace(base, plan_end=plan.legs[-1].segment)
    leg = plan.legs[index]
    near = sorted(facts.layout.conflicts(leg.segment))
    held: dict[int, list[int]] = {}
    for segment in near:
        for other in holders.get(segment, ()):
            if other != vid:
                held.setdefault(other, []).append(segment)
    if held:
        idle = tuple(other for other in sorted(held) if other not in facts.heads)
        return replace(
            base,
            reason="blocked-by-idle" if idle else "waits-for",
            leg_index=index,
            leg=leg,
            held=tuple((other, tuple(held[other])) for other in sorted(held)),
            idle=idle,
        )
    since = facts.last_moved.get(vid, 0.0)
    near_set = set(near)
    planned_near = tuple(
        other
        for other in sorted(facts.plans)
        if other != vid
        and any(leg.segment in near_set for leg in facts.plans[other].legs[len(facts.plans[other].fixed_legs) :])
    )
    return replace(
        base,
        reason="not-fixed",
        leg_index=index,
        leg=leg,
        since=since,
        standing=facts.time - since,
        planned_near=planned_near,
    )


def _moving(facts: StuckFacts, base: Finding, plan: FleetPlan, state: VehicleState, goal_index: int | None) -> Finding:
    segments = facts.layout.segments
    end = len(plan.legs) if goal_index is None else goal_index
    remaining = max(segments[plan.legs[0].segment].length - state.distance, 0.0) if end > 0 else 0.0
    remaining += sum(segments[leg.segment].length for leg in plan.legs[1:end])
    return replace(base, reason="moving", remaining=remaining)


def _cycles(graph: nx.DiGraph[int]) -> tuple[tuple[int, ...], ...]:
    """Every cycle of the wait-for graph (up to a bound), each from its smallest id, shortest first."""
    found: set[tuple[int, ...]] = set()
    for component in sorted(sorted(c) for c in nx.strongly_connected_components(graph) if len(c) > 1):
        for cycle in nx.simple_cycles(graph.subgraph(component)):
            first = cycle.index(min(cycle))
            found.add(tuple(cycle[first:] + cycle[:first]))
            if len(found) >= _MAX_CYCLES:
                break
    return tuple(sorted(found, key=lambda cycle: (len(cycle), cycle)))


def _detail(finding: Finding) -> str:
    if finding.reason == "not-fixed" and finding.leg is not None:
        standing = finding.standing or 0.0
        return f"its next leg (segment {finding.leg.segment}) is free, but the planner has not fixed it for {standing:.1f} s{_planned_near(finding.planned_near)}"
    if finding.reason == "no-route":
        return f"the planner finds no route ({finding.route_errors} route errors, the last: {finding.message})"
    if finding.reason == "no-plan":
        task = finding.task
        return f"its plan ends on segment {finding.plan_end}, before the goal of task {task.id} (segment {task.goal_segment}), and the planner adds nothing"
    return f"still driving ({finding.remaining or 0.0:.1f} m to its goal leg)"


def _roots(
    graph: nx.DiGraph[int], findings: Mapping[int, Finding], cycles: Sequence[tuple[int, ...]]
) -> tuple[RootCause, ...]:
    roots = []
    for component in (sorted(c) for c in nx.strongly_connected_components(graph)):
        members = set(component)
        cyclic = len(component) > 1
        if not cyclic and graph.out_degree(component[0]) > 0:
            continue  # it waits for others: its wait ends somewhere else
        waiting = sorted({p for v in component for p in graph.predecessors(v)} - members)
        behind = sorted(set().union(*(nx.ancestors(graph, v) for v in component)) - members)
        if cyclic:
            loop = next((c for c in cycles if members.issuperset(c)), tuple(component))
            segments = sorted(
                {s for v in component for other, held in findings[v].held if other in members for s in held}
            )
            roots.append(RootCause("cycle", tuple(component), tuple(segments), tuple(waiting), tuple(behind), "", loop))
            continue
        vehicle = component[0]
        finding = findings.get(vehicle)
        if finding is None:  # no tasks left: it will never move by itself
            segments = sorted(
                {s for w in waiting for other, held in findings[w].held if other == vehicle for s in held}
            )
            roots.append(RootCause("idle", (vehicle,), tuple(segments), tuple(waiting), tuple(behind), ""))
            continue
        kind: RootKind = finding.reason  # type: ignore[assignment]  # a sink is never waits-for
        where = (finding.leg.segment,) if finding.leg is not None else (finding.segment,)
        detail = f"{_detail(finding)}; {finding.note}" if finding.note else _detail(finding)
        roots.append(RootCause(kind, (vehicle,), where, tuple(waiting), tuple(behind), detail))
    return tuple(sorted(roots, key=lambda r: (-len(r.behind), _ROOT_ORDER[r.kind], r.vehicles)))


def _chains(
    graph: nx.DiGraph[int], roots: Sequence[RootCause], findings: Mapping[int, Finding]
) -> dict[int, tuple[int, ...]]:
    """For each waiting vehicle, the shortest way along wait-for edges to a vehicle of a root cause."""
    at_root = {v for root in roots for v in root.vehicles}
    chains: dict[int, tuple[int, ...]] = {}
    for vid, finding in findings.items():
        if not finding.held or vid in at_root:
            continue
        paths: dict[int, tuple[int, ...]] = {vid: (vid,)}
        frontier = [vid]
        while frontier and vid not in chains:
            following = []
            for node in frontier:
                for other in sorted(graph.successors(node)):
                    if other in paths:
                        continue
                    paths[other] = (*paths[node], other)
                    if other in at_root:
                        chains[vid] = paths[other]
                        break
                    following.append(other)
                if vid in chains:
                    break
            frontier = following
    return chains

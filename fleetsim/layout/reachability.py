"""Where a vehicle can drive: states, the progress rules and reachability (SPEC §4).

A vehicle's state is ``(segment, traverse, progress)``. Its next states follow the layout's connections
and the progress rules for its turn capability: a vehicle that can only follow curves keeps its progress
at smooth joints, flips it at cusps and cannot take corners; a vehicle that turns in place may take any
connection with either progress.

The rules themselves are :func:`~fleetsim.layout.continuations.progresses_after` (as the table
``RULES``), the one the plan check ``illegal-progress-change`` judges by. :func:`next_steps` is the
reference planners' version (:mod:`fleetsim.planners.routing`): it keeps an in-place turner's progress, because a planner sets the progress it arrives with on the last leg.
:func:`moves` is the exact version the static task check of scenario loading asks (:class:`ReachIndex`,
:func:`reach`); for a curve-only vehicle the two are the same, and for an in-place turner they reach the
same segments, so a goal the check accepts is one the planners' searches can find.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator
from dataclasses import dataclass

from fleetsim.enums import JointKind, Progress, Traverse, TurnCapability
from fleetsim.layout.continuations import RULES
from fleetsim.layout.layout import Layout

__all__ = [
    "Reach",
    "ReachIndex",
    "State",
    "arrivals",
    "goal_states",
    "moves",
    "next_states",
    "next_steps",
    "reach",
    "state_key",
    "state_text",
]

State = tuple[int, Traverse, Progress]


def next_steps(layout: Layout, capability: TurnCapability, state: State) -> Iterator[tuple[State, JointKind]]:
    """The states a vehicle may drive on to from ``state``, each with the joint it crosses: per
    connection, the first progress :func:`~fleetsim.layout.continuations.progresses_after` allows (an
    in-place turner keeps its progress; a corner is no way on for a vehicle that only follows curves)."""
    segment, traverse, progress = state
    rule = RULES[capability]  # hot in route searches: the rule as a table
    for next_segment, next_traverse, joint in layout.successors(segment, traverse):
        allowed = rule[joint][progress]
        if allowed:
            yield (next_segment, next_traverse, allowed[0]), joint


def next_states(layout: Layout, capability: TurnCapability, state: State) -> Iterator[State]:
    return (following for following, _ in next_steps(layout, capability, state))


def state_key(state: State) -> tuple[int, int, int]:
    """A total order on states (forward before backward), so output never depends on set order."""
    segment, traverse, progress = state
    return segment, traverse is Traverse.BACKWARD, progress is Progress.REVERSE


def state_text(state: State) -> str:
    """``segment 5 (driven forward, progress reverse)``: a state as messages name it."""
    segment, traverse, progress = state
    return f"segment {segment} (driven {traverse.value}, progress {progress.value})"


def moves(layout: Layout, capability: TurnCapability, state: State) -> Iterator[State]:
    """Every state a vehicle may be in on its next leg (an in-place turner chooses either progress)."""
    segment, traverse, progress = state
    rule = RULES[capability]
    for next_segment, next_traverse, joint in layout.successors(segment, traverse):
        for next_progress in rule[joint][progress]:
            yield next_segment, next_traverse, next_progress


@dataclass(frozen=True, slots=True)
class Reach:
    """Where a vehicle that may be in any of ``starts`` can get: ``entered`` holds every state it can
    drive on to in one or more legs (a start it can come back to included)."""

    capability: TurnCapability
    starts: frozenset[State]
    entered: frozenset[State]

    @property
    def segments(self) -> frozenset[int]:
        """Every segment the vehicle is on or can drive on to."""
        return frozenset(state[0] for state in self.starts | self.entered)


def reach(layout: Layout, capability: TurnCapability, starts: Iterable[State]) -> Reach:
    """Every state a vehicle of ``capability`` can enter from ``starts`` (a search of the map)."""
    begin = frozenset(starts)
    entered: set[State] = set()
    frontier = list(begin)
    while frontier:
        for following in moves(layout, capability, frontier.pop()):
            if following not in entered:
                entered.add(following)
                frontier.append(following)
    return Reach(capability, begin, frozenset(entered))


def goal_states(layout: Layout, goal: int) -> tuple[State, ...]:
    """Every state on segment ``goal`` that its direction allows."""
    segment = layout.segments[goal]
    return tuple((goal, t, p) for t in Traverse if segment.allows(t) for p in Progress)


def arrivals(
    starts: Iterable[State], entered: Iterable[State], goal: int, progress: Progress | None
) -> frozenset[State]:
    """The states a vehicle may be in once it has reached segment ``goal`` arriving with ``progress``
    (``None``: either); empty when it cannot.

    ``starts`` are where the vehicle may be now and ``entered`` states it can drive on to from there
    (those on other segments are passed over). A vehicle already on the goal has reached it if its
    progress matches: its leg is fixed, so the progress cannot change there.
    """
    return frozenset(s for group in (starts, entered) for s in group if s[0] == goal and progress in (None, s[2]))


class ReachIndex:
    """Which states a vehicle of one turn capability can drive on to from which, for many questions.

    One pass over the whole map finds the strongly connected components of its states (Tarjan); each
    question is then answered on the components, so checking thousands of tasks on a large map costs
    about one search of it. It answers what :func:`reach` answers, without searching again.
    """

    def __init__(self, layout: Layout, capability: TurnCapability) -> None:
        self.capability = capability
        # An in-place turner's progress never limits where it goes: index one progress, ask with it.
        self._free = capability is TurnCapability.IN_PLACE
        progresses = (Progress.FORWARD,) if self._free else tuple(Progress)
        states = [
            (sid, traverse, progress)
            for sid, segment in layout.segments.items()
            for traverse in Traverse
            if segment.allows(traverse)
            for progress in progresses
        ]
        if self._free:
            forward = Progress.FORWARD
            following = [
                [(sid, traverse, forward) for sid, traverse, _ in layout.successors(state[0], state[1])]
                for state in states
            ]
        else:
            following = [list(next_states(layout, capability, state)) for state in states]
        number = {state: n for n, state in enumerate(states)}
        successors = [[number[other] for other in others] for others in following]
        component = _strong_components(successors)
        self._component = dict(zip(states, component, strict=True))
        count = max(component, default=-1) + 1
        sizes = [0] * count
        self._cyclic = [False] * count  # a component a vehicle can drive round: size > 1 or a loop
        self._later: list[set[int]] = [set() for _ in range(count)]  # components one leg away
        for n, others in enumerate(successors):
            own = component[n]
            sizes[own] += 1
            for other in others:
                if other == n:
                    self._cyclic[own] = True
                elif component[other] != own:
                    self._later[own].add(component[other])
        self._cyclic = [cyclic or size > 1 for cyclic, size in zip(self._cyclic, sizes, strict=True)]
        self._below: dict[int, frozenset[int]] = {}

    def _key(self, state: State) -> State:
        return (state[0], state[1], Progress.FORWARD) if self._free else state

    def _descendants(self, component: int) -> frozenset[int]:
        """Components reachable from ``component`` in one or more legs, itself excluded."""
        found = self._below.get(component)
        if found is None:
            seen: set[int] = set()
            frontier = list(self._later[component])
            while frontier:
                other = frontier.pop()
                if other not in seen:
                    seen.add(other)
                    frontier.extend(self._later[other] - seen)
            found = self._below[component] = frozenset(seen)
        return found

    def entered(self, starts: Iterable[State], candidates: Iterable[State]) -> frozenset[State]:
        """The ``candidates`` a vehicle in any of ``starts`` can drive on to in one or more legs."""
        component = self._component
        wanted = [(state, self._key(state)) for state in candidates]
        found: set[State] = set()
        for start in starts:
            key = self._key(start)
            own = component[key]
            below = self._descendants(own)
            for state, state_key_ in wanted:
                other = component[state_key_]
                if other in below or (other == own and (state_key_ != key or self._cyclic[own])):
                    found.add(state)
        return frozenset(found)


def _strong_components(successors: list[list[int]]) -> list[int]:
    """Tarjan's algorithm without recursion over states numbered ``0..n-1``: each one's component
    number, descendants numbered first."""
    size = len(successors)
    index = [-1] * size
    low = [0] * size
    on_stack = bytearray(size)
    stack: list[int] = []
    component = [-1] * size
    counter = count = 0
    for root in range(size):
        if index[root] >= 0:
            continue
        index[root] = low[root] = counter
        counter += 1
        stack.append(root)
        on_stack[root] = 1
        work = [(root, iter(successors[root]))]
        while work:
            state, following = work[-1]
            for other in following:
                if index[other] < 0:
                    index[other] = low[other] = counter
                    counter += 1
                    stack.append(other)
                    on_stack[other] = 1
                    work.append((other, iter(successors[other])))
                    break
                if on_stack[other] and index[other] < low[state]:
                    low[state] = index[other]
            else:
                work.pop()
                if work and low[state] < low[work[-1][0]]:
                    low[work[-1][0]] = low[state]
                if low[state] == index[state]:
                    while True:
                        member = stack.pop()
                        on_stack[member] = 0
                        component[member] = count
                        if member == state:
                            break
                    count += 1
    return component

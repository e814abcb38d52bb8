"""Why a vehicle cannot reach a goal segment: the most specific reason that can be stated.

The reasons are tried from the most to the least specific, and the first that holds is given:

1. the goal segment can be reached, but not with the progress the task asks for;
2. the goal lies in a part of the map that touches no segment of the vehicle's part at all (a gap):
   the dangling end of what the vehicle can reach that is closest to the goal's part, and how far;
3. the vehicle cannot leave the segment it is on (a dead end, a one-way end, or only corners);
4. the goal can only be reached by turning in place at a corner, and the vehicle only follows curves;
5. the one-way directions lead elsewhere (the only thing left that separates connected segments).
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from itertools import pairwise

import numpy as np

from fleetsim.enums import JointKind, Progress, TurnCapability
from fleetsim.layout.connections import Endpoint, dangling_ends, endpoint_array, touching_endpoints
from fleetsim.layout.layout import Layout
from fleetsim.layout.reachability import Reach, State, next_states, state_key

__all__ = ["why_unreachable"]


def why_unreachable(layout: Layout, where: Reach, goal: int, progress: Progress | None, type_name: str) -> str:
    """A sentence (no final full stop) saying why a vehicle in ``where`` cannot reach ``goal``.

    ``type_name`` names the vehicle type in reasons that depend on its turn capability.
    """
    return (
        _other_progress(where, goal, progress)
        or _disconnected(layout, where, goal)
        or _stuck(layout, where, type_name)
        or _corner(layout, where, goal, type_name)
        or f"every route to segment {goal} would drive against a one-way segment"
    )


def _other_progress(where: Reach, goal: int, progress: Progress | None) -> str | None:
    if progress is None:
        return None
    wanted = progress.value
    entered = sorted({s[2].value for s in where.entered if s[0] == goal})
    if entered:
        return (
            f"segment {goal} can only be entered driving {_progress_words(entered[0])}, "
            f"and the task asks for {wanted} arrival"
        )
    if any(s[0] == goal for s in where.starts):
        return (
            f"no route leads back onto segment {goal}, and the vehicle is on it driving "
            f"{_progress_words(Progress(wanted).flipped.value)}; the task asks for {wanted} arrival"
        )
    return None


def _progress_words(progress: str) -> str:
    return "forward (nose first)" if progress == Progress.FORWARD.value else "in reverse (backing)"


def _parts(layout: Layout) -> dict[int, int]:
    """Each segment's part of the map: segments whose ends touch (directions aside) share a part."""
    parent = {sid: sid for sid in layout.segments}

    def root(sid: int) -> int:
        while parent[sid] != sid:
            parent[sid] = parent[parent[sid]]
            sid = parent[sid]
        return sid

    for t in touching_endpoints(tuple(layout.segments.values()), layout.connection_tolerance):
        a, b = root(t.a.segment.id), root(t.b.segment.id)
        parent[max(a, b)] = min(a, b)
    return {sid: root(sid) for sid in parent}


def _point(p: tuple[float, float]) -> str:
    return f"({p[0]:.3f}, {p[1]:.3f})"


def _end(end: Endpoint) -> str:
    return f"the {end.name} end of segment {end.segment.id} at {_point(end.point)}"


def _disconnected(layout: Layout, where: Reach, goal: int) -> str | None:
    parts = _parts(layout)
    reached = where.segments
    if parts[goal] in {parts[sid] for sid in reached}:
        return None
    others = tuple(layout.segments[sid] for sid in layout.segments if parts[sid] == parts[goal])
    targets = endpoint_array(others)  # row 2k: the first end of others[k], row 2k + 1: its last
    own = tuple(layout.segments[sid] for sid in sorted(reached))
    touches = touching_endpoints(tuple(layout.segments.values()), layout.connection_tolerance)
    loose = dangling_ends(own, [t for t in touches if reached & {t.a.segment.id, t.b.segment.id}])
    candidates = loose or tuple(Endpoint(segment, at_last) for segment in own for at_last in (False, True))
    found: list[tuple[float, Endpoint, Endpoint]] = []
    for end in candidates:  # in segment order: the first of equally close ends wins
        gaps = np.hypot(targets[:, 0] - end.point[0], targets[:, 1] - end.point[1])
        row = int(np.argmin(gaps))
        found.append((float(gaps[row]), end, Endpoint(others[row // 2], at_last=bool(row % 2))))
    gap, near, far = min(found, key=lambda item: item[0])
    closest = "the closest dangling end" if loose else "no end of that part is dangling; the closest end"
    return (
        f"segment {goal} lies in a part of the map that is not connected to the part the vehicle can "
        f"drive in; {closest} is {_end(near)}, {gap:.2f} m from {_end(far)}"
    )


def _stuck(layout: Layout, where: Reach, type_name: str) -> str | None:
    """The vehicle cannot get off the segment(s) it is on."""
    here = {state[0] for state in where.starts}
    if not where.segments <= here:
        return None
    states = sorted(where.starts | where.entered, key=state_key)
    corners = sorted(
        {
            to_segment
            for segment, traverse, _ in states
            for to_segment, _, joint in layout.successors(segment, traverse)
            if joint is JointKind.TURN_IN_PLACE and to_segment not in here
        }
    )
    name = " or ".join(f"segment {sid}" for sid in sorted(here))
    if corners and where.capability is TurnCapability.CURVE:
        onto = ", ".join(str(sid) for sid in corners)
        return (
            f"no route leaves {name}: the only ways on are corners (onto segment {onto}) that need "
            f"turning in place, and vehicle type {type_name!r} only follows curves"
        )
    exits = sorted({_point(layout.segments[s].exit(t)) for s, t, _ in states})
    ends = " and ".join(exits)
    return f"no route leaves {name}: no segment it may drive on to meets it at {ends} (a dead end)"


def _corner(layout: Layout, where: Reach, goal: int, type_name: str) -> str | None:
    """A curve-only vehicle that a vehicle turning in place could take there: name the first corner."""
    if where.capability is not TurnCapability.CURVE:
        return None
    path = _path(layout, where.starts, goal)
    if path is None:
        return None
    curve_states = {(s[0], s[1]) for s in where.starts | where.entered}
    for (a, _, _), (b, tb, _) in pairwise(path):
        if (b, tb) not in curve_states:
            return (
                f"every route to segment {goal} needs turning in place at a corner (the first from "
                f"segment {a} onto segment {b}), and vehicle type {type_name!r} only follows curves"
            )
    return None  # pragma: no cover - a path leaving the curve-reachable states crosses a corner


def _path(layout: Layout, starts: Iterable[State], goal: int) -> Sequence[State] | None:
    """The fewest legs to ``goal`` for a vehicle that turns in place (starts included), or ``None``."""
    came_from: dict[State, State | None] = {}
    frontier: list[State] = []
    for state in sorted(starts, key=state_key):
        came_from[state] = None
        frontier.append(state)
    while frontier:
        following_states = []
        for state in frontier:
            for following in next_states(layout, TurnCapability.IN_PLACE, state):
                if following in came_from:
                    continue
                came_from[following] = state
                if following[0] == goal:
                    path = [following]
                    while (previous := came_from[path[-1]]) is not None:
                        path.append(previous)
                    return path[::-1]
                following_states.append(following)
        frontier = following_states
    return None

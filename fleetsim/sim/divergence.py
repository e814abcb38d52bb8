"""Where two runs' traces first differ, told in words: the vehicles, plans and events of that step.

A trace (:mod:`fleetsim.sim.trace`) is compact: a vehicle is ``[1, 3, "f", "f", 1200, 0, 9000, 1000]``,
a plan ``[1, [[3, "f", "f", 1, None], ...]]``. A divergence reads them back into what they mean, each
difference as *first trace's value → second trace's value*::

    first divergence at step 1 (t = 0.20 s): vehicle 1's plan, leg 2 (segment 3 forward): fixed → planned

Legs are counted from 0, as rejections count them.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

__all__ = ["Divergence", "describe_event", "describe_leg", "first_divergence"]

_TRAVERSE = {"f": "forward", "b": "backward"}
_PROGRESS = {"f": "forward", "r": "reverse"}
_NONE = "none"


@dataclass(frozen=True, slots=True)
class Divergence:
    """Where two traces first differ, and how.

    Attributes:
        step: The first step whose lines differ (``-1``: the headers differ).
        time: Simulated seconds at the end of that step.
        differences: Each difference in words, the first trace's value before ``→``, the second's after.
    """

    step: int
    time: float
    differences: tuple[str, ...]

    def __str__(self) -> str:
        return f"first divergence at step {self.step} (t = {self.time:.2f} s): " + "; ".join(self.differences)


def first_divergence(a: Sequence[str], b: Sequence[str], time_step: float) -> Divergence | None:
    """The first step at which two traces' lines differ (``None`` if identical), described in words:
    each vehicle whose state differs (field by field, in metres, degrees and m/s), each vehicle whose
    accepted plan differs (from the first leg that does), and the events of each trace."""
    if a and b and a[0] != b[0]:
        return Divergence(-1, 0.0, ("the trace headers differ (different scenario, settings or format)",))
    state_a: dict[int, list[Any]] = {}
    state_b: dict[int, list[Any]] = {}
    # Compared up to the shorter trace; the length check below reports the rest.
    for line_a, line_b in zip(a[1:], b[1:], strict=False):
        step, vehicles_a, plans_a, events_a = json.loads(line_a)
        _, vehicles_b, plans_b, events_b = json.loads(line_b)
        state_a.update({record[0]: record for record in vehicles_a})
        state_b.update({record[0]: record for record in vehicles_b})
        if line_a == line_b:
            continue
        notes = [*_vehicles(state_a, state_b), *_plans(plans_a, plans_b)]
        if events_a != events_b:
            notes.append(f"events: {_events(events_a)} → {_events(events_b)}")
        return Divergence(step, (step + 1) * time_step, tuple(notes) or ("the step records differ",))
    if len(a) != len(b):
        step = min(len(a), len(b)) - 1
        return Divergence(
            step, step * time_step, (f"one run ended after {len(a) - 1} steps, the other after {len(b) - 1}",)
        )
    return None


# -- vehicles ---------------------------------------------------------------------------------------


def _metres(mm: int) -> str:
    return f"{mm / 1000:.3f} m"


# A vehicle record after its id: segment, traverse, progress, x mm, y mm, heading in 0.01°, speed mm/s.
_FIELDS: tuple[tuple[str, Any], ...] = (
    ("segment", str),
    ("traverse", lambda word: _TRAVERSE.get(word, word)),
    ("progress", lambda word: _PROGRESS.get(word, word)),
    ("x", _metres),
    ("y", _metres),
    ("heading", lambda centidegrees: f"{centidegrees / 100:.2f}°"),
    ("speed", lambda mm_s: f"{mm_s / 1000:.3f} m/s"),
)


def _vehicles(a: dict[int, list[Any]], b: dict[int, list[Any]]) -> list[str]:
    notes = []
    for vid in sorted(set(a) | set(b)):
        left, right = a.get(vid), b.get(vid)
        if left == right:
            continue
        if left is None or right is None:
            notes.append(f"vehicle {vid} is in the {'second' if left is None else 'first'} trace only")
            continue
        changes = [
            f"{name} {show(x)} → {show(y)}"
            for (name, show), x, y in zip(_FIELDS, left[1:], right[1:], strict=True)
            if x != y
        ]
        notes.append(f"vehicle {vid}: {', '.join(changes)}")
    return notes


# -- plans ------------------------------------------------------------------------------------------


def _leg_words(leg: Sequence[Any]) -> tuple[str, str, str, str]:
    """A trace leg ``[segment, traverse, progress, fixed, goal task]`` as its words: where, progress,
    fixed or planned, goal."""
    segment, traverse, progress, fixed, goal = leg
    return (
        f"segment {segment} {_TRAVERSE.get(traverse, traverse)}",
        f"progress {_PROGRESS.get(progress, progress)}",
        "fixed" if fixed else "planned",
        "no goal" if goal is None else f"goal of task {goal}",
    )


def describe_leg(leg: Sequence[Any]) -> str:
    """A trace leg ``[segment, traverse, progress, fixed, goal task]`` in words, what goes without saying
    (nose first, no goal) left out: ``segment 3 backward, progress reverse, fixed, goal of task 1``."""
    place, progress, fixed, goal = _leg_words(leg)
    return ", ".join(w for w in (place, progress, fixed, goal) if w not in ("progress forward", "no goal"))


def _leg_change(index: int, left: Sequence[Any], right: Sequence[Any]) -> str:
    """One leg that differs: where it is, then the words that changed."""
    before, after = _leg_words(left), _leg_words(right)
    if before[0] != after[0]:
        return f"leg {index}: {describe_leg(left)} → {describe_leg(right)}"
    changed = [k for k in range(1, 4) if before[k] != after[k]]
    was, now = ", ".join(before[k] for k in changed), ", ".join(after[k] for k in changed)
    return f"leg {index} ({before[0]}): {was} → {now}"


def _plan_change(legs_a: Sequence[Sequence[Any]], legs_b: Sequence[Sequence[Any]]) -> str:
    for index, (left, right) in enumerate(zip(legs_a, legs_b, strict=False)):
        if left != right:
            change = _leg_change(index, left, right)
            break
    else:  # one plan is the other with legs added at its end
        index = min(len(legs_a), len(legs_b))
        longer = "first" if len(legs_a) > index else "second"
        extra = legs_a[index] if longer == "first" else legs_b[index]
        change = f"leg {index} ({describe_leg(extra)}) in the {longer} trace only"
    sizes = f" ({len(legs_a)} legs → {len(legs_b)})" if len(legs_a) != len(legs_b) else ""
    return f"{change}{sizes}"


def _plans(a: Sequence[Sequence[Any]], b: Sequence[Sequence[Any]]) -> list[str]:
    """The plans accepted in the step, vehicle by vehicle (a vehicle's plan at most once per step)."""
    mine = {vid: legs for vid, legs in a}  # noqa: C416  # [vehicle, legs] lists, not pairs to mypy
    theirs = {vid: legs for vid, legs in b}  # noqa: C416
    notes = []
    for vid in sorted(mine.keys() | theirs.keys()):
        left, right = mine.get(vid), theirs.get(vid)
        if left == right:
            continue
        if left is None or right is None:
            legs = right if left is None else left
            assert legs is not None
            shown = " | ".join(describe_leg(leg) for leg in legs[:3]) + (" | ..." if len(legs) > 3 else "")
            which = "second" if left is None else "first"
            notes.append(f"vehicle {vid}'s plan accepted in the {which} trace only ({len(legs)} legs: {shown})")
            continue
        notes.append(f"vehicle {vid}'s plan, {_plan_change(left, right)}")
    return notes


# -- events -----------------------------------------------------------------------------------------


def _vehicles_listed(ids: Sequence[int]) -> str:
    return ", ".join(map(str, ids)) or "-"


def describe_event(event: Sequence[Any]) -> str:
    """A trace event in words (``["complete", 2]``: ``task 2 completed``); one this version does not
    know is shown as written."""
    kind, *rest = event
    if kind == "complete" and len(rest) == 1:
        return f"task {rest[0]} completed"
    if kind == "reject" and len(rest) == 3:
        code, vehicle, leg = rest
        return f"vehicle {vehicle}'s plan rejected ({code}{'' if leg is None else f' at leg {leg}'})"
    if kind == "route-error" and len(rest) == 2:
        vehicle, message = rest
        return f"route error{'' if vehicle is None else f' for vehicle {vehicle}'}: {message}"
    if kind == "alert" and len(rest) == 3:
        segment, primary, secondary = rest
        return (
            f"collision alert on segment {segment} (primary {_vehicles_listed(primary)}, "
            f"secondary {_vehicles_listed(secondary)})"
        )
    if kind == "planner-error" and len(rest) == 1:
        return "planner error" + ("" if rest[0] is None else f" (vehicle {rest[0]})")
    if kind in ("disturb", "resume") and len(rest) == 2:
        vehicle, what = rest
        noun = {"stop": "stop", "slow": "slow-down", "pause": "pause"}.get(what, what)
        return f"vehicle {vehicle}'s {noun} {'begins' if kind == 'disturb' else 'ends'}"
    if kind == "interrupted" and len(rest) == 1:
        return f"interrupted by {rest[0]}"
    return json.dumps(list(event))


def _events(events: Sequence[Sequence[Any]]) -> str:
    return ", ".join(map(describe_event, events)) or _NONE

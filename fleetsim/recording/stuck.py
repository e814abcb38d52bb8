"""Who waits for whom at the end of a stuck run, read from its failure's details (as in ``result.json``).

One reading for every picture of it: the failure picture (SVG), the recording's ``/fleetsim/stuck``
markers and the viewer page.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, NamedTuple

__all__ = ["StuckRelation", "contested_segments", "root_vehicles", "stuck_relations"]


class StuckRelation(NamedTuple):
    """One vehicle waiting for another (``waits``), or planned near it (not waiting), and whether the
    wait is part of a wait-for cycle."""

    source: int
    target: int
    waits: bool
    cycle: bool


def stuck_relations(stuck: Mapping[str, Any]) -> list[StuckRelation]:
    """Each finding's waits (``blocked_by``), then its near plans (``planned_near``), in finding order."""
    cycles = stuck.get("cycles", ())
    in_cycle = {(int(c[i]), int(c[(i + 1) % len(c)])) for c in cycles for i in range(len(c))}
    relations = []
    for finding in stuck.get("vehicles", ()):
        source = int(finding["vehicle"])
        for target in finding.get("blocked_by", ()):
            relations.append(StuckRelation(source, int(target), True, (source, int(target)) in in_cycle))
        for target in finding.get("planned_near", ()):
            relations.append(StuckRelation(source, int(target), False, (source, int(target)) in in_cycle))
    return relations


def contested_segments(stuck: Mapping[str, Any]) -> list[int]:
    """The segments waiting vehicles need and others hold, ascending."""
    return sorted({int(s) for finding in stuck.get("vehicles", ()) for s in finding.get("contested", ())})


def root_vehicles(stuck: Mapping[str, Any]) -> list[int]:
    """The vehicles of every root cause, ascending."""
    return sorted({int(v) for root in stuck.get("roots", ()) for v in root.get("vehicles", ())})

"""The disturbance keys of a suite entry (issue 20): ``disturbances``, ``random_disturbances`` and
``hunt_disturbances``, checked beyond what the schema says, each problem located at its value.

Every mistake of a block is reported (each disturbance of a list by its first problem), several as one
:class:`~fleetsim.errors.SuiteErrors`. What needs the scenario's files (a vehicle or segment that does
not exist) is checked when the scenario is loaded (:func:`check_disturbances`), located at the
disturbance's line in the suite.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from fleetsim.errors import Location, SuiteError
from fleetsim.load.common.collect import ErrorCollector
from fleetsim.load.common.yaml_source import Locate
from fleetsim.load.suites.schema import raise_suite_errors, suite_error
from fleetsim.scenario import Disturbance, RandomDisturbances, Scenario

__all__ = ["HuntDisturbances", "check_disturbances", "declared_disturbances", "hunt_block", "random_block"]


@dataclass(frozen=True, slots=True)
class HuntDisturbances:
    """A ``hunt_disturbances`` block: Hypothesis searches stop schedules (fleetsim.gating.disturbance_hunt).

    ``at``: when a stop may begin, seconds; ``None`` up to the scenario's time limit."""

    count: tuple[int, int] = (1, 3)
    stop: tuple[float, float] = (1.0, 60.0)
    at: tuple[float, float] | None = None
    examples: int = 100


def _range(raw: Mapping[str, Any], key: str, where: tuple[Any, ...], locate: Locate) -> tuple[float, float] | None:
    if key not in raw:
        return None
    low, high = raw[key]
    if low > high:
        msg = f"{key}={[low, high]!r} must be [min, max] with min <= max"
        raise suite_error(msg, (*where, key), locate((*where, key)))
    return (low, high)


def declared_disturbances(
    raw: Sequence[Mapping[str, Any]], where: tuple[Any, ...], locate: Locate
) -> tuple[Disturbance, ...]:
    """The ``disturbances`` list of an entry (the schema has checked types and bounds)."""
    errors = ErrorCollector()
    found = []
    for index, item in enumerate(raw):
        with errors.collecting():
            found.append(_declared(item, (*where, index), locate))
    raise_suite_errors(errors)
    return tuple(found)


def _declared(item: Mapping[str, Any], here: tuple[Any, ...], locate: Locate) -> Disturbance:
    line = locate(here).line
    if ("at" in item) == ("on_segment" in item):
        what = "both 'at' and 'on_segment'" if "at" in item else "neither 'at' nor 'on_segment'"
        msg = f"{item!r} has {what}: give exactly one (when it begins)"
        raise suite_error(msg, here, locate(here))
    if ("stop" in item) == ("slow" in item):
        what = "both 'stop' and 'slow'" if "stop" in item else "neither 'stop' nor 'slow'"
        msg = f"{item!r} has {what}: give exactly one (what happens)"
        raise suite_error(msg, here, locate(here))
    if ("slow" in item) != ("for" in item):
        key = "slow" if "slow" in item else "for"
        msg = f"{key}={item[key]!r} needs {'for' if key == 'slow' else 'slow'}: a slow is 'slow: FACTOR, for: SECONDS'"
        raise suite_error(msg, (*here, key), locate((*here, key)))
    at = float(item["at"]) if "at" in item else None
    if "stop" in item:
        return Disturbance(item["vehicle"], "stop", float(item["stop"]), at, item.get("on_segment"), line=line)
    return Disturbance(
        item["vehicle"], "slow", float(item["for"]), at, item.get("on_segment"), float(item["slow"]), line
    )


def random_block(raw: Mapping[str, Any], where: tuple[Any, ...], locate: Locate) -> RandomDisturbances:
    stop = _range(raw, "stop", where, locate)
    assert stop is not None  # required by the schema
    return RandomDisturbances(raw["seed"], float(raw["stops_per_vehicle_hour"]), (float(stop[0]), float(stop[1])))


def hunt_block(raw: Mapping[str, Any], where: tuple[Any, ...], locate: Locate) -> HuntDisturbances:
    errors = ErrorCollector()
    ranges: dict[str, tuple[float, float] | None] = {}
    for key in ("count", "stop", "at"):
        ranges[key] = None
        with errors.collecting():
            ranges[key] = _range(raw, key, where, locate)
    raise_suite_errors(errors)
    count, stop, at = ranges["count"], ranges["stop"], ranges["at"]
    defaults = HuntDisturbances()
    return HuntDisturbances(
        count=(int(count[0]), int(count[1])) if count else defaults.count,
        stop=(float(stop[0]), float(stop[1])) if stop else defaults.stop,
        at=(float(at[0]), float(at[1])) if at else None,
        examples=raw.get("examples", defaults.examples),
    )


def check_disturbances(scenario: Scenario, suite_path: Path | str) -> None:
    """Every declared disturbance names a vehicle and (``on_segment``) a segment of the scenario."""
    vehicles = sorted(v.id for v in scenario.vehicles)
    for disturbance in scenario.disturbances:
        where = Location(suite_path, line=disturbance.line)
        if disturbance.vehicle not in vehicles:
            msg = f"disturbances: vehicle={disturbance.vehicle!r} is not a vehicle of this scenario ({', '.join(map(str, vehicles))})"
            raise SuiteError(msg, Location(suite_path, line=disturbance.line, field="vehicle"))
        if disturbance.on_segment is not None and disturbance.on_segment not in scenario.layout.segments:
            msg = f"disturbances: on_segment={disturbance.on_segment!r} is not a segment of the map"
            raise SuiteError(msg, Location(where.path, line=where.line, field="on_segment"))

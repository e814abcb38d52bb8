"""Hunting for the smallest disturbance that breaks a planner (issue 20, ``hunt_disturbances``).

Each example runs the scenario with ``count`` stops, each of a drawn vehicle at a drawn time for a
drawn duration. Times and durations are drawn in tenths of a second, vehicles from the scenario's ids in
ascending order, so Hypothesis shrinks a failing schedule toward fewer stops, earlier and shorter ones
and lower vehicle ids, and the result pastes as plain numbers. A ``generate`` entry draws its scenario
first and the schedule for it, so layout and disturbances are searched (and shrunk) together. The hunt
itself, and how a counterexample is saved, is :func:`fleetsim.gating.generated.hunt`'s.
"""

from __future__ import annotations

import math
from dataclasses import replace

from hypothesis import strategies as st

from fleetsim.load.suites.disturbances import HuntDisturbances
from fleetsim.scenario import Disturbance, Scenario

__all__ = ["disturbance_lines", "disturbed", "stop_schedules"]


def stop_schedules(scenario: Scenario, hunt: HuntDisturbances) -> st.SearchStrategy[tuple[Disturbance, ...]]:
    """Schedules of ``hunt.count`` stops for ``scenario``'s vehicles."""
    ids = sorted(v.id for v in scenario.vehicles)
    if not ids:
        return st.just(())
    low_at, high_at = hunt.at if hunt.at is not None else (0.0, scenario.settings.time_limit)
    low, high = hunt.stop
    stop = st.builds(
        lambda vehicle, at, tenths: Disturbance(vehicle, "stop", tenths / 10, at=at / 10),
        st.sampled_from(ids),
        st.integers(math.ceil(low_at * 10), max(math.ceil(low_at * 10), math.floor(high_at * 10))),
        st.integers(math.ceil(low * 10), max(math.ceil(low * 10), math.floor(high * 10))),
    )
    return st.lists(stop, min_size=hunt.count[0], max_size=hunt.count[1]).map(tuple)


def disturbed(scenarios: st.SearchStrategy[Scenario], hunt: HuntDisturbances) -> st.SearchStrategy[Scenario]:
    """Each scenario of ``scenarios`` with a schedule of stops drawn for it."""
    return scenarios.flatmap(
        lambda scenario: stop_schedules(scenario, hunt).map(lambda ds: replace(scenario, disturbances=ds))
    )


def disturbance_lines(disturbances: tuple[Disturbance, ...], indent: str = "    ") -> list[str]:
    """A ready-to-paste ``disturbances:`` list, one flow mapping per line."""
    if not disturbances:
        return []
    items = [
        ", ".join(
            f"{key}: {value:g}" if isinstance(value, float) else f"{key}: {value}" for key, value in d.entry().items()
        )
        for d in disturbances
    ]
    return [f"{indent}disturbances:", *(f"{indent}  - {{{item}}}" for item in items)]

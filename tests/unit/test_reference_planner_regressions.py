"""Generated scenarios that once defeated the reference planner, kept as ordinary scenario folders.

Each was found by the property test (tests/property/test_reference_planner.py) or a hunt like it, saved
with ``fleetsim.strategies.save_scenario``, and fixed in the planner; the name says what went wrong.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import pytest

from fleetsim.enums import TurnCapability
from fleetsim.planners import ReservingPlanner
from fleetsim.scenario import DEFAULT_VEHICLE_TYPE, VehicleType
from fleetsim.sim.loop import run_scenario
from fleetsim.sim.report import failure_report
from fleetsim.strategies import load_saved

FOLDER = Path(__file__).resolve().parents[1] / "data" / "planner_regressions"
TYPES = (
    replace(DEFAULT_VEHICLE_TYPE, name="agv"),
    VehicleType("tugger", 1.4, 0.7, 0.5, 1.2, 0.4, TurnCapability.CURVE),
)


@pytest.mark.parametrize("name", sorted(p.name for p in FOLDER.iterdir()))
def test_the_reference_planner_completes_a_scenario_that_once_defeated_it(name: str) -> None:
    scenario = load_saved(FOLDER / name, TYPES)
    result = run_scenario(scenario, ReservingPlanner(), keep_trace=False)
    assert result.ended == "completed", failure_report(result, heading=name)
    assert (result.collisions, result.rejections) == ((), ())

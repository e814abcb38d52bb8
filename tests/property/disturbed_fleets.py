"""Generated fleets with stops and slow-downs drawn on top, for the property tests that run a fleet two
ways and compare (batched motion, the quiet hint)."""

from __future__ import annotations

from dataclasses import replace

from hypothesis import strategies as st

from fleetsim.enums import TurnCapability
from fleetsim.scenario import DEFAULT_VEHICLE_TYPE, Disturbance, Scenario, VehicleType
from fleetsim.strategies import GenerationSpec, scenarios

AGV = replace(DEFAULT_VEHICLE_TYPE, name="agv")
TUGGER = VehicleType("tugger", 1.4, 0.7, 0.5, 1.2, 0.4, TurnCapability.CURVE)
SPEC = GenerationSpec(layout="any", size=(1, 4), vehicles=(1, 6), tasks=(1, 3), vehicle_types=(AGV, TUGGER))


@st.composite
def disturbed(draw: st.DrawFn) -> Scenario:
    scenario = draw(scenarios(SPEC))
    ids = sorted(v.id for v in scenario.vehicles)
    disturbances = []
    for _ in range(draw(st.integers(0, 3))):
        vehicle = draw(st.sampled_from(ids))
        at = draw(st.integers(0, 300)) / 10.0
        duration = draw(st.integers(1, 100)) / 10.0
        if draw(st.booleans()):
            disturbances.append(Disturbance(vehicle, "stop", duration, at=at))
        else:
            factor = draw(st.sampled_from([0.2, 0.5, 0.9]))
            disturbances.append(Disturbance(vehicle, "slow", duration, at=at, factor=factor))
    return replace(scenario, disturbances=tuple(disturbances))

"""Replaying a run from its trace gives back the fleet the simulation had, step by step."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from fleetsim import load_scenario, load_suite
from fleetsim.planners import BFSPlanner, ReservingPlanner
from fleetsim.planning.plans import FleetPlan
from fleetsim.planning.reservations import ConflictTable, find_alerts
from fleetsim.recording.replay import TraceError, frame_at, replay
from fleetsim.scenario import Scenario
from fleetsim.sim import loop
from fleetsim.sim.trace import vehicle_record

SUITE = Path(__file__).resolve().parents[2] / "scenario_suites" / "examples.fleetsim.yaml"


def example(name: str) -> Scenario:
    suite = load_suite(SUITE)
    return load_scenario(next(spec for spec in suite.scenarios if spec.name == name), suite)


def _shape(plan: FleetPlan) -> list[tuple[Any, ...]]:
    """A plan without its goal markers (bookkeeping drops those; the trace does not show it)."""
    return [(leg.segment, leg.traverse, leg.progress, leg.fixed) for leg in plan.legs]


@pytest.mark.parametrize(
    ("name", "planner"),
    [("mixed-shapes", ReservingPlanner), ("crossing", BFSPlanner), ("loop-one-way", ReservingPlanner)],
)
def test_every_replayed_frame_has_the_simulations_poses_plans_and_alerts(
    name: str, planner: type, monkeypatch: pytest.MonkeyPatch
) -> None:
    scenario = example(name)
    seen: list[tuple[dict[int, Any], dict[int, Any]]] = []
    move = loop._Run.move

    def recording_move(self: Any, *args: Any) -> Any:
        records = move(self, *args)
        states = {vid: vehicle_record(self.controller.state_of(vid)) for vid in self.drivers}
        seen.append((states, {vid: _shape(plan) for vid, plan in self.controller.plans.items()}))
        return records

    monkeypatch.setattr(loop._Run, "move", recording_move)
    result = loop.run_scenario(scenario, planner())
    assert result.trace is not None
    frames = list(replay(scenario, result.trace.lines))
    assert [frame.step for frame in frames] == list(range(result.steps))
    table = ConflictTable(scenario.layout)
    for frame, (states, plans) in zip(frames, seen, strict=True):
        for vid, pose in frame.poses.items():
            x, y, heading = round(pose.x * 1000), round(pose.y * 1000), pose.heading
            assert (x, y) == states[vid][4:6]
            assert abs(heading * 18000 / 3.141592653589793 - states[vid][6]) < 0.5
        assert {vid: _shape(plan) for vid, plan in frame.plans.items()} == plans, f"step {frame.step}"
        assert frame.alerts == find_alerts(frame.plans, table)
    assert frames[-1].time == pytest.approx(result.sim_time)


def test_frame_at_gives_one_step_and_names_the_range_when_out_of_it() -> None:
    scenario = example("crossing")
    result = loop.run_scenario(scenario, ReservingPlanner())
    assert result.trace is not None
    assert frame_at(scenario, result.trace.lines, 3).step == 3
    assert frame_at(scenario, result.trace.lines, -1).step == result.steps - 1
    with pytest.raises(TraceError, match=f"step=9999 must be between 0 and {result.steps - 1}"):
        frame_at(scenario, result.trace.lines, 9999)


def test_a_trace_of_another_scenario_or_format_is_refused_by_name() -> None:
    crossing = example("crossing")
    result = loop.run_scenario(crossing, ReservingPlanner())
    assert result.trace is not None
    lines = result.trace.lines
    header = json.loads(lines[0])
    with pytest.raises(TraceError, match="format='fleetsim-trace/0' must be 'fleetsim-trace/1'"):
        list(replay(crossing, [json.dumps({**header, "format": "fleetsim-trace/0"}), *lines[1:]]))
    with pytest.raises(TraceError, match=r"trace vehicles=\[999\] must be scenario 'crossing'"):
        list(replay(crossing, [json.dumps({**header, "vehicles": [999]}), *lines[1:]]))
    with pytest.raises(TraceError, match="trace line 2="):
        list(replay(crossing, [lines[0], "not json"]))
    bad_step = json.dumps([0, [], [[header["vehicles"][0], [[987654, "f", "f", 1, None]]]], []])
    with pytest.raises(TraceError, match="names segment 987654, which scenario 'crossing' does not have"):
        list(replay(crossing, [lines[0], bad_step]))

"""Hunting disturbances (issue 20): Hypothesis finds and shrinks a one-stop schedule that breaks a planner
that is only safe on time, prints it as a ready-to-paste ``disturbances:`` list and saves it like a
generated counterexample; the conflict-free reference planner survives the same hunt."""

from __future__ import annotations

import time
from dataclasses import replace
from pathlib import Path

import yaml
from on_time_planner import OnTimePlanner

from fleetsim.gating.generated import counterexample_entry, hunt, record_counterexample
from fleetsim.load.suites.scenario import load_scenario, load_scenario_dir
from fleetsim.load.suites.suite import load_suite
from fleetsim.planners import ReservingPlanner
from fleetsim.sim.loop import run_scenario
from fleetsim.sim.record import RunOrigin

LATE_CROSSING = Path(__file__).resolve().parents[2] / "scenario_suites" / "caught-bugs" / "late-crossing"


def suite_file(tmp_path: Path, hunt_block: str) -> Path:
    path = tmp_path / "hunt.fleetsim.yaml"
    path.write_text(
        f"fleetsim: 1\nname: hunt\ndefaults: {{time_limit: 120}}\nscenarios:\n"
        f"  - name: late-crossing\n    dir: {LATE_CROSSING}\n    hunt_disturbances: {hunt_block}\n",
        encoding="utf-8",
    )
    return path


def test_the_on_time_planner_is_safe_on_time() -> None:
    result = run_scenario(load_scenario_dir(LATE_CROSSING), OnTimePlanner())
    assert result.status == "passed", [f.message for f in result.failures]


def test_a_hunt_finds_and_shrinks_a_one_stop_counterexample_and_saves_it(tmp_path: Path) -> None:
    path = suite_file(tmp_path, "{count: [1, 3], stop: [1, 60], examples: 100}")
    suite = load_suite(path)
    [spec] = suite.scenarios
    started = time.perf_counter()
    found = hunt(spec, suite, OnTimePlanner, identity="OnTimePlanner", derandomize=True)
    assert time.perf_counter() - started < 60
    assert found.counterexample is not None and found.result is not None and not found.result.passed
    [stop] = found.counterexample.disturbances
    # shrunk: the lowest vehicle id, the earliest time, and a duration just long enough to fail
    assert (stop.vehicle, stop.kind, stop.at) == (1, "stop", 0.0)
    shorter = load_scenario(spec, suite)
    barely = run_scenario(
        replace(shorter, disturbances=(replace(stop, duration=stop.duration - 0.1),)), OnTimePlanner()
    )
    assert barely.passed, "0.1 s shorter no longer fails: the duration is shrunk"
    assert any(f.kind == "collision" for f in found.result.failures)
    paths = record_counterexample(found, tmp_path / "found", RunOrigin(str(path)))
    assert {"picture", "mcap", "scenario"} <= set(paths), paths
    entry = counterexample_entry(spec, Path(paths["scenario"]), path, found.counterexample.disturbances)
    pasted = yaml.safe_load("scenarios:\n" + entry)["scenarios"][0]
    assert pasted["disturbances"] == [{"vehicle": 1, "at": 0, "stop": stop.duration}]
    # the entry loads and fails the same way
    suite_text = path.read_text(encoding="utf-8").split("scenarios:\n")[0] + "scenarios:\n" + entry
    (tmp_path / "again.fleetsim.yaml").write_text(suite_text, encoding="utf-8")
    again = load_suite(tmp_path / "again.fleetsim.yaml")
    rerun = run_scenario(load_scenario(again.scenarios[0], again), OnTimePlanner())
    assert rerun.trace_hash == found.result.trace_hash


def test_the_reserving_planner_survives_the_same_hunt(tmp_path: Path) -> None:
    # stops short enough that every task still fits in the time limit (a long one is a timeout, not a bug)
    path = suite_file(tmp_path, "{count: [1, 2], stop: [1, 20], examples: 15}")
    suite = load_suite(path)
    found = hunt(suite.scenarios[0], suite, ReservingPlanner, identity="ReservingPlanner", derandomize=True)
    assert found.counterexample is None and found.generated == 15

"""One sweep run on a worker: plain data in, one results row out; nothing a run does stops the sweep.

A planner that does not import on the worker, a scenario that does not load, a planner that raises or
hangs up: each fails its own run with a message saying what happened, in the row's ``error``.
"""

from __future__ import annotations

import traceback
from dataclasses import replace
from pathlib import Path
from typing import Any

from fleetsim.exec.spec import load_planner_factory
from fleetsim.gating.baseline import ScenarioMetrics
from fleetsim.recording.artifacts import artifact_folder, discard_run_folder, start_run_folder, write_run_artifacts
from fleetsim.sim.loop import run_scenario
from fleetsim.sim.planner_spec import PlannerSpecError
from fleetsim.sim.result import RunResult
from fleetsim.sweep.items import RunItem
from fleetsim.sweep.payload import scenario_from_payload

__all__ = ["failed_row", "result_row", "run_item"]

FAILURES_KEPT = 3


def run_item(item: RunItem) -> dict[str, Any]:
    """Run ``item`` and return its results row; never raises for anything the planner or scenario does."""
    if item["load_error"] is not None or item["scenario"] is None:
        return failed_row(item, f"the scenario did not load: {item['load_error']}", ended="load-error")
    try:
        factory = load_planner_factory(item["planner"], call_timeout=item["planner_timeout"])
    except PlannerSpecError as error:
        return failed_row(item, f"the planner cannot be loaded on this worker: {error}")
    try:
        scenario = scenario_from_payload(item["scenario"])
        folder = _folder(item)
        trace_file = start_run_folder(folder, {"scenario": item["id"], "planner": item["planner"]}) if folder else None
        result = run_scenario(
            scenario, factory(), planner_name=item["planner"], planner_timeout=item["planner_timeout"],
            keep_trace=folder is not None, trace_file=trace_file,
        )  # fmt: skip
        artifacts: dict[str, str] = {}
        if folder is not None and (item["record"] == "all" or not result.passed):
            artifacts = write_run_artifacts(folder, result, {"id": item["id"]}, scenario=scenario, streamed=True)
        elif folder is not None:
            discard_run_folder(folder, Path(item["artifacts"]))
        return result_row(item, replace(result, artifacts=artifacts))
    except Exception as error:  # a planner's constructor, a recording: this run only
        lines = traceback.format_exception_only(type(error), error)
        return failed_row(item, f"the run failed: {''.join(lines).strip()}")


def _folder(item: RunItem) -> Path | None:
    if item["record"] == "none":
        return None
    suite, _, name = item["id"].rpartition("::")
    planner = item["planner"].replace(":", "-").replace(" ", "_")[:60]
    return artifact_folder(Path(item["artifacts"]) / planner, Path(suite), name)


def _common(item: RunItem) -> dict[str, Any]:
    return {k: item[k] for k in ("key", "id", "planner", "source", "seed", "repetition", "vehicles")}


def result_row(item: RunItem, result: RunResult) -> dict[str, Any]:
    """The row of a run: the metrics-file fields (so ``--fleetsim-compare`` reads it) and the sweep's own."""
    metrics = ScenarioMetrics.from_result(item["id"], result.status, result).to_dict()
    hours = result.sim_time / 3600
    vehicles = max(item["vehicles"], 1)
    calls = result.metrics.planner_calls
    return {
        **metrics,
        **_common(item),
        "status": result.status,
        "ended": result.ended,
        "deadlock": result.deadlock is not None,
        "throughput": round(result.tasks_completed / hours, 6) if hours > 0 else 0.0,
        "waiting_share": round(metrics["waiting_time"] / (vehicles * result.sim_time), 6)
        if result.sim_time > 0
        else 0.0,
        "planner_time_per_call": round(result.metrics.planner_wall_time / calls, 9) if calls else None,
        "failures": [f"{f.kind}: {f.message}" for f in result.failures[:FAILURES_KEPT]],
        "error": None,
        "artifacts": {k: v for k, v in result.artifacts.items() if k in ("folder", "picture", "mcap", "result")},
    }


def failed_row(item: RunItem, error: str, ended: str = "planner-error") -> dict[str, Any]:
    """The row of a run that never ran (or broke down): failed, with no figures but the error."""
    zero: dict[str, Any] = {
        "outcome": "failed", "tasks_total": 0, "tasks_completed": 0, "makespan": None, "distance": 0.0,
        "waiting_time": 0.0, "alerts": 0, "rejections": 0, "planner_calls": 0, "planner_wall_time": 0.0,
        "wall_time": 0.0, "sim_time": 0.0, "realtime_factor": None, "trace_hash": "",
    }  # fmt: skip
    return {
        **zero,
        **_common(item),
        "status": "failed",
        "ended": ended,
        "deadlock": False,
        "throughput": None,
        "waiting_share": None,
        "planner_time_per_call": None,
        "failures": [error],
        "error": error,
        "artifacts": {},
    }

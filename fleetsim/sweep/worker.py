"""One sweep run on a worker: plain data in, one results record out; nothing a run does stops the sweep.

A record is the run's ordinary result (``schemas/result.schema.json``) plus the sweep's own keys. A
planner that does not import on the worker, a scenario that does not load, a planner that raises or
hangs up: each fails its own run with a message saying what happened, in the record's ``error``.
"""

from __future__ import annotations

import hashlib
import re
import traceback
from dataclasses import replace
from pathlib import Path
from typing import Any

from fleetsim.exec.spec import load_planner_factory
from fleetsim.recording.artifacts import artifact_folder, discard_run_folder, start_run_folder, write_run_artifacts
from fleetsim.sim.loop import run_scenario
from fleetsim.sim.result import Ending, Failure, RunResult
from fleetsim.specs.python import PlannerSpecError
from fleetsim.sweep.items import RunItem
from fleetsim.sweep.payload import scenario_from_payload
from fleetsim.view import write_view_file

__all__ = ["failed_row", "planner_folder", "result_row", "run_item"]

_NAME = re.compile(r"(~d\d+)?(@\d+)?$")
_MODULE_SPEC = re.compile(r"[\w.]+:[\w.]+")
_UNSAFE = re.compile(r"[^A-Za-z0-9._=,-]+")  # a path's separators too: a command's path is no folder tree
_FOLDER_LENGTH = 60


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
            artifacts = write_run_artifacts(
                folder, result, {"id": item["id"]}, scenario=scenario, streamed=True, more=write_view_file
            )
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
    return artifact_folder(Path(item["artifacts"]) / planner_folder(item["planner"]), Path(suite), name)


def planner_folder(planner: str) -> str:
    """The folder of a planner's runs, one level below the sweep's: ``fleetsim.planners-ReservingPlanner``
    for a ``module:attr`` spec; any other (``exec:``, ``vda5050:``: a command line, options) made
    file-safe, cut, and told apart by a digest of the whole spec. Two planners must never share a folder:
    a run starting empties its own, which would delete a run of the other one that a worker streams
    there at the same time (two master controls behind one ``vda5050:speed=20,exec=python ...`` prefix)."""
    if _MODULE_SPEC.fullmatch(planner) and len(planner) <= _FOLDER_LENGTH:
        return planner.replace(":", "-")
    safe = _UNSAFE.sub("_", planner.replace(":", "-")).strip("._")[: _FOLDER_LENGTH - 11]
    return f"{safe}-{hashlib.sha256(planner.encode()).hexdigest()[:10]}"


def _sweep_keys(item: RunItem, error: str | None) -> dict[str, Any]:
    keys = {"key": item["key"], "id": item["id"], "source": item["source"], "seed": item["seed"]}
    return {**keys, "repetition": item["repetition"], "vehicles": item["vehicles"], "error": error}


def result_row(item: RunItem, result: RunResult) -> dict[str, Any]:
    """The record of a run: the run's ordinary result (``schemas/result.schema.json``, as ``fleetsim run
    --json`` gives it) and the sweep's own keys (key, id, source, seed, repetition, vehicles, error)."""
    return {**result.to_dict(), **_sweep_keys(item, None)}


def failed_row(item: RunItem, error: str, ended: Ending = "planner-error") -> dict[str, Any]:
    """The record of a run that never ran (or broke down on its worker): a result without a run, failed
    with ``error`` (a ``load-error`` or a ``planner-error``), which ``error`` repeats."""
    # A scenario that did not load is named by its id: SUITE::NAME, with ~dSEED and @REPETITION after it.
    name = item["scenario"]["name"] if item["scenario"] is not None else _NAME.sub("", item["id"].rpartition("::")[2])
    failure = Failure("load-error" if ended == "load-error" else "planner-error", 0.0, error)
    return {**RunResult.unrun(name, item["planner"], (failure,), ended=ended).to_dict(), **_sweep_keys(item, error)}

"""One sweep run on a worker: plain data in, one results record out; nothing a run does stops the sweep.

A record is the run's record as every producer writes it (:func:`fleetsim.sim.record.run_record`,
``schemas/result.schema.json``) with the sweep's own keys. The scenario's folder is made afresh for each
run, holding the data files its suite entry sent; the planner is made with the entry's
``planner_options`` and that folder as ``scenario_dir``. A planner that does not import on the worker, a
scenario that does not load, a planner that raises, refuses its options or hangs up: each fails its own
run with a message saying what happened, in the record's ``error``.
"""

from __future__ import annotations

import hashlib
import re
import tempfile
import traceback
from dataclasses import replace
from pathlib import Path
from typing import Any

from fleetsim.exec.spec import load_planner_factory
from fleetsim.recording.artifacts import artifact_folder, discard_run_folder, start_run_folder, write_run_artifacts
from fleetsim.sim.loop import run_scenario
from fleetsim.sim.record import RunOrigin, run_record
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
        with tempfile.TemporaryDirectory(prefix="fleetsim-scenario-") as scenario_dir:
            scenario = scenario_from_payload(item["scenario"], Path(scenario_dir))
            try:
                planner = factory(scenario.planner_setup)
            except PlannerSpecError as error:  # a constructor that raised, options it does not take
                return failed_row(item, f"the planner cannot be made: {error}")
            folder = _folder(item)
            about = {"scenario": item["id"], "planner": item["planner"]}
            trace_file = start_run_folder(folder, about) if folder else None
            result = run_scenario(
                scenario, planner, planner_name=item["planner"], planner_timeout=item["planner_timeout"],
                keep_trace=folder is not None, trace_file=trace_file,
            )  # fmt: skip
        artifacts: dict[str, str] = {}
        if folder is not None and (item["record"] == "all" or not result.passed):
            artifacts = write_run_artifacts(
                folder, result, _origin(item, None), scenario=scenario, streamed=True, more=write_view_file
            )
        elif folder is not None:
            discard_run_folder(folder, Path(item["artifacts"]))
        return result_row(item, replace(result, artifacts=artifacts))
    except Exception as error:  # a recording, a planner's own failure outside the run: this run only
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


def _origin(item: RunItem, error: str | None) -> RunOrigin:
    """The run's origin: its suite entry, and the sweep's own keys (``error``: why it did not run)."""
    keys = {"key": item["key"], "id": item["id"], "source": item["source"], "seed": item["seed"]}
    own = {**keys, "repetition": item["repetition"], "vehicles": item["vehicles"], "error": error}
    return RunOrigin(**item["origin"], own=own)


def result_row(item: RunItem, result: RunResult) -> dict[str, Any]:
    """The record of a run, as ``fleetsim run --json`` gives it (:func:`~fleetsim.sim.record.run_record`),
    with the sweep's own keys (key, id, source, seed, repetition, vehicles, error)."""
    return run_record(result, _origin(item, None))


def failed_row(item: RunItem, error: str, ended: Ending = "planner-error") -> dict[str, Any]:
    """The record of a run that never ran (or broke down on its worker): a result without a run, failed
    with ``error`` (a ``load-error`` or a ``planner-error``), which ``error`` repeats."""
    # A scenario that did not load is named by its id: SUITE::NAME, with ~dSEED and @REPETITION after it.
    name = item["scenario"]["name"] if item["scenario"] is not None else _NAME.sub("", item["id"].rpartition("::")[2])
    failure = Failure("load-error" if ended == "load-error" else "planner-error", 0.0, error)
    return run_record(RunResult.unrun(name, item["planner"], (failure,), ended=ended), _origin(item, error))

"""Running a scenario for a gate: judge it, then hold its trace hash against the recorded one.

In *check* mode a run's hash must equal the hash recorded for its planner and scenario; a different hash
is a failure that says from when on the behaviour changed and how to record the new one. A missing hash
is no verdict on the planner: the run's own checks decide, and the run is marked ``unrecorded`` (with the
command that records it) — unless a recorded hash is required (``require_recorded``, as under CI, where a
lock entry that was never committed is a mistake): then it is a ``hash-missing`` failure. In
*update* mode the scenario runs twice with fresh planners; equal hashes give a lock entry to record,
different ones are a ``nondeterministic`` failure naming the first diverging step, and nothing is
recorded. An interrupted run (a stop signal) is never gated nor recorded: its trace ends early, so its
hash says nothing about the planner's behaviour. Nor is a run paced by a wall clock (``RunResult.paced``:
a VDA 5050 master control in another process): its hash is not repeatable, so its checks and metrics
alone judge it.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Literal

from fleetsim.gating.lockfile import LockEntry, compare_run
from fleetsim.planning.protocol import Planner
from fleetsim.scenario import Scenario
from fleetsim.sim.divergence import first_divergence
from fleetsim.sim.interrupt import StopSignals
from fleetsim.sim.loop import run_scenario
from fleetsim.sim.result import Failure, RunResult

__all__ = ["CheckedRun", "HashMode", "in_ci", "run_checked"]

HashMode = Literal["check", "update", "ignore"]


@dataclass(frozen=True, slots=True)
class CheckedRun:
    """The judged run (hash failures included); in update mode, the entry to record; in check mode,
    ``unrecorded`` when no hash was recorded to check against."""

    result: RunResult
    record: LockEntry | None = None
    unrecorded: bool = False


def in_ci() -> bool:
    """CI services set ``CI``: there a missing hash fails its scenario, and hunts are derandomised."""
    return os.environ.get("CI", "").lower() not in ("", "0", "false", "no")


def run_checked(
    scenario: Scenario,
    make_planner: Callable[[], Planner],
    *,
    identity: str,
    mode: HashMode,
    recorded: LockEntry | None,
    record_hint: str,
    planner_timeout: float | None,
    keep_trace: bool = False,
    stop: StopSignals | None = None,
    trace_file: Path | None = None,
    require_recorded: bool = False,
    watch: Callable[[str], None] | None = None,
) -> CheckedRun:
    """Run ``scenario`` with a planner from ``make_planner`` and gate its hash as ``mode`` says.

    ``record_hint`` completes "record it with ..." in the messages for a missing or changed hash. A
    missing hash fails the run only with ``require_recorded`` (and only a run that passed its checks:
    otherwise its failures are the story). ``stop`` and ``trace_file`` are :func:`run_scenario`'s (the
    trace file is the first run's). ``watch``: the first run's trace watcher (a live view).
    """

    def run(trace: Path | None = None, watched: Callable[[str], None] | None = None) -> RunResult:
        keep = keep_trace or mode == "update"  # a second run is compared line by line
        return run_scenario(
            scenario,
            make_planner(),
            planner_name=identity,
            planner_timeout=planner_timeout,
            keep_trace=keep,
            stop=stop,
            trace_file=trace,
            watch=watched,
        )

    result = run(trace_file, watch)
    if mode == "ignore" or result.ended in ("planner-error", "interrupted"):
        return CheckedRun(result)  # a broken or cut-short run has no behaviour worth pinning
    if result.paced is not None:
        return CheckedRun(result)  # a wall clock paced it (a VDA 5050 master control): no hash repeats
    if mode == "update":
        again = run()
        if again.ended == "interrupted":
            return CheckedRun(
                replace(result, status="failed", failures=(*again.failures, *result.failures), ended="interrupted")
            )
        if again.trace_hash != result.trace_hash:
            return CheckedRun(_failed(result, _nondeterministic(result, again, scenario.settings.time_step)))
        return CheckedRun(result, LockEntry.from_run(result.trace_hash, result.steps, result.checkpoints))
    if recorded is None:
        if not require_recorded or not result.passed:  # a failed run's failures are the story
            return CheckedRun(result, unrecorded=True)
        msg = (
            f"no trace hash is recorded for planner {identity!r} in this scenario, and under CI a missing hash "
            "fails (a lock entry that was never committed is a CI mistake); record it where you develop with:\n"
            f"  {record_hint}\nand commit the lock file beside the suite"
        )
        failure = Failure("hash-missing", result.sim_time, msg, {"planner": identity})
        return CheckedRun(_failed(result, failure), unrecorded=True)
    mismatch = compare_run(recorded, result.trace_hash, result.steps, result.checkpoints, scenario.settings.time_step)
    if mismatch is None:
        return CheckedRun(result)
    details = {"recorded": mismatch.recorded, "actual": mismatch.actual, "since": mismatch.since_time}
    msg = f"{mismatch.message}\nif the change is intended, record the new hash with:\n  {record_hint}"
    return CheckedRun(_failed(result, Failure("hash-mismatch", mismatch.since_time or 0.0, msg, details)))


def _nondeterministic(first: RunResult, second: RunResult, time_step: float) -> Failure:
    assert first.trace is not None and second.trace is not None
    divergence = first_divergence(first.trace.lines, second.trace.lines, time_step)
    where = str(divergence) if divergence is not None else "the traces differ"
    msg = (
        f"the planner is not deterministic: two runs of this scenario gave different trace hashes "
        f"({first.trace_hash[:12]} and {second.trace_hash[:12]}); {where}. Nothing was recorded. Look for "
        "iteration over sets, unseeded random numbers or wall-clock time in the planner"
    )
    time = divergence.time if divergence is not None else 0.0
    return Failure("nondeterministic", time, msg, {"hashes": [first.trace_hash, second.trace_hash]})


def _failed(result: RunResult, failure: Failure) -> RunResult:
    return replace(result, status="failed", failures=(*result.failures, failure))

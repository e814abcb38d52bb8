"""Stop signals in process: a run ends at the end of its step as ``interrupted``; its trace streams to disk."""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import signal
from pathlib import Path
from typing import Any

import pytest

from fleetsim import load_scenario, load_suite
from fleetsim.gating.lockfile import HashLock, lock_path_for
from fleetsim.gating.verify import run_checked
from fleetsim.planners import ReservingPlanner
from fleetsim.recording.artifacts import RUN_FILE, discard_run_folder, start_run_folder, write_run_artifacts
from fleetsim.scenario import Expectations, Scenario
from fleetsim.sim.interrupt import RunAborted, StopSignals
from fleetsim.sim.loop import run_scenario
from fleetsim.sim.trace import TraceFile, complete_lines

SUITE = Path(__file__).resolve().parents[2] / "scenario_suites" / "examples.fleetsim.yaml"


def example(name: str) -> Scenario:
    suite = load_suite(SUITE)
    return load_scenario(next(spec for spec in suite.scenarios if spec.name == name), suite)


class SignalAt(ReservingPlanner):
    """Sends this process ``signum`` from inside its ``at``-th call (optionally ``twice``)."""

    def __init__(self, at: int, signum: int = signal.SIGINT, *, twice: bool = False) -> None:
        super().__init__()
        self.at, self.signum, self.twice, self.calls = at, signum, twice, 0

    def fix_legs(self, task: Any, fleet: Any, layout: Any) -> Any:
        self.calls += 1
        if self.calls == self.at:
            if self.twice:  # a planner that swallows the first interruption; the second aborts
                with contextlib.suppress(BaseException):
                    os.kill(os.getpid(), self.signum)
            os.kill(os.getpid(), self.signum)
        return super().fix_legs(task, fleet, layout)


def test_a_signal_in_a_planner_call_ends_the_run_at_the_end_of_that_step() -> None:
    scenario = example("crossing")
    with StopSignals() as stop:
        result = run_scenario(scenario, SignalAt(30, signal.SIGTERM), stop=stop)
    assert stop.signum == signal.SIGTERM and stop.exit_status == 143
    assert result.ended == "interrupted" and result.status == "failed"
    first = result.failures[0]
    assert first.kind == "interrupted" and first.time == pytest.approx(result.sim_time)
    assert first.details["signal"] == "SIGTERM" and first.message.startswith(
        "stopped by SIGTERM at the end of the step"
    )
    assert [f.kind for f in result.failures] == ["interrupted"], "what the run did not get to is not judged"
    assert result.trace is not None and json.loads(result.trace.lines[-1])[3][-1] == ["interrupted", "SIGTERM"]
    assert result.steps < 220  # the complete run takes 220
    assert signal.getsignal(signal.SIGTERM) is signal.SIG_DFL, "the handlers are put back"


def test_without_a_signal_the_hash_is_the_locked_one() -> None:
    scenario = example("crossing")
    with StopSignals() as stop:
        result = run_scenario(scenario, ReservingPlanner(), stop=stop)
    locked = HashLock.load(lock_path_for(SUITE)).get("fleetsim.planners:ReservingPlanner", "crossing")
    assert locked is not None and result.trace_hash == locked.hash and result.ended == "completed"


def test_a_second_signal_aborts_at_once() -> None:
    with StopSignals() as stop, pytest.raises(RunAborted) as aborted:
        run_scenario(example("crossing"), SignalAt(30, twice=True), stop=stop)
    assert aborted.value.signum == signal.SIGINT and isinstance(aborted.value, KeyboardInterrupt)


def test_an_ignored_signal_stays_ignored() -> None:
    previous = signal.signal(signal.SIGTERM, signal.SIG_IGN)
    try:
        with StopSignals():
            assert signal.getsignal(signal.SIGTERM) is signal.SIG_IGN
    finally:
        signal.signal(signal.SIGTERM, previous)


def test_an_interrupted_run_is_never_gated_nor_recorded() -> None:
    scenario = example("crossing")
    for mode in ("check", "update"):
        with StopSignals() as stop:
            checked = run_checked(
                scenario,
                lambda: SignalAt(30),
                identity="p:Q",
                mode=mode,
                recorded=None,
                record_hint="",
                planner_timeout=None,
                stop=stop,
            )  # type: ignore[arg-type]
        assert checked.record is None
        assert [f.kind for f in checked.result.failures] == ["interrupted"], mode


def test_the_streamed_trace_is_the_hashed_trace_and_a_killed_one_is_read_to_its_last_whole_line(tmp_path: Path) -> None:
    scenario = example("loop-one-way")
    folder = tmp_path / "run"
    trace = start_run_folder(folder, {"suite": str(SUITE), "scenario": "loop-one-way"})
    assert json.loads((folder / RUN_FILE).read_text())["scenario"] == "loop-one-way"
    result = run_scenario(scenario, ReservingPlanner(), trace_file=trace)
    data = trace.read_bytes()
    assert hashlib.sha256(data).hexdigest() == result.trace_hash
    assert result.trace is not None and data.decode().splitlines() == result.trace.lines
    write_run_artifacts(folder, result, scenario=scenario, streamed=True)
    assert trace.read_bytes() == data and not (folder / RUN_FILE).exists()
    cut = data.decode()[:-7]  # killed while writing the last line
    lines, clean = complete_lines(cut)
    assert not clean and lines == result.trace.lines[:-1]


def test_a_trace_file_is_written_at_every_checkpoint(tmp_path: Path) -> None:
    sink = TraceFile(tmp_path / "trace.jsonl")
    sink.FLUSH_SECONDS = 1e9  # only checkpoints and the first step flush
    sink.add("header")
    sink.flush()
    sink.add("step")
    assert (tmp_path / "trace.jsonl").read_text() == "header\n"
    sink.close()
    assert (tmp_path / "trace.jsonl").read_text() == "header\nstep\n"


def test_a_passing_runs_folder_is_removed_with_the_parents_it_leaves_empty(tmp_path: Path) -> None:
    root = tmp_path / "results"
    start_run_folder(root / "suite" / "a", {})
    start_run_folder(root / "suite" / "b", {})
    discard_run_folder(root / "suite" / "a", root)
    assert sorted(p.name for p in (root / "suite").iterdir()) == ["b"]
    discard_run_folder(root / "suite" / "b", root)
    assert not root.exists() and tmp_path.exists()


def test_expectations_of_what_did_not_happen_yet_are_not_judged_when_interrupted() -> None:
    from dataclasses import replace

    scenario = replace(example("crossing"), expect=Expectations(collisions="any", deadlock=True))
    with StopSignals() as stop:
        result = run_scenario(scenario, SignalAt(10), stop=stop)
    assert [f.kind for f in result.failures] == ["interrupted"]


def test_a_stop_signal_ends_a_hunt_without_shrinking_anything() -> None:
    from fleetsim.gating.generated import hunt

    suite = load_suite(SUITE.with_name("caught-bugs.fleetsim.yaml"))
    spec = next(spec for spec in suite.scenarios if spec.generate is not None)
    with StopSignals() as stop:
        found = hunt(
            spec, suite, lambda: SignalAt(3), identity="p:Q", planner_timeout=None, stop=stop, derandomize=True
        )
    assert found.counterexample is None and found.shrink_runs == 0 and found.generated >= 1
    assert found.result is not None and found.result.ended == "interrupted"

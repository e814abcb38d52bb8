"""A recorded run read back from its folder: ``fleetsim render --trace`` and ``fleetsim record --trace``.

A run folder holds ``trace.jsonl`` and, once the run has ended, ``result.json``; a run killed outright
(SIGKILL, out of memory) leaves its trace, written while it went, and ``run.json`` naming its suite and
scenario. Either way the folder says which scenario to replay the trace against (or ``--suite`` does).
A trace that ends early — an interrupted run's, or a killed run's, whose last line may be cut short —
is replayed as far as its last complete line, and the command says so and where it ends.
"""

from __future__ import annotations

import argparse
import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from fleetsim.cli.run import UsageError
from fleetsim.load.common.closest import did_you_mean
from fleetsim.load.common.text import json_problem, write_text_atomically
from fleetsim.load.suites.scenario import load_scenario
from fleetsim.load.suites.suite import load_suite
from fleetsim.recording.artifacts import (
    MCAP_FILE,
    RESULT_FILE,
    RUN_FILE,
    RVIZ_CONFIG,
    RVIZ_FILE,
    TRACE_FILE,
    stuck_overlay,
)
from fleetsim.recording.picture import (
    contact_moment,
    failure_caption,
    failure_step,
    picture_overlays,
    render_frame_svg,
)
from fleetsim.recording.recorder import partial_path, record_mcap
from fleetsim.recording.replay import Frame, TraceError, frame_at
from fleetsim.recording.rviz import rviz_config
from fleetsim.scenario import Scenario
from fleetsim.sim.result import Failure
from fleetsim.sim.trace import complete_lines

__all__ = ["RecordedRun", "read_recorded_run", "record", "render_step"]


@dataclass(frozen=True, slots=True)
class RecordedRun:
    """A run's trace (its complete lines), the scenario it is of, its result (if it ended) and notes on
    how complete the trace is."""

    trace_path: Path
    scenario: Scenario
    lines: list[str]
    document: dict[str, Any]  # result.json; empty for a run that never ended
    notes: list[str]
    unfinished: bool  # the folder holds run.json and no result.json: the run was killed before it ended

    @property
    def last_step(self) -> int:
        return len(self.lines) - 2  # a header line, then one line per step

    @property
    def failures(self) -> list[Failure]:
        return (
            _failures(self.document, self.trace_path.parent / RESULT_FILE)
            if self.document.get("status") == "failed"
            else []
        )


def read_recorded_run(path: Path, suite: str | None) -> RecordedRun:
    """The run in folder (or trace file) ``path``; ``suite``: ``SUITE::SCENARIO`` to replay it against
    instead of the one the folder names."""
    trace_path, result_path = _run_files(path)
    run_path = trace_path.parent / RUN_FILE
    document = _read_object(result_path) if result_path is not None else {}
    named = document or (_read_object(run_path) if run_path.is_file() else {})
    scenario = _recorded_scenario(suite, named, result_path or (run_path if run_path.is_file() else trace_path))
    lines, clean = complete_lines(_read_text(trace_path))
    if len(lines) < 2:
        raise UsageError(f"{trace_path}: the trace has no steps")
    dt = scenario.settings.time_step
    notes = []
    if not clean:
        notes.append(f"{trace_path}: the last line is cut short (the run was killed while writing it) and is left out")
    end = f"step {len(lines) - 2} (t = {(len(lines) - 1) * dt:.2f} s)"
    unfinished = not document and run_path.is_file()
    if unfinished:
        notes.append(
            f"{trace_path}: the trace ends early, at {end}: the run did not end (no {RESULT_FILE}; was it killed?)"
        )
    elif document.get("ended") == "interrupted":
        notes.append(f"{trace_path}: the trace ends early, at {end}: the run was interrupted")
    elif isinstance(document.get("steps"), int) and document["steps"] > len(lines) - 1:
        notes.append(f"{trace_path}: the trace ends early, at {end}; the run went on to step {document['steps'] - 1}")
    return RecordedRun(trace_path, scenario, lines, document, notes, unfinished)


# -- render --trace ------------------------------------------------------------------------------


def render_step(args: argparse.Namespace) -> int:
    """``fleetsim render --trace RUN -o OUT.svg [--step N] [--suite SUITE::SCENARIO]``."""
    run = read_recorded_run(Path(args.trace), args.suite)
    scenario, last_step = run.scenario, run.last_step
    failures = run.failures
    found = failure_step(failures, scenario.settings.time_step, last_step) if failures else None
    if args.step is None:
        step = found[0] if found is not None else last_step
    elif 0 <= args.step <= last_step:
        step = args.step
    else:
        raise UsageError(
            f"{run.trace_path}: --step={args.step!r} must be between 0 and {last_step} (the run's last step)"
        )
    frame = _frame(run, step)
    stuck = rejected = contact = None
    if found is not None and found[0] == step:
        caption = failure_caption(found[1], failures, at=frame.time)
        stuck, rejected = picture_overlays(found[1])
        contact = contact_moment(found[1], frame, _frame(run, step - 1) if step > 0 else None)
    else:
        caption = f"t = {frame.time:.2f} s \u2014 {scenario.name}, step {step} of {last_step}"
        if step == last_step and run.unfinished:
            caption += " (the trace ends here: the run did not end)"
    output = Path(args.output)
    write_text_atomically(
        output, render_frame_svg(scenario, frame, caption=caption, stuck=stuck, rejected=rejected, contact=contact)
    )
    _print_notes(run, partial_path(run.trace_path.parent / MCAP_FILE))
    print(f"wrote {output} ({scenario.name}, step {step} of {last_step}, t = {frame.time:.2f} s)")
    return 0


def _frame(run: RecordedRun, step: int) -> Frame:
    try:
        frame = frame_at(run.scenario, run.lines, step)
        _check_segments(run.scenario, frame)
    except TraceError as error:  # a trace of another scenario, or not a trace at all
        raise UsageError(f"{run.trace_path}: {error}") from None
    except KeyError as error:  # an id the scenario does not have: the trace is of another scenario
        msg = (
            f"{run.trace_path}: the trace names id {error.args[0]!r}, which scenario {run.scenario.name!r} does not have; "
            "name the run's scenario with --suite SUITE::SCENARIO"
        )
        raise UsageError(msg) from None
    return frame


def _check_segments(scenario: Scenario, frame: Frame) -> None:
    """Raise KeyError for the first segment of a pose or plan that the scenario's map lacks."""
    segments = scenario.layout.segments
    used = {pose.segment for pose in frame.poses.values()}
    used.update(leg.segment for plan in frame.plans.values() for leg in plan.legs)
    for sid in sorted(used):
        if sid not in segments:
            raise KeyError(sid)


# -- record --trace ------------------------------------------------------------------------------


def record(args: argparse.Namespace) -> int:
    """Rebuild a run's MCAP recording from its trace (a run killed outright, or one recorded without it).

    fleetsim record --trace RUN [-o OUT.mcap] [--suite SUITE::SCENARIO] [--record-every N]
      RUN is a run's artifact folder (trace.jsonl with result.json or run.json) or a trace.jsonl. The
      recording goes to OUT.mcap (default: run.mcap beside the trace), with fleetsim.rviz beside it. A
      trace that ends early is recorded up to its last complete line, and this says where it ends; a
      partial recording left by a writer that was stopped is replaced.
    """
    run = read_recorded_run(Path(args.trace), args.suite)
    output = Path(args.output) if args.output is not None else run.trace_path.parent / MCAP_FILE
    partial = partial_path(output)
    left_over = partial.exists()
    try:  # a trace that does not fit the scenario stops the writer, which then leaves nothing behind
        contacts = [f.details for f in run.failures if f.kind == "contact"]  # the contacts that failed the run
        written = record_mcap(
            output,
            run.scenario,
            run.lines,
            every=args.record_every,
            stuck=stuck_overlay(run.failures),
            contacts=contacts,
        )
    except TraceError as error:
        raise UsageError(f"{run.trace_path}: {error}; name the run's scenario with --suite SUITE::SCENARIO") from None
    rviz = output.with_name(RVIZ_FILE)
    if not rviz.exists():
        write_text_atomically(rviz, rviz_config(run.scenario, RVIZ_CONFIG.read_text(encoding="utf-8")))
    _print_notes(run, None)
    if left_over:
        print(
            f"note: {partial} (a recording cut short when its writer was stopped) was replaced by the complete {output.name}"
        )
    end = (run.last_step + 1) * run.scenario.settings.time_step
    print(
        f"wrote {output} ({run.scenario.name}, steps 0-{run.last_step} up to t = {end:.2f} s, {written.messages} messages) and {rviz}"
    )
    return 0


def _print_notes(run: RecordedRun, partial: Path | None) -> None:
    for note in run.notes:
        print(f"note: {note}")
    if partial is not None and partial.exists():
        print(
            f"note: {partial} is a recording cut short when its writer was stopped; `fleetsim record --trace {run.trace_path.parent}` rebuilds it"
        )


# -- reading the folder --------------------------------------------------------------------------


def _run_files(path: Path) -> tuple[Path, Path | None]:
    """The trace and, when there is one beside it, the result.json of a run folder or trace file."""
    if not path.exists():
        raise UsageError(f"{path}: no such file or directory")
    if path.is_dir():
        trace = path / TRACE_FILE
        if not trace.is_file():
            raise UsageError(f"{path}: no {TRACE_FILE} in this folder (the run did not keep its trace)")
    elif path.suffix == ".json":  # a run's result.json: its trace is beside it
        trace = path.parent / TRACE_FILE
        if not trace.is_file():
            raise UsageError(f"{path}: no {TRACE_FILE} beside it (the run did not keep its trace)")
    else:
        trace = path
    result = trace.parent / RESULT_FILE
    return trace, result if result.is_file() else None


def _read_text(path: Path) -> str:
    try:
        return path.read_text(encoding="utf-8")
    except UnicodeDecodeError as error:
        # A run killed while writing may cut a character in two at the very end; anything else is not a trace.
        raw = path.read_bytes()
        if error.start >= len(raw) - 4:
            return raw[: error.start].decode("utf-8")
        raise UsageError(f"{path}: not a text file (byte {error.start} is not UTF-8)") from None


def _read_object(path: Path) -> dict[str, Any]:
    try:
        document = json.loads(_read_text(path))
    except json.JSONDecodeError as error:
        raise UsageError(f"{path}:{error.lineno}:{error.colno}: {json_problem(error)}") from None
    if not isinstance(document, dict):
        raise UsageError(f"{path}: must hold a JSON object (a run's result), not {type(document).__name__}")
    return document


def _failures(document: dict[str, Any], path: Path | None) -> list[Failure]:
    try:
        return [
            Failure(
                str(f["kind"]),
                float(f["time"]),
                str(f["message"]),
                {k: v for k, v in f.items() if k not in ("kind", "time", "message")},
            )
            for f in document.get("failures", [])
        ]
    except (KeyError, TypeError, ValueError):
        msg = f"{path}: failures={document.get('failures')!r} must be a list of {{kind, time, message}} objects"
        raise UsageError(msg) from None


def _recorded_scenario(selector: str | None, document: dict[str, Any], source: Path) -> Scenario:
    """The scenario the run was of: ``--suite SUITE::SCENARIO`` if given, else what result.json (or
    run.json) names."""
    if selector is not None:
        suite_text, separator, name = selector.rpartition("::")
        if not (separator and suite_text and name):
            raise UsageError(f"--suite={selector!r} must be SUITE::SCENARIO, e.g. suites/demo.fleetsim.yaml::crossing")
        where = "--suite"
    else:
        recorded_suite, recorded_name = document.get("suite"), document.get("scenario")
        if not isinstance(recorded_suite, str) or not isinstance(recorded_name, str):
            raise UsageError(
                f"{source}: does not name the run's suite and scenario; name them with --suite SUITE::SCENARIO"
            )
        suite_text, name, where = recorded_suite, recorded_name, str(source)
    suite_path = Path(suite_text)
    if not suite_path.is_file():
        raise UsageError(f"{suite_path}: no such suite file (named by {where})")
    suite = load_suite(suite_path)
    spec = next((spec for spec in suite.scenarios if spec.name == name), None)
    if spec is None:
        names = [spec.name for spec in suite.scenarios]
        msg = f"{suite_path} has no scenario {name!r} (named by {where}; its scenarios: {', '.join(names)}){did_you_mean(name, names)}"
        raise UsageError(msg)
    return load_scenario(spec, suite)

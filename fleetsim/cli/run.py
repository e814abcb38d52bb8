"""``fleetsim run SUITE[::SCENARIO]... --planner SPEC``: simulate scenarios with a planner and judge them.

Every suite named on the command line is loaded and every ``::scenario`` selector checked before the
first run, so a typo costs no waiting. Then each scenario, in file order, is loaded (a load error fails
that scenario only), given a fresh planner and run. Progress goes to stderr; the summary table goes to
stdout, or to stderr with ``--json``, where stdout carries one result object (SPEC §10) per line.
Exit status: 0 when every scenario passed, 1 when any failed, 2 for a usage error.

SIGINT (Ctrl-C) or SIGTERM ends the scenario that is running at the end of its step (``interrupted``),
writes its artifacts like any failed run's, runs no further scenario, prints the summary of what ran and
exits with 128 + the signal's number (130, 143). A second signal aborts the clean-up at once.
"""

from __future__ import annotations

import argparse
import json
import shutil
import sys
from collections.abc import Callable, Iterable
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any, TextIO

from fleetsim.errors import FleetsimError, LoadError
from fleetsim.exec.spec import load_planner_factory
from fleetsim.gating.generated import (
    DEFAULT_ARTIFACTS,
    Hunt,
    counterexample_entry,
    counterexample_story,
    hunt,
    hunt_facts,
    hunt_label,
    record_counterexample,
)
from fleetsim.load.common.closest import did_you_mean
from fleetsim.load.suites.scenario import load_scenario
from fleetsim.load.suites.suite import SUITE_SUFFIX, ScenarioSpec, Suite, discover_suites, load_suite
from fleetsim.recording.artifacts import artifact_folder, start_run_folder, write_run_artifacts
from fleetsim.sim.interrupt import StopSignals, signal_name
from fleetsim.sim.loop import RunProgress, run_scenario
from fleetsim.sim.record import RunOrigin, run_record
from fleetsim.sim.report import (
    LORR_COLUMNS,
    ORDER_COLUMNS,
    failure_lines,
    format_table,
    lorr_cells,
    order_cells,
    outcome_cell,
    outcome_notes,
    summary_cells,
)
from fleetsim.sim.result import Failure, RunResult
from fleetsim.specs.python import PlannerFactory, PlannerSpecError

if TYPE_CHECKING:
    from fleetsim.view.session import LiveSession

__all__ = ["UsageError", "run"]

FAILURES_SHOWN = 3  # per failed scenario, below the table; --json has them all


class UsageError(FleetsimError, ValueError):
    """A mistake on the command line itself (exit status 2): a missing path, an unknown scenario name."""


@dataclass(frozen=True, slots=True)
class _Target:
    """One scenario to run, or a suite file that could not be loaded."""

    label: str  # shown in the table and progress
    suite_path: Path
    suite: Suite | None = None
    spec: ScenarioSpec | None = None
    error: LoadError | None = None  # the suite failed to load


@dataclass(frozen=True, slots=True)
class _Outcome:
    target: _Target
    result: RunResult
    loaded: bool
    hunt: Hunt | None = None  # a generated entry's hunt

    @property
    def label(self) -> str:
        """The target's label; a generated entry's says what its hunt ran."""
        return self.target.label if self.hunt is None else hunt_label(self.target.label, self.hunt)

    @property
    def xfail(self) -> str | None:
        return self.target.spec.xfail if self.target.spec is not None else None

    @property
    def origin(self) -> RunOrigin:
        """Where the run comes from, for its record: the suite entry, and a hunt's counts."""
        own = hunt_facts(self.hunt) if self.hunt is not None else {}
        return RunOrigin.of_entry(self.target.suite_path, self.target.spec, **own)

    @property
    def word(self) -> str:
        """passed, failed, interrupted, load error (a scenario whose files did not load: it never ran), or
        pytest's xfailed/xpassed for scenarios marked ``xfail`` that loaded and ran to their end."""
        if self.result.ended == "interrupted":
            return "interrupted"
        if self.result.ended == "load-error":
            return "load error"
        if self.xfail is not None and self.loaded:
            return "xpassed" if self.result.passed else "xfailed"
        return self.result.status

    @property
    def note(self) -> str:
        """What the word alone would hide (``expected collisions happened``), or ``""``."""
        if not self.loaded or self.target.spec is None:
            return ""
        return outcome_notes(self.target.spec.expect, self.result).get(self.word, "")

    @property
    def counts_as_failure(self) -> bool:
        return self.word in ("failed", "interrupted", "load error")


def run(args: argparse.Namespace) -> int:
    """Run every scenario of the given suites with a fresh planner each and print a summary table.

    SUITE is a *.fleetsim.yaml file or a folder holding them, or a League of Robot Runners problem file
    (.json: one scenario named after it, 5000 timesteps); SUITE::NAME selects one scenario of a file.
    Exit status 0 when every scenario passed (an xfail scenario may fail), 1 when any failed;
    after Ctrl-C or SIGTERM (the running scenario ends at the end of its step and is written like any
    failed run; no further scenario runs) 130 or 143.
    """
    live_only = [name for name, given in (("--speed", args.speed != 1.0), ("--port", args.port != 0),
                 ("--no-open", args.no_open), ("--foxglove", args.foxglove is not None)) if given]  # fmt: skip
    if live_only and not args.live:
        raise UsageError(f"{', '.join(live_only)}: only with --live (a run watched in the browser)")
    with StopSignals() as stop:
        if not args.live:
            return _run_all(args, stop)
        from fleetsim.view.session import LiveSession

        with LiveSession(
            args.speed, port=args.port, open_browser=not args.no_open, foxglove_port=args.foxglove, say=_say
        ) as live:
            return _run_all(args, stop, live)


def _dispatcher_option(spec: str | None) -> str | None:
    """``--dispatcher``, checked before any run: a spec that gives no dispatcher is a usage error."""
    if spec is not None:
        from fleetsim.specs.dispatcher import DispatcherSpecError, import_dispatcher_factory

        try:
            import_dispatcher_factory(spec)
        except DispatcherSpecError as error:
            raise UsageError(str(error)) from None
    return spec


def _say(text: str) -> None:
    """A line for the user at once, on stderr (stdout may carry --json)."""
    print(text, file=sys.stderr, flush=True)


def _run_all(args: argparse.Namespace, stop: StopSignals, live: LiveSession | None = None) -> int:
    timeout = args.planner_timeout or None  # 0 switches the timeout off
    factory = load_planner_factory(args.planner, call_timeout=timeout)
    dispatcher = _dispatcher_option(args.dispatcher)
    targets = _targets(args.suites)
    record = (Path(args.record), args.record_every) if args.record else None
    counterexamples = record or (DEFAULT_ARTIFACTS, args.record_every)  # always saved
    table = sys.stderr if args.json else sys.stdout
    progress = _Progress(sys.stderr, len(targets))
    outcomes = []
    for index, target in enumerate(targets, 1):
        if stop.requested:
            break
        with progress.scenario(index, target.label):
            outcome = _run_target(
                target, factory, timeout, progress.update, record, counterexamples, stop, live, dispatcher
            )
        progress.done(outcome)
        outcomes.append(outcome)
        if args.json:
            print(json.dumps(_document(outcome)), flush=True)
    _print_summary(outcomes, table)
    if record is not None and outcomes:
        print("", *artifact_lines(o.result for o in outcomes), sep="\n", file=table)
    if stop.signum is not None:
        left = len(targets) - len(outcomes)
        not_run = f"; {left} scenario(s) not run" if left else ""
        print(f"\ninterrupted by {signal_name(stop.signum)}{not_run}", file=table, flush=True)
        return stop.exit_status
    return 1 if any(o.counts_as_failure for o in outcomes) else 0


# -- what to run ----------------------------------------------------------------------------------


def _targets(arguments: Iterable[str]) -> list[_Target]:
    targets: list[_Target] = []
    seen: set[tuple[Path, str]] = set()
    pending: list[tuple[Path, str | None]] = []
    for argument in arguments:
        path_text, selector, name = argument.rpartition("::") if "::" in argument else (argument, "", "")
        path = Path(path_text)
        if not path.exists():
            raise UsageError(f"{path_text}: no such file or directory")
        if selector and path.is_dir():
            msg = f"{argument!r}: ::{name} selects a scenario of a suite file, but {path_text} is a folder"
            raise UsageError(msg)
        if selector and not name:
            raise UsageError(f"{argument!r}: name a scenario after '::', or leave '::' out to run them all")
        files = discover_suites([path])
        if not files:
            raise UsageError(f"{path_text}: no *{SUITE_SUFFIX} files in this folder")
        pending += [(file, name or None) for file in files]
    many = len({file.resolve() for file, _ in pending}) > 1
    for file, selected in pending:
        for target in _suite_targets(file, selected, many):
            key = (file.resolve(), target.spec.name if target.spec is not None else "")
            if key not in seen:
                seen.add(key)
                targets.append(target)
    return targets


def _suite_targets(file: Path, name: str | None, many: bool) -> list[_Target]:
    try:
        suite = load_suite(file)
    except LoadError as error:
        return [_Target(f"{file}::{name}" if name else str(file), file, error=error)]
    specs = suite.scenarios
    if name is not None:
        specs = tuple(spec for spec in specs if spec.name == name)
        if not specs:
            names = [spec.name for spec in suite.scenarios]
            msg = f"{file} has no scenario {name!r} (its scenarios: {', '.join(names)}){did_you_mean(name, names)}"
            raise UsageError(msg)
    return [_Target(f"{file.name}::{spec.name}" if many else spec.name, file, suite, spec) for spec in specs]


# -- running --------------------------------------------------------------------------------------


def _run_target(
    target: _Target,
    factory: PlannerFactory,
    timeout: float | None,
    on_progress: Callable[[RunProgress], None],
    record: tuple[Path, int] | None = None,
    counterexamples: tuple[Path, int] = (DEFAULT_ARTIFACTS, 1),
    stop: StopSignals | None = None,
    live: LiveSession | None = None,
    dispatcher: str | None = None,
) -> _Outcome:
    if target.error is not None:
        return _Outcome(target, _load_failure(target.label, factory.spec, target.error), loaded=False)
    assert target.suite is not None and target.spec is not None
    try:
        if target.suite.planner is not None:  # the suite documents this planner, whatever was asked
            factory = load_planner_factory(target.suite.planner, call_timeout=timeout)
        if target.spec.hunts:
            return _hunt_target(target, factory, timeout, counterexamples, stop)
        scenario = load_scenario(target.spec, target.suite)
        if dispatcher is not None:  # the command line's dispatcher, whatever the suite names
            scenario = replace(scenario, dispatcher=dispatcher)
    except (LoadError, PlannerSpecError) as error:
        return _Outcome(target, _load_failure(target.spec.name, factory.spec, error), loaded=False)
    try:
        planner = factory(scenario.planner_setup)
    except PlannerSpecError as error:  # a constructor that raised, planner_options it does not take
        failure = Failure("planner-error", 0.0, str(error))
        unmade = RunResult.unrun(target.spec.name, factory.spec, (failure,), ended="planner-error")
        return _Outcome(target, unmade, loaded=False)
    extra = {"suite": str(target.suite_path), "line": target.spec.line}
    folder = artifact_folder(record[0], target.suite_path, target.spec.name) if record is not None else None
    # The trace goes into the artifact folder while the run goes: a run killed outright leaves it.
    trace_file = (
        start_run_folder(folder, {**extra, "scenario": target.spec.name, "planner": factory.spec}) if folder else None
    )
    about = {"planner": factory.spec, "suite": str(target.suite_path)}
    watch = live.begin(scenario, about, lambda: stop is not None and stop.requested) if live else None
    result = run_scenario(
        scenario, planner, planner_name=factory.spec, planner_timeout=timeout, on_progress=on_progress,
        keep_trace=record is not None, stop=stop, trace_file=trace_file, watch=watch,
    )  # fmt: skip
    if live is not None:
        _say(live.end(scenario, result))
    if record is not None and folder is not None:
        from fleetsim.view import write_view_file

        origin = RunOrigin.of_entry(target.suite_path, target.spec)
        paths = write_run_artifacts(
            folder, result, origin, scenario=scenario, record_every=record[1], streamed=True, more=write_view_file
        )
        result = replace(result, artifacts={**result.artifacts, **paths})
    return _Outcome(target, result, loaded=True)


def _hunt_target(
    target: _Target,
    factory: PlannerFactory,
    timeout: float | None,
    counterexamples: tuple[Path, int],
    stop: StopSignals | None,
) -> _Outcome:
    """A generated entry: hunt for a failing scenario; a shrunk counterexample is always saved (under
    ``--record``'s folder, else the default artifact folder) and its suite entry printed."""
    assert target.suite is not None and target.spec is not None and target.spec.hunts
    root, every = counterexamples
    folder = artifact_folder(root, target.suite_path, target.spec.name)
    about = {
        "suite": str(target.suite_path),
        "line": target.spec.line,
        "scenario": target.spec.name,
        "planner": factory.spec,
    }
    found = hunt(
        target.spec,
        target.suite,
        factory.for_setup(target.spec.planner_setup),
        identity=factory.spec,
        planner_timeout=timeout,
        stop=stop,
        record_to=(folder, about),
    )
    if found.result is None:  # examples: 0
        unrun = RunResult.unrun(target.spec.name, factory.spec, status="passed", ended="no-counterexample")
        return _Outcome(target, unrun, loaded=True, hunt=found)
    result = found.result
    if found.counterexample is not None:
        origin = RunOrigin.of_entry(target.suite_path, target.spec, **hunt_facts(found))
        paths = record_counterexample(found, folder, origin, record_every=every, streamed=True)
        result = replace(result, artifacts={**result.artifacts, **paths})
        entry = counterexample_entry(
            target.spec, Path(paths["scenario"]), target.suite_path, found.counterexample.disturbances
        )
        story = counterexample_story(found, target.spec.hunt_examples, paths["scenario"], str(target.suite_path), entry)
        print(f"{target.label}: {story}", file=sys.stderr)
    return _Outcome(target, result, loaded=True, hunt=found)


def _load_failure(name: str, planner: str, error: LoadError | PlannerSpecError) -> RunResult:
    """A result for a scenario that never ran, shaped like any other (its JSON has the same keys)."""
    location = getattr(error, "location", None)
    details = {"location": str(location)} if location is not None else {}
    return RunResult.unrun(name, planner, (Failure("load-error", 0.0, str(error), details),))


def _document(outcome: _Outcome) -> dict[str, Any]:
    return run_record(outcome.result, outcome.origin)


def artifact_lines(results: Iterable[RunResult]) -> list[str]:
    """The run folders written, in run order, each with the files it holds; a scenario that left none
    (it did not load, or its hunt found nothing) is not listed. A saved counterexample's scenario is a
    folder too (``counterexample/``)."""
    lines = []
    for result in results:
        folder = result.artifacts.get("folder")
        if folder is None:
            continue
        paths = (Path(path) for kind, path in result.artifacts.items() if kind != "folder")
        files = sorted(path.name + ("/" if path.is_dir() else "") for path in paths)
        lines.append(f"{Path(folder).as_posix()}/ ({', '.join(files)})")
    if not lines:
        return ["artifacts: none written (no scenario ran)"]
    return [("artifacts: " if index == 0 else " " * len("artifacts: ")) + line for index, line in enumerate(lines)]


class _Progress:
    """A live line on a terminal (overwritten, then cleared); one line per result anywhere else."""

    def __init__(self, stream: TextIO, total: int) -> None:
        self.stream = stream
        self.total = total
        self.live = _isatty(stream)
        self._prefix = ""
        self._width = 0

    def scenario(self, index: int, label: str) -> _Progress:
        self._prefix = f"[{index}/{self.total}] {label}"
        return self

    def __enter__(self) -> None:
        self._show(self._prefix)

    def __exit__(self, *exc: object) -> None:
        if self.live and self._width:
            self.stream.write("\r" + " " * self._width + "\r")
            self.stream.flush()
            self._width = 0

    def update(self, progress: RunProgress) -> None:
        self._show(f"{self._prefix}  t={progress.time:.1f} s  tasks {progress.completed}/{progress.total}")

    def _show(self, text: str) -> None:
        if self.live:
            text = text[: shutil.get_terminal_size().columns - 1]  # a wrapped line cannot be overwritten
            self.stream.write("\r" + text.ljust(self._width))
            self.stream.flush()
            self._width = max(self._width, len(text))

    def done(self, outcome: _Outcome) -> None:
        if self.live:
            return
        if outcome.word == "load error":  # its errors follow the table
            print(f"{self._prefix}: load error", file=self.stream, flush=True)
            return
        r = outcome.result
        facts = f"tasks {r.tasks_completed}/{r.tasks_total}, t={r.sim_time:.1f} s" if outcome.loaded else "not loaded"
        if outcome.note:
            facts = f"{outcome.note}; {facts}"
        if outcome.word == "interrupted":
            facts += f", stopped by {r.failures[0].details.get('signal', 'a signal')}" if r.failures else ""
        print(f"{self._prefix}: {outcome.word} ({facts})", file=self.stream, flush=True)


def _isatty(stream: TextIO) -> bool:
    try:
        return stream.isatty()
    except (AttributeError, ValueError):
        return False


# -- the summary ----------------------------------------------------------------------------------


def _gate(outcome: _Outcome) -> str:
    """The suite entry's ``gate`` (``fleetsim run`` compares no hash: it says what pytest would gate on)."""
    return outcome.target.spec.gate if outcome.target.spec is not None else "-"


def _print_summary(outcomes: list[_Outcome], stream: TextIO) -> None:
    if not outcomes:
        print("no scenario ran", file=stream)
        return
    rows = [summary_cells(o.label, outcome_cell(o.word, o.note), o.result if o.loaded else None) for o in outcomes]
    for line in format_table(rows):
        print(line, file=stream)
    shifts = [cells for o in outcomes if o.loaded and (cells := order_cells(o.label, o.result, _gate(o))) is not None]
    if shifts:
        print("\norders:", *format_table(shifts, ORDER_COLUMNS), sep="\n", file=stream)
    league = [cells for o in outcomes if o.loaded and (cells := lorr_cells(o.label, o.result)) is not None]
    if league:
        print(
            "\nLeague of Robot Runners counts (timesteps):", *format_table(league, LORR_COLUMNS), sep="\n", file=stream
        )
    words = [o.word for o in outcomes]
    counts = ", ".join(
        f"{words.count(w)} {w}"
        for w in ("passed", "failed", "interrupted", "xfailed", "xpassed", "load error")
        if w in words
    )
    planners = ", ".join(dict.fromkeys(o.result.planner for o in outcomes))  # first-seen order
    print(f"\n{len(outcomes)} scenario(s) with {planners}: {counts}", file=stream)
    for outcome in outcomes:
        if outcome.counts_as_failure:
            print(f"\n{outcome.word.upper()} {outcome.target.label}", file=stream)
            for line in failure_lines(outcome.result, FAILURES_SHOWN, "--json lists them all"):
                print("  " + line, file=stream)

"""The plugin's state for one pytest session: options, the planner, lock files, results, gating.

Workers and a serial session run scenarios (:meth:`FleetsimState.run_item`). Only the controlling
process (the serial session, or pytest-xdist's controller) receives every report, and only it writes lock
files and the metrics document and decides on regressions, so nothing is written twice and nothing
depends on how tests were spread over workers.

While a scenario runs, SIGINT and SIGTERM stop it cleanly (:mod:`fleetsim.sim.interrupt`): it ends at the
end of its step, fails as ``interrupted`` with its artifacts written, and the session then stops as
pytest does on Ctrl-C (``stopped_by`` tells the plugin's hook to end it).
"""

from __future__ import annotations

import os
import shlex
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Literal

import pytest

from fleetsim.errors import FleetsimError, LoadError
from fleetsim.gating.baseline import (
    Comparison,
    ScenarioMetrics,
    Threshold,
    compare,
    parse_threshold,
    read_metrics,
    write_metrics,
)
from fleetsim.gating.lockfile import HashLock, LockEntry, LockFileError, lock_path_for
from fleetsim.gating.regression import judge_against
from fleetsim.gating.verify import in_ci, run_checked
from fleetsim.load.suites.scenario import load_scenario
from fleetsim.load.suites.suite import load_suite
from fleetsim.recording.artifacts import artifact_folder, discard_run_folder, start_run_folder, write_run_artifacts
from fleetsim.scenario import Scenario
from fleetsim.sim.interrupt import StopSignals
from fleetsim.sim.record import RunOrigin
from fleetsim.sim.report import (
    LORR_COLUMNS,
    ORDER_COLUMNS,
    SUMMARY_COLUMNS,
    failure_report,
    format_table,
    lorr_cells,
    order_cells,
    outcome_cell,
    outcome_notes,
    summary_cells,
)
from fleetsim.sim.result import RunResult
from fleetsim.specs.python import PlannerFactory, PlannerSpecError
from pytest_fleetsim._items import ScenarioFailed, ScenarioItem, ScenarioNotLoaded
from pytest_fleetsim._planner import load_factory, planner_source

__all__ = ["NO_PLANNER", "FleetsimState"]

NO_PLANNER = (
    "no planner to test: run pytest with --planner module:Planner (a class or zero-argument factory), set "
    "fleetsim_planner in the [pytest] ini section, or override the fleetsim_planner fixture in conftest.py"
)
OUTCOME_WORDS = ("passed", "failed", "interrupted", "xfailed", "xpassed", "load error")
NOT_RECORDED = "not recorded"  # the hash cell of a run whose hash no lock file holds yet
_PACING_SHOWN = 10  # paced scenarios whose pace and order latency the summary shows
NOT_GATED = "not gated"  # the hash cell of a run a wall clock paced (a VDA 5050 master control)
MEASURES_GATED = "measures"  # the hash cell of a run gated on its measures alone (gate: measures)
RecordMode = Literal["failed", "all", "none"]


@dataclass
class _Outcome:
    """What the controller learned about one scenario test from its report."""

    nodeid: str
    suite: str
    index: int
    outcome: str
    payload: dict[str, Any]


@dataclass(eq=False)
class FleetsimState:
    config: pytest.Config
    planner: PlannerFactory | None
    update_hashes: bool
    artifacts: Path
    record: RecordMode
    record_every: int
    timeout: float | None
    metrics_json: Path | None
    baseline: dict[str, ScenarioMetrics] | None
    baseline_path: Path | None
    thresholds: tuple[Threshold, ...]
    require_hashes: bool = False  # under CI a missing hash fails its scenario
    _locks: dict[Path, HashLock] = field(default_factory=dict)
    outcomes: dict[str, _Outcome] = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)
    comparison: Comparison | None = None
    stopped_by: int | None = None  # the stop signal that ended a scenario; the session ends after its report
    live: tuple[float | None, int, bool] | None = None  # --fleetsim-live: (speed, port, open a browser)
    dispatcher: str | None = None  # --dispatcher: for every scenario with orders, whatever its suite names
    _live_session: Any = None  # the page server, made for the first run

    # -- set-up -------------------------------------------------------------------------------------

    @classmethod
    def configure(cls, config: pytest.Config) -> FleetsimState:
        """Read and check every option; a mistake is a :class:`pytest.UsageError` before any test runs."""
        option = config.option
        spec = option.fleetsim_planner or config.getini("fleetsim_planner") or None
        timeout = float(option.fleetsim_planner_timeout or config.getini("fleetsim_planner_timeout") or 0)
        try:
            planner = load_factory(spec, call_timeout=timeout if timeout > 0 else None) if spec else None
        except PlannerSpecError as error:
            details = f"\n{error.details.rstrip()}" if error.details else ""
            raise pytest.UsageError(f"--planner: {error}{details}") from None
        dispatcher = option.fleetsim_dispatcher or config.getini("fleetsim_dispatcher") or None
        if dispatcher is not None:
            from fleetsim.specs.dispatcher import DispatcherSpecError, import_dispatcher_factory

            try:
                import_dispatcher_factory(dispatcher)
            except DispatcherSpecError as error:
                raise pytest.UsageError(f"--dispatcher: {error}") from None
        thresholds = []
        for text in option.fleetsim_compare_fail or ():
            try:
                thresholds.append(parse_threshold(text))
            except FleetsimError as error:
                raise pytest.UsageError(str(error)) from None
        baseline_path = _path(config, option.fleetsim_compare)
        if thresholds and baseline_path is None:
            raise pytest.UsageError(
                "--fleetsim-compare-fail needs --fleetsim-compare PATH (the baseline metrics to compare with)"
            )
        baseline = None
        if baseline_path is not None:  # every process: a regression fails its scenario's item where it ran
            try:
                baseline = read_metrics(baseline_path, planner=spec)
            except FleetsimError as error:
                raise pytest.UsageError(f"--fleetsim-compare: {error}") from None
        if option.fleetsim_record_every < 1:
            raise pytest.UsageError(
                f"--fleetsim-record-every={option.fleetsim_record_every} must be a whole number of steps >= 1"
            )
        live = None
        if option.fleetsim_live:
            from fleetsim.view.live import parse_speed

            if getattr(option, "numprocesses", None) or hasattr(config, "workerinput"):
                raise pytest.UsageError(
                    "--fleetsim-live shows one run at a time, in this process: run without -n (pytest-xdist)"
                )
            try:
                live = (parse_speed(option.fleetsim_speed), option.fleetsim_live_port, not option.fleetsim_no_open)
            except ValueError as error:
                raise pytest.UsageError(f"--fleetsim-{error}") from None
        return cls(
            dispatcher=dispatcher,
            live=live,
            config=config,
            planner=planner,
            update_hashes=bool(option.fleetsim_update_hashes),
            artifacts=_path(config, option.fleetsim_artifacts) or Path("fleetsim-results"),
            record=option.fleetsim_record,
            record_every=option.fleetsim_record_every,
            timeout=timeout if timeout > 0 else None,
            metrics_json=_path(config, option.fleetsim_metrics_json),
            baseline=baseline,
            baseline_path=baseline_path,
            thresholds=tuple(thresholds),
            require_hashes=in_ci(),
        )

    @property
    def is_controller(self) -> bool:
        return not hasattr(self.config, "workerinput")

    # -- one scenario -------------------------------------------------------------------------------

    def run_item(self, item: pytest.Function, fixture_value: object) -> None:
        """Run the item's scenario; raise :class:`ScenarioFailed` with the whole story if it failed.

        A stop signal while it runs ends it early (``interrupted``) and sets :attr:`stopped_by`."""
        assert isinstance(item, ScenarioItem)
        with StopSignals() as stop:
            try:
                self._run_item(item, fixture_value, stop)
            finally:
                self.stopped_by = stop.signum

    def _run_item(self, item: ScenarioItem, fixture_value: object, stop: StopSignals) -> None:
        heading = f"fleetsim scenario {item.spec.name!r} ({_relative(self.config, item.path)}:{item.spec.line})"
        try:
            if item.suite.planner is not None:  # the suite documents this planner, whatever was asked
                fixture_value = load_factory(item.suite.planner, call_timeout=self.timeout)
            elif fixture_value is None:
                # Located at the scenario, not here, so -rs points at the suite file.
                raise pytest.skip.Exception(NO_PLANNER, _use_item_location=True)
            source = planner_source(fixture_value)
            make = source.for_setup(item.spec.planner_setup)
        except PlannerSpecError as error:
            raise ScenarioFailed(_story(str(error), heading)) from None
        heading += f" with planner {source.identity}"
        if item.spec.hunts:
            self._hunt(item, make, source.identity, heading, stop)
            return
        try:
            scenario = load_scenario(item.spec, item.suite)
            if self.dispatcher is not None and (scenario.orders or scenario.order_stream is not None):
                scenario = replace(scenario, dispatcher=self.dispatcher)
            lock = self._lock(item.suite.path)
        except (LoadError, LockFileError) as error:
            self._describe_unrun(item, source.identity, load_error=isinstance(error, LoadError))
            failure = ScenarioNotLoaded if isinstance(error, LoadError) else ScenarioFailed
            raise failure(_story(str(error), heading)) from None
        # Relative to where pytest was run, like pytest's own FAILED lines, so it can be pasted there.
        here = os.path.relpath(item.path, self.config.invocation_params.dir)
        planner_option = source.from_option and item.suite.planner is None
        hint = _record_command([f"{here}::{item.name}"], source.identity if planner_option else None)
        # Any run may fail, so a kept trace goes into the artifact folder while the run goes (a run killed
        # outright leaves it); the folder is removed again when the run passes and only failures are kept.
        folder = artifact_folder(self.artifacts, item.path, item.spec.name)
        about = {"suite": str(item.path), "nodeid": item.nodeid, "line": item.spec.line, "scenario": item.spec.name}
        trace_file = start_run_folder(folder, {**about, "planner": source.identity}) if self.record != "none" else None
        try:
            checked = run_checked(
                scenario,
                make,
                identity=source.identity,
                mode="ignore" if item.spec.gate == "measures" else "update" if self.update_hashes else "check",
                recorded=lock.get(source.identity, item.spec.name),
                record_hint=hint,
                planner_timeout=self.timeout,
                keep_trace=self.record != "none",
                stop=stop,
                trace_file=trace_file,
                require_recorded=self.require_hashes,
                watch=self._watch(scenario, source.identity, item, stop),
            )
        except PlannerSpecError as error:  # the planner could not even be made
            if trace_file is not None:
                discard_run_folder(folder, self.artifacts)
            self._describe_unrun(item, source.identity, load_error=False)
            raise ScenarioFailed(_story(f"planner-error: {error}", heading, error.details)) from None
        result = checked.result
        if self.baseline is not None:  # a metric regression fails this scenario's own item, not only the session
            result = judge_against(self.baseline, item.nodeid, result, self.thresholds)
        if self._live_session is not None:
            self._tell(self._live_session.end(scenario, result))
        if self.record == "all" or (self.record == "failed" and not result.passed):
            result = self._write_artifacts(item, scenario, result, streamed=trace_file is not None)
        elif trace_file is not None:
            discard_run_folder(folder, self.artifacts)
        unrecorded = (here, source.identity if planner_option else None) if checked.unrecorded else None
        self._describe(item, result, checked.record, source.identity, unrecorded=unrecorded)
        if not result.passed:
            raise ScenarioFailed(failure_report(result, heading=heading))

    def _watch(self, scenario: Scenario, identity: str, item: ScenarioItem, stop: StopSignals) -> Any:
        """With --fleetsim-live: the trace watcher that paces this run and shows it (the page is served from
        the first run on); else None."""
        if self.live is None:
            return None
        if self._live_session is None:
            from fleetsim.view.session import LiveSession

            speed, port, open_browser = self.live
            self._live_session = LiveSession(speed, port=port, open_browser=open_browser, say=self._tell)
        about = {"planner": identity, "suite": _relative(self.config, item.path)}
        return self._live_session.begin(scenario, about, lambda: stop.requested)

    def _tell(self, text: str) -> None:
        """A line for the user at once, past pytest's capture (the live page's address)."""
        reporter = self.config.pluginmanager.get_plugin("terminalreporter")
        if reporter is not None:
            reporter.write_line(text)

    def close_live(self) -> None:
        if self._live_session is not None:
            self._live_session.close()
            self._live_session = None

    def _hunt(self, item: ScenarioItem, make: Any, identity: str, heading: str, stop: StopSignals) -> None:
        """A generated entry: Hypothesis hunts for a failing scenario; a shrunk one is saved and reported."""
        # Hypothesis (and the strategies built on it) only for a session that collected a generated entry.
        from fleetsim.gating.generated import (
            counterexample_entry,
            counterexample_story,
            counts_story,
            hunt,
            hunt_facts,
            hunt_label,
            record_counterexample,
        )

        assert item.spec.hunts
        folder = artifact_folder(self.artifacts, item.path, item.spec.name)
        about = {
            "suite": str(item.path),
            "nodeid": item.nodeid,
            "line": item.spec.line,
            "scenario": item.spec.name,
            "planner": identity,
        }
        try:
            found = hunt(
                item.spec,
                item.suite,
                make,
                identity=identity,
                planner_timeout=self.timeout,
                stop=stop,
                record_to=(folder, about),
            )
        except LoadError as error:  # a generate block no layout has room for
            raise ScenarioFailed(_story(str(error), heading)) from None
        except PlannerSpecError as error:
            raise ScenarioFailed(_story(f"planner-error: {error}", heading, error.details)) from None
        item.user_properties += [(f"fleetsim_{key}", str(value)) for key, value in hunt_facts(found).items()]
        label = hunt_label(item.spec.name, found)
        if found.counterexample is None or found.result is None:
            if found.result is not None:
                self._describe(item, found.result, None, identity, label=label, generated=True)
                if found.result.ended == "interrupted":
                    raise ScenarioFailed(
                        failure_report(found.result, heading=heading)
                        + "\n\n"
                        + counts_story(found, item.spec.hunt_examples)
                    )
            return
        origin = RunOrigin.of_entry(item.path, item.spec, nodeid=item.nodeid, **hunt_facts(found))
        paths = record_counterexample(found, folder, origin, record_every=self.record_every, streamed=True)
        shown = {kind: _relative(self.config, Path(path)) for kind, path in paths.items()}
        result = replace(found.result, artifacts={**found.result.artifacts, **shown})
        self._describe(item, result, None, identity, label=label, generated=True)
        entry = counterexample_entry(item.spec, Path(paths["scenario"]), item.path, found.counterexample.disturbances)
        where = _relative(self.config, item.path)
        story = "\n\n" + counterexample_story(found, item.spec.hunt_examples, shown["scenario"], where, entry)
        raise ScenarioFailed(failure_report(result, heading=heading) + story)

    def _lock(self, suite: Path) -> HashLock:
        path = lock_path_for(suite)
        if path not in self._locks:
            self._locks[path] = HashLock.load(path)
        return self._locks[path]

    def _write_artifacts(
        self, item: ScenarioItem, scenario: Scenario, result: RunResult, *, streamed: bool
    ) -> RunResult:
        folder = artifact_folder(self.artifacts, item.path, item.spec.name)
        origin = RunOrigin.of_entry(item.path, item.spec, nodeid=item.nodeid)
        from fleetsim.view import write_view_file

        paths = write_run_artifacts(
            folder,
            result,
            origin,
            scenario=scenario,
            record_every=self.record_every,
            streamed=streamed,
            more=write_view_file,
        )
        shown = {kind: _relative(self.config, Path(path)) for kind, path in paths.items()}
        return replace(result, artifacts={**result.artifacts, **shown})

    def _describe(
        self,
        item: ScenarioItem,
        result: RunResult,
        record: LockEntry | None,
        identity: str,
        *,
        label: str = "",
        generated: bool = False,
        unrecorded: tuple[str, str | None] | None = None,
    ) -> None:
        """JUnit properties, and the payload that travels to the controller with the test's report.

        ``unrecorded``: no hash was recorded for this run, which the suite file at this path (relative to
        where pytest was run) records with this ``--planner`` (``None``: the fixture's planner).

        A generated entry (``generated``) gets its summary row but stays out of the metrics document:
        its runs are different scenarios every time, so there is nothing to compare with a baseline.
        """
        metrics = result.metrics
        item.user_properties += [
            ("fleetsim_planner", identity),
            ("fleetsim_trace_hash", result.trace_hash),
            ("fleetsim_tasks", f"{result.tasks_completed}/{result.tasks_total}"),
            ("fleetsim_makespan", "" if metrics.makespan is None else f"{metrics.makespan:.3f}"),
            ("fleetsim_alerts", str(len(result.collisions))),
            ("fleetsim_rejections", str(len(result.rejections))),
            ("fleetsim_sim_time", f"{result.sim_time:.3f}"),
        ]
        item.user_properties += [(f"fleetsim_artifact_{kind}", path) for kind, path in sorted(result.artifacts.items())]
        cells = list(summary_cells(label or item.spec.name, "", result))
        if unrecorded is not None:
            item.user_properties.append(("fleetsim_trace_hash_recorded", "no"))
            cells[SUMMARY_COLUMNS.index("hash")] = NOT_RECORDED
        elif result.paced is not None:
            cells[SUMMARY_COLUMNS.index("hash")] = NOT_GATED
        elif item.spec.gate == "measures":
            cells[SUMMARY_COLUMNS.index("hash")] = MEASURES_GATED
        item.fleetsim_payload = {
            "suite": str(item.path),
            "scenario": item.spec.name,
            "index": item.index,
            "planner": identity,
            "metrics": ScenarioMetrics.from_result(item.nodeid, "failed", result).to_dict(),  # outcome: see _metrics
            "cells": cells,
            "order_cells": order_cells(label or item.spec.name, result, item.spec.gate),
            "lorr_cells": lorr_cells(label or item.spec.name, result),
            "outcome_notes": outcome_notes(item.spec.expect, result),  # by the word the report gives
            "generated": generated,
            "interrupted": result.ended == "interrupted",
            "record": None
            if record is None
            else {"hash": record.hash, "steps": record.steps, "checkpoints": list(record.checkpoints)},
            "unrecorded": None if unrecorded is None else list(unrecorded),
            "only_unrecorded": bool(result.failures) and all(f.kind == "hash-missing" for f in result.failures),
            "pacing": None if result.pacing is None else result.pacing.to_dict(),
        }

    def _describe_unrun(self, item: ScenarioItem, identity: str, *, load_error: bool) -> None:
        """The summary row of a scenario that never ran: its files did not load (``load_error``), or its
        lock file did not, or its planner could not be made. It has no metrics and no hash to record."""
        item.user_properties.append(("fleetsim_planner", identity))
        item.fleetsim_payload = {
            "suite": str(item.path),
            "scenario": item.spec.name,
            "index": item.index,
            "planner": identity,
            "metrics": None,
            "cells": list(summary_cells(item.spec.name, "", None)),
            "generated": False,
            "interrupted": False,
            "load_error": load_error,
            "record": None,
            "unrecorded": None,
            "only_unrecorded": False,
        }

    # -- the controller -----------------------------------------------------------------------------

    def pytest_runtest_logreport(self, report: pytest.TestReport) -> None:
        """Every test report reaches the controller, from whichever worker ran the test."""
        payload = getattr(report, "fleetsim", None)
        if not isinstance(payload, dict) or report.when != "call":
            return
        wasxfail = hasattr(report, "wasxfail")
        if payload.get("interrupted"):
            outcome = "interrupted"
        elif payload.get("load_error") and report.failed:
            outcome = "load error"  # never excused by xfail: the scenario did not run
        elif report.skipped and wasxfail:
            outcome = "xfailed"
        elif report.passed:
            outcome = "xpassed" if wasxfail else "passed"
        else:
            outcome = "failed"
        self.outcomes[report.nodeid] = _Outcome(report.nodeid, payload["suite"], payload["index"], outcome, payload)

    def finish(self, session: pytest.Session) -> None:
        """Write what the session recorded and gate on regressions (controller only)."""
        self.close_live()
        if not self.is_controller:
            return
        ordered = self.ordered()
        if self.update_hashes:
            self._record_hashes(ordered)
        else:
            self._note_stale_entries(ordered)
        # Generated entries run other scenarios every time; an interrupted run did not finish: neither has
        # metrics to compare.
        # A scenario that never ran has none either.
        rows = [
            self._metrics(o)
            for o in ordered
            if not o.payload.get("generated") and o.outcome != "interrupted" and o.payload["metrics"] is not None
        ]
        if self.metrics_json is not None:
            write_metrics(self.metrics_json, rows)
            self.notes.append(f"metrics of {len(rows)} scenario(s) written to {self.metrics_json}")
        if self.baseline is not None:
            self.comparison = compare(self.baseline, {row.id: row for row in rows}, self.thresholds)
            if self.comparison.regressions and session.exitstatus == pytest.ExitCode.OK:
                session.exitstatus = pytest.ExitCode.TESTS_FAILED

    def ordered(self) -> list[_Outcome]:
        return sorted(self.outcomes.values(), key=lambda o: (o.suite, o.index))

    def _metrics(self, outcome: _Outcome) -> ScenarioMetrics:
        # Only the report says how the test ended (an xfail marker turns a failure into "xfailed").
        return ScenarioMetrics.from_dict(
            {**outcome.payload["metrics"], "outcome": outcome.outcome}, where=outcome.nodeid
        )

    def _record_hashes(self, ordered: list[_Outcome]) -> None:
        by_suite: dict[str, list[_Outcome]] = {}
        for outcome in ordered:
            by_suite.setdefault(outcome.suite, []).append(outcome)
        for suite, outcomes in by_suite.items():
            path = lock_path_for(Path(suite))
            try:
                lock = HashLock.load(path)
            except LockFileError as error:
                self.notes.append(f"not recorded: {error}")
                continue
            counts = {"new": 0, "changed": 0, "unchanged": 0}
            for outcome in outcomes:
                record = outcome.payload["record"]
                if record is None:
                    continue  # not recordable: the failure report says why
                entry = LockEntry(record["hash"], record["steps"], tuple(record["checkpoints"]))
                before = lock.get(outcome.payload["planner"], outcome.payload["scenario"])
                counts["new" if before is None else "unchanged" if before == entry else "changed"] += 1
                if before != entry:
                    lock.set(outcome.payload["planner"], outcome.payload["scenario"], entry)
            pruned = self._prune(lock, Path(suite))
            written = lock.save()
            parts = [f"{sum(counts.values())} hash(es) recorded ({', '.join(f'{n} {k}' for k, n in counts.items())})"]
            if pruned:
                parts.append(f"{len(pruned)} stale entr{'y' if len(pruned) == 1 else 'ies'} pruned ({_pairs(pruned)})")
            self.notes.append(
                f"{_relative(self.config, path)}: {', '.join(parts)}{'' if written else ' (file unchanged)'}"
            )

    def _prune(self, lock: HashLock, suite: Path) -> list[tuple[str, str]]:
        try:
            names = [spec.name for spec in load_suite(suite).scenarios]
        except FleetsimError:
            return []  # a suite that does not load was reported at collection; keep its entries
        return lock.prune(names)

    def _note_stale_entries(self, ordered: list[_Outcome]) -> None:
        for suite in sorted({o.suite for o in ordered}):
            try:
                stale = self._lock(Path(suite)).stale([spec.name for spec in load_suite(Path(suite)).scenarios])
            except FleetsimError:
                continue
            if stale:
                path = _relative(self.config, lock_path_for(Path(suite)))
                self.notes.append(
                    f"{path} holds {len(stale)} stale entr{'y' if len(stale) == 1 else 'ies'} for scenarios no longer in "
                    f"the suite ({_pairs(stale)}); --fleetsim-update-hashes prunes them"
                )

    # -- the terminal -------------------------------------------------------------------------------

    def _unrecorded_lines(self, ordered: list[_Outcome]) -> list[str]:
        """The scenarios' verdicts and the hashes not recorded yet, with the commands that record them: a
        suite file when none of its scenarios has a hash, else the scenarios' node ids."""
        unrecorded = [o for o in ordered if o.payload.get("unrecorded")]
        if not unrecorded:
            return []
        words = [o.outcome for o in ordered]
        counts = ", ".join(f"{words.count(w)} {w}" for w in OUTCOME_WORDS if w in words)
        by_planner: dict[str | None, dict[str, list[_Outcome]]] = {}
        # A failed run's hash would pin the failure; one that failed only for want of a hash (CI) is fine.
        recordable = [
            o for o in unrecorded if o.outcome not in ("failed", "interrupted") or o.payload["only_unrecorded"]
        ]
        for outcome in recordable:
            here, planner = outcome.payload["unrecorded"]
            by_planner.setdefault(planner, {}).setdefault(here, []).append(outcome)
        commands = []
        for planner, suites in by_planner.items():
            targets: list[str] = []
            for here, outcomes in suites.items():
                names = [o.payload["scenario"] for o in outcomes]
                if sorted(names) == sorted(self._scenario_names(Path(outcomes[0].suite))):
                    targets.append(here)
                else:
                    targets += [f"{here}::{name}" for name in names]
            commands.append(f"  {_record_command(targets, planner)}")
        head = (
            f"{_plural(len(ordered), 'scenario', 'scenarios')}: {counts}; "
            f"{_plural(len(unrecorded), 'trace hash', 'trace hashes')} not recorded"
        )
        if self.require_hashes:
            head += ", which fails under CI (CI is set: a lock entry that was never committed is a CI mistake)"
        if not recordable:
            return ["", f"{head}; record them once the scenarios pass"]
        them = (
            ("it" if len(unrecorded) == 1 else "them")
            if len(recordable) == len(unrecorded)
            else f"the {'hash' if len(recordable) == 1 else 'hashes'} of the "
            f"{_plural(len(recordable), 'scenario that', 'scenarios that')} did not fail"
        )
        where = " where you develop" if self.require_hashes else ""
        tail = ["and commit the lock files"] if self.require_hashes else []
        return ["", f"{head}; record {them}{where} with:", *commands, *tail]

    def _scenario_names(self, suite: Path) -> list[str]:
        try:
            return [spec.name for spec in load_suite(suite).scenarios]
        except FleetsimError:
            return []

    def summary_lines(self) -> list[str]:
        ordered = self.ordered()
        several = len({o.suite for o in ordered}) > 1
        rows = []
        for outcome in ordered:
            cells = list(outcome.payload["cells"])
            cells[0] = f"{Path(outcome.suite).name}::{cells[0]}" if several else cells[0]
            notes = outcome.payload.get("outcome_notes") or {}  # none for a scenario that never ran
            cells[1] = outcome_cell(outcome.outcome, notes.get(outcome.outcome, ""))
            rows.append(cells)
        lines = format_table(rows) if rows else []
        # Beside the scenarios: what the runs with orders delivered, and the League problems' own counts.
        for key, title, columns in (
            ("order_cells", "orders:", ORDER_COLUMNS),
            ("lorr_cells", "League of Robot Runners counts (timesteps):", LORR_COLUMNS),
        ):
            table = []
            for outcome in ordered:
                found = outcome.payload.get(key)
                if found:
                    label = f"{Path(outcome.suite).name}::{found[0]}" if several else found[0]
                    table.append([label, *found[1:]])
            if table:
                lines += ["", title, *format_table(table, columns)]
        lines += self._unrecorded_lines(ordered)
        paced = [o for o in ordered if o.payload["cells"][SUMMARY_COLUMNS.index("hash")] == NOT_GATED]
        if paced:
            lines += [
                "",
                f"{_plural(len(paced), 'scenario', 'scenarios')} paced by a wall clock (a VDA 5050 master control in "
                "another process): a trace hash does not repeat there, so it is not gated; the checks decide",
                *(_pacing_line(o) for o in paced[:_PACING_SHOWN] if o.payload.get("pacing") is not None),
            ]
            if len(paced) > _PACING_SHOWN:
                lines.append(f"  ... and {len(paced) - _PACING_SHOWN} more (each result.json's pacing)")
        if self.comparison is not None:
            source = f" with {_relative(self.config, self.baseline_path)}" if self.baseline_path else ""
            lines += ["", f"compared{source}:", *self.comparison.lines()]
        if self.notes:
            lines += ["", *self.notes]
        return lines


def _pacing_line(outcome: _Outcome) -> str:
    """``  crossing: paced at 20x; order latency median 4 ms, max 12 ms (3 orders); the pace was kept``."""
    pacing = outcome.payload["pacing"]
    latency = pacing["order_latency"]
    said = (
        "no order arrived"
        if latency is None
        else f"order latency median {latency['median'] * 1000:.0f} ms, max {latency['max'] * 1000:.0f} ms "
        f"({_plural(latency['orders'], 'order', 'orders')})"
    )
    kept = (
        "the pace was kept"
        if pacing["late_steps"] == 0
        else f"{_plural(pacing['late_steps'], 'step', 'steps')} began late, by up to {pacing['lag_max']:.2f} s"
    )
    return f"  {outcome.payload['scenario']}: paced at {pacing['speed']:g}x; {said}; {kept}"


def _plural(count: int, one: str, many: str) -> str:
    return f"{count} {one if count == 1 else many}"


def _record_command(targets: list[str], planner: str | None) -> str:
    """The pytest command that records the hashes of ``targets`` (node ids or suite files)."""
    command = " ".join(["pytest", *map(shlex.quote, targets), "--fleetsim-update-hashes"])
    return command if planner is None else f"{command} --planner {shlex.quote(planner)}"


def _story(error: str, heading: str, details: str = "") -> str:
    """A failure before any run: the error's first line first (pytest's short summary shows it)."""
    first, _, rest = error.partition("\n")
    return "\n".join(part for part in (first, heading, rest, details.rstrip()) if part)


def _pairs(pairs: list[tuple[str, str]]) -> str:
    return ", ".join(f"{planner} / {scenario}" for planner, scenario in pairs)


def _path(config: pytest.Config, value: str | None) -> Path | None:
    if not value:
        return None
    return config.invocation_params.dir / value


def _relative(config: pytest.Config, path: Path | None) -> str:
    if path is None:
        return ""
    try:
        return str(path.relative_to(config.invocation_params.dir))
    except ValueError:
        return str(path)

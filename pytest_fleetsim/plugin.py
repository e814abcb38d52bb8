"""The pytest11 entry point of fleetsim: options, hooks and the ``fleetsim_planner`` fixture.

It stays thin: collection lives in :mod:`pytest_fleetsim._items`, the session's state and gating in
:mod:`pytest_fleetsim._state`, and everything a run does in :mod:`fleetsim`. The plugin is loaded in every
pytest session of an environment where fleetsim is installed, so the harness is imported only when a
session uses it: a fleetsim option is given (checked before any test runs), a suite file is collected,
the ``fleetsim_planner`` fixture is asked for, or (pytest-xdist's controller) a scenario's report arrives.
"""

from __future__ import annotations

from collections.abc import Generator
from fnmatch import fnmatch
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path
from typing import Any

import pytest

from pytest_fleetsim._key import STATE_KEY, SessionState

DEFAULT_SUITE_PATTERN = "*.fleetsim.yaml"
_WORKER_USAGE_ERROR = pytest.StashKey[str]()  # pytest-xdist's controller: a worker's usage error


def pytest_addoption(parser: pytest.Parser) -> None:
    group = parser.getgroup("fleetsim", "fleetsim: fleet planner scenarios")
    group.addoption(
        "--planner",
        "--fleetsim-planner",
        dest="fleetsim_planner",
        metavar="SPEC",
        help="the planner under test: module:attr naming a class or zero-argument factory "
        "(default: the fleetsim_planner ini option)",
    )
    group.addoption(
        "--dispatcher",
        "--fleetsim-dispatcher",
        dest="fleetsim_dispatcher",
        metavar="SPEC",
        help="the dispatcher of the scenarios with transport orders: module:attr naming a class or zero-argument "
        "factory (default: the fleetsim_dispatcher ini option, else each suite's dispatcher:, else the planner's "
        "own dispatch method)",
    )
    group.addoption(
        "--fleetsim-update-hashes",
        action="store_true",
        dest="fleetsim_update_hashes",
        help="run each scenario twice and record its trace hash in the lock file beside its suite "
        "(refused for a nondeterministic planner); prunes entries of removed scenarios",
    )
    group.addoption(
        "--fleetsim-artifacts",
        dest="fleetsim_artifacts",
        metavar="DIR",
        default="fleetsim-results",
        help="folder for run artifacts (default: fleetsim-results)",
    )
    group.addoption(
        "--fleetsim-record",
        dest="fleetsim_record",
        choices=("failed", "all", "none"),
        default="failed",
        help="which runs leave artifacts: result, trace, MCAP recording, RViz layout, failure picture (default: failed)",
    )
    group.addoption(
        "--fleetsim-record-every",
        dest="fleetsim_record_every",
        metavar="N",
        type=int,
        default=1,
        help="record every N-th step in the MCAP files (steps with new plans, alerts or events always; default: 1)",
    )
    group.addoption(
        "--fleetsim-metrics-json",
        dest="fleetsim_metrics_json",
        metavar="PATH",
        help="write every scenario's metrics to this JSON file (a baseline for --fleetsim-compare)",
    )
    group.addoption(
        "--fleetsim-compare",
        dest="fleetsim_compare",
        metavar="PATH",
        help="compare metrics with a file written earlier by --fleetsim-metrics-json",
    )
    group.addoption(
        "--fleetsim-compare-fail",
        dest="fleetsim_compare_fail",
        metavar="METRIC:LIMIT",
        action="append",
        help="fail the session when METRIC regressed by more than LIMIT against --fleetsim-compare: "
        "makespan:5%% (relative) or makespan:2.5 (absolute); repeatable",
    )
    group.addoption(
        "--fleetsim-planner-timeout",
        dest="fleetsim_planner_timeout",
        metavar="SECONDS",
        type=float,
        help="wall-clock limit per planner call (default: the fleetsim_planner_timeout ini option, 10; 0 = none)",
    )
    group.addoption(
        "--fleetsim-skip-without-planner",
        action="store_true",
        dest="fleetsim_skip_without_planner",
        help="skip the scenarios that need a planner when none is given (default: a usage error before any "
        "test runs, so a forgotten --planner cannot pass)",
    )
    group.addoption(
        "--fleetsim-live",
        action="store_true",
        dest="fleetsim_live",
        help="pace each scenario's run against the wall clock and show it live in the browser (fleetsim view's "
        "page: pause, step, speed); results and hashes are those of a headless run; not with -n",
    )
    group.addoption(
        "--fleetsim-speed",
        dest="fleetsim_speed",
        metavar="X",
        default="1",
        help="with --fleetsim-live: simulated seconds per wall second, or 'max' (default: 1)",
    )
    group.addoption(
        "--fleetsim-live-port",
        dest="fleetsim_live_port",
        metavar="N",
        type=int,
        default=0,
        help="with --fleetsim-live: the loopback port of the page (default: any free one)",
    )
    group.addoption(
        "--fleetsim-no-open",
        action="store_true",
        dest="fleetsim_no_open",
        help="with --fleetsim-live: do not open a browser on the page",
    )
    parser.addini("fleetsim_planner", "the planner under test (module:attr) when --planner is not given")
    parser.addini(
        "fleetsim_dispatcher", "the dispatcher (module:attr) of scenarios with orders, when --dispatcher is not given"
    )
    parser.addini(
        "fleetsim_skip_without_planner",
        "skip the scenarios that need a planner when none is given, instead of a usage error",
        type="bool",
        default=False,
    )
    parser.addini(
        "fleetsim_suite_patterns",
        "file name patterns of fleetsim suites",
        type="args",
        default=[DEFAULT_SUITE_PATTERN],
    )
    parser.addini("fleetsim_planner_timeout", "wall-clock limit per planner call in seconds (0 = none)", default="10")


def _active(config: pytest.Config) -> SessionState | None:
    return config.stash.get(STATE_KEY, None)


def _activate(config: pytest.Config) -> SessionState:
    """The session's state, made (and its options checked) on first use."""
    state = _active(config)
    if state is None:
        from pytest_fleetsim._state import FleetsimState

        made = FleetsimState.configure(config)
        config.pluginmanager.register(made, "fleetsim-state")  # it receives every test report from now on
        state = config.stash[STATE_KEY] = made
    return state


def _asked_for(config: pytest.Config) -> bool:
    """A fleetsim option is given: the session is meant to run scenarios, and a mistake in an option is
    reported before any test runs."""
    option = config.option
    return bool(
        option.fleetsim_planner
        or config.getini("fleetsim_planner")
        or option.fleetsim_dispatcher
        or option.fleetsim_update_hashes
        or option.fleetsim_metrics_json
        or option.fleetsim_compare
        or option.fleetsim_compare_fail
        or option.fleetsim_record_every != 1
        or option.fleetsim_live
    )


class _Waker:
    """Until the state exists: makes it when the first scenario report arrives (pytest-xdist's controller
    collects nothing, so only reports tell it that the session runs scenarios)."""

    def __init__(self, config: pytest.Config) -> None:
        self.config = config

    def pytest_runtest_logreport(self, report: pytest.TestReport) -> None:
        if getattr(report, "fleetsim", None) is not None and _active(self.config) is None:
            _activate(self.config).pytest_runtest_logreport(report)


def _library_not_rewritten(config: pytest.Config) -> None:
    """pytest rewrites the asserts of every top-level package of a plugin's distribution, so in an
    ordinary (not editable) install every fleetsim module imported in a session is parsed, rewritten and
    compiled again wherever pytest cannot keep its own bytecode cache (``PYTHONDONTWRITEBYTECODE``, a
    read-only site-packages), on every start and in every xdist worker. fleetsim's library holds no test
    code whose asserts pytest should explain; only the plugin's own package stays marked. pytest has no
    public way to unmark a package: the hook's set of marked names is used when it is there."""
    marked = getattr(config.pluginmanager.rewrite_hook, "_must_rewrite", None)
    if isinstance(marked, set):
        marked.discard("fleetsim")


def pytest_configure(config: pytest.Config) -> None:
    _library_not_rewritten(config)
    if _asked_for(config):
        _activate(config)
    else:
        config.pluginmanager.register(_Waker(config), "fleetsim-waker")


def pytest_report_header(config: pytest.Config) -> str:
    try:
        installed = version("fleetsim")
    except PackageNotFoundError:  # running from a source tree that was never installed
        installed = "(not installed)"
    state = _active(config)
    planner = state.planner if state is not None else None
    return f"fleetsim: {installed}, planner: {planner.spec if planner is not None else '(none given)'}"


def pytest_collect_file(file_path: Path, parent: pytest.Collector) -> pytest.Collector | None:
    patterns = parent.config.getini("fleetsim_suite_patterns")
    if any(fnmatch(file_path.name, pattern) for pattern in patterns):
        _activate(parent.config)
        from pytest_fleetsim._items import SuiteFile

        return SuiteFile.from_parent(parent, path=file_path)
    return None


def _needs_the_option(item: pytest.Item) -> bool:
    """The item is a scenario whose planner can only come from ``--planner`` or the ini value: its suite
    names none, and the ``fleetsim_planner`` fixture it uses is this plugin's own (not a conftest's)."""
    from pytest_fleetsim._items import ScenarioItem  # imported already: a suite file was collected

    if not isinstance(item, ScenarioItem) or item.suite.planner is not None:
        return False
    definitions = item._fixtureinfo.name2fixturedefs.get("fleetsim_planner", ())
    return bool(definitions) and getattr(definitions[-1].func, "__module__", None) == __name__


USAGE_ERROR_KEY = "fleetsim_usage_error"  # a pytest-xdist worker's usage error, in its workeroutput


@pytest.hookimpl(tryfirst=True)  # before pytest-xdist's worker sends its collection to the controller
def pytest_collection_finish(session: pytest.Session) -> None:
    """No silent pass: scenarios that need a planner, in a session that has none, are a usage error
    (exit status 4) before any test runs, unless skipping them is asked for.

    A pytest-xdist worker cannot raise it (the controller would see a crashed worker): it runs nothing,
    asks the session to stop with the message, and the controller ends with status 4 (see
    :func:`pytest_testnodedown` and :func:`pytest_sessionfinish`)."""
    config = session.config
    state = _active(config)
    if state is None or state.planner is not None or config.option.collectonly:
        return
    if config.option.fleetsim_skip_without_planner or config.getini("fleetsim_skip_without_planner"):
        return
    waiting = [item for item in session.items if _needs_the_option(item)]
    if not waiting:
        return
    from pytest_fleetsim._state import NO_PLANNER

    some = ", ".join(item.nodeid for item in waiting[:3]) + (", ..." if len(waiting) > 3 else "")
    message = (
        f"{NO_PLANNER}.\n{len(waiting)} collected scenario(s) need one ({some}); pass "
        "--fleetsim-skip-without-planner (or set fleetsim_skip_without_planner = true) to skip them instead"
    )
    workeroutput = getattr(config, "workeroutput", None)
    if workeroutput is None:
        raise pytest.UsageError(message)
    workeroutput[USAGE_ERROR_KEY] = message
    session.shouldstop = message
    session.items = []


@pytest.hookimpl(optionalhook=True)  # a pytest-xdist hook: pytest-xdist need not be installed
def pytest_testnodedown(node: Any, error: object) -> None:
    """pytest-xdist's controller: a worker that stopped on a usage error ends the session with it
    (``node`` is pytest-xdist's WorkerController, with the controller's config)."""
    message = getattr(node, "workeroutput", {}).get(USAGE_ERROR_KEY)
    if message is not None:
        node.config.stash[_WORKER_USAGE_ERROR] = message


@pytest.fixture
def fleetsim_planner(request: pytest.FixtureRequest) -> object:
    """The planner under test, made fresh for every run: by default from ``--planner``.

    Override it in a conftest.py to return a planner class, a zero-argument factory, or an instance
    (copied before each run). ``None`` skips the scenario tests, saying how to pass a planner. Without an
    override and without a planner, collecting such a scenario is a usage error (see
    :func:`pytest_collection_finish`).
    """
    return _activate(request.config).planner


@pytest.hookimpl(wrapper=True)
def pytest_runtest_makereport(
    item: pytest.Item, call: pytest.CallInfo[None]
) -> Generator[None, pytest.TestReport, pytest.TestReport]:
    report = yield
    payload = getattr(item, "fleetsim_payload", None)
    if call.when == "call" and payload is not None:
        report.fleetsim = payload  # type: ignore[attr-defined]  # plain data: it travels from xdist workers
    return report


@pytest.hookimpl(wrapper=True)
def pytest_runtest_protocol(item: pytest.Item, nextitem: pytest.Item | None) -> Generator[None, object, object]:
    """After a scenario a stop signal ended (reported as interrupted, its artifacts written), the session
    stops as on Ctrl-C: pytest's interrupt summary follows, and the exit status is 128 + the signal's
    number (130, 143; see :func:`pytest_sessionfinish`)."""
    outcome = yield
    state = _active(item.config)
    stopped_by = state.stopped_by if state is not None else None
    if stopped_by is not None:
        from fleetsim.sim.interrupt import signal_name

        item.session.shouldstop = f"{signal_name(stopped_by)} stopped the session during {item.nodeid}"
    return outcome


def pytest_report_teststatus(report: pytest.TestReport) -> tuple[str, str, str] | None:
    """A scenario a stop signal cut short is a failure, shown as INTERRUPTED; one that passed with no hash
    recorded for it says so under ``-v`` (the terminal summary counts them)."""
    payload = getattr(report, "fleetsim", None)
    if report.when != "call" or not isinstance(payload, dict):
        return None
    if report.failed and payload.get("interrupted"):
        return "failed", "!", "INTERRUPTED"
    if report.passed and payload.get("unrecorded") and not hasattr(report, "wasxfail"):
        return "passed", ".", "PASSED (hash not recorded)"
    return None


def pytest_sessionfinish(session: pytest.Session) -> None:
    if _WORKER_USAGE_ERROR in session.config.stash:
        session.exitstatus = pytest.ExitCode.USAGE_ERROR
    state = _active(session.config)
    if state is None:
        return
    state.finish(session)
    if state.stopped_by is not None and session.exitstatus == pytest.ExitCode.INTERRUPTED:
        # pytest has printed its interrupt summary for INTERRUPTED (2); the session ends with the status of
        # the signal that stopped it, as the process would without the plugin's clean stop.
        session.exitstatus = 128 + state.stopped_by


def pytest_terminal_summary(terminalreporter: pytest.TerminalReporter, config: pytest.Config) -> None:
    state = _active(config)
    lines = state.summary_lines() if state is not None else []
    if lines:
        terminalreporter.write_sep("=", "fleetsim")
        for line in lines:
            terminalreporter.write_line(line)

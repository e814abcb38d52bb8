"""Run results as text for people: the summary table and failure details (CLI and pytest plugin alike).

Both front ends show the same columns and the same failure wording, so a scenario reads the same in a
terminal, in a pytest report and in CI logs.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from fleetsim.contact.monitor import ContactReport
from fleetsim.scenario import Expectations
from fleetsim.sim.result import MOMENTLESS, Failure, RunResult

__all__ = [
    "LORR_COLUMNS",
    "ORDER_COLUMNS",
    "SUMMARY_COLUMNS",
    "broken_expectation",
    "expected_failures",
    "failure_lines",
    "failure_report",
    "failure_text",
    "first_line",
    "format_table",
    "lorr_cells",
    "order_cells",
    "outcome_cell",
    "outcome_notes",
    "route_error_lines",
    "summary_cells",
    "when",
]

# What each failure kind breaks, in the words of the suite file (SPEC §13 ``expect``) or the harness.
_BROKEN = {
    "rejection": "expect.rejections: none",
    "collision": "expect.collisions: none",
    "contact": "expect.contacts: none",
    "deadlock": "expect.deadlock: false",
    "timeout": "expect.tasks",
    "planner-error": "the planner failed",
    "interrupted": "finishing the run (a stop signal ended it early)",
    "hash-mismatch": "the recorded trace hash",
    "hash-missing": "the recorded trace hash",
    "nondeterministic": "a deterministic planner",
    "regression": "the baseline (--fleetsim-compare-fail)",
    "load-error": "loading the scenario",
}

SUMMARY_COLUMNS = (
    "scenario",
    "outcome",
    "tasks",
    "makespan",
    "alerts",
    "contacts",
    "clearance",
    "rejections",
    "route errors",
    "hash",
    "realtime",
)


# A second table, for the runs with transport orders: what each delivered (fleetsim.sim.measures).
ORDER_COLUMNS = (
    "scenario",
    "orders",
    "orders/h",
    "service median",
    "p95",
    "max",
    "wait p95",
    "deadlines missed",
    "stalls",
    "utilisation",
    "backlog",
    "gate",
)


# A third, for the runs of League of Robot Runners problems: the competition's own counts, in timesteps.
LORR_COLUMNS = ("scenario", "edition", "robots", "task pool", "horizon", "tasks finished", "sum of cost", "makespan")


def lorr_cells(label: str, result: RunResult) -> tuple[str, ...] | None:
    """One row of the League table, or ``None`` for a run that is not of a League problem."""
    counts = None if result.measures is None else result.measures.lorr
    if counts is None:
        return None
    setup = counts.setup
    return (
        label,
        setup.edition,
        str(setup.team_size),
        str(setup.task_pool),
        str(setup.horizon),
        f"{counts.tasks_finished}/{counts.tasks_revealed}",
        str(counts.sum_of_cost),
        str(counts.makespan),
    )


def order_cells(label: str, result: RunResult, gate: str = "-") -> tuple[str, ...] | None:
    """One row of the orders table, or ``None`` for a run without orders; ``gate``: what a change of its
    behaviour fails on (a suite entry's ``gate``: ``hash``, ``measures`` or ``both``)."""
    m = result.measures
    if m is None:
        return None
    service = m.service_time
    wait = m.wait_for_pickup

    def seconds(value: float | None) -> str:
        return "-" if value is None else f"{value:.0f} s"

    backlog = "overloaded" if m.overloaded else "bounded"
    return (
        label,
        f"{m.completed}/{m.released}",
        f"{m.orders_per_hour:.1f}",
        seconds(None if service is None else service.median),
        seconds(None if service is None else service.p95),
        seconds(None if service is None else service.max),
        seconds(None if wait is None else wait.p95),
        str(m.deadline_misses),
        str(m.stalls),
        f"{100 * m.utilisation:.0f} %",
        f"{backlog} ({m.backlog_slope:+.1f}/h)",
        gate,
    )


def summary_cells(label: str, outcome: str, result: RunResult | None) -> tuple[str, ...]:
    """One row of the summary table; ``result`` is ``None`` for a scenario that never ran."""
    if result is None or not result.trace_hash:
        return (label, outcome, *("-" for _ in SUMMARY_COLUMNS[2:]))
    makespan = result.metrics.makespan
    factor = result.metrics.realtime_factor
    contact = result.contact
    return (
        label,
        outcome,
        f"{result.tasks_completed}/{result.tasks_total}",
        "-" if makespan is None else f"{makespan:.1f} s",
        str(len(result.collisions)),
        "-" if contact is None else str(len(contact.contacts)),
        _clearance(contact),
        str(len(result.rejections)),
        str(len(result.route_errors)),
        result.trace_hash[:12],
        "-" if factor is None else f"{factor:.0f}x",
    )


def expected_failures(expect: Expectations, result: RunResult) -> str:
    """What a passed run showed because its ``expect`` asked for it, in words for its row, or ``""``.

    ``expected collisions happened``, ``expected goal-direction rejection and deadlock happened``; a run
    that was only allowed to leave tasks undone (``expect.tasks``) says ``1 of 2 tasks, as expected``. A
    pass beside ``tasks 0/2, alerts 4`` would otherwise read as a pass that did nothing.
    """
    happened = []
    if expect.collisions != "none" and result.collisions:
        happened.append(_named("collision", len(result.collisions), expect.collisions, "on segment"))
    if expect.rejections != "none" and result.rejections:
        if isinstance(expect.rejections, str):
            happened.append(_plural("rejection", len(result.rejections)))
        else:
            happened.append(f"{_listed(expect.rejections)} {_plural('rejection', len(expect.rejections))}")
    if expect.deadlock and result.deadlock is not None:
        happened.append("deadlock")
    if expect.contacts == "any" and result.contact is not None and result.contact.contacts:
        happened.append(_plural("contact", len(result.contact.contacts)))
    if happened:
        return f"expected {_listed(happened)} happened"
    if result.tasks_completed < result.tasks_total and result.ended != "shift-end":  # a shift ends mid-work
        return f"{result.tasks_completed} of {result.tasks_total} tasks, as expected"
    return ""


def _named(noun: str, count: int, which: str | tuple[int, ...], where: str) -> str:
    """``collisions``, or those the scenario named: ``collision on segment 2``, ``collisions on segments 2, 3``."""
    if isinstance(which, str):
        return _plural(noun, count)
    return f"{_plural(noun, count)} {_plural(where, len(which))} {', '.join(map(str, which))}"


def _plural(words: str, count: int) -> str:
    """``words`` for one, else with an ``s`` (``on segment``: ``on segments``)."""
    return words if count == 1 else f"{words}s"


def _listed(words: Sequence[str]) -> str:
    """``a``, ``a and b``, ``a, b and c``."""
    return words[0] if len(words) == 1 else f"{', '.join(words[:-1])} and {words[-1]}"


def outcome_notes(expect: Expectations, result: RunResult) -> dict[str, str]:
    """What a summary row adds to its outcome word, by the word (only the runner knows which it will be).

    A pass (or an xfail scenario's pass) that expected a failure says the failure happened
    (:func:`expected_failures`); an ``xfailed`` row says what failed it (``failed: collision``).
    """
    notes = {}
    expected = expected_failures(expect, result) if result.passed else ""
    if expected:
        notes["passed"] = notes["xpassed"] = expected
    # What happened (a collision, a deadlock); the expectations it left unmet only when nothing else did.
    kinds = dict.fromkeys(failure.kind for failure in result.failures if failure.kind != "expectation")
    kinds = kinds or dict.fromkeys(broken_expectation(failure) for failure in result.failures)
    if kinds:
        notes["xfailed"] = f"failed: {', '.join(kinds)}"
    return notes


def outcome_cell(word: str, note: str) -> str:
    """The outcome column: ``passed``, or with its note ``passed (expected collisions happened)``."""
    return f"{word} ({note})" if note else word


def _clearance(contact: ContactReport | None) -> str:
    """The clearance cell: metres, ``> reach`` when no two footprints came within reach, ``-`` when the
    contact check was off."""
    if contact is None:
        return "-"
    if contact.clearance is None:
        return f"> {contact.reach:g} m"
    return f"{contact.clearance.distance:.2f} m"


def format_table(rows: Sequence[Sequence[str]], header: Sequence[str] = SUMMARY_COLUMNS) -> list[str]:
    """Left-aligned columns two spaces apart, header first."""
    table = [tuple(header), *map(tuple, rows)]
    widths = [max(len(row[i]) for row in table) for i in range(len(header))]
    return ["  ".join(cell.ljust(width) for cell, width in zip(row, widths, strict=True)).rstrip() for row in table]


def failure_text(result: RunResult, failure: Failure) -> str:
    """What went wrong, in the words a planner author needs: the thesis's alert text for a collision,
    the planner's own traceback for a planner error."""
    if failure.kind == "collision":
        for event in result.collisions:
            if event.time == failure.time and event.alert.segment == failure.details.get("segment"):
                return event.alert.text()
    if failure.kind in ("deadlock", "timeout", "interrupted") and result.diagnosis is not None:
        return "\n".join([failure.message, *result.diagnosis.lines()])
    if failure.kind == "planner-error" and failure.details.get("traceback"):
        return f"{failure.message}\n{str(failure.details['traceback']).rstrip()}"
    return failure.message


def first_line(text: str) -> str:
    """A message's first line; one that ends with a colon goes on with the next (a command to run, say)."""
    lines = text.splitlines() or [""]
    if len(lines) > 1 and lines[0].endswith(":"):
        return f"{lines[0]} {lines[1].strip()}"
    return lines[0]


def when(failure: Failure) -> str:
    """``deadlock at t=47.00 s``; a failure of the whole run (the trace hash) has no moment: ``hash-missing``."""
    return failure.kind if failure.kind in MOMENTLESS else f"{failure.kind} at t={failure.time:.2f} s"


def broken_expectation(failure: Failure) -> str:
    """Which expectation (or harness rule) a failure broke, as the user would look it up."""
    expect = failure.details.get("expect")
    if expect:
        return f"expect.{expect}"
    return _BROKEN.get(failure.kind, failure.kind)


def failure_report(result: RunResult, *, heading: str, shown: int = 5) -> str:
    """The whole story of a failed run for a test report: what ran, what broke, where the files are.

    Failures are grouped by the expectation they broke, the first ``shown`` of each group in full.
    """
    lines = []
    if result.failures:  # first, since pytest's short summary shows a report's first line
        first = result.failures[0]
        lines.append(f"{when(first)}: {first_line(failure_text(result, first))}{_others(result.failures)}")
    lines.append(heading)
    if result.trace_hash:
        lines.append(
            f"run ended ({result.ended}) at t = {result.sim_time:.2f} s after {result.steps} steps; "
            f"tasks {result.tasks_completed}/{result.tasks_total} completed; trace hash {result.trace_hash[:12]}"
        )
    groups: dict[str, list[Failure]] = {}
    for failure in result.failures:
        groups.setdefault(broken_expectation(failure), []).append(failure)
    for broken, failures in groups.items():
        count = f" ({len(failures)} times)" if len(failures) > 1 else ""
        lines += ["", f"broken: {broken}{count}"]
        for failure in failures[:shown]:
            lines.append(f"  {when(failure)}:")
            lines += ["    " + line for line in failure_text(result, failure).splitlines()]
        if len(failures) > shown:
            lines.append(f"  ... and {len(failures) - shown} more (all in result.json)")
    if result.route_errors:
        lines += ["", *route_error_lines(result)]
    if result.artifacts:
        lines.append("")
        # What a reviewer opens first comes first: the picture, the recording and its RViz layout.
        rank = {kind: index for index, kind in enumerate(_ARTIFACT_ORDER)}
        kinds = sorted(
            (kind for kind in result.artifacts if kind != "folder"), key=lambda kind: (rank.get(kind, len(rank)), kind)
        )
        files = [result.artifacts[kind] for kind in kinds]
        lines += [("artifacts: " if i == 0 else "           ") + path for i, path in enumerate(files)]
    return "\n".join(lines)


# What one failure of a kind is called when counted in a headline.
_NOUNS = {"collision": ("alert", "alerts"), "rejection": ("rejection", "rejections")}


def _others(failures: Sequence[Failure]) -> str:
    """`` (+3 more alerts; 1 other failure)`` after a headline's first failure; empty when it is alone."""
    first = failures[0]
    same = sum(1 for f in failures[1:] if f.kind == first.kind)
    other = len(failures) - 1 - same
    singular, plural = _NOUNS.get(first.kind, (f"{first.kind} failure", f"{first.kind} failures"))
    parts = []
    if same:
        parts.append(f"+{same} more {singular if same == 1 else plural}")
    if other:
        parts.append(f"{other} other failure{'s' if other > 1 else ''}")
    return f" ({'; '.join(parts)})" if parts else ""


def route_error_lines(result: RunResult, shown: int = 10) -> list[str]:
    """How many route errors the planner answered, and each distinct message: how often, for whom, when."""
    errors = result.route_errors
    distinct: dict[str, list[dict[str, Any]]] = {}
    for error in errors:
        distinct.setdefault(str(error["message"]), []).append(error)
    lines = [f"route errors: {len(errors)} ({len(distinct)} distinct message{'s' if len(distinct) > 1 else ''})"]
    for message, group in list(distinct.items())[:shown]:
        vehicles = sorted({int(e["vehicle"]) for e in group if e["vehicle"] is not None})
        who = "vehicle " if len(vehicles) == 1 else "vehicles "
        span = (
            f"t = {group[0]['time']:.2f} s"
            if len(group) == 1
            else f"t = {group[0]['time']:.2f}-{group[-1]['time']:.2f} s"
        )
        lines.append(f"  {len(group)}x, {who}{', '.join(map(str, vehicles))}, {span}: {message}")
    if len(distinct) > shown:
        lines.append(f"  ... and {len(distinct) - shown} more distinct messages (all in result.json)")
    return lines


_ARTIFACT_ORDER = ("picture", "view", "mcap", "rviz", "trace", "result")


def failure_lines(result: RunResult, shown: int, more_hint: str) -> list[str]:
    """The first ``shown`` failures, each as ``kind at t=...:`` with its text indented below."""
    lines = []
    for failure in result.failures[:shown]:
        lines.append(f"{when(failure)}:")
        lines += ["  " + line for line in failure_text(result, failure).splitlines()]
    hidden = len(result.failures) - shown
    if hidden > 0:
        lines.append(f"... and {hidden} more failure(s) ({more_hint})")
    if result.failures and result.route_errors:
        lines += route_error_lines(result)
    return lines

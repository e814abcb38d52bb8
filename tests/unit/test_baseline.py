"""Metric documents and regression gating against a saved baseline (fleetsim.gating.baseline)."""

from __future__ import annotations

import json
import re
from dataclasses import replace
from pathlib import Path

import pytest

from fleetsim.contact.monitor import Approach, Contact, ContactReport
from fleetsim.errors import FleetsimError
from fleetsim.gating.baseline import (
    METRICS,
    BaselineError,
    Comparison,
    ScenarioMetrics,
    Threshold,
    compare,
    metrics_document,
    parse_threshold,
    read_metrics,
    write_metrics,
)
from fleetsim.planning.checks import Rejection, RejectionCode
from fleetsim.planning.reservations import CollisionAlert
from fleetsim.sim.result import AlertEvent, Metrics, RejectionEvent, RunResult

CROSSING = "scenario_suites/x.fleetsim.yaml::crossing"
PLANNER = "fleetsim.planners:ReservingPlanner"


def _result(
    *,
    makespan: float | None = 22.0,
    distance: dict[int, float] | None = None,
    alerts: int = 0,
    rejections: int = 0,
    completed: int = 2,
) -> RunResult:
    """A RunResult with just the facts the metrics read; the rest is empty."""
    metrics = Metrics(
        makespan=makespan,
        distance={1: 10.25, 2: 5.5} if distance is None else distance,
        waiting_time={1: 1.5, 2: 0.25},
        planner_calls=7,
        planner_wall_time=0.125,
        wall_time=0.5,
        sim_time=30.0,
    )
    rejection = Rejection(RejectionCode.UNKNOWN_SEGMENT, 1, 0, 9, "no segment 9")
    return RunResult(
        scenario="crossing",
        planner=PLANNER,
        status="passed",
        failures=(),
        trace_hash="sha256:abc",
        sim_time=30.0,
        steps=300,
        tasks_total=2,
        tasks_completed=completed,
        pending=(),
        rejections=tuple(RejectionEvent(1.0, rejection) for _ in range(rejections)),
        collisions=tuple(AlertEvent(2.0, CollisionAlert(4, (1,), (2,))) for _ in range(alerts)),
        route_errors=(),
        ended="completed",
        deadlock=None,
        metrics=metrics,
    )


ROW = ScenarioMetrics.from_result(CROSSING, "passed", _result())


def _row(sid: str = CROSSING, **changes: object) -> ScenarioMetrics:
    return replace(ROW, id=sid, **changes)  # type: ignore[arg-type]


def _compare(metric: str, before: float | None, after: float | None, threshold: str) -> Comparison:
    baseline, current = _row(CROSSING, **{metric: before}), _row(CROSSING, **{metric: after})
    return compare({CROSSING: baseline}, {CROSSING: current}, [parse_threshold(threshold)])


# --- rows ----------------------------------------------------------------------------------------


def test_a_row_sums_vehicles_and_counts_alerts_and_rejections() -> None:
    row = ScenarioMetrics.from_result(CROSSING, "failed", _result(alerts=1, rejections=2))
    assert (row.id, row.planner, row.outcome, row.trace_hash) == (CROSSING, PLANNER, "failed", "sha256:abc")
    assert (row.distance, row.waiting_time) == (15.75, 1.75)
    assert (row.alerts, row.rejections, row.planner_calls) == (1, 2, 7)
    assert (row.makespan, row.sim_time, row.wall_time, row.realtime_factor) == (22.0, 30.0, 0.5, 60.0)


def test_a_row_of_a_run_that_left_tasks_undone_has_no_makespan() -> None:
    row = ScenarioMetrics.from_result(CROSSING, "failed", _result(makespan=None, completed=1))
    assert (row.makespan, row.tasks_completed, row.tasks_total) == (None, 1, 2)


def test_a_row_with_no_vehicles_driven_has_zero_distance() -> None:
    assert ScenarioMetrics.from_result(CROSSING, "passed", _result(distance={})).distance == 0.0


# --- documents -----------------------------------------------------------------------------------


def test_written_metrics_read_back_equal_and_parent_folders_are_created(tmp_path: Path) -> None:
    rows = [_row("b::two", makespan=None, realtime_factor=None), _row("a::one")]
    path = tmp_path / "out" / "nested" / "metrics.json"
    write_metrics(path, rows)
    assert read_metrics(path) == {"a::one": rows[1], "b::two": rows[0]}
    assert [p.name for p in path.parent.iterdir()] == ["metrics.json"]  # no temporary file left behind


def test_the_same_rows_in_any_order_give_identical_bytes(tmp_path: Path) -> None:
    rows = [_row("b::two"), _row("a::one", makespan=3.5), _row("c::three")]
    write_metrics(tmp_path / "first.json", rows)
    write_metrics(tmp_path / "second.json", reversed(rows))
    text = (tmp_path / "first.json").read_bytes()
    assert text == (tmp_path / "second.json").read_bytes()
    assert text.endswith(b"}\n")
    document = json.loads(text)
    assert document["format"] == "fleetsim-metrics/1"
    assert [s["id"] for s in document["scenarios"]] == ["a::one", "b::two", "c::three"]


def test_a_session_document_refuses_two_rows_with_one_id() -> None:
    with pytest.raises(BaselineError, match=r"scenario id 'a::one' appears twice"):
        metrics_document([_row("a::one"), _row("b::two"), _row("a::one")])


def test_baseline_errors_are_fleetsim_errors_and_value_errors() -> None:
    assert issubclass(BaselineError, FleetsimError)
    assert issubclass(BaselineError, ValueError)


def test_a_missing_metrics_file_is_named(tmp_path: Path) -> None:
    path = tmp_path / "nowhere.json"
    with pytest.raises(BaselineError, match=f"^{re.escape(str(path))}: no such metrics file"):
        read_metrics(path)


def test_an_unreadable_metrics_file_is_named(tmp_path: Path) -> None:
    (tmp_path / "latin1.json").write_bytes(b'{"format": "fleetsim-metrics/1", "scenarios": ["caf\xe9"]}')
    for name in ("latin1.json", "."):
        with pytest.raises(BaselineError, match=f"^{re.escape(str(tmp_path / name))}: cannot read the metrics file: "):
            read_metrics(tmp_path / name)


def test_a_metrics_file_saved_with_a_byte_order_mark_reads(tmp_path: Path) -> None:
    write_metrics(tmp_path / "metrics.json", [ROW])
    (tmp_path / "bom.json").write_bytes(b"\xef\xbb\xbf" + (tmp_path / "metrics.json").read_bytes())
    assert read_metrics(tmp_path / "bom.json") == {CROSSING: ROW}


def test_malformed_json_is_reported_with_line_and_column(tmp_path: Path) -> None:
    path = tmp_path / "metrics.json"
    path.write_text('{\n  "format": "fleetsim-metrics/1",\n  "scenarios": [,]\n}\n', encoding="utf-8")
    with pytest.raises(
        BaselineError, match=f"^{re.escape(str(path))}:3:17: the file is not valid JSON: a value .* is expected here"
    ):
        read_metrics(path)


def _scenario(**changes: object) -> dict[str, object]:
    return {**ROW.to_dict(), **changes}


@pytest.mark.parametrize(
    ("document", "problem"),
    [
        ([], "its \"format\" is None, not 'fleetsim-metrics/1'"),
        (
            {"format": "fleetsim-metrics/2", "scenarios": []},
            "its \"format\" is 'fleetsim-metrics/2', not 'fleetsim-metrics/1'",
        ),
        ({"format": "fleetsim-metrics/1", "scenarios": {}}, "scenarios={} must be a list"),
        (
            {"format": "fleetsim-metrics/1", "scenarios": [_scenario(), _scenario()]},
            f"scenarios[1]: id {CROSSING!r} appears twice",
        ),
        ({"format": "fleetsim-metrics/1", "scenarios": [7]}, "scenarios[0]: scenario=7 must be a JSON object"),
        (
            {"format": "fleetsim-metrics/1", "scenarios": [_scenario(makespan="22")]},
            "scenarios[0]: field 'makespan' value='22' must be a finite number or null",
        ),
        (
            {"format": "fleetsim-metrics/1", "scenarios": [_scenario(alerts=True)]},
            "scenarios[0]: field 'alerts' value=True must be an integer",
        ),
        (
            {"format": "fleetsim-metrics/1", "scenarios": [_scenario(distance=None)]},
            "scenarios[0]: field 'distance' value=None must be a finite number",
        ),
        (
            {"format": "fleetsim-metrics/1", "scenarios": [_scenario(planner=3)]},
            "scenarios[0]: field 'planner' value=3 must be a string",
        ),
        (
            {"format": "fleetsim-metrics/1", "scenarios": [_scenario(outcome="ok")]},
            "scenarios[0]: field 'outcome' value='ok' must be one of passed",
        ),
        ({"format": "fleetsim-metrics/1", "scenarios": [{"id": "a::one"}]}, "scenarios[0]: field 'planner' is missing"),
    ],
)
def test_an_unusable_metrics_document_is_named_with_the_bad_value(
    tmp_path: Path, document: object, problem: str
) -> None:
    path = tmp_path / "metrics.json"
    path.write_text(json.dumps(document), encoding="utf-8")
    with pytest.raises(BaselineError) as caught:
        read_metrics(path)
    assert str(caught.value).startswith(f"{path}: {problem}")


def test_integers_in_float_fields_read_back_as_floats(tmp_path: Path) -> None:
    path = tmp_path / "metrics.json"
    path.write_text(
        json.dumps({"format": "fleetsim-metrics/1", "scenarios": [_scenario(makespan=22, distance=0)]}),
        encoding="utf-8",
    )
    row = read_metrics(path)[CROSSING]
    assert (type(row.makespan), type(row.distance)) == (float, float)


def test_fields_a_later_version_adds_are_left_alone(tmp_path: Path) -> None:
    path = tmp_path / "metrics.json"
    path.write_text(
        json.dumps({"format": "fleetsim-metrics/1", "scenarios": [_scenario(energy=3.0)]}), encoding="utf-8"
    )
    assert read_metrics(path) == {CROSSING: ROW}


# --- thresholds ----------------------------------------------------------------------------------


def test_the_catalogue_knows_which_way_is_better() -> None:
    assert {name for name, metric in METRICS.items() if metric.better == "higher"} == {
        "tasks_completed",
        "realtime_factor",
        "clearance",
        "orders_per_hour",
        "utilisation",
    }
    assert len(METRICS) == 20
    assert METRICS["makespan"].read(ROW) == 22.0


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("makespan:5%", Threshold("makespan", 5.0, relative=True)),
        ("makespan:2.5", Threshold("makespan", 2.5, relative=False)),
        ("realtime_factor:0%", Threshold("realtime_factor", 0.0, relative=True)),
        (" alerts : 1 ", Threshold("alerts", 1.0, relative=False)),
    ],
)
def test_a_threshold_is_relative_with_a_percent_sign_and_absolute_without(text: str, expected: Threshold) -> None:
    assert parse_threshold(text) == expected


def test_a_threshold_prints_as_written() -> None:
    assert (str(parse_threshold("makespan:5%")), str(parse_threshold("distance:2.5"))) == ("5%", "2.5")


@pytest.mark.parametrize(
    ("text", "problem"),
    [
        ("speed:5%", "unknown metric 'speed'"),
        ("makespan", "missing ':' between the metric and the limit"),
        ("makespan:-5%", "limit=-5.0 must be a finite number >= 0"),
        ("makespan:fast", "limit 'fast' is not a number"),
        ("makespan:", "limit '' is not a number"),
        ("makespan:nan%", "limit=nan must be a finite number >= 0"),
    ],
)
def test_a_bad_threshold_names_the_text_the_problem_and_the_known_metrics(text: str, problem: str) -> None:
    with pytest.raises(BaselineError) as caught:
        parse_threshold(text)
    message = str(caught.value)
    assert message.startswith(f"--fleetsim-compare-fail={text!r}: {problem}; ")
    known = (
        "alerts, clearance, contacts, deadline_misses, distance, empty_travel_share, makespan, orders_per_hour, "
        "planner_calls, planner_wall_time, realtime_factor, rejections, service_time_median, service_time_p95, "
        "stalls, tasks_completed, utilisation, wait_for_pickup_p95, waiting_time, wall_time"
    )
    assert message.endswith(f"; known: {known}")


def test_a_threshold_made_directly_is_checked_too() -> None:
    with pytest.raises(BaselineError, match="unknown metric 'speed'"):
        Threshold("speed", 5.0, relative=True)


# --- compare -------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("metric", "before", "inside", "outside", "threshold"),
    [
        ("makespan", 100.0, 104.99, 105.01, "makespan:5%"),  # lower is better, relative
        ("makespan", 22.0, 23.1, 23.11, "makespan:5%"),  # exactly at the limit despite binary rounding
        ("distance", 10.0, 12.5, 12.51, "distance:2.5"),  # lower is better, absolute
        ("realtime_factor", 100.0, 95.01, 94.99, "realtime_factor:5%"),  # higher is better, relative
        ("tasks_completed", 4, 3, 2, "tasks_completed:1"),  # higher is better, absolute
        ("clearance", 0.5, 0.45, 0.44, "clearance:0.05"),  # metres; closer is worse
        ("contacts", 0, 0, 1, "contacts:0"),
    ],
)
def test_a_metric_regresses_only_beyond_its_limit(
    metric: str, before: float, inside: float, outside: float, threshold: str
) -> None:
    assert _compare(metric, before, inside, threshold).regressions == ()
    (regression,) = _compare(metric, before, outside, threshold).regressions
    assert (regression.metric, regression.baseline, regression.current) == (metric, before, outside)


@pytest.mark.parametrize(("metric", "before", "after"), [("makespan", 22.0, 11.0), ("realtime_factor", 60.0, 600.0)])
def test_an_improvement_is_never_a_regression(metric: str, before: float, after: float) -> None:
    assert _compare(metric, before, after, f"{metric}:0").regressions == ()


def test_a_regression_reads_as_the_change_against_its_limit() -> None:
    (relative,) = _compare("makespan", 22.0, 24.1, "makespan:5%").regressions
    assert str(relative) == f"{CROSSING}: makespan 22.0 -> 24.1 (+9.5%, limit 5%)"
    (absolute,) = _compare("planner_calls", 7, 12, "planner_calls:2").regressions
    assert str(absolute) == f"{CROSSING}: planner_calls 7 -> 12 (+5, limit 2)"
    (higher,) = _compare("realtime_factor", 60.0, 30.0, "realtime_factor:10%").regressions
    assert str(higher) == f"{CROSSING}: realtime_factor 60.0 -> 30.0 (-50.0%, limit 10%)"


def test_a_makespan_no_longer_reached_is_a_regression() -> None:
    (regression,) = _compare("makespan", 22.0, None, "makespan:50%").regressions
    assert regression.current is None
    assert str(regression) == f"{CROSSING}: makespan 22.0 -> not reached (limit 50%)"


def test_a_clearance_no_longer_measured_is_no_regression() -> None:
    # None now: no two footprints came within reach, farther apart than any measured clearance.
    assert _compare("clearance", 0.4, None, "clearance:0").regressions == ()


def test_a_baseline_written_before_contacts_and_clearance_reads_as_none_and_unmeasured(tmp_path: Path) -> None:
    older = {key: value for key, value in ROW.to_dict().items() if key not in ("contacts", "clearance")}
    path = tmp_path / "metrics.json"
    path.write_text(json.dumps({"format": "fleetsim-metrics/1", "scenarios": [older]}), encoding="utf-8")
    row = read_metrics(path)[CROSSING]
    assert (row.contacts, row.clearance) == (0, None)


def test_a_row_counts_contacts_and_takes_the_clearance() -> None:
    contact = ContactReport(
        (Contact(1.0, (1, 2), 0.0, 0.0, 0.1),), Approach((1, 2), 0.0, 1.0, 0.0, 0.0), (), 2.0, 0.5, 0.0
    )
    result = _result()
    result = replace(result, contact=contact, metrics=replace(result.metrics, clearance=0.0))
    row = ScenarioMetrics.from_result(CROSSING, "failed", result)
    assert (row.contacts, row.clearance) == (1, 0.0)
    assert (ROW.contacts, ROW.clearance) == (0, None)  # the contact check off: nothing


def test_a_baseline_without_a_value_has_nothing_to_compare() -> None:
    assert _compare("makespan", None, 1000.0, "makespan:0").regressions == ()
    assert _compare("realtime_factor", None, None, "realtime_factor:0%").regressions == ()


def test_any_worsening_from_a_zero_baseline_exceeds_a_relative_limit() -> None:
    (regression,) = _compare("alerts", 0, 1, "alerts:50%").regressions
    assert str(regression) == f"{CROSSING}: alerts 0 -> 1 (+1 from 0, limit 50%)"
    assert _compare("alerts", 0, 0, "alerts:50%").regressions == ()


def test_only_scenarios_in_both_are_compared_and_the_rest_are_listed() -> None:
    baseline = {"a::one": _row("a::one", makespan=1.0), "b::two": _row("b::two")}
    current = {"b::two": _row("b::two"), "c::three": _row("c::three", makespan=1000.0)}
    comparison = compare(baseline, current, [parse_threshold("makespan:0")])
    assert (comparison.compared, comparison.regressions) == (1, ())
    assert (comparison.missing, comparison.new, comparison.planner_changed) == (("a::one",), ("c::three",), ())


def test_a_changed_planner_is_noted_and_still_compared() -> None:
    baseline = {CROSSING: _row(planner="old:Planner")}
    current = {CROSSING: _row(makespan=30.0)}
    comparison = compare(baseline, current, [parse_threshold("makespan:5%")])
    assert comparison.planner_changed == (CROSSING,)
    assert [r.metric for r in comparison.regressions] == ["makespan"]


def test_regressions_are_sorted_by_id_then_metric_one_per_breached_threshold() -> None:
    worse = {"alerts": 3, "makespan": 40.0}
    baseline = {sid: _row(sid) for sid in ("b::two", "a::one")}
    current = {sid: _row(sid, **worse) for sid in ("b::two", "a::one")}
    thresholds = [parse_threshold(t) for t in ("makespan:5%", "alerts:0", "makespan:1")]
    found = [(r.id, r.metric, str(r.threshold)) for r in compare(baseline, current, thresholds).regressions]
    assert found == [
        ("a::one", "alerts", "0"),
        ("a::one", "makespan", "5%"),
        ("a::one", "makespan", "1"),
        ("b::two", "alerts", "0"),
        ("b::two", "makespan", "5%"),
        ("b::two", "makespan", "1"),
    ]


def test_the_report_lines_count_regressions_and_list_the_rest_briefly() -> None:
    baseline = {CROSSING: _row(), **{f"gone::{i}": _row(f"gone::{i}") for i in range(7)}}
    current = {CROSSING: _row(makespan=24.1, planner="new:Planner"), "fresh::one": _row("fresh::one")}
    lines = compare(baseline, current, [parse_threshold("makespan:5%")]).lines()
    assert lines == [
        "fleetsim compare: 1 compared, 1 regression",
        f"  {CROSSING}: makespan 22.0 -> 24.1 (+9.5%, limit 5%)",
        f"  planner changed since the baseline (compared anyway): 1: {CROSSING}",
        "  no baseline yet: 1: fresh::one",
        "  in the baseline but not run now: 7: gone::0, gone::1, gone::2, gone::3, gone::4 and 2 more",
    ]


def test_a_clean_comparison_reports_one_line() -> None:
    assert compare({CROSSING: ROW}, {CROSSING: ROW}, [parse_threshold("makespan:5%")]).lines() == [
        "fleetsim compare: 1 compared, 0 regressions"
    ]

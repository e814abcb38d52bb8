"""Baselines of runs with transport orders: the measures in a session's metrics document, compared with
their direction, and a regression as a failure of the run itself (``fleetsim.gating.regression``)."""

from __future__ import annotations

import dataclasses
import json
from functools import cache
from pathlib import Path

from fleetsim import load_scenario, load_suite
from fleetsim.gating.baseline import METRICS, ScenarioMetrics, Threshold, compare, parse_threshold, read_metrics
from fleetsim.gating.measures import GATED_MEASURES
from fleetsim.gating.regression import judge_against
from fleetsim.planners import ReservingPlanner
from fleetsim.sim import run_scenario
from fleetsim.sim.record import RunOrigin, run_record
from fleetsim.sim.result import RunResult
from fleetsim.sim.result_schema import result_problem

ROOT = Path(__file__).resolve().parents[2]
ID = "warehouse.fleetsim.yaml::shift"
FIVE_PERCENT = (parse_threshold("orders_per_hour:5%"),)


@cache
def shift_run() -> RunResult:
    """The shipped warehouse's shift, cut to ten minutes."""
    suite = load_suite(ROOT / "scenario_suites" / "warehouse.fleetsim.yaml")
    scenario = load_scenario(next(spec for spec in suite.scenarios if spec.name == "shift"), suite)
    assert scenario.shift is not None
    shortened = dataclasses.replace(scenario, shift=dataclasses.replace(scenario.shift, duration=600, warmup=60))
    return run_scenario(shortened, ReservingPlanner(), keep_trace=False)


def baseline_with(**changed: float | None) -> dict[str, ScenarioMetrics]:
    row = ScenarioMetrics.from_result(ID, "passed", shift_run())
    return {ID: dataclasses.replace(row, **changed)}  # type: ignore[arg-type]


def test_a_shifts_metrics_hold_its_measures_as_its_result_document_shows_them() -> None:
    result = shift_run()
    assert result.measures is not None
    row = ScenarioMetrics.from_result(ID, "passed", result)
    document = ScenarioMetrics.from_document(ID, "passed", run_record(result, RunOrigin()))
    assert [getattr(document, m.name) for m in GATED_MEASURES] == [getattr(row, m.name) for m in GATED_MEASURES]
    assert row.orders_per_hour == result.measures.to_dict()["orders_per_hour"] > 0
    assert row.service_time_p95 == result.measures.value("service_time_p95")
    assert (row.deadline_misses, row.stalls) == (0, 0) and isinstance(row.stalls, int)
    assert [m.name for m in GATED_MEASURES] == [f.name for f in dataclasses.fields(row)][-len(GATED_MEASURES) :]


def test_a_run_without_orders_has_none_of_the_measures() -> None:
    row = ScenarioMetrics.from_result(ID, "failed", RunResult.unrun("s", "p", ()))
    assert {getattr(row, m.name) for m in GATED_MEASURES} == {None}


def test_a_baseline_written_before_the_measures_reads_as_unmeasured_and_is_not_compared(tmp_path: Path) -> None:
    now = ScenarioMetrics.from_result(ID, "passed", shift_run())
    old = {k: v for k, v in now.to_dict().items() if k not in {m.name for m in GATED_MEASURES}}
    path = tmp_path / "old.json"
    path.write_text(json.dumps({"format": "fleetsim-metrics/1", "scenarios": [old]}), encoding="utf-8")
    before = read_metrics(path)
    assert before[ID].orders_per_hour is None
    assert compare(before, {ID: now}, FIVE_PERCENT).regressions == ()


def test_a_hand_edited_measure_of_the_wrong_type_is_refused(tmp_path: Path) -> None:
    row = ScenarioMetrics.from_result(ID, "passed", shift_run()).to_dict()
    path = tmp_path / "bad.json"
    path.write_text(json.dumps({"format": "fleetsim-metrics/1", "scenarios": [{**row, "stalls": 1.5}]}))
    try:
        read_metrics(path)
    except ValueError as error:
        assert "field 'stalls' value=1.5 must be an integer or null" in str(error)
    else:
        raise AssertionError("a stall count of 1.5 was read")


def test_each_measure_is_compared_in_its_direction() -> None:
    assert {name: METRICS[name].better for name in ("orders_per_hour", "service_time_p95", "utilisation")} == {
        "orders_per_hour": "higher",
        "service_time_p95": "lower",
        "utilisation": "higher",
    }
    now = {ID: ScenarioMetrics.from_result(ID, "passed", shift_run())}
    rate = now[ID].orders_per_hour
    assert rate is not None
    assert compare(baseline_with(orders_per_hour=rate * 1.06), now, FIVE_PERCENT).regressions
    assert not compare(baseline_with(orders_per_hour=rate * 0.5), now, FIVE_PERCENT).regressions  # faster is fine


def test_a_regression_fails_the_run_itself_with_a_located_message() -> None:
    result = shift_run()
    rate = ScenarioMetrics.from_result(ID, "passed", result).orders_per_hour
    assert rate is not None
    judged = judge_against(baseline_with(orders_per_hour=round(rate * 1.06, 6)), ID, result, FIVE_PERCENT)
    assert judged.status == "failed" and not judged.passed
    (failure,) = [f for f in judged.failures if f.kind == "regression"]
    shown = float(f"{rate * 1.06:.6g}")  # six significant digits, as the comparison's lines show figures
    assert failure.message == f"orders_per_hour {shown} -> {rate} (-5.7%, limit 5%) against the baseline"
    assert failure.details == {
        "metric": "orders_per_hour",
        "baseline": round(rate * 1.06, 6),
        "value": rate,
        "limit": "5%",
    }
    assert result_problem(run_record(judged, RunOrigin())) is None  # the one result schema knows the kind


def test_within_the_limit_or_without_a_baseline_row_the_run_stands() -> None:
    result = shift_run()
    rate = ScenarioMetrics.from_result(ID, "passed", result).orders_per_hour
    assert rate is not None
    assert judge_against(baseline_with(orders_per_hour=rate * 1.04), ID, result, FIVE_PERCENT) is result
    assert judge_against(baseline_with(orders_per_hour=rate * 2), "other::id", result, FIVE_PERCENT) is result
    assert judge_against(baseline_with(orders_per_hour=rate * 2), ID, result, ()) is result
    interrupted = dataclasses.replace(result, ended="interrupted")
    assert judge_against(baseline_with(orders_per_hour=rate * 2), ID, interrupted, FIVE_PERCENT) is interrupted


def test_a_figure_the_run_no_longer_has_is_a_regression() -> None:
    result = shift_run()
    assert result.measures is not None
    gone = dataclasses.replace(result, measures=dataclasses.replace(result.measures, service_time=None))
    judged = judge_against(baseline_with(), ID, gone, (Threshold("service_time_p95", 5, relative=True),))
    (failure,) = [f for f in judged.failures if f.kind == "regression"]
    assert "service_time_p95" in failure.message and "-> no value (limit 5%)" in failure.message

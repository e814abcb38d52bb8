"""Sweeps of runs with transport orders: what travels to a worker, order stream seeds, the dispatcher a spec
names, and the measures as sweep metrics (read, summed up, compared, gated)."""

from __future__ import annotations

import dataclasses
import json
from functools import cache
from pathlib import Path
from typing import Any

import pytest
from dispatch_support import ORDERS
from dispatch_support import scenario as loop_scenario

from fleetsim import load_scenario, load_suite
from fleetsim.planners import ReservingPlanner
from fleetsim.scenario import Scenario
from fleetsim.sim import run_scenario
from fleetsim.sweep.gate import judge, parse_condition
from fleetsim.sweep.items import expand
from fleetsim.sweep.payload import scenario_from_payload, scenario_payload
from fleetsim.sweep.report import build_report, markdown
from fleetsim.sweep.report_html import html_page
from fleetsim.sweep.spec import SweepSpecError, load_sweep_spec
from fleetsim.sweep.stats import METRICS, ORDER_METRICS, summarise

ROOT = Path(__file__).resolve().parents[2]
WAREHOUSE = ROOT / "scenario_suites" / "warehouse.fleetsim.yaml"
NEAREST = "fleetsim.dispatchers:NearestVehicleDispatcher"
OLDEST = "fleetsim.dispatchers:OldestFirstDispatcher"
PLANNER = "fleetsim.planners:ReservingPlanner"


@cache
def shipped(name: str) -> Scenario:
    suite = load_suite(WAREHOUSE)
    return load_scenario(next(spec for spec in suite.scenarios if spec.name == name), suite)


def shortened(name: str, minutes: float = 5) -> Scenario:
    """A scenario of the shipped warehouse suite with its shift cut to ``minutes`` (a minute's warm-up)."""
    scenario = shipped(name)
    assert scenario.shift is not None
    return dataclasses.replace(scenario, shift=dataclasses.replace(scenario.shift, duration=60 * minutes, warmup=60))


def sent(scenario: Scenario) -> Scenario:
    """``scenario`` as a worker gets it: through JSON, as any scheduler may carry it."""
    return scenario_from_payload(json.loads(json.dumps(scenario_payload(scenario))))


# -- 1. what a worker gets --------------------------------------------------------------------------


@pytest.mark.parametrize("name", ["shift", "deadlines-oldest-first"])
def test_a_shift_sent_to_a_worker_runs_as_the_loaded_one(name: str) -> None:
    scenario = shortened(name)
    worker = sent(scenario)
    assert worker.order_stream == scenario.order_stream and worker.order_stream is not None
    assert dict(worker.stations) == dict(scenario.stations) and worker.stations
    assert (worker.shift, worker.dispatcher) == (scenario.shift, scenario.dispatcher)
    assert worker.expect == scenario.expect and worker.expect.measures  # the bounds on measures travel too
    here, there = run_scenario(scenario, ReservingPlanner()), run_scenario(worker, ReservingPlanner())
    assert here.measures is not None and here.measures.released > 0
    assert there.trace_hash == here.trace_hash
    assert there.failures == here.failures  # judged on the worker against the same bounds


def test_orders_made_in_code_travel_with_their_stops_release_and_vehicle_types() -> None:
    scenario = dataclasses.replace(loop_scenario(ORDERS[:3]), dispatcher=OLDEST)
    worker = sent(scenario)
    assert worker.orders == scenario.orders and [o.release for o in worker.orders] == [0.0, 0.0, 30.0]
    assert worker.dispatcher == OLDEST
    assert run_scenario(worker, ReservingPlanner()).trace_hash == run_scenario(scenario, ReservingPlanner()).trace_hash
    typed = dataclasses.replace(scenario, orders=ORDERS)  # one only a "tugger" may carry
    assert sent(typed).orders[3].vehicle_types == ("tugger",)


def test_orders_released_as_a_pool_travel_with_their_pool() -> None:
    scenario = dataclasses.replace(loop_scenario(ORDERS[:3]), dispatcher=OLDEST, order_pool=1)
    worker = sent(scenario)
    assert worker.order_pool == 1
    pooled = run_scenario(scenario, ReservingPlanner())
    assert run_scenario(worker, ReservingPlanner()).trace_hash == pooled.trace_hash
    # The pool is what decides when the orders come: without it they come at their own times.
    unpooled = run_scenario(dataclasses.replace(scenario, order_pool=None), ReservingPlanner())
    assert unpooled.trace_hash != pooled.trace_hash


def test_a_scenario_without_orders_sends_none() -> None:
    suite = load_suite(ROOT / "scenario_suites" / "examples.fleetsim.yaml")
    scenario = load_scenario(suite.scenarios[0], suite)
    payload = scenario_payload(scenario)
    assert (payload["orders"], payload["order_stream"], payload["shift"], payload["dispatcher"]) == (
        [],
        None,
        None,
        None,
    )
    assert sent(scenario).order_stream is None and sent(scenario).shift is None


# -- 2. the spec: order stream seeds, the dispatcher ------------------------------------------------


def _spec(tmp_path: Path, extra: str = "", source: str = f"{WAREHOUSE}::shift") -> Path:
    path = tmp_path / "orders.sweep.yaml"
    path.write_text(
        f"fleetsim-sweep: 1\nname: orders\nplanners: [{PLANNER}]\nrecord: none\n{extra}"
        f"sources:\n  - suite: {source}\n  - suite: {ROOT / 'scenario_suites' / 'examples.fleetsim.yaml'}::crossing\n",
        encoding="utf-8",
    )
    return path


def test_order_seeds_run_each_order_stream_once_per_seed(tmp_path: Path) -> None:
    items = expand(load_sweep_spec(_spec(tmp_path, "order_seeds: [4, 9]\n")), tmp_path / "runs")
    ids = sorted(item["id"].rpartition("/")[2] for item in items)
    # The scenario of fixed tasks runs once, as it is: there is no stream to draw.
    assert ids == [
        "examples.fleetsim.yaml::crossing",
        "warehouse.fleetsim.yaml::shift~o4",
        "warehouse.fleetsim.yaml::shift~o9",
    ]
    seeds = {item["id"][-3:]: item["scenario"]["order_stream"]["seed"] for item in items if "~o" in item["id"]}
    assert seeds == {"~o4": 4, "~o9": 9}
    plain = expand(load_sweep_spec(_spec(tmp_path)), tmp_path / "runs")  # narrowly: without it, the suite's own seed
    assert sorted(i["scenario"]["order_stream"]["seed"] for i in plain if i["scenario"]["order_stream"]) == [1]


def test_order_seeds_and_disturbance_seeds_multiply(tmp_path: Path) -> None:
    extra = "order_seeds: [1, 2]\ndisturbances: {seeds: [7]}\n"
    items = expand(load_sweep_spec(_spec(tmp_path, extra)), tmp_path / "runs")
    assert sorted(item["id"].rpartition("::")[2] for item in items) == ["crossing~d7", "shift~o1~d7", "shift~o2~d7"]


def test_the_spec_dispatcher_serves_every_scenario_with_orders(tmp_path: Path) -> None:
    items = expand(load_sweep_spec(_spec(tmp_path, f"dispatcher: {OLDEST}\n")), tmp_path / "runs")
    dispatchers = {item["id"].rpartition("::")[2]: item["scenario"]["dispatcher"] for item in items}
    assert dispatchers == {"shift": OLDEST, "crossing": None}  # a scenario without orders needs none
    plain = expand(load_sweep_spec(_spec(tmp_path)), tmp_path / "runs")
    assert {i["scenario"]["dispatcher"] for i in plain} == {NEAREST, None}  # narrowly: the suite's own


@pytest.mark.parametrize(
    ("extra", "column", "words"),
    [
        ("order_seeds: []", 14, "order_seeds=[] must be a non-empty list of whole numbers >= 0"),
        ("order_seeds: 3", 14, "order_seeds=3 must be a non-empty list"),
        ("order_seeds: [1, 1]", 18, "order_seeds[1]=1 must be a whole number >= 0, listed once"),
        ("order_seeds: [-2]", 15, "order_seeds[0]=-2 must be a whole number >= 0"),
        ("order_seeds: [true]", 15, "order_seeds[0]=True must be a whole number >= 0"),
        ("dispatcher: nearest", 13, "dispatcher='nearest' must be a dispatcher spec, module:attr"),
        ("dispatcher: [a:B]", 13, "dispatcher=['a:B'] must be a dispatcher spec"),
        ("order_seed: [1]", 1, "unknown key 'order_seed'; did you mean 'order_seeds'?"),
    ],
)
def test_bad_order_seeds_or_dispatcher_are_located_errors(tmp_path: Path, extra: str, column: int, words: str) -> None:
    path = _spec(tmp_path, extra + "\n")
    with pytest.raises(SweepSpecError) as caught:
        load_sweep_spec(path)
    assert caught.value.location is not None
    assert (caught.value.location.path, caught.value.location.line) == (path, 5)
    assert caught.value.location.column == column, str(caught.value)
    assert words in str(caught.value)


def test_good_order_seeds_and_dispatcher_load(tmp_path: Path) -> None:
    spec = load_sweep_spec(_spec(tmp_path, "order_seeds: [0, 3]\ndispatcher: my_pkg.dispatch:Mine\n"))
    assert (spec.order_seeds, spec.dispatcher) == ((0, 3), "my_pkg.dispatch:Mine")  # imported by the workers only
    assert load_sweep_spec(_spec(tmp_path)).order_seeds is None


# -- 3. the measures as sweep metrics ---------------------------------------------------------------

MEASURES: dict[str, Any] = {
    "orders_per_hour": 60.0,
    "service_time": {"count": 9, "median": 120.0, "p95": 300.0, "max": 310.0},
    "wait_for_vehicle": {"count": 9, "median": 10.0, "p95": 40.0, "max": 41.0},
    "wait_for_pickup": {"count": 9, "median": 60.0, "p95": 150.0, "max": 160.0},
    "deadline_misses": 2,
    "utilisation": 0.75,
    "empty_travel_share": 0.4,
    "stalls": 1,
}


def record(planner: str, id: str, measures: dict[str, Any] | None, **changed: Any) -> dict[str, Any]:
    """A sweep record with what the metrics read (the rest of a result does not matter to them)."""
    shown = None if measures is None else {**measures, **changed}
    return {
        "key": f"{planner} | {id} | 1", "id": id, "planner": planner, "status": "passed", "error": None,
        "sim_time": 900.0, "tasks": {"completed": 10, "total": 10}, "vehicles": 6, "collisions": [],
        "rejections": [], "deadlock": None, "contact": None, "measures": shown,
        "metrics": {"makespan": None, "waiting_time": {"1": 0.0}, "planner_calls": 10, "planner_wall_time": 0.1},
    }  # fmt: skip


def test_each_measure_is_read_from_a_records_measures_in_its_unit() -> None:
    row = record("a", "x", MEASURES)
    read = {name: METRICS[name].read(row) for name in ORDER_METRICS}
    assert read == {
        "orders_per_hour": 60.0, "service_time_median": 120.0, "service_time_p95": 300.0,
        "wait_for_pickup_p95": 150.0, "deadline_misses": 2.0, "utilisation": 75.0, "empty_travel_share": 40.0,
        "stalls": 1.0,
    }  # fmt: skip
    better = {name: METRICS[name].better for name in ORDER_METRICS}
    assert [name for name, way in better.items() if way == "higher"] == ["orders_per_hour", "utilisation"]
    assert (METRICS["utilisation"].unit, METRICS["service_time_p95"].unit) == ("%", "s")


def test_a_run_without_orders_has_no_measure_and_a_run_without_a_figure_none_of_it() -> None:
    assert {METRICS[name].read(record("a", "x", None)) for name in ORDER_METRICS} == {None}
    nothing_done = record("a", "x", MEASURES, service_time=None, empty_travel_share=None)
    assert METRICS["service_time_p95"].read(nothing_done) is None
    assert METRICS["empty_travel_share"].read(nothing_done) is None
    assert METRICS["orders_per_hour"].read(nothing_done) == 60.0


def _rows(candidate_factor: float, n: int = 6) -> list[dict[str, Any]]:
    rows = []
    for k in range(n):
        base = 60.0 + 4 * k
        rows.append(record("base:B", f"s{k}", MEASURES, orders_per_hour=base))
        rows.append(record("cand:C", f"s{k}", MEASURES, orders_per_hour=round(base * candidate_factor + k % 2, 4)))
    return rows


def test_orders_per_hour_gates_with_the_paired_interval() -> None:
    condition = parse_condition("orders_per_hour < baseline - 5%")
    (worse,) = judge(_rows(0.8), [condition], "base:B", ["cand:C"])
    assert worse.holds and worse.comparison.high < worse.limit < 0
    (slightly,) = judge(_rows(0.97), [condition], "base:B", ["cand:C"])  # narrowly: 3 % worse is within 5 %
    assert not slightly.holds
    (unmeasured,) = judge([record("base:B", "s", None), record("cand:C", "s", None)], [condition], "base:B", ["cand:C"])
    assert unmeasured.holds and "no paired runs to judge" in unmeasured.line()  # no evidence never passes a gate


def test_the_report_shows_the_measures_and_a_dash_where_a_planner_has_none(tmp_path: Path) -> None:
    rows = [*_rows(0.8), record("none:N", "s0", None)]
    text = markdown(build_report("t", rows, "base:B", [], tmp_path))
    table = text.split("## Orders\n\n")[1].split("\n\n")[0].splitlines()
    assert table[0] == (
        "| planner | runs with orders | orders per hour (orders/h) | service time median (s) | service time p95 (s) "
        "| wait for pick-up p95 (s) | deadline misses | utilisation (%) | empty travel (%) | stalls |"
    )
    assert table[2].startswith("| B | 6 | 70 | 120 | 300 | 150 | 12 | 75 | 40 | 6 |")  # misses and stalls summed
    assert table[4] == "| N | 0 | – | – | – | – | – | – | – | – |"
    assert "| orders per hour (orders/h) | 6 | 70 | -13.5 | -14.57 .. -12.43 | -19.3% | worse |" in text  # paired
    assert "| stalls | 0 | – | – | – | – | no pairs |" in text  # N against B: no run of N has the figure


def test_the_page_has_the_orders_table_and_their_distribution(tmp_path: Path) -> None:
    page = html_page(build_report("t", _rows(0.8), "base:B", [], tmp_path))
    assert '<table id="orders">' in page and "<title>orders per hour (orders/h) per run</title>" in page


def test_a_sweep_without_orders_reports_no_measures() -> None:
    rows = [record("base:B", "s", None), record("cand:C", "s", None)]
    report = build_report("t", rows, "base:B", [], Path("."))
    assert "## Orders" not in markdown(report)
    assert '<table id="orders">' not in html_page(report) and "orders per hour" not in html_page(report)
    assert [c.metric for c in report.comparisons["cand:C"]][-1] == "planner_time_per_call"
    assert summarise(rows)[0].means["orders_per_hour"] is None

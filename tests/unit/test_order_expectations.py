"""A suite's expectations on the measures of a run with orders (``expect: {min_orders_per_hour: ...}``):
each kind of bound failing a run that misses it, and passing one that narrowly keeps it; a suite that
names a bad one is refused at its line."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from fleetsim import load_scenario, load_suite
from fleetsim.errors import SuiteError
from fleetsim.planners import ReservingPlanner
from fleetsim.sim.loop import run_scenario
from fleetsim.sim.result import RunResult

REPO = Path(__file__).resolve().parents[2]
LOOP = REPO / "scenario_suites" / "examples" / "loop"
ORDERS = """order_id,release,deadline,stops,dwell
a,0,60,7>2,2
b,5,30,2>7,2
c,10,,4,0
"""


def suite(tmp_path: Path, expect: str) -> Path:
    tmp_path.mkdir(parents=True, exist_ok=True)
    (tmp_path / "orders.csv").write_text(ORDERS, encoding="utf-8")
    path = tmp_path / "shift.fleetsim.yaml"
    path.write_text(
        f"""fleetsim: 1
name: shift
scenarios:
  - name: loop
    map: {LOOP / "map.tmx"}
    vehicles: {LOOP / "vehicles.csv"}
    tasks: {LOOP / "tasks.csv"}
    orders: orders.csv
    shift: {{duration: 120}}
    dispatcher: fleetsim.dispatchers:NearestVehicleDispatcher
    stop_on: []
    expect: {expect}
""",
        encoding="utf-8",
    )
    return path


def _run_at(folder: Path, expect: str) -> RunResult:
    loaded = load_suite(suite(folder, expect))
    scenario = load_scenario(loaded.scenarios[0], loaded)
    return run_scenario(scenario, ReservingPlanner())


def expectations(result: RunResult) -> list[str]:
    return [f.details.get("expect", "") for f in result.failures if f.kind == "expectation"]


@pytest.fixture(scope="module")
def measures(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    return _run_at(tmp_path_factory.mktemp("plain"), "{}").to_dict()["measures"]


@pytest.mark.parametrize(
    ("key", "read", "nudge"),
    [
        ("min_orders_per_hour", lambda m: m["orders_per_hour"], +1.0),
        ("max_service_time_p95", lambda m: m["service_time"]["p95"], -1.0),
        ("max_service_time_median", lambda m: m["service_time"]["median"], -1.0),
        ("max_wait_for_pickup_max", lambda m: m["wait_for_pickup"]["max"], -1.0),
        ("max_deadline_misses", lambda m: m["deadline_misses"], -1.0),
        ("min_utilisation", lambda m: m["utilisation"], +0.01),
        ("max_empty_travel_share", lambda m: m["empty_travel_share"], -0.01),
    ],
)
def test_a_bound_the_run_misses_fails_it_and_the_bound_it_meets_does_not(
    tmp_path: Path, measures: dict[str, Any], key: str, read: Any, nudge: float
) -> None:
    value = read(measures)
    if key == "max_deadline_misses":
        assert value >= 1  # order b's deadline (30 s) is too soon to keep
    missed = _run_at(tmp_path / "missed", f"{{{key}: {max(value + nudge, 0.0)}}}")
    assert expectations(missed) == [key], missed.failures
    assert missed.status == "failed"
    message = next(f.message for f in missed.failures if f.kind == "expectation")
    assert key in message and ("below" in message or "exceeds" in message)
    kept = _run_at(tmp_path / "kept", f"{{{key}: {value}}}")
    assert expectations(kept) == [] and kept.status == "passed"
    assert missed.trace_hash == kept.trace_hash  # expectations judge a run, they do not change it


def test_overloaded_false_passes_a_fleet_that_keeps_up(tmp_path: Path) -> None:
    assert _run_at(tmp_path / "a", "{overloaded: false}").status == "passed"
    expected_overload = _run_at(tmp_path / "b", "{overloaded: true}")
    assert expectations(expected_overload) == ["overloaded"]
    assert "the scenario expects it overloaded" in expected_overload.failures[0].message


def test_a_bound_on_a_measure_without_a_value_fails_saying_so(tmp_path: Path) -> None:
    path = suite(tmp_path, "{max_service_time_p95: 1000}")
    path.write_text(path.read_text(encoding="utf-8").replace("duration: 120", "duration: 5"), encoding="utf-8")
    loaded = load_suite(path)
    result = run_scenario(load_scenario(loaded.scenarios[0], loaded), ReservingPlanner())
    assert result.measures is not None and result.measures.completed == 0  # five seconds: nothing delivered
    assert expectations(result) == ["max_service_time_p95"]
    assert "service_time_p95 has no value in this run" in result.failures[0].message


@pytest.mark.parametrize(
    ("expect", "words"),
    [
        ("{min_orders_per_hour: -1}", "expect.min_orders_per_hour"),
        ("{max_service_time_p99: 10}", "max_service_time_p99"),
        ("{overloaded: maybe}", "expect.overloaded"),
    ],
)
def test_a_bad_bound_is_refused_at_its_line(tmp_path: Path, expect: str, words: str) -> None:
    with pytest.raises(SuiteError) as raised:
        load_suite(suite(tmp_path, expect))
    assert words in str(raised.value) and ":12:" in str(raised.value)

"""The measures of a run with transport orders (fleetsim.sim.measures): each definition on hand-made
records, and the figures of real runs (a warm-up left out, a shift whose backlog grows)."""

from __future__ import annotations

import dataclasses

import pytest
from dispatch_support import FirstIdle, scenario

from fleetsim.dispatch.book import OrderRecord
from fleetsim.orders import Order, Shift, Stop
from fleetsim.planners import ReservingPlanner
from fleetsim.sim.loop import run_scenario
from fleetsim.sim.measures import FleetTimes, Stats, measure_orders


def record(name: str, released: float, completed: float | None, deadline: float | None = None) -> OrderRecord:
    order = Order(name, (Stop(1),), release=released, deadline=deadline)
    return OrderRecord(order, released=released, assigned=released + 1.0, started=released + 2.0, completed=completed)


TIMES = FleetTimes(vehicles=2, idle=600.0, dwelling=100.0, blocked=200.0, distance=1000.0, loaded_distance=250.0)


def test_percentiles_are_nearest_rank_and_the_median_of_an_even_count_is_the_mean_of_the_middle_two() -> None:
    stats = Stats.of([float(v) for v in range(1, 21)])  # 1..20
    assert stats is not None
    assert (stats.count, stats.median, stats.p95, stats.max) == (20, 10.5, 19.0, 20.0)
    assert Stats.of([]) is None
    one = Stats.of([7.0])
    assert one is not None and (one.median, one.p95, one.max) == (7.0, 7.0, 7.0)


def test_throughput_and_service_time_count_the_window_only() -> None:
    records = {
        "early": record("early", 10.0, 500.0),  # released in the warm-up: completed in the window counts,
        "a": record("a", 700.0, 1000.0),  # its service time does not
        "b": record("b", 800.0, 1400.0),
        "open": record("open", 900.0, None),
    }
    m = measure_orders(records, (600.0, 2400.0), TIMES, [])
    assert m.completed == 2 and m.released == 3  # "early" completed before the window
    assert m.orders_per_hour == pytest.approx(2 / 0.5)
    assert m.orders_per_vehicle_hour == pytest.approx(2 / 0.5 / 2)
    assert m.service_time is not None and (m.service_time.count, m.service_time.max) == (2, 600.0)
    assert m.wait_for_vehicle is not None and m.wait_for_vehicle.max == 1.0


def test_a_deadline_in_the_window_is_missed_when_the_order_is_late_or_still_open() -> None:
    records = {
        "kept": record("kept", 0.0, 100.0, deadline=200.0),
        "late": record("late", 0.0, 300.0, deadline=200.0),
        "open": record("open", 0.0, None, deadline=250.0),
        "later": record("later", 0.0, None, deadline=9999.0),  # its deadline is after the run: not yet missed
    }
    assert measure_orders(records, (0.0, 1000.0), TIMES, []).deadline_misses == 2


def test_shares_of_vehicle_time_and_distance() -> None:
    m = measure_orders({}, (0.0, 3600.0), TIMES, [])
    assert m.idle_share == pytest.approx(600 / 7200)
    assert m.utilisation == pytest.approx(1 - 600 / 7200)
    assert m.dwelling_share == pytest.approx(100 / 7200)
    assert m.blocked_share == pytest.approx(200 / 7200)
    assert m.empty_travel_share == pytest.approx(0.75)
    still = dataclasses.replace(TIMES, distance=0.0, loaded_distance=0.0)
    assert measure_orders({}, (0.0, 3600.0), still, []).empty_travel_share is None


def test_a_growing_backlog_is_overloaded_and_a_steady_one_is_not() -> None:
    arrivals = {f"o{i}": record(f"o{i}", 36.0 * i, None) for i in range(100)}  # 100 per hour
    growing = [(60.0 * k, 2 * k) for k in range(61)]  # +120 per hour
    m = measure_orders(arrivals, (0.0, 3600.0), TIMES, growing)
    assert m.backlog_slope == pytest.approx(120.0) and m.overloaded
    steady = [(60.0 * k, 4 + k % 2) for k in range(61)]
    assert not measure_orders(arrivals, (0.0, 3600.0), TIMES, steady).overloaded
    # A slope above 5 % of arrivals, but a backlog up by 5 orders only: not (yet) overloaded.
    small = [(60.0 * k, k // 12) for k in range(61)]
    assert not measure_orders(arrivals, (0.0, 3600.0), TIMES, small).overloaded


DWELLING = (Order("a", (Stop(7, dwell=4.0), Stop(2, dwell=2.0)), release=0.0), Order("b", (Stop(2),), release=6.0))


def test_a_run_reports_its_measures_and_a_warm_up_is_left_out() -> None:
    whole = run_scenario(
        dataclasses.replace(scenario(DWELLING), shift=Shift(duration=100.0)), ReservingPlanner(), dispatcher=FirstIdle()
    )
    assert whole.measures is not None and whole.measures.completed == 2
    assert 0.0 < whole.measures.dwelling_share < 1.0 and 0.0 < whole.measures.idle_share < 1.0
    assert whole.measures.empty_travel_share is not None and 0.0 < whole.measures.empty_travel_share < 1.0
    warmed = run_scenario(
        dataclasses.replace(scenario(DWELLING), shift=Shift(duration=100.0, warmup=30.0)),
        ReservingPlanner(),
        dispatcher=FirstIdle(),
    )
    assert warmed.trace_hash == whole.trace_hash  # the warm-up changes what is measured, not what happens
    assert warmed.measures is not None and warmed.measures.window == (30.0, 100.0)
    assert warmed.measures.released == 0  # both were released in the warm-up
    assert warmed.measures.orders_per_hour == pytest.approx(whole.measures.completed / (70 / 3600))

"""The League's own counts of a run (tasks finished, sum of cost, makespan) and its pool's refill order, on
hand-made runs of a small problem."""

from __future__ import annotations

import itertools
import math
from dataclasses import replace
from pathlib import Path
from typing import Any

from fleetsim.dispatchers import NearestVehicleDispatcher
from fleetsim.orders import LorrSetup
from fleetsim.planners import ReservingPlanner
from fleetsim.sim.loop import run_scenario
from fleetsim.sim.lorr_counts import HoldClock, lorr_counts
from fleetsim.sim.result_schema import result_problem
from tests.unit.test_lorr import load_problem

SETUP = LorrSetup("p.json", "2024", team_size=3, task_pool=4, horizon=100)


def test_a_hold_clock_sums_each_vehicles_time_with_orders_and_closes_at_the_end() -> None:
    clock = HoldClock()
    clock.update({1, 2}, 0.0)
    clock.update({2}, 12.3)
    clock.update({1, 2}, 20.0)
    clock.update(set(), 25.0)
    clock.update({3}, 90.0)
    assert clock.totals(100.0) == {1: 12.3 + 5.0, 2: 25.0, 3: 10.0}


def test_counts_round_each_robots_seconds_up_to_timesteps_and_sum_and_max_them() -> None:
    counts = lorr_counts(SETUP, [0, 1, 2], {0: 12.3, 1: 40.0}, revealed=9, finished=5)
    assert dict(counts.cost) == {0: 13, 1: 40, 2: 0}
    assert (counts.sum_of_cost, counts.makespan, counts.tasks_finished, counts.tasks_revealed) == (53, 40, 5, 9)
    document = counts.to_dict()
    assert document["cost"] == [13, 40, 0] and document["horizon"] == 100 and document["edition"] == "2024"


def run(tmp_path: Path, entry: str = "    horizon: 200\n", **problem: Any) -> dict[str, Any]:
    scenario = load_problem(tmp_path, entry, **problem)
    result = run_scenario(scenario, ReservingPlanner(), dispatcher=NearestVehicleDispatcher())
    document = result.to_dict()
    assert result_problem(document) is None  # the published schema knows the lorr object
    return document


def test_one_robot_with_a_pool_of_one_is_given_the_tasks_in_file_order_one_after_another(tmp_path: Path) -> None:
    document = run(tmp_path, teamSize=1, numTasksReveal=1)
    orders = document["orders"]
    assert [o["id"] for o in orders] == ["t0", "t1", "t2"]
    assert orders[0]["release"] == 0.0
    for before, after in itertools.pairwise(orders):
        # The next task is revealed at the start of the next step: the moment the one before it was
        # finished (a step's events are stamped with its end).
        assert after["release"] == before["completed"]
    counts = document["lorr"]
    assert counts["task_pool"] == 1 and counts["team_size"] == 1 and counts["tasks_finished"] == 3
    held = sum(o["completed"] - o["assigned"] for o in orders)
    assert counts["cost"] == [math.ceil(held - 1e-6)]
    assert counts["sum_of_cost"] == counts["makespan"] == counts["cost"][0]


def test_a_pool_reveals_its_first_tasks_at_once_and_one_more_per_finished_task(tmp_path: Path) -> None:
    tasks = ["3,19", "20,4", "23", "16,7", "5", "18,2"]
    document = run(tmp_path, teamSize=2, numTasksReveal=1.5, tasks=tasks)
    orders = document["orders"]
    assert [o["id"] for o in orders] == [f"t{k}" for k in range(len(tasks))]  # file order
    assert [o["release"] for o in orders[:3]] == [0.0, 0.0, 0.0]
    completions = sorted(o["completed"] for o in orders if o["completed"] is not None)
    for index, order in enumerate(orders[3:]):
        assert order["release"] == completions[index]
    counts = document["lorr"]
    assert counts["tasks_finished"] == len(completions) == len(tasks)
    assert counts["sum_of_cost"] == sum(counts["cost"]) and counts["makespan"] == max(counts["cost"])


def test_a_horizon_that_ends_with_tasks_open_counts_only_the_finished_and_holds_to_the_end(tmp_path: Path) -> None:
    document = run(tmp_path, "    horizon: 10\n", teamSize=2, numTasksReveal=1.5)
    counts = document["lorr"]
    assert document["ended"] == "shift-end" and document["sim_time"] == 10.0
    finished = sum(1 for o in document["orders"] if o["completed"] is not None)
    assert counts["tasks_finished"] == finished < counts["tasks_revealed"]
    # Both robots took a task at once and neither finished it in 10 s: each has all ten timesteps.
    assert counts["cost"] == [10, 10] and counts["makespan"] == 10 and counts["sum_of_cost"] == 20


def test_a_run_without_a_league_problem_has_no_lorr_object(tmp_path: Path) -> None:
    scenario = load_problem(tmp_path, "    horizon: 50\n")
    result = run_scenario(replace(scenario, lorr=None), ReservingPlanner(), dispatcher=NearestVehicleDispatcher())
    assert "lorr" not in result.to_dict() and result.measures is not None

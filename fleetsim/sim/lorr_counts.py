"""The League of Robot Runners' own counts of a run of one of its problems (the result's ``lorr``).

The Start-Kit counts, over its horizon of timesteps: ``numTaskFinished`` (tasks with every errand done),
``sumOfCost`` (for each robot, the timesteps during which it had an assigned, unfinished task; summed
over the robots) and ``makespan`` (the largest of those per-robot counts). fleetsim counts the same of
its run, at ``timestep`` seconds per timestep (one: a robot of the MovingAI type drives one cell a
second): a vehicle *has a task* while its sequence holds an order not yet completed, from the step the
dispatcher's assignment took effect to the step its last stop was served; its seconds so are summed over
the run and rounded up to whole timesteps (a timestep begun with a task counts, as the Start-Kit counts
every timestep an agent starts with one). ``tasks_finished`` counts the orders completed by the horizon.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Any

from fleetsim.orders import LorrSetup

__all__ = ["HoldClock", "LorrCounts", "lorr_counts"]


class HoldClock:
    """Per vehicle, the seconds it held an order (assigned, not completed), kept as the holders change."""

    def __init__(self) -> None:
        self._since: dict[int, float] = {}
        self._held: dict[int, float] = {}

    def update(self, holding: Iterable[int], now: float) -> None:
        """The vehicles holding orders from ``now`` on."""
        holding = frozenset(holding)
        for vehicle in sorted(holding.difference(self._since)):
            self._since[vehicle] = now
        for vehicle in sorted(set(self._since).difference(holding)):
            since = self._since.pop(vehicle)
            self._held[vehicle] = self._held.get(vehicle, 0.0) + (now - since)

    def totals(self, end: float) -> dict[int, float]:
        """Each vehicle's seconds holding orders up to ``end`` (those still holding, up to it)."""
        totals = dict(self._held)
        for vehicle, since in self._since.items():
            totals[vehicle] = totals.get(vehicle, 0.0) + max(0.0, end - since)
        return totals


@dataclass(frozen=True, slots=True)
class LorrCounts:
    """The competition's counts of a run of a League problem, beside fleetsim's measures.

    Attributes:
        setup: The problem ([`LorrSetup`][fleetsim.orders.LorrSetup]): file, edition, team, pool, horizon.
        tasks_revealed: Tasks revealed (released) by the end of the run.
        tasks_finished: Tasks with every errand done within the horizon (``numTaskFinished``).
        sum_of_cost: Timesteps with an assigned, unfinished task, summed over the robots (``sumOfCost``).
        makespan: The largest of those per-robot counts (``makespan``).
        cost: Each robot's count, by vehicle id (every robot, 0 for one that never had a task).
    """

    setup: LorrSetup
    tasks_revealed: int
    tasks_finished: int
    sum_of_cost: int
    makespan: int
    cost: Mapping[int, int]

    def to_dict(self) -> dict[str, Any]:
        setup = self.setup
        return {
            "problem": setup.problem,
            "edition": setup.edition,
            "team_size": setup.team_size,
            "task_pool": setup.task_pool,
            "horizon": setup.horizon,
            "timestep": setup.timestep,
            "tasks_revealed": self.tasks_revealed,
            "tasks_finished": self.tasks_finished,
            "sum_of_cost": self.sum_of_cost,
            "makespan": self.makespan,
            "cost": [self.cost[vehicle] for vehicle in sorted(self.cost)],
            "not_mapped": list(setup.not_mapped),
        }


def lorr_counts(
    setup: LorrSetup, vehicles: Iterable[int], held: Mapping[int, float], revealed: int, finished: int
) -> LorrCounts:
    """The counts from each vehicle's seconds ``held`` holding orders (see the module docstring)."""
    cost = {vehicle: _timesteps(held.get(vehicle, 0.0), setup.timestep) for vehicle in sorted(vehicles)}
    return LorrCounts(setup, revealed, finished, sum(cost.values()), max(cost.values(), default=0), cost)


def _timesteps(seconds: float, timestep: float) -> int:
    return max(0, math.ceil(seconds / timestep - 1e-6))

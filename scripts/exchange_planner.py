"""The planner process of docs/protocol-exchange.md: ``python scripts/exchange_planner.py LOG``.

A first planner as it is often written: BFSPlanner's routes, but every leg driven in the progress
direction the task asks for at its goal (nose first, or backing, all the way). Served over the JSON-lines
protocol one request per call (``fleetsim.exec.client.serve``), it writes every line it reads and every
line it answers to LOG, prefixed ``> `` (from fleetsim) and ``< `` (to fleetsim), and ``> EOF`` when
fleetsim closes its stdin.
"""

from __future__ import annotations

import io
import sys
from collections.abc import Iterator
from dataclasses import replace
from typing import IO

from fleetsim import FleetPlan, FleetSnapshot, Layout, RouteError, Task
from fleetsim.exec.client import serve
from fleetsim.planners import BFSPlanner
from fleetsim.planning.plans import Response


class GoalProgressPlanner:
    """BFSPlanner, with each new plan's legs all in the goal's progress direction (when the task names one)."""

    def __init__(self) -> None:
        self.routes = BFSPlanner()

    def plan_routes(self, task: Task, fleet: FleetSnapshot, layout: Layout) -> Response:
        return [self._goal_progress(item, task) for item in self.routes.plan_routes(task, fleet, layout)]

    def fix_legs(self, task: Task, fleet: FleetSnapshot, layout: Layout) -> Response:
        return self.routes.fix_legs(task, fleet, layout)

    @staticmethod
    def _goal_progress(item: FleetPlan | RouteError, task: Task) -> FleetPlan | RouteError:
        if not isinstance(item, FleetPlan) or task.goal_progress is None:
            return item
        legs = [leg if leg.fixed else replace(leg, progress=task.goal_progress) for leg in item.legs]
        return FleetPlan(item.vehicle_id, tuple(legs))


class Logged:
    """fleetsim's lines as the planner reads them, each also written to the log."""

    def __init__(self, source: IO[bytes], log: IO[str]) -> None:
        self.source = source
        self.log = log

    def __iter__(self) -> Iterator[bytes]:
        for line in self.source:
            self.log.write("> " + line.decode("utf-8").rstrip("\n") + "\n")
            self.log.flush()
            yield line
        self.log.write("> EOF\n")
        self.log.flush()


class LoggedAnswers(io.StringIO):
    """The planner's answers, written to its stdout and to the log."""

    def __init__(self, log: IO[str]) -> None:
        super().__init__()
        self.log = log

    def write(self, text: str) -> int:
        sys.stdout.write(text)
        for line in text.splitlines():
            self.log.write("< " + line + "\n")
        return len(text)

    def flush(self) -> None:
        sys.stdout.flush()
        self.log.flush()


def main(argv: list[str]) -> int:
    (log_path,) = argv
    with open(log_path, "w", encoding="utf-8") as log:
        return serve(GoalProgressPlanner(), Logged(sys.stdin.buffer, log), LoggedAnswers(log), rounds=False)  # type: ignore[arg-type]


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

"""Planners for the sweep tests; workers import this module through PYTHONPATH."""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

from fleetsim.planners import BFSPlanner, ReservingPlanner


class SlowReserving(ReservingPlanner):
    """ReservingPlanner that takes a moment to start, so a sweep lasts long enough to lose a worker."""

    def __init__(self) -> None:
        time.sleep(0.15)
        super().__init__()


class SlowBFS(BFSPlanner):
    def __init__(self) -> None:
        time.sleep(0.15)
        super().__init__()


class Exploding:
    """A planner whose constructor raises: its runs fail, the sweep goes on."""

    def __init__(self) -> None:
        raise RuntimeError("boom in the constructor")

    def plan_routes(self, *args: Any) -> list[Any]:
        return []

    def fix_legs(self, *args: Any) -> list[Any]:
        return []


class TablePlanner(ReservingPlanner):
    """ReservingPlanner that needs a data file: ``planner_options: {table: PATH}``, read from the scenario's
    folder (``scenario_dir``), whose first line must be ``fleetsim table``. Without it, it cannot start."""

    def __init__(self, table: str = "", scenario_dir: Path | None = None) -> None:
        if not table or scenario_dir is None:
            msg = f"TablePlanner needs planner_options: {{table: FILE}} and a scenario folder (got {table=!r}, {scenario_dir=!r})"
            raise ValueError(msg)
        first = (Path(scenario_dir) / table).read_text(encoding="utf-8").splitlines()[0]
        if first != "fleetsim table":
            raise ValueError(f"{table}: the first line is {first!r}, not 'fleetsim table'")
        self.table = table
        super().__init__()

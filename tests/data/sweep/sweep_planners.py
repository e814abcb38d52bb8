"""Planners for the sweep tests; workers import this module through PYTHONPATH."""

from __future__ import annotations

import time
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

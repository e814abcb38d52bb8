"""Where a pytest session keeps fleetsim's state, and what the hooks and items ask of it; a module of its
own, importing nothing of the plugin's, so that the plugin can ask whether the state exists without
importing the harness (the state itself is ``pytest_fleetsim._state.FleetsimState``)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Protocol

import pytest

if TYPE_CHECKING:
    from fleetsim.specs.python import PlannerFactory

__all__ = ["STATE_KEY", "SessionState"]


class SessionState(Protocol):
    """The session's fleetsim state as the plugin's hooks and the scenario items use it."""

    planner: PlannerFactory | None
    stopped_by: int | None  # the stop signal that ended a scenario; the session ends after its report

    def run_item(self, item: pytest.Function, fixture_value: object) -> None:
        """Run a scenario item with the planner the fixture gave; raise its failure story if it failed."""

    def pytest_runtest_logreport(self, report: pytest.TestReport) -> None:
        """A test report (on pytest-xdist's controller, from whichever worker ran the test)."""

    def finish(self, session: pytest.Session) -> None:
        """At the session's end: write lock files and metrics, compare with the baseline."""

    def summary_lines(self) -> list[str]:
        """The terminal summary's lines."""


STATE_KEY = pytest.StashKey[SessionState]()

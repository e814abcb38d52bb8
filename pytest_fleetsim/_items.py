"""Suite files as pytest collectors, scenarios as pytest test functions.

A scenario item is a real :class:`pytest.Function`, so fixtures (the user's ``fleetsim_planner``
override, autouse fixtures), markers (suite ``tags``), ``-k`` and ``xfail`` behave as for any test.
Its report points at the scenario's line in the suite file and shows fleetsim's own failure story
instead of a traceback through the harness.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import pytest

from fleetsim.errors import FleetsimError
from fleetsim.load.suites.suite import ScenarioSpec, Suite, load_suite
from pytest_fleetsim._key import STATE_KEY

__all__ = ["ScenarioFailed", "ScenarioItem", "ScenarioNotLoaded", "SuiteFile"]


class _Story(Exception):
    """``report`` is the text pytest shows for the failure, instead of a traceback through the harness."""

    def __init__(self, report: str) -> None:
        self.report = report
        super().__init__(report)


class ScenarioFailed(_Story):
    """A scenario failed (a suite's ``xfail`` expects this)."""


class ScenarioNotLoaded(_Story):
    """A scenario's files did not load: it never ran, and no ``xfail`` excuses that (as in ``fleetsim run``)."""


class SuiteFile(pytest.File):
    """A ``*.fleetsim.yaml`` file: one test per scenario, in file order."""

    def collect(self) -> Iterator[ScenarioItem]:
        try:
            suite = load_suite(self.path)
        except FleetsimError as error:
            raise self.CollectError(f"fleetsim could not load this suite:\n{error}") from None
        for index, spec in enumerate(suite.scenarios):
            item = ScenarioItem.from_parent(
                self, name=spec.name, callobj=fleetsim_scenario, suite=suite, spec=spec, index=index
            )
            for tag in spec.tags:
                self.config.addinivalue_line("markers", f"{tag}: fleetsim suite tag")  # for --strict-markers
                item.add_marker(tag)
            if spec.xfail is not None:
                item.add_marker(pytest.mark.xfail(reason=spec.xfail, raises=ScenarioFailed))
            yield item


def fleetsim_scenario(fleetsim_planner: object, request: pytest.FixtureRequest) -> None:
    """Simulate this scenario with the planner from the ``fleetsim_planner`` fixture and judge it."""
    item = request.node
    assert isinstance(item, ScenarioItem)
    item.config.stash[STATE_KEY].run_item(item, fleetsim_planner)


class ScenarioItem(pytest.Function):
    """One scenario of a suite file."""

    def __init__(self, *, suite: Suite, spec: ScenarioSpec, index: int, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self.suite = suite
        self.spec = spec
        self.index = index  # position in the suite file, for ordering reports from several workers
        self.fleetsim_payload: dict[str, Any] | None = None  # set by the run, sent with the report

    def reportinfo(self) -> tuple[Any, int, str]:
        return self.path, self.spec.line - 1, f"scenario {self.spec.name}"

    def repr_failure(self, excinfo: pytest.ExceptionInfo[BaseException]) -> Any:  # type: ignore[override]
        if isinstance(excinfo.value, _Story):
            return excinfo.value.report
        return super().repr_failure(excinfo)

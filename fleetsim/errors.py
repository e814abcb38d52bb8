"""One error hierarchy for everything fleetsim rejects.

Every error says *where* (file, line, column or field, object id) and *what* is wrong, showing the
offending value's repr. Each class also subclasses the builtin it resembles so callers may catch either.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

__all__ = [
    "FleetsimError",
    "LayoutError",
    "LoadError",
    "LoadErrors",
    "Location",
    "MapError",
    "MasterControlError",
    "PlannerError",
    "PlannerProcessError",
    "ScenarioError",
    "ScenarioFileError",
    "SuiteError",
    "SuiteErrors",
    "UnreachableTaskError",
]


@dataclass(frozen=True, slots=True)
class Location:
    """A place in a user's file: ``path[:line[:column]]`` plus the field or object concerned."""

    path: Path | str
    line: int | None = None
    column: int | None = None
    field: str | None = None
    object_id: int | None = None

    def __str__(self) -> str:
        text = str(self.path)
        if self.line is not None:
            text += f":{self.line}"
            if self.column is not None:
                text += f":{self.column}"
        if self.object_id is not None:
            text += f": object {self.object_id}"
        if self.field is not None:
            text += f": field {self.field!r}"
        return text


class FleetsimError(Exception):
    """Root of every error fleetsim raises about user input or a run."""


class LoadError(FleetsimError, ValueError):
    """A file could not be loaded; ``location`` says where and ``problem`` says what is wrong."""

    def __init__(self, problem: str, location: Location | None = None) -> None:
        self.problem = problem
        self.location = location
        super().__init__(f"{location}: {problem}" if location is not None else problem)


class LoadErrors(LoadError):
    """Several load errors found in one pass over a scenario's or suite's files, reported together.

    `errors` are the located errors in the order they were found (file by file, row by row);
    `omitted` counts, per file, the further errors left out after the cap of 50 per file.
    `location` is the first error's. A scenario or suite with a `LoadErrors` is not loaded at all;
    a single error is raised as itself, never wrapped. Catch `LoadError` to handle one or many.
    """

    def __init__(self, errors: Sequence[LoadError], omitted: Mapping[str, int] | None = None) -> None:
        if not errors:
            msg = "LoadErrors needs at least one error"
            raise ValueError(msg)
        self.errors = tuple(errors)
        self.omitted = dict(omitted or {})
        lines = [f"{len(self.errors) + sum(self.omitted.values())} errors:"]
        lines += [f"  {_indented(str(error))}" for error in self.errors]
        lines += [f"  ... and {count} more in {path}" for path, count in self.omitted.items()]
        first = self.errors[0]
        self.problem = "\n".join(lines)
        self.location = first.location
        Exception.__init__(self, self.problem)


def _indented(text: str) -> str:
    return text.replace("\n", "\n    ")


class MapError(LoadError):
    """A Tiled map (or one of its templates) is unusable."""


class ScenarioFileError(LoadError):
    """``vehicles.csv`` or ``tasks.csv`` is malformed or refers to something that does not exist."""


class UnreachableTaskError(ScenarioFileError):
    """A task whose goal its vehicle cannot reach from where it will be (its start, or its previous
    task's goal), found before any run. ``location`` is the task's row in ``tasks.csv``.

    ``notes`` are the map warnings and layout lint of the scenario, which often show the cause (a gap
    between two segment ends); ``fleetsim validate`` prints them with the error.
    """

    def __init__(
        self,
        problem: str,
        location: Location | None = None,
        *,
        task_id: int,
        vehicle_id: int,
        goal_segment: int,
        notes: tuple[str, ...] = (),
    ) -> None:
        self.task_id = task_id
        self.vehicle_id = vehicle_id
        self.goal_segment = goal_segment
        self.notes = notes
        super().__init__(problem, location)


class SuiteError(LoadError):
    """A ``*.fleetsim.yaml`` suite is malformed or violates the suite schema."""


class SuiteErrors(LoadErrors, SuiteError):
    """Several mistakes in one `*.fleetsim.yaml` suite, reported together: a `LoadErrors` that is
    also a `SuiteError`, so code that catches either keeps working."""


class ScenarioError(FleetsimError, ValueError):
    """A scenario built in code names what it does not have: a task's goal segment or a vehicle's start
    segment that is not in its layout, or a task for a vehicle it does not have. Raised when the
    [`Scenario`][fleetsim.scenario.Scenario] is made, before any run; loaded scenarios have these checked
    at their files' rows (a [`ScenarioFileError`][fleetsim.errors.ScenarioFileError]).

    ``problems`` lists each, in the scenario's order (vehicles, then tasks).
    """

    def __init__(self, message: str, problems: Sequence[str] = ()) -> None:
        self.problems = tuple(problems)
        super().__init__(message)


class LayoutError(FleetsimError, ValueError):
    """Segments cannot form a layout (for example two segments share an id)."""


class PlannerError(FleetsimError, TypeError):
    """A planner broke the protocol: it raised, returned something that is not a response, or hung.

    ``vehicle_id`` is the vehicle whose call it was, where one is known.
    """

    def __init__(self, message: str, *, vehicle_id: int | None = None) -> None:
        self.vehicle_id = vehicle_id
        super().__init__(message)


class PlannerProcessError(PlannerError):
    """A planner process failed (see :mod:`fleetsim.exec`): ``details`` is the tail of its stderr."""

    def __init__(self, message: str, details: str = "") -> None:
        self.details = details
        super().__init__(message)


class MasterControlError(PlannerError):
    """A VDA 5050 master control cannot drive the run (see :mod:`fleetsim.vda5050`): it could not be
    started, exited, lost its connection, went OFFLINE with tasks queued, or never spoke. A fault fleetsim
    expects: the message is the whole sentence the run's ``planner-error`` shows, with no traceback."""

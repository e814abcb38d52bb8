"""Dispatcher specs: ``module:attr`` names a dispatcher class or zero-argument factory (issue 45).

A suite entry's ``dispatcher:``, ``fleetsim run --dispatcher`` and ``pytest --dispatcher`` take one. It is
read as a planner spec is (``fleetsim.specs.python``: the module imported once, the current working
directory importable, the user's own import errors shown as their message and place), and every mistake
is one ``DispatcherSpecError`` saying what is wrong; a fresh dispatcher is made for every run.
"""

from __future__ import annotations

import inspect
from collections.abc import Callable
from dataclasses import dataclass
from typing import cast

from fleetsim.dispatch.protocol import Dispatcher
from fleetsim.specs import python

__all__ = ["DispatcherFactory", "DispatcherSpecError", "import_dispatcher_factory"]

EXAMPLE = "fleetsim.dispatchers:NearestVehicleDispatcher"


class DispatcherSpecError(python.SpecError):
    """A dispatcher spec cannot give dispatchers: malformed, not importable, not callable, or makes none."""


@dataclass(frozen=True, slots=True)
class DispatcherFactory:
    """Makes a fresh dispatcher per call; ``spec`` is the identity shown in results."""

    spec: str
    make: Callable[[], object]

    def __call__(self) -> Dispatcher:
        try:
            dispatcher = self.make()
        except Exception as exc:  # the user's constructor: report it, do not crash the harness
            msg = f"dispatcher spec {self.spec!r}: {python._name(self.make)}() raised {python._exception_line(exc)}"
            raise DispatcherSpecError(msg + python._where(exc), self.spec, python._user_traceback(exc)) from None
        if not callable(getattr(dispatcher, "dispatch", None)):
            msg = (
                f"dispatcher spec {self.spec!r}: {python._name(self.make)}() returned {dispatcher!r}, which has no "
                "callable dispatch; a dispatcher needs dispatch(board, fleet, layout)"
            )
            raise DispatcherSpecError(msg, self.spec)
        return cast(Dispatcher, dispatcher)


def import_dispatcher_factory(spec: str) -> DispatcherFactory:
    """The factory that a ``module:attr`` spec names: a dispatcher class or zero-argument factory.

    Every mistake in ``spec`` is a [`DispatcherSpecError`][fleetsim.specs.dispatcher.DispatcherSpecError].
    """
    try:
        module_name, attr_path = python._split(spec)
        target = python._resolve(spec, python._import(spec, module_name), attr_path)
    except python.PlannerSpecError as error:
        # The planner spec's reading, word for word, but for what the spec names here.
        words = str(error).replace("planner spec", "dispatcher spec").replace(python.EXAMPLE, EXAMPLE)
        raise DispatcherSpecError(words, spec, error.details) from None
    if not callable(target):
        msg = f"dispatcher spec {spec!r} names {python._describe(target)}, which is not callable; it must be a dispatcher class or a zero-argument function returning one"
        raise DispatcherSpecError(msg, spec)
    if inspect.isclass(target) and not callable(getattr(target, "dispatch", None)):
        msg = f"dispatcher spec {spec!r}: class {target.__qualname__} has no dispatch method; a dispatcher needs dispatch(board, fleet, layout)"
        raise DispatcherSpecError(msg, spec)
    return DispatcherFactory(spec, cast(Callable[[], object], target))

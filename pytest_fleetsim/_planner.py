"""What the ``fleetsim_planner`` fixture may give, turned into fresh planners and a stable identity.

The fixture may return a planner factory from ``--planner`` (the plugin's own fixture), a planner class,
a zero-argument function returning a planner, or a planner instance. Every run needs a fresh planner
(hash recording runs a scenario twice), so an instance is deep-copied before its first use and each
further run gets a copy of that pristine copy.

A planner spec is read as :func:`fleetsim.exec.spec.load_planner_factory` reads it, but the exec protocol
(its package, the JSON Schemas it validates with) is imported only for an ``exec:`` spec, so a session
testing an in-process planner does not pay for it.
"""

from __future__ import annotations

import copy
import inspect
from collections.abc import Callable
from dataclasses import dataclass
from typing import cast

from fleetsim.planning.protocol import Planner
from fleetsim.scenario import PlannerSetup
from fleetsim.specs.python import METHODS, PlannerFactory, PlannerSpecError, import_planner_factory

__all__ = ["PlannerSource", "load_factory", "planner_source"]

EXEC_PREFIX = "exec:"  # fleetsim.exec.spec.EXEC_PREFIX, which this module must not import to read it
VDA5050_PREFIX = "vda5050:"  # likewise fleetsim.vda5050.spec.VDA5050_PREFIX


def load_factory(spec: str, *, call_timeout: float | None) -> PlannerFactory:
    """The factory ``spec`` names (:class:`PlannerSpecError` for a mistake in it); the exec protocol is
    imported for an ``exec:`` spec only."""
    if spec.startswith(EXEC_PREFIX):
        from fleetsim.exec.spec import load_planner_factory

        return load_planner_factory(spec, call_timeout=call_timeout)
    if spec.startswith(VDA5050_PREFIX):
        from fleetsim.vda5050 import load_vda5050_factory

        return load_vda5050_factory(spec)
    return import_planner_factory(spec)


@dataclass(frozen=True, slots=True)
class PlannerSource:
    """Fresh planners on demand; ``identity`` keys recorded hashes (``module:attr``)."""

    identity: str
    make: Callable[[], Planner]
    from_option: bool  # built from --planner / the ini option (so a command can repeat it)

    def for_setup(self, setup: PlannerSetup) -> Callable[[], Planner]:
        """Fresh planners made with a suite entry's ``setup`` (its planner_options and folder); a planner
        instance (copied for each run) cannot take options: a :class:`PlannerSpecError` if there are any."""
        if isinstance(self.make, PlannerFactory):
            return self.make.for_setup(setup)
        if setup.options:
            where = f"{setup.where}: " if setup.where else ""
            msg = (
                f"{where}the fleetsim_planner fixture returned a planner instance, which cannot be made with the "
                f"scenario's planner_options {dict(setup.options)!r}; return its class or a factory instead"
            )
            raise PlannerSpecError(msg, self.identity)
        return self.make


def _path(obj: object) -> str:
    return f"{getattr(obj, '__module__', '?')}:{getattr(obj, '__qualname__', type(obj).__qualname__)}"


def _is_planner(obj: object) -> bool:
    return not inspect.isclass(obj) and all(callable(getattr(obj, name, None)) for name in METHODS)


def planner_source(value: object) -> PlannerSource:
    """The source for a ``fleetsim_planner`` fixture value; :class:`PlannerSpecError` if it is none."""
    if isinstance(value, PlannerFactory):
        return PlannerSource(value.spec, value, from_option=True)
    if _is_planner(value):
        try:
            pristine = cast(Planner, copy.deepcopy(value))  # _is_planner: it has both planner methods
        except Exception as exc:  # a planner holding a socket, a lock, ...
            msg = (
                f"the fleetsim_planner fixture returned a planner instance that cannot be copied "
                f"({type(exc).__name__}: {exc}); return its class or a zero-argument factory instead, so every "
                "run gets a fresh planner"
            )
            raise PlannerSpecError(msg, _path(type(value))) from None
        return PlannerSource(_path(type(value)), lambda: copy.deepcopy(pristine), from_option=False)
    if callable(value):
        identity = _path(value)
        return PlannerSource(identity, PlannerFactory(identity, value), from_option=False)
    msg = (
        f"the fleetsim_planner fixture returned {value!r}; it must return a planner (an object with "
        "plan_routes and fix_legs), a planner class, or a zero-argument function that makes one"
    )
    raise PlannerSpecError(msg, repr(value))

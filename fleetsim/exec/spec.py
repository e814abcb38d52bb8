"""A planner spec of any form (SPEC §14): ``module:attr``, a planner imported into this process
(``fleetsim.specs.python``), ``exec:COMMAND``, a planner process per run speaking the JSON-lines
protocol, or ``vda5050:...``, the vehicles as VDA 5050 vehicles driven by a master control
(``fleetsim.vda5050.spec``). The command line, the pytest plugin and sweeps read ``--planner`` through
this module.
"""

from __future__ import annotations

import functools
from pathlib import Path
from typing import Any

from fleetsim.exec.process import SubprocessPlanner
from fleetsim.specs.python import PlannerFactory, command_words, import_planner_factory

__all__ = ["EXEC_PREFIX", "VDA5050_PREFIX", "load_planner_factory"]

EXEC_PREFIX = "exec:"
VDA5050_PREFIX = "vda5050:"  # fleetsim.vda5050.spec.VDA5050_PREFIX, read without importing the extra


def load_planner_factory(spec: str, *, call_timeout: float | None = 10.0) -> PlannerFactory:
    """The factory that ``spec`` names: ``module:attr`` (a planner class or zero-argument factory; attr
    possibly dotted), or ``exec:COMMAND``, a planner process per run speaking the JSON-lines protocol
    (whose per-call timeout is ``call_timeout`` seconds, and whose init message carries a run's planner
    options and scenario folder).

    The factory makes a fresh planner for every run; the current working directory is importable.
    Every mistake in ``spec`` is a [`PlannerSpecError`][fleetsim.specs.python.PlannerSpecError].
    """
    if isinstance(spec, str) and spec.startswith(EXEC_PREFIX):
        return _exec_factory(spec, call_timeout)
    if isinstance(spec, str) and spec.startswith(VDA5050_PREFIX):
        from fleetsim.vda5050 import load_vda5050_factory

        return load_vda5050_factory(spec)
    return import_planner_factory(spec)


def _exec_factory(spec: str, call_timeout: float | None) -> PlannerFactory:
    empty = f"planner spec {spec!r} names no command; write exec:COMMAND, e.g. 'exec:node planner.js'"
    command = list(command_words(spec, spec[len(EXEC_PREFIX) :], whose="the", empty=empty))
    return PlannerFactory(spec, functools.partial(_planner_process, command, call_timeout))


def _planner_process(
    command: list[str], timeout: float | None, /, scenario_dir: Path | None = None, **planner_options: Any
) -> SubprocessPlanner:
    """A planner process for one run: any planner options go to it in the init message, with the
    scenario's folder (what the process makes of them is its own business)."""
    return SubprocessPlanner(command, timeout=timeout, planner_options=planner_options, scenario_dir=scenario_dir)

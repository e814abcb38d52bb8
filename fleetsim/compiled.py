"""The modules an optional compiled build of fleetsim compiles with mypyc, and which are compiled here.

fleetsim is pure Python, and that is how it installs by default. Its hot paths (the motion, the plan
checks and the controller, the reference planners, the trace and the contact check) may also be
compiled to C extension modules with mypyc, from the same source, for a faster run with the same
answers: every trace hash is the same either way (docs/performance.md, "The compiled build").
``setup.py`` reads :data:`COMPILED_MODULES` when the build is asked for (``FLEETSIM_COMPILE=1``);
:func:`compiled_modules` says which of them this installation runs compiled.
"""

from __future__ import annotations

import importlib.util
from importlib.machinery import EXTENSION_SUFFIXES

__all__ = ["COMPILED_MODULES", "build_note", "compiled_modules"]

# A plain tuple of string literals: setup.py reads it without importing fleetsim.
COMPILED_MODULES = (
    "fleetsim.contact.geometry",
    "fleetsim.contact.monitor",
    "fleetsim.layout.reachability",
    "fleetsim.layout.segment",
    "fleetsim.motion.driver",
    "fleetsim.motion.profile",
    "fleetsim.motion.slowdown",
    "fleetsim.motion.track",
    "fleetsim.planners.bfs",
    "fleetsim.planners.choreography",
    "fleetsim.planners.fleet_index",
    "fleetsim.planners.greedy",
    "fleetsim.planners.making_way",
    "fleetsim.planners.reserving",
    "fleetsim.planners.routing",
    "fleetsim.planning.checks",
    "fleetsim.planning.controller",
    "fleetsim.planning.quiet",
    "fleetsim.planning.reservations",
    "fleetsim.planning.snapshot",
    "fleetsim.planning.tasks",
    "fleetsim.planning.views",
    "fleetsim.sim.loop",
    "fleetsim.sim.trace",
)


def compiled_modules() -> list[str]:
    """The modules of :data:`COMPILED_MODULES` this installation loads from compiled extension modules
    (empty for the pure-Python install). Found without running them."""
    compiled = []
    for name in COMPILED_MODULES:
        spec = importlib.util.find_spec(name)
        if spec is not None and (spec.origin or "").endswith(tuple(EXTENSION_SUFFIXES)):
            compiled.append(name)
    return compiled


def build_note() -> str:
    """How this installation runs, for ``fleetsim --version``."""
    compiled = compiled_modules()
    if not compiled:
        return "pure Python"
    return f"compiled: {len(compiled)} of {len(COMPILED_MODULES)} hot-path modules"

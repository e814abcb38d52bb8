"""A run's record: the one JSON document of a run, whoever ran it (``schemas/result.schema.json``).

``fleetsim run --json`` prints it, a run folder's ``result.json`` holds it (``fleetsim run --record``, the
pytest plugin, a sweep), and a sweep's results file has one per line. :func:`run_record` alone builds it,
so the producers cannot drift apart: the run's own keys (:meth:`RunResult.to_dict`), the keys of the
suite entry the scenario came from (:data:`ENTRY_KEYS`, in every record, ``null`` where there is no
entry), and the producer's own keys (:data:`PRODUCER_KEYS`, listed here and in the schema, and only
these).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import Any

from fleetsim.load.suites.suite import ScenarioSpec
from fleetsim.sim.result import RunResult

__all__ = ["ENTRY_KEYS", "PRODUCER_KEYS", "RunOrigin", "run_record"]

# What every record says of the suite entry its scenario came from.
ENTRY_KEYS = ("suite", "line", "xfail", "planner_options")

# The keys only some producers add, by producer: what a reader may find besides the run's and the entry's.
PRODUCER_KEYS: Mapping[str, tuple[str, ...]] = MappingProxyType(
    {
        "pytest": ("nodeid",),  # a result.json written under pytest
        "hunt": ("generated", "shrink_runs"),  # a generated entry's (or a disturbance hunt's) counts
        "sweep": ("key", "id", "source", "seed", "repetition", "vehicles", "error"),
    }
)
_OWN = frozenset(key for keys in PRODUCER_KEYS.values() for key in keys)


@dataclass(frozen=True, slots=True)
class RunOrigin:
    """Where a run comes from, for its record.

    Attributes:
        suite: The suite file, as the producer names it, or ``None`` (a scenario a sweep generated).
        line: The line of the scenario's entry in the suite file, or ``None``.
        xfail: The entry's ``xfail`` reason, or ``None``.
        planner_options: The entry's ``planner_options``, which the planner was made with.
        own: The producer's own keys (each one of :data:`PRODUCER_KEYS`).
    """

    suite: str | None = None
    line: int | None = None
    xfail: str | None = None
    planner_options: Mapping[str, Any] = field(default_factory=lambda: MappingProxyType({}))
    own: Mapping[str, Any] = field(default_factory=lambda: MappingProxyType({}))

    def __post_init__(self) -> None:
        unknown = sorted(set(self.own) - _OWN)
        if unknown:
            msg = f"own={unknown!r}: a record's own keys must be among PRODUCER_KEYS ({', '.join(sorted(_OWN))})"
            raise ValueError(msg)

    @classmethod
    def of_entry(cls, suite: Path | str, spec: ScenarioSpec | None, **own: Any) -> RunOrigin:
        """The origin of a run of suite entry ``spec`` (``None``: the suite did not load) in ``suite``."""
        if spec is None:
            return cls(str(suite), own=own)
        options = spec.planner_setup.options
        return cls(str(suite), spec.line, spec.xfail, options, own)

    def keys(self) -> dict[str, Any]:
        """The keys a record adds to the run's: the entry's, then the producer's own."""
        entry = {"suite": self.suite, "line": self.line, "xfail": self.xfail}
        return {**entry, "planner_options": dict(self.planner_options), **self.own}


def run_record(result: RunResult, origin: RunOrigin) -> dict[str, Any]:
    """The record of ``result``, a run of a scenario from ``origin``: what every producer writes."""
    return {**result.to_dict(), **origin.keys()}

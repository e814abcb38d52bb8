"""The published JSON Schema of a run's result (``schemas/result.schema.json``), for readers of results.

One format for every producer: a line of ``fleetsim run --json``, a run folder's ``result.json`` and a
sweep's record are :meth:`fleetsim.sim.result.RunResult.to_dict` plus the producer's own keys, which
the schema lists too. Readers of result documents written elsewhere (a sweep's results file fed to
``--fleetsim-compare``, say) check them here first, so a hand-edited or foreign file fails with the
key and the value that are wrong rather than half-way through.
"""

from __future__ import annotations

from typing import Any

from fleetsim.json_schemas import load_schema_file, violation

__all__ = ["result_problem", "result_schema"]


def result_schema() -> dict[str, Any]:
    """The result schema shipped inside the package."""
    return load_schema_file("result.schema.json").document


def result_problem(document: Any) -> str | None:
    """``None`` for a valid result document, else its most relevant violation in words: where (a path
    such as ``metrics.makespan``) and what is wrong with the value there."""
    return violation(load_schema_file("result.schema.json"), document, whole="the result")

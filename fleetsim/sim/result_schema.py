"""The published JSON Schema of a run's result (``schemas/result.schema.json``), for readers of results.

One format for every producer: a line of ``fleetsim run --json``, a run folder's ``result.json`` and a
sweep's record are :meth:`fleetsim.sim.result.RunResult.to_dict` plus the producer's own keys, which
the schema lists too. Readers of result documents written elsewhere (a sweep's results file fed to
``--fleetsim-compare``, say) check them here first, so a hand-edited or foreign file fails with the
key and the value that are wrong rather than half-way through.
"""

from __future__ import annotations

import importlib.resources
import json
from functools import cache
from typing import Any

import jsonschema
import jsonschema_rs

__all__ = ["result_problem", "result_schema"]


@cache
def result_schema() -> dict[str, Any]:
    """The result schema shipped inside the package."""
    text = (importlib.resources.files("fleetsim") / "schemas" / "result.schema.json").read_text("utf-8")
    schema: dict[str, Any] = json.loads(text)
    return schema


@cache
def _validators() -> tuple[Any, jsonschema.Draft202012Validator]:
    """The schema compiled twice, as the planner protocol's are: jsonschema-rs decides quickly whether a
    document is valid (a sweep's file holds thousands), jsonschema explains a violation."""
    return jsonschema_rs.validator_for(result_schema()), jsonschema.Draft202012Validator(result_schema())


def result_problem(document: Any) -> str | None:
    """``None`` for a valid result document, else its most relevant violation in words: where (a path
    such as ``metrics.makespan``) and what is wrong with the value there."""
    fast, precise = _validators()
    if fast.is_valid(document):
        return None
    error = jsonschema.exceptions.best_match(precise.iter_errors(document))
    if error is None:
        return None
    where = "".join(f"[{part}]" if isinstance(part, int) else f".{part}" for part in error.absolute_path)
    return f"{where.lstrip('.') or 'the result'}: {error.message}"

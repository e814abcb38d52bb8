"""The published JSON Schema of a run's trace (``schemas/trace.schema.json``), for readers of traces.

A trace (``trace.jsonl``) is JSON lines: a header object, then one array per step. The schema describes
one line, either kind; :func:`trace_problem` also checks what no single line can show: that the header
comes first and the steps follow it numbered from 0, one by one. Readers of traces written elsewhere (a
run folder copied from CI, a trace another tool made) check them here first, so a foreign or hand-edited
line fails with its line number, the element and the value that are wrong.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

import jsonschema
import orjson

from fleetsim.json_schemas import load_schema_file

__all__ = ["trace_line_problem", "trace_problem", "trace_schema"]

_FILE = "trace.schema.json"
# A step line's elements, by position: a violation names the element rather than its index.
_STEP_PARTS = ("step", "vehicles", "plans", "events")


def trace_schema() -> dict[str, Any]:
    """The trace schema shipped inside the package (one line of ``trace.jsonl``)."""
    return load_schema_file(_FILE).document


def trace_line_problem(document: Any) -> str | None:
    """``None`` for a valid trace line (parsed: a header object or a step array), else its most relevant
    violation in words: where (``events[0][1]``, ``time_step_us``) and what is wrong with the value."""
    schema = load_schema_file(_FILE)
    if schema.fast.is_valid(document):
        return None
    error = jsonschema.exceptions.best_match(schema.precise.iter_errors(document))
    if error is None:
        return None
    parts = list(error.absolute_path)
    path = ""
    if isinstance(document, list) and parts and isinstance(parts[0], int) and parts[0] < len(_STEP_PARTS):
        path = _STEP_PARTS[parts.pop(0)]
    path += "".join(f"[{part}]" if isinstance(part, int) else f".{part}" for part in parts)
    return f"{path.lstrip('.') or 'the line'}: {error.message}"


def trace_problem(lines: Iterable[str]) -> str | None:
    """``None`` for a valid trace (its lines, header first, without their newlines), else the first
    problem, prefixed with its 1-based line number: a line that is not JSON, breaks the schema, is not in
    its place (the header first, then steps 0, 1, 2, ...). An empty trace has no header: a problem."""
    number = 0
    for number, line in enumerate(lines, start=1):
        try:
            document = orjson.loads(line)
        except orjson.JSONDecodeError as error:
            return f"line {number}: not JSON ({error})"
        header = number == 1
        if isinstance(document, dict) != header:
            return f"line {number}: {'the header must be an object' if header else 'a step must be an array'}"
        problem = trace_line_problem(document)
        if problem is not None:
            return f"line {number}: {problem}"
        if not header and document[0] != number - 2:
            return f"line {number}: step={document[0]!r} must be {number - 2} (steps are numbered from 0, one by one)"
    return None if number else "line 1: the trace is empty (a trace begins with its header)"

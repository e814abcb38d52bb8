"""The JSON Schemas shipped in ``fleetsim/schemas/``, compiled twice: once to decide quickly whether a
document is valid, once to explain a violation (the planner protocol's messages, a run's result, its trace's lines)."""

from __future__ import annotations

import json
from dataclasses import dataclass
from functools import cache
from pathlib import Path
from typing import Any

import jsonschema
import jsonschema_rs

__all__ = ["SCHEMAS", "Schema", "load_schema_file", "violation"]

SCHEMAS = Path(__file__).resolve().parent / "schemas"


@dataclass(frozen=True, slots=True)
class Schema:
    """A schema twice compiled: ``fast`` (jsonschema-rs, in Rust) decides whether a document is valid in
    microseconds; ``precise`` (jsonschema) explains a violation, naming the field and value."""

    document: dict[str, Any]
    fast: Any
    precise: jsonschema.protocols.Validator


@cache
def load_schema_file(file_name: str) -> Schema:
    """The validators of ``fleetsim/schemas/<file_name>``."""
    schema: dict[str, Any] = json.loads((SCHEMAS / file_name).read_text(encoding="utf-8"))
    validator_class = jsonschema.validators.validator_for(schema)
    validator_class.check_schema(schema)
    return Schema(schema, jsonschema_rs.validator_for(schema), validator_class(schema))


def violation(schema: Schema, document: Any, where: str = "", whole: str = "the answer") -> str | None:
    """``None`` for a valid document, else its most relevant violation: where (after ``where``, the
    document's own place in a larger one; ``whole`` when the document itself is wrong), and the value."""
    if schema.fast.is_valid(document):
        return None
    error = jsonschema.exceptions.best_match(schema.precise.iter_errors(document))
    if error is None:
        return None
    path = where + "".join(f"[{part!r}]" if isinstance(part, int) else f".{part}" for part in error.absolute_path)
    return f"{path.lstrip('.') or whole}: {error.message}"

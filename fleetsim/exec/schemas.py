"""The JSON Schemas of the planner protocol's messages (``schemas/planner-*.schema.json``), compiled
twice: once to decide quickly whether an answer is valid, once to explain a violation."""

from __future__ import annotations

import json
from dataclasses import dataclass
from functools import cache
from pathlib import Path
from typing import Any

import jsonschema
import jsonschema_rs

__all__ = ["SCHEMAS", "Schema", "load_schema", "violation"]

SCHEMAS = Path(__file__).resolve().parents[1] / "schemas"


@dataclass(frozen=True, slots=True)
class Schema:
    """A message schema twice compiled: ``fast`` (jsonschema-rs, in Rust) decides whether an answer is
    valid in microseconds; ``precise`` (jsonschema) explains a violation, naming the field and value."""

    fast: Any
    precise: jsonschema.protocols.Validator


@cache
def load_schema(name: str) -> Schema:
    """The validators of ``schemas/planner-<name>.schema.json``."""
    schema = json.loads((SCHEMAS / f"planner-{name}.schema.json").read_text(encoding="utf-8"))
    validator_class = jsonschema.validators.validator_for(schema)
    validator_class.check_schema(schema)
    return Schema(jsonschema_rs.validator_for(schema), validator_class(schema))


def violation(schema: Schema, document: Any, where: str = "") -> str | None:
    """``None`` for a valid document, else the first violation: where (after ``where``, the document's own
    place in a larger one), and the offending value."""
    if schema.fast.is_valid(document):
        return None
    error = jsonschema.exceptions.best_match(schema.precise.iter_errors(document))
    if error is None:
        return None
    path = where + "".join(f"[{part!r}]" if isinstance(part, int) else f".{part}" for part in error.absolute_path)
    return f"{path.lstrip('.') or 'the answer'}: {error.message}"

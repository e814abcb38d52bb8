"""What every test of a run's JSON document expects it to hold (SPEC §10), in one place: its keys, and
the published schema (``schemas/result.schema.json``) it must satisfy, checked with jsonschema."""

from __future__ import annotations

import json
from functools import cache
from pathlib import Path
from typing import Any

import jsonschema

SCHEMA = Path(__file__).resolve().parents[1] / "schemas" / "result.schema.json"

RESULT_KEYS = frozenset(
    {
        "scenario",
        "planner",
        "status",
        "failures",
        "trace_hash",
        "sim_time",
        "steps",
        "tasks",
        "rejections",
        "collisions",
        "metrics",
        "artifacts",
    }
)


@cache
def _validator() -> jsonschema.Draft202012Validator:
    schema = json.loads(SCHEMA.read_text(encoding="utf-8"))
    jsonschema.Draft202012Validator.check_schema(schema)
    return jsonschema.Draft202012Validator(schema)


def schema_errors(document: Any) -> list[str]:
    """Every way ``document`` breaks the published result schema (empty: it satisfies it)."""
    return [f"{error.json_path}: {error.message}" for error in _validator().iter_errors(document)]

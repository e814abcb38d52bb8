"""The JSON Schemas of the planner protocol's messages (``schemas/planner-*.schema.json``), compiled
twice (:mod:`fleetsim.json_schemas`): once to decide quickly whether an answer is valid, once to explain
a violation."""

from __future__ import annotations

from fleetsim.json_schemas import SCHEMAS, Schema, load_schema_file, violation

__all__ = ["SCHEMAS", "Schema", "load_schema", "violation"]


def load_schema(name: str) -> Schema:
    """The validators of ``schemas/planner-<name>.schema.json``."""
    return load_schema_file(f"planner-{name}.schema.json")

"""Checking suite data against ``suite.schema.json`` and saying what is wrong in a user's words.

jsonschema's own messages talk about schemas ("is not valid under any of the given schemas"); a suite
author wants the key, the bad value and what would be accepted, at the line and column of the value.
:func:`schema_check` reports every mistake (one error per place, every unknown key);
:func:`check_against_schema` the single most relevant one.
"""

from __future__ import annotations

import functools
import importlib.resources
import json
import math
from collections.abc import Hashable, Iterable, Iterator, Sequence
from dataclasses import dataclass
from typing import Any, cast

from jsonschema import Draft202012Validator
from jsonschema.exceptions import ValidationError, best_match

from fleetsim.errors import LoadErrors, Location, SuiteError, SuiteErrors
from fleetsim.load.common.closest import did_you_mean
from fleetsim.load.common.collect import ErrorCollector
from fleetsim.load.common.yaml_source import Locate

__all__ = [
    "SchemaCheck",
    "check_against_schema",
    "dotted_path",
    "raise_suite_errors",
    "schema_check",
    "suite_error",
    "suite_schema",
]

YamlPath = tuple[Hashable, ...]

_KINDS = {
    "object": "a mapping",
    "array": "a list",
    "string": "a string",
    "number": "a number",
    "integer": "a whole number",
    "boolean": "true or false",
    "null": "empty",
}
_BOUNDS = {"minimum": ">=", "exclusiveMinimum": ">", "maximum": "<=", "exclusiveMaximum": "<"}
_ALTERNATIVES = ("oneOf", "anyOf")


@functools.cache
def suite_schema() -> dict[str, Any]:
    """The suite JSON Schema shipped inside the package."""
    text = (importlib.resources.files("fleetsim") / "schemas" / "suite.schema.json").read_text("utf-8")
    schema: dict[str, Any] = json.loads(text)
    return schema


@functools.cache
def _validator() -> Draft202012Validator:
    return Draft202012Validator(suite_schema())


def check_against_schema(data: Any, locate: Locate) -> None:
    """Raise one :class:`SuiteError` for the most relevant schema violation in ``data``, if any."""
    for path, value in _non_finite(data, ()):  # the first, as the schema's errors would mislead
        raise suite_error(f"{value!r} is not a finite number", path, locate(path))
    error = _most_relevant(_validator().iter_errors(data), locate)
    if error is not None:
        raise _as_suite_error(error, locate)


@dataclass(frozen=True, slots=True)
class SchemaCheck:
    """What the schema says of a suite's data: every mistake, and where the data cannot be trusted.

    Attributes:
        errors: One error per place, in file order: the most relevant violation of each value (an
            alternative's branches and a value's several rules give one message), every unknown key.
        broken: The paths of every violation found (reported or not), non-finite numbers included.
        faulted: The paths of mappings and values that break a rule themselves (a missing key, a wrong
            type), as opposed to only holding an unknown key.
    """

    errors: tuple[SuiteError, ...] = ()
    broken: frozenset[YamlPath] = frozenset()
    faulted: frozenset[YamlPath] = frozenset()

    def clean(self, path: YamlPath) -> bool:
        """Whether nothing at ``path`` or below it breaks the schema (its values may be used as they are)."""
        return not any(broken[: len(path)] == path for broken in self.broken)

    def intact(self, path: YamlPath) -> bool:
        """Whether the value at ``path`` itself breaks no rule but perhaps unknown keys (its parts may)."""
        return path not in self.faulted


def schema_check(data: Any, locate: Locate) -> SchemaCheck:
    """Every schema violation of ``data``: the most relevant one per place (see :class:`SchemaCheck`).

    One mistake gives one error: the violations jsonschema reports at one value (a misspelt key also
    leaves a required one missing; each branch of a oneOf fails) are told as one, unknown keys first.
    """
    found: list[SuiteError] = []
    non_finite: set[YamlPath] = set()
    for path, value in _non_finite(data, ()):
        found.append(suite_error(f"{value!r} is not a finite number", path, locate(path)))
        non_finite.add(path)
    by_place: dict[YamlPath, list[ValidationError]] = {}
    faulted: set[YamlPath] = set()
    for error in _validator().iter_errors(data):
        path = tuple(error.absolute_path)
        by_place.setdefault(path, []).append(error)
        if not _about_keys(error):
            faulted.add(path)
    for path, errors in by_place.items():
        if path in non_finite:  # .nan also fails every bound; its own message says more
            continue
        about_keys = [error for error in errors if _about_keys(error)]
        if about_keys:
            found += [_key_error(error, key, locate) for error in about_keys for key in _keys_of(error)]
            continue
        top = _most_relevant(errors, locate)
        assert top is not None
        found.append(_as_suite_error(top, locate))
    return SchemaCheck(tuple(sorted(found, key=_position)), frozenset(non_finite | set(by_place)), frozenset(faulted))


def raise_suite_errors(errors: ErrorCollector) -> None:
    """Raise what ``errors`` holds: one error as itself, several as one :class:`SuiteErrors`."""
    try:
        errors.raise_if_any()
    except SuiteErrors:
        raise
    except LoadErrors as several:
        raise SuiteErrors(several.errors, several.omitted) from None


def _position(error: SuiteError) -> tuple[int, int]:
    location = error.location
    return (0, 0) if location is None else (location.line or 0, location.column or 0)


def _about_keys(error: ValidationError) -> bool:
    """Whether ``error`` is about keys of its mapping (unknown, or not a valid name), not its values."""
    return error.validator == "additionalProperties" or "propertyNames" in error.absolute_schema_path


def _keys_of(error: ValidationError) -> list[Hashable]:
    """The keys ``error`` is about: each unknown key, or the one badly named key."""
    if "propertyNames" in error.absolute_schema_path:
        return [cast(Hashable, error.instance)]
    schema: Any = error.schema
    value: Any = error.instance
    return [key for key in value if key not in schema.get("properties", {})]


def _key_error(error: ValidationError, key: Hashable, locate: Locate) -> SuiteError:
    path: YamlPath = tuple(error.absolute_path)
    if "propertyNames" in error.absolute_schema_path:
        problem, _ = _describe(error)
    else:
        problem = _unknown_key(key, error)
    return suite_error(problem, path, locate((*path, key), key=True))


def _unknown_key(key: Hashable, error: ValidationError) -> str:
    schema: Any = error.schema
    known = list(schema.get("properties", {}))
    return f"unknown key {key!r}{did_you_mean(str(key), known)}"


def _as_suite_error(error: ValidationError, locate: Locate) -> SuiteError:
    path: YamlPath = tuple(error.absolute_path)
    problem, key = _describe(error)
    if "propertyNames" in error.absolute_schema_path:  # the error is about a key of this mapping
        key = error.instance
    where = locate(path) if key is None else locate((*path, key), key=True)
    return suite_error(problem, path, where)


def _most_relevant(errors: Iterable[ValidationError], locate: Locate) -> ValidationError | None:
    """The one error to report.

    Like best_match's own choice (shallow errors first, oneOf/anyOf last), but ties go to the error
    earliest in the file rather than the last sibling, so a mistake repeated in every scenario is
    reported at its first occurrence.
    """

    def position(error: ValidationError) -> tuple[int, int]:
        location = locate(tuple(error.absolute_path))
        return (location.line or 0, location.column or 0)

    in_file_order = sorted(errors, key=position)
    top = max(in_file_order, key=lambda e: (-len(e.path), e.validator not in _ALTERNATIVES), default=None)
    if top is None:
        return None
    error = cast(ValidationError, best_match([top]))  # descends into oneOf/anyOf to the branch that fits best
    # When that branch's error is about the same value, "is not one of A, B or C" (every alternative)
    # says more than why branch B failed.
    while error.parent is not None and error.parent.validator in _ALTERNATIVES and not error.relative_path:
        error = cast(ValidationError, error.parent)
    return error


def suite_error(problem: str, path: Sequence[Hashable], where: Location) -> SuiteError:
    """``scenarios[1].expect.tasks: <problem>`` located at ``where``."""
    dotted = dotted_path(path)
    return SuiteError(f"{dotted}: {problem}" if dotted else problem, where)


def dotted_path(path: Sequence[Hashable]) -> str:
    """``scenarios[1].expect.collisions`` for ("scenarios", 1, "expect", "collisions")."""
    text = ""
    for step in path:
        text += f"[{step}]" if isinstance(step, int) else f".{step}" if text else str(step)
    return text


def _non_finite(value: Any, path: YamlPath) -> Iterator[tuple[YamlPath, float]]:
    """Every ``.nan`` and ``.inf`` in ``value``, in file order: schema bounds cannot catch .nan (every
    comparison with it is false), so they are checked apart."""
    if isinstance(value, float) and not math.isfinite(value):
        yield path, value
    if isinstance(value, (dict, list)):
        for key, child in value.items() if isinstance(value, dict) else enumerate(value):
            yield from _non_finite(child, (*path, key))


def _show(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def _either(choices: Sequence[str]) -> str:
    return choices[0] if len(choices) == 1 else f"{', '.join(choices[:-1])} or {choices[-1]}"


def _kind_of(value: Any) -> str:
    for kind, python_type in (("boolean", bool), ("integer", int), ("number", float), ("string", str)):
        if isinstance(value, python_type):
            return _KINDS[kind]
    if isinstance(value, dict):
        return _KINDS["object"]
    return _KINDS["array"] if isinstance(value, list) else _KINDS["null"]


def _alternatives(schemas: Sequence[dict[str, Any]]) -> str:
    values = [repr(v) for schema in schemas for v in schema.get("enum", ())]
    titles = [schema["title"] for schema in schemas if "title" in schema]
    return ("one of " if values else "") + _either(values + titles)


def _describe(error: ValidationError) -> tuple[str, Hashable | None]:
    """(problem text, the key of ``error.instance`` it is about, if it is about a key)."""
    # Plain JSON values here (the stubs allow jsonschema's "unset" marker, which a reported error never has).
    value: Any = error.instance
    rule: Any = error.validator_value
    schema: Any = error.schema
    title = schema.get("title") if isinstance(schema, dict) else None
    kind = error.validator
    if kind == "required":
        missing = next(key for key in rule if key not in value)
        if "then" in error.relative_schema_path:
            return f"give 'dir', all of 'map', 'vehicles' and 'tasks', or 'generate' ({missing!r} is missing)", None
        return f"missing required key {missing!r}", None
    if kind == "additionalProperties":
        extra = _keys_of(error)[0]
        return _unknown_key(extra, error), extra
    if kind in _ALTERNATIVES:
        return f"{_show(value)} is not {_alternatives(rule)}", None
    if kind == "enum":
        return f"{_show(value)} is not {_alternatives([schema])}", None
    if kind == "const":
        return f"{_show(value)} must be {title or repr(rule)}", None
    if kind == "type":
        expected = _either([_KINDS[t] for t in ([rule] if isinstance(rule, str) else rule)])
        return f"{_show(value)} is not {expected} (it is {_kind_of(value)})", None
    if kind in _BOUNDS:
        return f"{_show(value)} must be {_BOUNDS[kind]} {rule}", None
    if kind in ("minItems", "minProperties", "minLength") and rule == 1:
        return "must not be empty", None
    if kind == "uniqueItems":
        repeated = next(item for index, item in enumerate(value) if item in value[:index])
        return f"lists {_show(repeated)} more than once", None
    if kind == "pattern":
        return f"{_show(value)} is not {title or f'matching {rule!r}'}", None
    if kind == "not" and "dependentSchemas" in error.relative_schema_path:
        given = [key for key in ("dir", "map", "vehicles", "tasks", "orders") if key in value]
        return f"'generate' makes the scenario, so it cannot also name files ({', '.join(map(repr, given))})", None
    if kind == "not":
        return f"{_show(value)} must not be {rule.get('title', 'this value')}", None
    return error.message, None

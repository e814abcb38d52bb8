"""A JSON value together with its JSON pointer (RFC 6901), so every complaint can say where it is.

Imported site files (LIF) are checked by hand rather than by a schema: the messages then speak of the
site (``startNodeId 'N9' is not a node of layout 'hall'``) and each one names the pointer and the value.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

from fleetsim.errors import Location, MapError

__all__ = ["JsonAt", "pointer_step"]


def pointer_step(key: str | int) -> str:
    """One reference token of a JSON pointer, escaped (``~`` → ``~0``, ``/`` → ``~1``)."""
    return "/" + str(key).replace("~", "~0").replace("/", "~1")


def _kind(value: object) -> str:
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "a boolean"
    if isinstance(value, (int, float)):
        return "a number"
    if isinstance(value, str):
        return "a string"
    if isinstance(value, list):
        return "a list"
    return "an object"


@dataclass(frozen=True, slots=True)
class JsonAt:
    """``value`` found at ``pointer`` in the JSON file ``path``."""

    path: Path
    pointer: str
    value: object

    def error(self, problem: str) -> MapError:
        return MapError(problem, Location(self.path, field=self.pointer or "/"))

    def has(self, key: str) -> bool:
        return isinstance(self.value, dict) and key in self.value

    def child(self, key: str | int, value: object) -> JsonAt:
        return JsonAt(self.path, self.pointer + pointer_step(key), value)

    def keys(self) -> list[str]:
        """The keys of an object, in file order."""
        return list(self.object_value()) if isinstance(self.value, dict) else []

    def object_value(self) -> dict[str, object]:
        if not isinstance(self.value, dict):
            raise self.error(f"{self._shown()} must be an object, not {_kind(self.value)}")
        return self.value

    def get(self, key: str) -> JsonAt | None:
        """The member ``key`` of this object, or ``None`` when it is absent."""
        members = self.object_value()
        return self.child(key, members[key]) if key in members else None

    def need(self, key: str) -> JsonAt:
        """The member ``key`` of this object; its absence is an error naming this object."""
        found = self.get(key)
        if found is None:
            raise self.error(f"required member {key!r} is missing")
        return found

    def items(self, *, allow_empty: bool = True) -> Iterator[JsonAt]:
        """The items of a list, each with its pointer."""
        if not isinstance(self.value, list):
            raise self.error(f"{self._shown()} must be a list, not {_kind(self.value)}")
        if not allow_empty and not self.value:
            raise self.error("must not be empty")
        for index, item in enumerate(self.value):
            yield self.child(index, item)

    def string(self) -> str:
        if not isinstance(self.value, str):
            raise self.error(f"{self._shown()} must be a string, not {_kind(self.value)}")
        return self.value

    def identifier(self) -> str:
        """A non-empty string (an id)."""
        text = self.string()
        if not text.strip():
            raise self.error(f"{text!r} must not be empty")
        return text

    def number(self) -> float:
        value = self.value
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise self.error(f"{self._shown()} must be a number, not {_kind(value)}")
        if not math.isfinite(value):
            raise self.error(f"{value!r} must be a finite number")
        return float(value)

    def integer(self) -> int:
        number = self.number()
        if not number.is_integer():
            raise self.error(f"{self.value!r} must be a whole number")
        return int(number)

    def _shown(self) -> str:
        text = repr(self.value)
        return text if len(text) <= 60 else text[:57] + "..."

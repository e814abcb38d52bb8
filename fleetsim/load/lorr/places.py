"""Where each key of a League problem file is written, for located errors (line, column, JSON pointer)."""

from __future__ import annotations

import re
from pathlib import Path

from fleetsim.errors import Location

__all__ = ["KeyPlaces"]

_KEY = re.compile(r'"((?:[^"\\]|\\.)*)"\s*:')


class KeyPlaces:
    """Where each key of the problem file is written (line and column of its quotes), for errors: a
    top-level key's first occurrence, a ``delayConfig`` member's first after ``delayConfig``."""

    def __init__(self, path: Path, text: str) -> None:
        self.path = path
        self._found: list[tuple[str, int, int, int]] = []  # key, offset, line, column
        for match in _KEY.finditer(text):
            offset = match.start()
            line = text.count("\n", 0, offset) + 1
            column = offset - (text.rfind("\n", 0, offset) + 1) + 1
            self._found.append((match.group(1), offset, line, column))

    def at(self, key: str, within: str | None = None) -> Location:
        """The location of ``key`` (inside the object member ``within``), with its JSON pointer."""
        pointer = f"/{within}/{key}" if within else f"/{key}"
        after = -1
        if within is not None:
            after = next((offset for name, offset, _, _ in self._found if name == within), -1)
            if after < 0:
                return Location(self.path, field=pointer)
        for name, offset, line, column in self._found:
            if name == key and offset > after:
                return Location(self.path, line=line, column=column, field=pointer)
        return Location(self.path, field=pointer)

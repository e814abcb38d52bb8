"""Collecting every load error of a pass instead of stopping at the first (all errors at once).

A loader walks its whole input (every CSV row, every map object, every suite key), hands each located
error to an :class:`ErrorCollector` and, at the end, calls :meth:`ErrorCollector.raise_if_any`: nothing is
returned when anything was wrong, so nothing is half loaded. One error is raised as itself (its type and
message unchanged); several become one :class:`~fleetsim.errors.LoadErrors`. Each file keeps at most
``cap`` errors; the rest are counted ("... and 12 more in tasks.csv").
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager

from fleetsim.errors import LoadError, LoadErrors

__all__ = ["CAP_PER_FILE", "ErrorCollector"]

CAP_PER_FILE = 50


class ErrorCollector:
    """Located load errors of one pass, in the order found, capped per file."""

    def __init__(self, cap: int = CAP_PER_FILE) -> None:
        self.cap = cap
        self.errors: list[LoadError] = []
        self.omitted: dict[str, int] = {}
        self._per_file: dict[str, int] = {}

    def __bool__(self) -> bool:
        return bool(self.errors)

    def add(self, error: LoadError) -> None:
        """Keep ``error`` (a :class:`LoadErrors` adds each of its errors and omissions)."""
        if isinstance(error, LoadErrors):
            for inner in error.errors:
                self.add(inner)
            for path, count in error.omitted.items():
                self.omitted[path] = self.omitted.get(path, 0) + count
            return
        key = _file_of(error)
        seen = self._per_file.get(key, 0)
        self._per_file[key] = seen + 1
        if seen < self.cap:
            self.errors.append(error)
        else:
            self.omitted[key] = self.omitted.get(key, 0) + 1

    @contextmanager
    def collecting(self) -> Iterator[None]:
        """Run the block and keep the :class:`LoadError` it raises, if any, instead of propagating it."""
        try:
            yield
        except LoadError as error:
            self.add(error)

    def raise_if_any(self) -> None:
        """Raise what was collected: the error itself when there is one, else a :class:`LoadErrors`."""
        if not self.errors:
            return
        if len(self.errors) == 1 and not self.omitted:
            raise self.errors[0]
        raise LoadErrors(self.errors, self.omitted)


def _file_of(error: LoadError) -> str:
    if error.location is None:
        return ""
    return str(error.location.path)

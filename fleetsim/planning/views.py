"""Read-only copies of the controller's live dicts for planner snapshots, kept current at the cost of what
changed rather than of the fleet's size.

Every planner call gets a snapshot whose mappings are read-only copies (SPEC §6). A planning round
changes plans one vehicle at a time; copying a 10,000-vehicle dict after each change made a round cost
the square of the fleet. A :class:`LiveCopy` keeps one copy and, before handing it out again, updates
only the entries that changed, in place, provided that nobody but the controller holds that copy,
its read-only view, or the snapshot that showed it. CPython's reference counts say so exactly (and
deterministically: the same run always takes the same path); a planner that keeps a snapshot, or a
mapping or iterator from one, makes them higher, and then a fresh copy is made as before, so what a
planner holds never changes under it. Where reference counts are unknown (not CPython), every change
makes a fresh copy.
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Iterable, KeysView, Mapping
from itertools import compress
from operator import is_not
from types import MappingProxyType
from typing import Any, Generic, TypeVar, cast

__all__ = ["LiveCopy", "LiveKeys", "held_only_here", "replaced"]

K = TypeVar("K")
V = TypeVar("V")

_refcount: Callable[[object], int] | None = getattr(sys, "getrefcount", None)


class _Probe:
    __slots__ = ("held",)

    def __init__(self, held: object) -> None:
        self.held = held


def _count(holder: object, name: str) -> int:
    """The reference count of ``holder.name``, counted the same way for every attribute (so the
    interpreter's own temporary references are the same in every count)."""
    assert _refcount is not None
    return _refcount(getattr(holder, name))


# The count of an object that one attribute holds and nothing else.
_ONE = _count(_Probe(object()), "held") if _refcount is not None else -1


def held_only_here(holder: object, name: str, others: int = 0) -> bool:
    """Whether ``holder.name`` is held by that attribute and by exactly ``others`` more references that
    the caller accounts for, and by nothing else. Always False where reference counts are unknown."""
    return _refcount is not None and _count(holder, name) == _ONE + others


class LiveCopy(Generic[K, V]):
    """A read-only copy of ``live`` (a dict the controller changes), kept up to date on demand.

    Tell it each changed key (:meth:`changed`; a key deleted from ``live`` is a change too); :meth:`view`
    then gives a read-only mapping equal to ``live`` at that moment: the view handed out last when
    nothing changed, that same view brought up to date when only the caller holds it (``exclusive``),
    and else a new copy.
    """

    __slots__ = ("_changed", "_copy", "_live", "_view")

    def __init__(self, live: dict[K, V]) -> None:
        self._live = live
        self._copy: dict[K, V] = {}
        self._view: object = None  # what _over(copy) made
        self._changed: set[K] = set()  # keys changed since the view was made

    def changed(self, key: K) -> None:
        if self._view is not None:
            self._changed.add(key)

    def changed_many(self, keys: Iterable[K]) -> None:
        if self._view is not None:
            self._changed.update(keys)

    def view(self, exclusive: bool) -> Mapping[K, V]:
        """The live dict as it is now, read-only. ``exclusive``: the caller knows that the snapshot which
        showed the last view is held by nobody else (the copy and the view themselves are checked here)."""
        view = self._view if self._view is not None and not self._changed else self._current(exclusive)
        return cast("Mapping[K, V]", view)

    def _over(self, copy: dict[K, V]) -> object:
        """The read-only view handed out over a copy."""
        return MappingProxyType(copy)

    def _current(self, exclusive: bool) -> Any:
        """The view after a change (or the first): the last one brought up to date, or a new copy's."""
        changed = self._changed
        live = self._live
        # Updating in place pays while the changes are few; a whole copy is one fast C loop.
        if (
            self._view is not None
            and exclusive
            and len(changed) * 8 < len(live)
            and held_only_here(self, "_view", others=1)  # ... and the snapshot that shows it
            and held_only_here(self, "_copy", others=1)  # ... and the view over it
        ):
            copy = self._copy
            for key in changed:
                try:
                    copy[key] = live[key]
                except KeyError:  # gone from the live dict
                    del copy[key]
        else:
            self._copy = dict(live)
            self._view = self._over(self._copy)
        changed.clear()
        return self._view


class LiveKeys(LiveCopy[K, None]):
    """:class:`LiveCopy` of a dict used as an insertion-ordered set, handed out as a read-only set (the
    copy's keys view): the routed tasks. Its iteration order is the order keys came in, so a reader that
    needs an order sorts."""

    __slots__ = ()

    def keys(self, exclusive: bool) -> KeysView[K]:
        """The live keys as they are now, read-only (``exclusive`` as for :meth:`LiveCopy.view`)."""
        keys = self._view if self._view is not None and not self._changed else self._current(exclusive)
        return cast("KeysView[K]", keys)

    def _over(self, copy: dict[K, None]) -> object:
        return copy.keys()


def replaced(mapping: Mapping[K, V], before: Mapping[K, V]) -> list[K]:
    """The keys of ``mapping`` whose values are other objects than in ``before`` (or absent there), in
    ``mapping``'s order. Two copies of one of a run's dicts list the same keys in the same order, and are
    then compared value by value in C (a large fleet's snapshots differ in a few entries); other
    mappings key by key."""
    if list(mapping) == list(before):
        return list(compress(mapping, map(is_not, mapping.values(), before.values())))
    old = before.get
    return [key for key, value in mapping.items() if old(key) is not value]

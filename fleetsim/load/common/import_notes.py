"""Warnings of a map import, reported once per kind (SPEC: an honest import).

A LIF or RMF file describes more than fleetsim models (actions, speed limits, doors, lifts, other levels,
...). Instead of dropping that silently, the importer notes each kind once, with how often it occurs and
where it first does, and ``fleetsim validate`` prints the notes. Codes:

- ``not-modelled``: an attribute or object fleetsim ignores;
- ``skipped-edge``: an edge or lane that cannot become a segment (it leads off the chosen layout or level);
- ``option-ignored``: a map option that does not apply to this kind of map.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

__all__ = ["IMPORT_WARNING_CODES", "ImportNotes"]

IMPORT_WARNING_CODES = ("not-modelled", "skipped-edge", "option-ignored")


@dataclass(slots=True)
class _Kind:
    code: str
    what: str
    first: str
    count: int = 1


@dataclass(slots=True)
class ImportNotes:
    """Collects notes in the order their kinds first occur (file order: deterministic)."""

    path: Path
    _kinds: dict[tuple[str, str], _Kind] = field(default_factory=dict)

    def note(self, code: str, what: str, where: str) -> None:
        """One occurrence of ``what`` (e.g. ``"edge attribute 'maxSpeed'"``) at ``where`` (a pointer or line)."""
        if code not in IMPORT_WARNING_CODES:  # pragma: no cover - a programming error
            raise ValueError(f"code={code!r} must be one of {IMPORT_WARNING_CODES}")
        kind = self._kinds.get((code, what))
        if kind is None:
            self._kinds[(code, what)] = _Kind(code, what, where)
        else:
            kind.count += 1

    def warnings(self) -> tuple[str, ...]:
        """``"FILE: warning CODE: WHAT (N times, first at WHERE); ..."`` per kind."""
        lines = []
        for kind in self._kinds.values():
            times = "once" if kind.count == 1 else f"{kind.count} times"
            tail = {
                "not-modelled": "fleetsim does not model it and ignores it",
                "skipped-edge": "no segment was made for it",
                "option-ignored": "it does not apply to this map",
            }[kind.code]
            lines.append(f"{self.path}: warning {kind.code}: {kind.what} ({times}, first at {kind.first}); {tail}")
        return tuple(lines)

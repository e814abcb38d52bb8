"""How messages name a map's segment ids, and a segment id the map does not have.

A check or a scenario that meets a segment the map lacks says so in these words, whichever check or
object it is about: ``segment 999, which is not in the map (segments 1–42)``. The ids are shown as runs
(``1–8, 10, 12–20``), so a map of thousands of segments still reads in one line.
"""

from __future__ import annotations

from collections.abc import Iterable

__all__ = ["SHOWN_RUNS", "id_runs", "not_in_map", "segment_ids"]

SHOWN_RUNS = 6  # runs of ids shown before the rest are counted


def id_runs(ids: Iterable[int], shown: int = SHOWN_RUNS) -> str:
    """``1–8, 10, 12–20``: the ids in ascending runs; past ``shown`` runs, the first ones, ``...`` and the
    last, then how many ids there are."""
    ordered = sorted(set(ids))
    runs: list[list[int]] = []
    for number in ordered:
        if runs and number == runs[-1][1] + 1:
            runs[-1][1] = number
        else:
            runs.append([number, number])
    texts = [_run(first, last) for first, last in runs]
    if len(texts) <= shown:
        return ", ".join(texts)
    return f"{', '.join(texts[: shown - 1])}, ..., {texts[-1]} ({len(ordered)} ids)"


def _run(first: int, last: int) -> str:
    if first == last:
        return str(first)
    return f"{first}, {last}" if last == first + 1 else f"{first}–{last}"


def segment_ids(ids: Iterable[int]) -> str:
    """``segments 1–42``, ``segment 7``, or ``no segments``."""
    ordered = sorted(set(ids))
    if not ordered:
        return "no segments"
    return f"segment {ordered[0]}" if len(ordered) == 1 else f"segments {id_runs(ordered)}"


def not_in_map(segment: int, ids: Iterable[int]) -> str:
    """``segment 999, which is not in the map (segments 1–42)``."""
    return f"segment {segment}, which is not in the map ({segment_ids(ids)})"

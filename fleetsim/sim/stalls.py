"""A shift's stalls (issue 45): vehicles that have work and have not moved for ``stall_after`` seconds.

Looked for every simulated second (the loop's call): a vehicle is *busy* from the first look that finds it
with a task, and stalled when it has stood, busy and not dwelling at a stop, for ``stall_after`` seconds
(standing is counted from its last move or from when it got work, whichever is later). Each stall is
found once; a vehicle that moves again may stall again later. Why it stands is the stuck-fleet
diagnosis's business (the loop asks it about the vehicles found).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Mapping, Sequence

__all__ = ["StallWatch"]


class StallWatch:
    """Which vehicles stall, look by look; the loop owns one for a shift."""

    def __init__(self, stall_after: float, index: Mapping[int, int]) -> None:
        self.stall_after = stall_after
        self._index = index  # vehicle id -> its place in the loop's last-moved array
        self.stalled: dict[int, float] = {}  # vehicle -> since when it stands
        self._busy_since: dict[int, float] = {}

    def look(
        self, end: float, busy: Iterable[int], last_moved: Sequence[float], dwelling: Callable[[int], bool]
    ) -> list[int]:
        """The vehicles found stalled at ``end``, in ``busy`` order (each found once per stall)."""
        for vehicle in list(self.stalled):
            last = last_moved[self._index[vehicle]]
            if not math.isnan(last) and last > self.stalled[vehicle]:
                del self.stalled[vehicle]  # it moved since: the stall is over
        busy = list(busy)
        working = set(busy)
        for vehicle in [v for v in self._busy_since if v not in working]:
            del self._busy_since[vehicle]
        found = []
        for vehicle in busy:
            work = self._busy_since.setdefault(vehicle, end)  # when it got work, to the second it is looked at
            if vehicle in self.stalled or dwelling(vehicle):
                continue
            last = last_moved[self._index[vehicle]]
            since = max(work, 0.0 if math.isnan(last) else float(last))
            if end - since >= self.stall_after - 1e-9:
                self.stalled[vehicle] = since
                found.append(vehicle)
        return found

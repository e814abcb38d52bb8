"""Durations as suites write them: a number of seconds, or a string with units (``"90s"``, ``"15min"``,
``"8h"``, ``"1h30min"``, ``"2h 15min 30s"``): hours, then minutes, then seconds, each at most once.

The suite schema checks the form with :data:`DURATION_PATTERN` (the same expression), so a suite's
mistake is reported at its line before :func:`duration_seconds` is asked.
"""

from __future__ import annotations

import math
import re

__all__ = ["DURATION_PATTERN", "DURATION_TITLE", "duration_seconds"]

_NUMBER = r"[0-9]+(?:\.[0-9]+)?"
DURATION_PATTERN = rf"^(?=[^0-9]*[0-9]) *(?:({_NUMBER}) *h)? *(?:({_NUMBER}) *min)? *(?:({_NUMBER}) *s)? *$"
DURATION_TITLE = "a duration: seconds, or a number with a unit ('90s', '15min', '8h', '1h30min')"
_DURATION = re.compile(DURATION_PATTERN)
_FACTORS = (3600.0, 60.0, 1.0)


def duration_seconds(value: float | str) -> float:
    """Seconds: a number as it is, a string by its units; a ``ValueError`` names what is wrong."""
    if isinstance(value, bool) or not isinstance(value, (int, float, str)):
        raise ValueError(f"{value!r} is not {DURATION_TITLE}")
    if isinstance(value, str):
        match = _DURATION.fullmatch(value)
        if match is None:
            raise ValueError(f"{value!r} is not {DURATION_TITLE}")
        seconds = math.fsum(float(part) * factor for part, factor in zip(match.groups(), _FACTORS, strict=True) if part)
    else:
        seconds = float(value)
    if not math.isfinite(seconds) or seconds < 0:
        raise ValueError(f"{value!r} is not {DURATION_TITLE}")
    return seconds

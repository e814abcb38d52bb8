"""The search for the highest arrival rate a fleet sustains: bracketing, then bisection.

A rate is tried by running the scenario once per order stream seed at that rate (one call of the
evaluator, all seeds together); it is *sustained* when every seed's run sustains it
(:mod:`fleetsim.capacity.criteria`). The search starts at the entry's own rate and doubles (while
sustained) or halves (while not) until it holds a sustained and an unsustained rate, never beyond
``max_rate`` nor below ``min_rate``; then it tries the midpoint of the bracket, which becomes its new low
or high end, until the bracket is within the resolution. Every rate below the final bracket that was
tried was sustained and every one above it was not, so the bracket is the highest sustained and the
lowest unsustained rate tried. The search depends on nothing but the evaluator's answers: the same
answers give the same rates in the same order.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Literal

from fleetsim.capacity.criteria import Judgement
from fleetsim.errors import FleetsimError

__all__ = [
    "STOP_REASONS",
    "RateOutcome",
    "Resolution",
    "SearchError",
    "SearchResult",
    "SearchSettings",
    "SeedBracket",
    "rate_value",
    "search",
]

Stop = Literal["resolution", "max-runs", "max-rate", "nothing-sustained"]
STOP_REASONS: tuple[Stop, ...] = ("resolution", "max-runs", "max-rate", "nothing-sustained")
Evaluate = Callable[[float], Mapping[int, Judgement]]  # a rate -> each seed's run at it

_RESOLUTION = re.compile(r"^\s*(\d+(?:\.\d*)?|\.\d+)\s*(%?)\s*$")
_DIGITS = 2  # rates are tried rounded to hundredths of an order per hour


class SearchError(FleetsimError, ValueError):
    """Settings a search cannot start from: a rate that is not a positive number, a bracket out of order."""


def rate_value(name: str, text: str) -> float:
    """``text`` as a rate in orders per hour (> 0); the error names the option: ``--max-rate='x' must ...``."""
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and value > 0):
        msg = f"{name}={text!r} must be a positive number of orders per hour"
        raise SearchError(msg)
    return value


@dataclass(frozen=True, slots=True)
class Resolution:
    """How narrow the final bracket must be: ``amount`` orders per hour, or percent of its low end."""

    amount: float
    relative: bool

    @classmethod
    def parse(cls, text: str) -> Resolution:
        """``"2%"`` (of the bracket's low end) or ``"5"`` (orders per hour)."""
        match = _RESOLUTION.match(text)
        amount = float(match.group(1)) if match else 0.0
        if match is None or amount <= 0 or (match.group(2) and amount >= 100):
            msg = f"--resolution={text!r} must be a percentage of the rate below 100 (2%) or orders per hour (5), > 0"
            raise SearchError(msg)
        return cls(amount, bool(match.group(2)))

    def reached(self, low: float, high: float) -> bool:
        return high - low <= (self.amount / 100 * low if self.relative else self.amount) + 1e-9

    def __str__(self) -> str:
        return f"{self.amount:g}%" if self.relative else f"{self.amount:g} orders/h"


@dataclass(frozen=True, slots=True)
class SearchSettings:
    """Where the search starts and where it must stop.

    Attributes:
        start: Orders per hour: the first rate tried (the entry's own).
        seeds: The order stream seeds each rate is run with.
        resolution: When the bracket is narrow enough.
        min_rate, max_rate: Orders per hour: halving and doubling stop there.
        max_runs: Runs at most (a rate costs one run per seed; a rate that would exceed it is not tried).
    """

    start: float
    seeds: tuple[int, ...]
    resolution: Resolution
    min_rate: float
    max_rate: float
    max_runs: int

    def __post_init__(self) -> None:
        if not self.seeds:
            raise SearchError("--seeds must name at least one order stream seed")
        if len(set(self.seeds)) != len(self.seeds):
            raise SearchError(f"--seeds={','.join(map(str, self.seeds))}: a seed is named twice")
        if self.min_rate < 10**-_DIGITS:
            raise SearchError(f"--min-rate={self.min_rate:g} must be at least {10**-_DIGITS:g} orders/h")
        if not self.min_rate <= self.start <= self.max_rate:
            msg = f"the search must start between --min-rate={self.min_rate:g} and --max-rate={self.max_rate:g} orders/h; it starts at the entry's rate, {self.start:g}"
            raise SearchError(msg)
        if self.max_runs < len(self.seeds):
            msg = f"--max-runs={self.max_runs} must allow one rate: at least one run per seed ({len(self.seeds)})"
            raise SearchError(msg)


@dataclass(frozen=True, slots=True)
class RateOutcome:
    """One rate tried: each seed's run at it, by seed."""

    rate: float
    runs: Mapping[int, Judgement]

    @property
    def sustained(self) -> bool:
        """Every seed sustained the rate: the capacity is what every stream of orders is served at."""
        return all(run.sustained for run in self.runs.values())


@dataclass(frozen=True, slots=True)
class SeedBracket:
    """One seed on its own: the highest rate tried that it sustained, as every lower rate tried, and the
    lowest rate tried that it did not (``None``: none)."""

    seed: int
    sustained: float | None
    unsustained: float | None


@dataclass(frozen=True, slots=True)
class SearchResult:
    """Where the search ended: the rates it tried, in order, its bracket and why it stopped."""

    settings: SearchSettings
    tried: tuple[RateOutcome, ...]
    sustained: float | None  # the highest rate sustained (by every seed); None: none was
    unsustained: float | None  # the lowest rate not sustained; None: every rate tried was
    stop: Stop

    @property
    def capacity(self) -> float:
        """Orders per hour: the highest rate sustained, 0 when none was."""
        return self.sustained or 0.0

    @property
    def runs(self) -> int:
        return sum(len(outcome.runs) for outcome in self.tried)

    def seed_brackets(self) -> list[SeedBracket]:
        """Each seed's own bracket over the rates tried: the spread of the capacity over order streams."""
        ordered = sorted(self.tried, key=lambda outcome: outcome.rate)
        brackets = []
        for seed in self.settings.seeds:
            sustained: float | None = None
            unsustained: float | None = None
            for outcome in ordered:
                run = outcome.runs.get(seed)
                if run is None:
                    continue
                if not run.sustained:
                    unsustained = outcome.rate
                    break
                sustained = outcome.rate
            brackets.append(SeedBracket(seed, sustained, unsustained))
        return brackets

    def why(self) -> str:
        """Where the search stopped and why, in a sentence."""
        s = self.settings
        if self.stop == "max-rate":
            return f"every rate tried was sustained, up to --max-rate {s.max_rate:g} orders/h: the capacity is at least that"
        if self.stop == "nothing-sustained":
            return f"no rate tried was sustained, down to --min-rate {s.min_rate:g} orders/h"
        if self.stop == "max-runs":
            return f"--max-runs {s.max_runs} reached ({self.runs} runs) before the bracket was within {s.resolution}"
        return f"resolution reached: the bracket is within {s.resolution}"


def search(settings: SearchSettings, evaluate: Evaluate) -> SearchResult:
    """Bracket the capacity, then bisect the bracket (the module's description says how)."""
    tried: list[RateOutcome] = []

    def affordable() -> bool:
        return sum(len(o.runs) for o in tried) + len(settings.seeds) <= settings.max_runs

    def sustained_at(rate: float) -> bool:
        outcome = RateOutcome(rate, dict(evaluate(rate)))
        missing = set(settings.seeds) - set(outcome.runs)
        if missing:  # an evaluator's mistake, not the user's
            raise ValueError(f"the evaluator gave no run at {rate:g} orders/h for seeds {sorted(missing)}")
        tried.append(outcome)
        return outcome.sustained

    def result(stop: Stop) -> SearchResult:
        return SearchResult(settings, tuple(tried), low, high, stop)

    low: float | None = None
    high: float | None = None
    rate = _rounded(settings.start)
    while low is None or high is None:
        if not affordable():
            return result("max-runs")
        if sustained_at(rate):
            low = rate
            if high is None and rate >= settings.max_rate:
                return result("max-rate")
            rate = _rounded(min(rate * 2, settings.max_rate))
        else:
            high = rate
            if low is None and rate <= settings.min_rate:
                return result("nothing-sustained")
            rate = _rounded(max(rate / 2, settings.min_rate))
    while not settings.resolution.reached(low, high):
        middle = _rounded((low + high) / 2)
        if not low < middle < high:  # the bracket is as narrow as rates are tried
            break
        if not affordable():
            return result("max-runs")
        if sustained_at(middle):
            low = middle
        else:
            high = middle
    return result("resolution")


def _rounded(rate: float) -> float:
    return round(rate, _DIGITS)

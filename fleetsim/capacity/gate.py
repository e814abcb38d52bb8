"""``--fail-if`` for a capacity: ``"capacity < baseline - 5%"`` against an earlier search or a number.

The baseline is a capacity results file (its ``capacity``: the highest rate it found sustained) or a
number of orders per hour. As a sweep's conditions are judged on a whole confidence interval, a
capacity's are judged on its whole bracket: the capacity lies at or above the highest rate sustained and
below the lowest rate not sustained, so ``capacity < BOUND`` holds only when the lowest rate not
sustained is at or below BOUND (the fleet failed a rate no higher than the bound), and ``capacity >
BOUND`` only when the highest rate sustained is above it. The search's resolution is its doubt: a drop
smaller than the bracket is never a failure; keep ``--resolution`` below the margin the gate allows.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

from fleetsim.capacity.results import read_capacity
from fleetsim.sweep.gate import Condition, GateError, parse_condition

__all__ = ["Baseline", "CapacityVerdict", "GateError", "judge_capacity", "parse_baseline", "parse_gate"]


def parse_gate(text: str) -> Condition:
    """``capacity OP baseline [+|- AMOUNT[%]]``, AMOUNT in orders per hour or percent of the baseline."""
    return parse_condition(text, known=("capacity",), example="capacity")


@dataclass(frozen=True, slots=True)
class Baseline:
    """The capacity a search is gated against, and where it comes from (a file, or the command line)."""

    capacity: float
    source: str


def parse_baseline(text: str) -> Baseline:
    """``--baseline``: a number of orders per hour, else a capacity results file."""
    try:
        value = float(text)
    except ValueError:
        document = read_capacity(Path(text))
        return Baseline(float(document["capacity"]), f"{text}: {document.get('scenario', '?')}")
    if not (math.isfinite(value) and value >= 0):
        msg = f"--baseline={text!r} must be a capacity results file or a number of orders per hour >= 0"
        raise GateError(msg)
    return Baseline(value, "--baseline")


@dataclass(frozen=True, slots=True)
class CapacityVerdict:
    """One condition judged: its bound in orders per hour, and whether it holds (the gate fails)."""

    condition: Condition
    baseline: Baseline
    sustained: float | None
    unsustained: float | None
    bound: float
    holds: bool

    def line(self) -> str:
        low = 0.0 if self.sustained is None else self.sustained
        high = "none" if self.unsustained is None else f"{self.unsustained:g}"
        return (
            f"{'FAIL' if self.holds else 'ok'}  {self.condition.text}: capacity {low:g} orders/h "
            f"(lowest rate not sustained: {high}), bound {self.bound:.4g} orders/h "
            f"(baseline {self.baseline.capacity:g}, {self.baseline.source})"
        )


def judge_capacity(
    conditions: tuple[Condition, ...], baseline: Baseline, sustained: float | None, unsustained: float | None
) -> list[CapacityVerdict]:
    """Each condition against the bracket [``sustained``, ``unsustained``) (the module's description)."""
    verdicts = []
    for condition in conditions:
        offset = condition.offset * baseline.capacity / 100 if condition.relative else condition.offset
        bound = baseline.capacity + offset
        low = 0.0 if sustained is None else sustained
        if condition.operator in ("<", "<="):
            holds = unsustained is not None and unsustained <= bound
        elif condition.operator == ">":
            holds = low > bound
        else:
            holds = low >= bound
        verdicts.append(CapacityVerdict(condition, baseline, sustained, unsustained, bound, holds))
    return verdicts

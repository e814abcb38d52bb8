"""``--fail-if`` conditions: CI gating on a sweep's paired comparisons, judged with their intervals.

``"throughput < baseline - 2%"`` holds when the candidate's throughput is lower than the baseline's
minus 2 % of the baseline's mean *beyond doubt*: the whole 95 % bootstrap interval of the mean paired
difference lies below -2 %. A difference the data cannot tell from noise never fails a build; a raw mean
is never compared. Forms: ``METRIC (<|<=|>|>=) baseline [(+|-) AMOUNT[%]]``; AMOUNT is in the metric's
unit, or percent of the baseline mean.
"""

from __future__ import annotations

import math
import re
from collections.abc import Collection, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from fleetsim.errors import FleetsimError
from fleetsim.sweep.stats import METRICS, Paired, paired

__all__ = ["Condition", "GateError", "Verdict", "judge", "parse_condition"]

_FORM = re.compile(r"^\s*(\w+)\s*(<=|>=|<|>)\s*baseline\s*(?:([+-])\s*(\d+(?:\.\d*)?|\.\d+)\s*(%?))?\s*$")


class GateError(FleetsimError, ValueError):
    """A ``--fail-if`` condition that cannot be read."""


@dataclass(frozen=True, slots=True)
class Condition:
    text: str
    metric: str
    operator: str
    offset: float  # signed
    relative: bool


def parse_condition(text: str, known: Collection[str] = METRICS.keys(), example: str = "throughput") -> Condition:
    """``text`` read as ``METRIC OP baseline [+|- AMOUNT[%]]``, METRIC one of ``known`` (a sweep's metrics
    by default; ``fleetsim capacity`` knows ``capacity``)."""
    match = _FORM.match(text)
    if match is None:
        msg = f"--fail-if={text!r} must read METRIC OP baseline [+|- AMOUNT[%]], e.g. '{example} < baseline - 2%'"
        raise GateError(msg)
    metric, operator, sign, amount, percent = match.groups()
    if metric not in known:
        msg = f"--fail-if={text!r}: unknown metric {metric!r}; known: {', '.join(sorted(known))}"
        raise GateError(msg)
    offset = float(amount or 0) * (-1 if sign == "-" else 1)
    return Condition(text.strip(), metric, operator, offset, bool(percent))


@dataclass(frozen=True, slots=True)
class Verdict:
    condition: Condition
    candidate: str
    comparison: Paired
    limit: float  # the condition's bound on the mean difference, in the metric's unit
    holds: bool  # the condition holds beyond doubt: the gate fails

    def line(self) -> str:
        c = self.comparison
        unit = METRICS[c.metric].unit
        if c.n == 0:
            return f"{'FAIL' if self.holds else 'ok'}  {self.candidate}: {self.condition.text}: no paired runs to judge"
        word = "FAIL" if self.holds else "ok"
        return (
            f"{word}  {self.candidate}: {self.condition.text}: mean difference {c.mean:+.4g} {unit} "
            f"(95% CI {c.low:+.4g} .. {c.high:+.4g}, n={c.n}), bound {self.limit:+.4g} {unit}"
        )


def judge(
    rows: Sequence[Mapping[str, Any]], conditions: Sequence[Condition], baseline: str, candidates: Sequence[str]
) -> list[Verdict]:
    """Every condition for every candidate. With no paired runs a condition holds (nothing shows the
    candidate is not worse, and a gate must not pass on no evidence)."""
    verdicts = []
    for condition in conditions:
        for candidate in candidates:
            comparison = paired(rows, condition.metric, candidate, baseline)
            limit = condition.offset * abs(comparison.baseline_mean) / 100 if condition.relative else condition.offset
            verdicts.append(
                Verdict(condition, candidate, comparison, limit, _holds(condition.operator, comparison, limit))
            )
    return verdicts


def _holds(operator: str, c: Paired, limit: float) -> bool:
    if c.n == 0 or math.isnan(c.low):
        return True
    if operator == "<":
        return c.high < limit
    if operator == "<=":
        return c.high <= limit
    if operator == ">":
        return c.low > limit
    return c.low >= limit

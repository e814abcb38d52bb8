"""Statistics of a sweep: per-planner figures and paired comparisons with bootstrap confidence intervals.

A comparison pairs each candidate run with the baseline planner's run of the same scenario (same id),
takes the per-scenario differences and resamples them (a paired bootstrap, percentile interval, 95 %,
2000 resamples) from a generator with a fixed seed: the same results give the same intervals on any
machine, whatever order the runs finished in.
"""

from __future__ import annotations

import math
import zlib
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["BOOTSTRAP_SEED", "METRICS", "Paired", "PlannerSummary", "SweepMetric", "paired", "summarise"]

BOOTSTRAP_SEED = 20260521
RESAMPLES = 2000
LEVEL = 0.95


@dataclass(frozen=True, slots=True)
class SweepMetric:
    name: str
    label: str
    unit: str
    better: str  # "lower" | "higher"
    read: Callable[[Mapping[str, Any]], float | None]


def _field(name: str) -> Callable[[Mapping[str, Any]], float | None]:
    def read(row: Mapping[str, Any]) -> float | None:
        value = row.get(name)
        return None if value is None or isinstance(value, bool) else float(value)

    return read


METRICS: Mapping[str, SweepMetric] = {
    m.name: m
    for m in (
        SweepMetric("success", "success rate", "%", "higher", lambda r: 100.0 if r.get("status") == "passed" else 0.0),
        SweepMetric("throughput", "throughput", "tasks/h", "higher", _field("throughput")),
        SweepMetric("makespan", "makespan", "s", "lower", _field("makespan")),
        SweepMetric(
            "waiting_share",
            "waiting share",
            "%",
            "lower",
            lambda r: None if r.get("waiting_share") is None else 100 * float(r["waiting_share"]),
        ),
        SweepMetric("alerts", "alerts", "", "lower", _field("alerts")),
        SweepMetric("rejections", "rejections", "", "lower", _field("rejections")),
        SweepMetric("deadlocks", "deadlocks", "", "lower", lambda r: 1.0 if r.get("deadlock") else 0.0),
        SweepMetric(
            "planner_time_per_call",
            "planner time per call",
            "ms",
            "lower",
            lambda r: None if r.get("planner_time_per_call") is None else 1000 * float(r["planner_time_per_call"]),
        ),
    )
}


@dataclass(frozen=True, slots=True)
class PlannerSummary:
    planner: str
    runs: int
    errors: int  # runs that never ran: planner not importable, scenario not loading, worker lost
    means: Mapping[str, float | None]  # metric name -> mean over the runs that have the figure
    totals: Mapping[str, float]  # alerts, rejections, deadlocks: summed


def summarise(rows: Sequence[Mapping[str, Any]]) -> list[PlannerSummary]:
    """One summary per planner, in planner order of first appearance in key-sorted rows."""
    planners = list(dict.fromkeys(str(row["planner"]) for row in sorted(rows, key=lambda r: str(r["key"]))))
    summaries = []
    for planner in planners:
        mine = [row for row in rows if row["planner"] == planner]
        means: dict[str, float | None] = {}
        for name, metric in METRICS.items():
            values = [v for v in map(metric.read, mine) if v is not None]
            means[name] = math.fsum(values) / len(values) if values else None
        totals = {
            name: math.fsum(v for v in map(METRICS[name].read, mine) if v is not None)
            for name in ("alerts", "rejections", "deadlocks")
        }
        summaries.append(
            PlannerSummary(planner, len(mine), sum(row.get("error") is not None for row in mine), means, totals)
        )
    return summaries


@dataclass(frozen=True, slots=True)
class Paired:
    """A candidate against the baseline on one metric, over the scenarios both have the figure for."""

    metric: str
    candidate: str
    baseline: str
    ids: tuple[str, ...]  # sorted
    differences: tuple[float, ...]  # candidate - baseline, per id
    baseline_mean: float
    mean: float  # mean difference
    low: float  # confidence interval of the mean difference
    high: float

    @property
    def n(self) -> int:
        return len(self.ids)

    def relative(self, value: float) -> float | None:
        """``value`` as a share of the baseline mean (None when that is 0)."""
        return None if self.baseline_mean == 0 else value / abs(self.baseline_mean)

    def worse(self, value: float) -> bool:
        return value < 0 if METRICS[self.metric].better == "higher" else value > 0


def paired(rows: Sequence[Mapping[str, Any]], metric: str, candidate: str, baseline: str) -> Paired:
    """The paired comparison of ``candidate`` with ``baseline`` on ``metric``."""
    read = METRICS[metric].read
    base = {str(r["id"]): read(r) for r in rows if r["planner"] == baseline}
    mine = {str(r["id"]): read(r) for r in rows if r["planner"] == candidate}
    ids = tuple(sorted(i for i in base.keys() & mine.keys() if base[i] is not None and mine[i] is not None))
    before = np.array([base[i] for i in ids], dtype=float)
    after = np.array([mine[i] for i in ids], dtype=float)
    differences = after - before
    if not ids:
        return Paired(metric, candidate, baseline, ids, (), 0.0, math.nan, math.nan, math.nan)
    low, high = _bootstrap(differences, f"{metric}|{candidate}|{baseline}")
    return Paired(
        metric,
        candidate,
        baseline,
        ids,
        tuple(float(d) for d in differences),
        float(before.mean()),
        float(differences.mean()),
        low,
        high,
    )


def _bootstrap(differences: np.ndarray[Any, np.dtype[np.float64]], label: str) -> tuple[float, float]:
    """Percentile interval of the mean of ``differences``; the generator's seed depends only on the label."""
    rng = np.random.default_rng([BOOTSTRAP_SEED, zlib.crc32(label.encode())])
    picks = rng.integers(0, len(differences), size=(RESAMPLES, len(differences)))
    means = differences[picks].mean(axis=1)
    tail = (1 - LEVEL) / 2 * 100
    low, high = np.percentile(means, [tail, 100 - tail])
    return float(low), float(high)

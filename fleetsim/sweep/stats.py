"""Statistics of a sweep: per-planner figures and paired comparisons with bootstrap confidence intervals.

Each figure is read from a sweep's records (a run's result plus the sweep's keys): throughput, waiting
share and planner time per call are worked out from the result's tasks, times and metrics; the measures of
runs with transport orders (:data:`ORDER_METRICS`: orders per hour, service times, ...) from its
``measures``, and a run without orders has none of them.

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

from fleetsim.gating.measures import GATED_MEASURES, GatedMeasure, measure_value

__all__ = [
    "BOOTSTRAP_SEED",
    "METRICS",
    "ORDER_METRICS",
    "Paired",
    "PlannerSummary",
    "SweepMetric",
    "contacts",
    "paired",
    "planner_time_per_call",
    "summarise",
    "throughput",
    "waiting_share",
]

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


# What a record (a run's result plus the sweep's keys, schemas/result.schema.json) says, per metric; None
# where the run has no such figure (a run that never ran has none of them).


def _number(value: Any) -> float | None:
    return None if value is None else float(value)


def _ran(record: Mapping[str, Any]) -> bool:
    return record.get("error") is None and record["sim_time"] > 0


def throughput(record: Mapping[str, Any]) -> float | None:
    """Tasks completed per simulated hour."""
    return int(record["tasks"]["completed"]) / (float(record["sim_time"]) / 3600) if _ran(record) else None


def waiting_share(record: Mapping[str, Any]) -> float | None:
    """The share of the fleet's time spent standing with tasks pending (0..1)."""
    if not _ran(record):
        return None
    waited = math.fsum(record["metrics"]["waiting_time"].values())
    return waited / (max(int(record.get("vehicles") or 0), 1) * float(record["sim_time"]))


def planner_time_per_call(record: Mapping[str, Any]) -> float | None:
    """Wall-clock seconds per planner call."""
    metrics = record["metrics"]
    calls = int(metrics["planner_calls"])
    return float(metrics["planner_wall_time"]) / calls if calls else None


def contacts(record: Mapping[str, Any]) -> float | None:
    """How many times two footprints touched; None when the run's contact check was off."""
    contact = record.get("contact")
    return None if contact is None else float(len(contact["contacts"]))


def _scaled(
    read: Callable[[Mapping[str, Any]], float | None], by: float
) -> Callable[[Mapping[str, Any]], float | None]:
    def scaled(record: Mapping[str, Any]) -> float | None:
        value = read(record)
        return None if value is None else by * value

    return scaled


def _measure(measure: GatedMeasure) -> SweepMetric:
    """A measure of runs with transport orders, read from a record's ``measures``; shares in percent."""

    def read(record: Mapping[str, Any]) -> float | None:
        return measure_value(record.get("measures"), measure.name)

    if measure.unit == "share":
        return SweepMetric(measure.name, measure.label, "%", measure.better, _scaled(read, 100))
    return SweepMetric(measure.name, measure.label, measure.unit, measure.better, read)


# The measures of runs with transport orders, in the order the report shows them.
ORDER_METRICS = tuple(measure.name for measure in GATED_MEASURES)

METRICS: Mapping[str, SweepMetric] = {
    m.name: m
    for m in (
        SweepMetric("success", "success rate", "%", "higher", lambda r: 100.0 if r["status"] == "passed" else 0.0),
        SweepMetric("throughput", "throughput", "tasks/h", "higher", throughput),
        SweepMetric("makespan", "makespan", "s", "lower", lambda r: _number(r["metrics"]["makespan"])),
        SweepMetric("waiting_share", "waiting share", "%", "lower", _scaled(waiting_share, 100)),
        SweepMetric("alerts", "alerts", "", "lower", lambda r: float(len(r["collisions"]))),
        SweepMetric("contacts", "contacts", "", "lower", contacts),
        SweepMetric("clearance", "clearance", "m", "higher", lambda r: _number(r["metrics"].get("clearance"))),
        SweepMetric("rejections", "rejections", "", "lower", lambda r: float(len(r["rejections"]))),
        SweepMetric("deadlocks", "deadlocks", "", "lower", lambda r: 0.0 if r["deadlock"] is None else 1.0),
        SweepMetric(
            "planner_time_per_call", "planner time per call", "ms", "lower", _scaled(planner_time_per_call, 1000)
        ),
        *map(_measure, GATED_MEASURES),
    )
}


@dataclass(frozen=True, slots=True)
class PlannerSummary:
    planner: str
    runs: int
    errors: int  # runs that never ran: planner not importable, scenario not loading, worker lost
    means: Mapping[str, float | None]  # metric name -> mean over the runs that have the figure
    totals: Mapping[str, float]  # alerts, contacts, rejections, deadlocks, deadline misses, stalls: summed
    least_clearance: float | None  # the closest two footprints came in any run (None: never within reach)


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
            for name in ("alerts", "contacts", "rejections", "deadlocks", "deadline_misses", "stalls")
        }
        clearances = [v for v in map(METRICS["clearance"].read, mine) if v is not None]
        summaries.append(
            PlannerSummary(
                planner,
                len(mine),
                sum(row.get("error") is not None for row in mine),
                means,
                totals,
                min(clearances, default=None),
            )
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

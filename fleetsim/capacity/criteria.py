"""Whether one run sustained its arrival rate, judged from the run's result document alone.

A run of a shift *sustains* its order stream's rate when all of these hold over the measured window (the
shift after its warm-up; docs/orders.md, "Measures", defines each figure):

1. it ran to its end without failing (a run that fails — a planner error, a collision alert it does not
   expect, a stall that ends it — sustains nothing);
2. no vehicle stalled (``stalls`` is 0): a fleet whose vehicles stand stuck survives the rate, it does
   not serve it;
3. the backlog stays bounded: the run is not ``overloaded`` (its backlog's least-squares slope exceeds 5 %
   of the window's arrival rate *and* the backlog ended more than 5 orders above where the window began);
4. throughput keeps up with demand: the orders completed in the window fall short of those released in
   it by no more than ``tolerance`` of them, or by no more than one order per vehicle (each vehicle may
   hold one order more when the window closes than when it opened). Released − completed over the window
   is the backlog's growth over it, so this bounds the backlog's level where 3 bounds its trend (whose
   5 orders let a short window's queue build up unseen);
5. with a service-time bound, the 95th percentile of the service times is within it (a run that
   completed no order released in the window has none, and does not sustain the rate).

The entry's own ``expect`` bounds on measures are not applied (the search strips them): capacity has its
criteria, the same for every rate.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, replace
from typing import Any

from fleetsim.sim.measures import measure_value

__all__ = ["Criteria", "Judgement", "judge_run"]


@dataclass(frozen=True, slots=True)
class Criteria:
    """What a run must show to sustain its rate (the module's description gives the rules).

    Attributes:
        tolerance: The share of the window's released orders its completions may fall short by (0.1: 10 %).
        max_service_p95: Seconds: a bound on the service times' 95th percentile, or ``None`` for none.
    """

    tolerance: float = 0.1
    max_service_p95: float | None = None

    def to_dict(self) -> dict[str, Any]:
        return {"tolerance": self.tolerance, "max_service_p95": self.max_service_p95}


@dataclass(frozen=True, slots=True)
class Judgement:
    """One run (one rate, one order stream seed), as the search and the report see it.

    Attributes:
        sustained: Whether the run sustained its rate.
        reason: Why not (the first rule it broke), or ``""``.
        released: Orders released in the window; ``completed``: orders completed in it.
        orders_per_hour: Throughput: orders completed per hour of the window.
        arrivals_per_hour: Orders released per hour of the window (the realised demand).
        service_median, service_p95: Seconds, or ``None`` when no order released in the window was completed.
        backlog_slope: Orders per hour; ``overloaded``: the run's measure.
    """

    sustained: bool
    reason: str = ""
    released: int = 0
    completed: int = 0
    orders_per_hour: float = 0.0
    arrivals_per_hour: float = 0.0
    service_median: float | None = None
    service_p95: float | None = None
    backlog_slope: float = 0.0
    overloaded: bool = False

    def to_dict(self) -> dict[str, Any]:
        return {
            "sustained": self.sustained,
            "reason": self.reason,
            "released": self.released,
            "completed": self.completed,
            "orders_per_hour": round(self.orders_per_hour, 4),
            "arrivals_per_hour": round(self.arrivals_per_hour, 4),
            "service_time_median": self.service_median,
            "service_time_p95": self.service_p95,
            "backlog_slope": self.backlog_slope,
            "overloaded": self.overloaded,
        }

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> Judgement:
        return cls(
            bool(data["sustained"]), str(data["reason"]), int(data["released"]), int(data["completed"]),
            float(data["orders_per_hour"]), float(data["arrivals_per_hour"]),
            _number(data.get("service_time_median")), _number(data.get("service_time_p95")),
            float(data["backlog_slope"]), bool(data["overloaded"]),
        )  # fmt: skip


def _number(value: Any) -> float | None:
    return None if value is None else float(value)


def judge_run(record: Mapping[str, Any], criteria: Criteria) -> Judgement:
    """Whether the run whose result document is ``record`` (``fleetsim run --json``'s, a sweep row) sustained
    its rate under ``criteria``."""
    measures = record.get("measures")
    if not isinstance(measures, Mapping):
        return Judgement(False, _failed(record) or "the run has no measures of orders")
    window = measures["window"]
    hours = max(float(window[1]) - float(window[0]), 1e-9) / 3600.0
    released, completed = int(measures["released"]), int(measures["completed"])
    figures = Judgement(
        True, "", released, completed, float(measures["orders_per_hour"]), released / hours,
        measure_value(measures, "service_time_median"), measure_value(measures, "service_time_p95"),
        float(measures["backlog_slope"]), bool(measures["overloaded"]),
    )  # fmt: skip
    stalls = int(measures.get("stalls") or 0)
    reason = _failed(record) or _broken_rule(figures, stalls, _fleet_size(record, measures), criteria)
    return figures if not reason else replace(figures, sustained=False, reason=reason)


def _failed(record: Mapping[str, Any]) -> str:
    """Why the run failed (its first failure), or ``""``; an ``expectation`` of the entry's is not capacity's."""
    failures = [f for f in record.get("failures") or () if f.get("kind") != "expectation"]
    if record.get("error"):
        return f"the run did not run: {record['error']}"
    if not failures:
        return ""
    first = failures[0]
    return f"the run failed: {first.get('kind')}: {first.get('message', '')}".strip()


def _fleet_size(record: Mapping[str, Any], measures: Mapping[str, Any]) -> int:
    """The run's vehicles: a sweep row says it; ``fleetsim run --json``'s document shows it as the ratio of
    two of its measures (rounded to four places, which a fleet of up to a thousand survives)."""
    if isinstance(record.get("vehicles"), int):
        return int(record["vehicles"])
    per_vehicle = float(measures.get("orders_per_vehicle_hour") or 0.0)
    return round(float(measures["orders_per_hour"]) / per_vehicle) if per_vehicle > 0 else 0


def _broken_rule(run: Judgement, stalls: int, vehicles: int, criteria: Criteria) -> str:
    if stalls:
        return f"{stalls} vehicle(s) stalled"
    if run.overloaded:
        return f"overloaded: the backlog grew ({run.backlog_slope:+.1f} orders/h)"
    shortfall = run.released - run.completed
    allowed = max(criteria.tolerance * run.released, vehicles)
    if shortfall > allowed:
        return f"throughput fell behind: {run.completed} of {run.released} orders completed ({shortfall} short, {allowed:.4g} allowed)"
    bound = criteria.max_service_p95
    if bound is not None and (run.service_p95 is None or run.service_p95 > bound):
        shown = "none" if run.service_p95 is None else f"{run.service_p95:.4g} s"
        return f"service time p95 {shown} above {bound:.4g} s"
    return ""

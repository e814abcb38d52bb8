"""A metric regression fails the scenario's own run, not only the session (issue 45).

``--fleetsim-compare-fail orders_per_hour:5%`` compares each run, as it ends, with its row in the
baseline: every threshold it breaks is one ``regression`` failure in its result, so the scenario's test
item is red (in pytest's summary and in JUnit), its artifacts are kept as any failed run's, and its
``result.json`` says why. The session's comparison (:func:`fleetsim.gating.baseline.compare`) still
lists every regression under the summary.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import replace

from fleetsim.gating.baseline import Outcome, Regression, ScenarioMetrics, Threshold, compare
from fleetsim.sim.result import Failure, RunResult

__all__ = ["judge_against", "regression_failure"]


def judge_against(
    baseline: Mapping[str, ScenarioMetrics],
    id: str,
    result: RunResult,
    thresholds: Sequence[Threshold],
    outcome: Outcome = "passed",
) -> RunResult:
    """``result`` as it is, or failed with one ``regression`` for each threshold its figures break against
    the baseline's row ``id``; a scenario the baseline lacks, or an interrupted run, is not judged."""
    if not thresholds or id not in baseline or result.ended == "interrupted":
        return result
    now = ScenarioMetrics.from_result(id, outcome, result)
    found = compare({id: baseline[id]}, {id: now}, thresholds).regressions
    if not found:
        return result
    failures = (*result.failures, *(regression_failure(r, result.sim_time) for r in found))
    return replace(result, status="failed", failures=failures)


def regression_failure(regression: Regression, time: float) -> Failure:
    """The failure of a run whose ``regression.metric`` got worse than its threshold allows."""
    details = {
        "metric": regression.metric,
        "baseline": regression.baseline,
        "value": regression.current,
        "limit": str(regression.threshold),
    }
    return Failure("regression", time, f"{regression.change()} against the baseline", details)

"""Metric documents for a test session, and regression gating against a saved baseline.

Trace hashes catch *any* change in behaviour; metrics say whether a change made things *worse*. A
session writes one document of per-scenario metrics (``--fleetsim-metrics-json``); a later session
compares itself with a saved one and fails when a metric got worse beyond a threshold
(``--fleetsim-compare-fail makespan:5%``), in the spirit of pytest-benchmark's ``--benchmark-compare-fail``.
The document is deterministic (sorted, no timestamps or host data) so a baseline can be committed and
its diffs reviewed.

Runs with transport orders add their measures (:data:`fleetsim.gating.measures.GATED_MEASURES`:
``orders_per_hour:5%`` fails a drop of throughput by more than 5 %). A regression fails the scenario's
own run (:func:`fleetsim.gating.regression.judge_against`: a ``regression`` failure), not only the session.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import MISSING, asdict, dataclass, fields
from itertools import pairwise
from operator import attrgetter
from pathlib import Path
from types import MappingProxyType
from typing import Any, Literal, NamedTuple, get_args

from fleetsim.errors import FleetsimError, Location
from fleetsim.gating.measures import GATED_MEASURES, measure_value
from fleetsim.load.common.text import json_problem, write_text_atomically
from fleetsim.sim.result import RunResult

__all__ = [
    "METRICS",
    "METRICS_FORMAT",
    "SWEEP_RESULTS_FORMAT",
    "BaselineError",
    "Comparison",
    "Metric",
    "Outcome",
    "Regression",
    "ScenarioMetrics",
    "Threshold",
    "compare",
    "metrics_document",
    "parse_threshold",
    "read_metrics",
    "write_metrics",
]

METRICS_FORMAT = "fleetsim-metrics/1"
# fleetsim sweep's JSON lines: a header, then a run's result (schemas/result.schema.json) per row. Format 1
# held flat rows of our fields; 2 the run's ordinary result plus the sweep's keys.
SWEEP_RESULTS_FORMAT = "fleetsim-sweep-results/2"
Outcome = Literal["passed", "failed", "xfailed", "xpassed", "skipped"]  # pytest's words for a test's end
_SWEEP_FAMILY = SWEEP_RESULTS_FORMAT.rpartition("/")[0] + "/"
_SLACK = 1e-9  # relative; a value exactly at a limit written in decimal must not trip on binary rounding


class BaselineError(FleetsimError, ValueError):
    """A metrics document or a compare threshold is unusable; the message names the file or the text."""


@dataclass(frozen=True, slots=True)
class ScenarioMetrics:
    """One scenario's figures in a session: flat numbers only, so baselines diff and compare simply."""

    id: str  # the pytest node id, e.g. "scenario_suites/examples.fleetsim.yaml::crossing"
    planner: str
    outcome: Outcome
    tasks_total: int
    tasks_completed: int
    makespan: float | None  # None: not every task was completed
    distance: float  # metres, summed over vehicles
    waiting_time: float  # seconds, summed over vehicles
    alerts: int
    rejections: int
    planner_calls: int
    planner_wall_time: float
    wall_time: float
    sim_time: float
    realtime_factor: float | None
    trace_hash: str
    # Added with the contact check: a baseline written before has neither, and reads as no contacts and
    # no clearance measured.
    contacts: int = 0
    clearance: float | None = None  # metres: the closest two footprints came (None: not within reach, or off)
    # A run with transport orders: its measures (fleetsim.gating.measures.GATED_MEASURES); None without
    # orders, or without the figure (no order completed). A baseline written before reads as none.
    orders_per_hour: float | None = None
    service_time_median: float | None = None  # seconds
    service_time_p95: float | None = None  # seconds
    wait_for_pickup_p95: float | None = None  # seconds
    deadline_misses: int | None = None
    utilisation: float | None = None  # share, 0..1
    empty_travel_share: float | None = None  # share, 0..1
    stalls: int | None = None

    @classmethod
    def from_result(cls, id: str, outcome: Outcome, result: RunResult) -> ScenarioMetrics:
        """Floats are rounded to 6 places like ``fleetsim run --json``, so baselines read without noise."""
        m = result.metrics
        return cls(
            id=id,
            planner=result.planner,
            outcome=outcome,
            tasks_total=result.tasks_total,
            tasks_completed=result.tasks_completed,
            makespan=_round(m.makespan),
            distance=round(math.fsum(m.distance.values()), 6),  # fsum: the same total in any order
            waiting_time=round(math.fsum(m.waiting_time.values()), 6),
            alerts=len(result.collisions),
            rejections=len(result.rejections),
            planner_calls=m.planner_calls,
            planner_wall_time=round(m.planner_wall_time, 6),
            wall_time=round(m.wall_time, 6),
            sim_time=round(m.sim_time, 6),
            realtime_factor=_round(m.realtime_factor),
            trace_hash=result.trace_hash,
            contacts=len(result.contact.contacts) if result.contact is not None else 0,
            clearance=_round(m.clearance),
            **_measures(None if result.measures is None else result.measures.to_dict()),
        )

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)

    @classmethod
    def from_document(cls, id: str, outcome: Outcome, document: Mapping[str, Any]) -> ScenarioMetrics:
        """The figures of a run's result document (``schemas/result.schema.json``: a sweep's record, a
        ``result.json``), as :meth:`from_result` takes them from the run itself (the document's figures
        are rounded already)."""
        m = document["metrics"]
        return cls(
            id=id,
            planner=document["planner"],
            outcome=outcome,
            tasks_total=document["tasks"]["total"],
            tasks_completed=document["tasks"]["completed"],
            makespan=_round(m["makespan"]),
            distance=round(math.fsum(m["distance"].values()), 6),
            waiting_time=round(math.fsum(m["waiting_time"].values()), 6),
            alerts=len(document["collisions"]),
            rejections=len(document["rejections"]),
            planner_calls=m["planner_calls"],
            planner_wall_time=float(m["planner_wall_time"]),
            wall_time=float(m["wall_time"]),
            sim_time=float(document["sim_time"]),
            realtime_factor=_round(m["realtime_factor"]),
            trace_hash=document["trace_hash"] or "",
            contacts=len((document.get("contact") or {}).get("contacts", ())),
            clearance=_round(m.get("clearance")),
            **_measures(document.get("measures")),
        )

    @classmethod
    def from_dict(cls, data: object, where: str) -> ScenarioMetrics:
        """Check every field's type, so a hand-edited baseline fails here and not mid-comparison."""
        if not isinstance(data, Mapping):
            msg = f"{where}: scenario={data!r} must be a JSON object"
            raise BaselineError(msg)
        values: dict[str, Any] = {}
        for f in fields(cls):
            if f.name not in data and f.default is not MISSING:
                continue  # a figure added later: its default
            if f.name not in data:
                msg = f"{where}: field {f.name!r} is missing"
                raise BaselineError(msg)
            value = data[f.name]
            accepts, expected = _FIELD_CHECKS[str(f.type)]
            if not accepts(value):
                msg = f"{where}: field {f.name!r} value={value!r} must be {expected}"
                raise BaselineError(msg)
            values[f.name] = float(value) if str(f.type).startswith("float") and value is not None else value
        return cls(**values)  # fields it does not know are left alone: a later version may add figures


def _round(value: float | None) -> float | None:
    return None if value is None else round(value, 6)


def _measures(shown: Mapping[str, Any] | None) -> dict[str, Any]:
    """The gated measures of a result document's ``measures`` (None: a run without orders), as read."""
    values: dict[str, Any] = {}
    for measure in GATED_MEASURES:
        value = measure_value(shown, measure.name)
        values[measure.name] = int(value) if measure.whole and value is not None else value
    return values


def _is_number(value: object) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


# Keyed by each field's annotation as written (a string, under ``from __future__ import annotations``).
_FIELD_CHECKS: dict[str, tuple[Callable[[object], bool], str]] = {
    "str": (lambda v: isinstance(v, str), "a string"),
    "int": (lambda v: isinstance(v, int) and not isinstance(v, bool), "an integer"),
    "int | None": (lambda v: v is None or (isinstance(v, int) and not isinstance(v, bool)), "an integer or null"),
    "float": (_is_number, "a finite number"),
    "float | None": (lambda v: v is None or _is_number(v), "a finite number or null"),
    "Outcome": (lambda v: v in get_args(Outcome), f"one of {', '.join(get_args(Outcome))}"),
}


# --- documents -----------------------------------------------------------------------------------


def metrics_document(rows: Iterable[ScenarioMetrics]) -> dict[str, Any]:
    """The session's document; sorted by id so the same results give the same bytes."""
    ordered = sorted(rows, key=attrgetter("id"))
    for before, after in pairwise(ordered):
        if before.id == after.id:
            msg = f"scenario id {after.id!r} appears twice; each scenario must have one row"
            raise BaselineError(msg)
    return {"format": METRICS_FORMAT, "scenarios": [row.to_dict() for row in ordered]}


def write_metrics(path: Path | str, rows: Iterable[ScenarioMetrics]) -> None:
    """Write atomically: an interrupted session must not leave a half baseline behind."""
    text = json.dumps(metrics_document(rows), indent=2, sort_keys=True) + "\n"
    write_text_atomically(Path(path), text)


def read_metrics(path: Path | str, planner: str | None = None) -> dict[str, ScenarioMetrics]:
    """The rows of a metrics document by id; anything unusable is a BaselineError naming ``path``.

    A sweep's results file (``fleetsim sweep``) is read too: its runs of suite scenarios (first
    repetition) by ``planner``, or by its only planner when ``planner`` ran none of them.
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8-sig")  # a BOM from a hand edit is harmless
    except FileNotFoundError:
        msg = f"{path}: no such metrics file; write one with --fleetsim-metrics-json {path}"
        raise BaselineError(msg) from None
    except (OSError, ValueError) as exc:  # ValueError: not UTF-8, or a NUL in the path
        msg = f"{path}: cannot read the metrics file: {exc}"
        raise BaselineError(msg) from None
    first = text.partition("\n")[0]
    if text.startswith('{"') and f'"format": "{SWEEP_RESULTS_FORMAT}"' in first:
        return _sweep_rows(path, text, planner)
    if text.startswith('{"') and f'"format": "{_SWEEP_FAMILY}' in first:
        msg = f"{Location(path, 1)}: a sweep results file of another fleetsim version (this one reads {SWEEP_RESULTS_FORMAT!r}); run the sweep again"
        raise BaselineError(msg)
    try:
        document = json.loads(text)
    except json.JSONDecodeError as exc:
        msg = f"{Location(path, exc.lineno, exc.colno)}: {json_problem(exc)}"
        raise BaselineError(msg) from None
    found = document.get("format") if isinstance(document, dict) else None
    if found != METRICS_FORMAT:
        msg = f'{path}: its "format" is {found!r}, not {METRICS_FORMAT!r}: this is not a metrics file written by --fleetsim-metrics-json'
        raise BaselineError(msg)
    if not isinstance(document.get("scenarios"), list):
        msg = f"{path}: scenarios={document.get('scenarios')!r} must be a list"
        raise BaselineError(msg)
    rows: dict[str, ScenarioMetrics] = {}
    for index, data in enumerate(document["scenarios"]):
        row = ScenarioMetrics.from_dict(data, where=f"{path}: scenarios[{index}]")
        if row.id in rows:
            msg = f"{path}: scenarios[{index}]: id {row.id!r} appears twice"
            raise BaselineError(msg)
        rows[row.id] = row
    return rows


def _sweep_rows(path: Path, text: str, planner: str | None) -> dict[str, ScenarioMetrics]:
    from fleetsim.sim.result_schema import result_problem  # jsonschema only for a sweep's file

    rows: dict[str, dict[str, ScenarioMetrics]] = {}
    lines = text.split("\n")
    for number, line in enumerate(lines[1:-1], start=2):  # text after the last newline: a row cut short
        try:
            data = json.loads(line) if line.strip() else None
        except json.JSONDecodeError as exc:
            msg = f"{Location(path, number, exc.colno)}: {json_problem(exc)}"
            raise BaselineError(msg) from None
        if data is None:
            continue
        problem = result_problem(data) or (None if isinstance(data.get("id"), str) else "its 'id' is missing")
        if problem is not None:
            msg = f"{Location(path, number)}: not a run's result: {problem}"
            raise BaselineError(msg)
        if data.get("source") != "suite" or data.get("repetition") != 1:
            continue  # generated scenarios have no pytest id to compare with
        row = ScenarioMetrics.from_document(data["id"], data["status"], data)
        rows.setdefault(row.planner, {}).setdefault(row.id, row)
    if planner in rows:
        return rows[planner]
    if len(rows) == 1:
        return next(iter(rows.values()))
    if not rows:
        return {}
    msg = f"{path}: a sweep of {len(rows)} planners ({', '.join(sorted(rows))}); run pytest with --planner one of them"
    raise BaselineError(msg)


# --- thresholds ----------------------------------------------------------------------------------


class Metric(NamedTuple):
    """How to read a metric from a row, and which way is better."""

    read: Callable[[ScenarioMetrics], float | None]
    better: Literal["lower", "higher"]
    # What a figure the run no longer produces means: worse (makespan: tasks left undone) or better
    # (clearance: no two footprints came within reach any more).
    missing: Literal["worse", "better"] = "worse"


METRICS: Mapping[str, Metric] = MappingProxyType(
    {
        "makespan": Metric(attrgetter("makespan"), "lower"),
        "distance": Metric(attrgetter("distance"), "lower"),
        "waiting_time": Metric(attrgetter("waiting_time"), "lower"),
        "planner_wall_time": Metric(attrgetter("planner_wall_time"), "lower"),
        "wall_time": Metric(attrgetter("wall_time"), "lower"),
        "planner_calls": Metric(attrgetter("planner_calls"), "lower"),
        "alerts": Metric(attrgetter("alerts"), "lower"),
        "rejections": Metric(attrgetter("rejections"), "lower"),
        "tasks_completed": Metric(attrgetter("tasks_completed"), "higher"),
        "realtime_factor": Metric(attrgetter("realtime_factor"), "higher"),
        "contacts": Metric(attrgetter("contacts"), "lower"),
        "clearance": Metric(attrgetter("clearance"), "higher", missing="better"),
        **{measure.name: Metric(attrgetter(measure.name), measure.better) for measure in GATED_MEASURES},
    }
)
_KNOWN = ", ".join(sorted(METRICS))


@dataclass(frozen=True, slots=True)
class Threshold:
    """How much worse ``metric`` may get: ``limit`` percent of the baseline if ``relative``, else in its unit."""

    metric: str
    limit: float
    relative: bool

    def __post_init__(self) -> None:
        if self.metric not in METRICS:
            msg = f"unknown metric {self.metric!r}"
            raise BaselineError(msg)
        if not (math.isfinite(self.limit) and self.limit >= 0):
            msg = f"limit={self.limit!r} must be a finite number >= 0"
            raise BaselineError(msg)

    def __str__(self) -> str:
        return f"{self.limit:g}%" if self.relative else f"{self.limit:g}"


def parse_threshold(text: str) -> Threshold:
    """``"makespan:5%"`` (relative to the baseline) or ``"makespan:2.5"`` (absolute, in the metric's unit)."""
    try:
        return _parse_threshold(text)
    except BaselineError as exc:
        msg = f"--fleetsim-compare-fail={text!r}: {exc}; write METRIC:PERCENT% or METRIC:AMOUNT; known: {_KNOWN}"
        raise BaselineError(msg) from None


def _parse_threshold(text: str) -> Threshold:
    metric, colon, limit = text.partition(":")
    if not colon:
        msg = "missing ':' between the metric and the limit"
        raise BaselineError(msg)
    number = limit.strip().removesuffix("%")
    try:
        value = float(number)
    except ValueError:
        msg = f"limit {limit!r} is not a number"
        raise BaselineError(msg) from None
    return Threshold(metric.strip(), value, relative=limit.strip().endswith("%"))


# --- comparison ----------------------------------------------------------------------------------


def _show(value: float) -> str:
    return str(value) if isinstance(value, int) else repr(float(f"{value:.6g}"))


@dataclass(frozen=True, slots=True)
class Regression:
    """A metric of one scenario that got worse than its threshold allows."""

    id: str
    metric: str
    baseline: float
    current: float | None  # None: the run no longer produces the figure (makespan: tasks left undone)
    threshold: Threshold

    def __str__(self) -> str:
        return f"{self.id}: {self.change()}"

    def change(self) -> str:
        """``makespan 20.0 -> 21.5 (+7.5%, limit 5%)``: what got worse, without the scenario's id."""
        head = f"{self.metric} {_show(self.baseline)} -> "
        if self.current is None:
            gone = "not reached" if self.metric == "makespan" else "no value"
            return f"{head}{gone} (limit {self.threshold})"
        change = self.current - self.baseline
        signed = ("+" if change > 0 else "") + _show(change)
        if not self.threshold.relative:
            delta = signed
        elif self.baseline == 0:
            delta = f"{signed} from 0"  # any worsening of a zero exceeds a relative limit
        else:
            delta = f"{change / abs(self.baseline) * 100:+.1f}%"
        return f"{head}{_show(self.current)} ({delta}, limit {self.threshold})"


@dataclass(frozen=True, slots=True)
class Comparison:
    """The outcome of comparing a session with a baseline; only ``regressions`` fail the session."""

    regressions: tuple[Regression, ...]  # sorted by id, then metric
    missing: tuple[str, ...]  # in the baseline, not run now: not a failure (a subset may be selected)
    new: tuple[str, ...]  # run now, without a baseline
    planner_changed: tuple[str, ...]  # compared anyway: a new planner is what one wants to gate
    compared: int

    def lines(self) -> list[str]:
        """Lines for a terminal summary."""
        count = len(self.regressions)
        lines = [f"fleetsim compare: {self.compared} compared, {count} regression{'' if count == 1 else 's'}"]
        lines += [f"  {regression}" for regression in self.regressions]
        for label, ids in (
            ("planner changed since the baseline (compared anyway)", self.planner_changed),
            ("no baseline yet", self.new),
            ("in the baseline but not run now", self.missing),
        ):
            if ids:
                more = f" and {len(ids) - 5} more" if len(ids) > 5 else ""
                lines.append(f"  {label}: {len(ids)}: {', '.join(ids[:5])}{more}")
        return lines


def compare(
    baseline: Mapping[str, ScenarioMetrics], current: Mapping[str, ScenarioMetrics], thresholds: Sequence[Threshold]
) -> Comparison:
    """Check every threshold for every scenario present in both; each breached threshold is one regression."""
    common = sorted(baseline.keys() & current.keys())
    ordered = sorted(thresholds, key=attrgetter("metric"))
    found = (_regression(sid, baseline[sid], current[sid], threshold) for sid in common for threshold in ordered)
    return Comparison(
        regressions=tuple(r for r in found if r is not None),
        missing=tuple(sorted(baseline.keys() - current.keys())),
        new=tuple(sorted(current.keys() - baseline.keys())),
        planner_changed=tuple(sid for sid in common if baseline[sid].planner != current[sid].planner),
        compared=len(common),
    )


def _regression(sid: str, before: ScenarioMetrics, now: ScenarioMetrics, threshold: Threshold) -> Regression | None:
    metric = METRICS[threshold.metric]
    old, new = metric.read(before), metric.read(now)
    if old is None:
        return None  # nothing to compare against
    if new is None and metric.missing == "better":
        return None
    if new is not None:
        worse = new - old if metric.better == "lower" else old - new
        allowed = abs(old) * threshold.limit / 100 if threshold.relative else threshold.limit
        if worse <= allowed + _SLACK * max(1.0, abs(old)):
            return None
    return Regression(sid, threshold.metric, old, new, threshold)

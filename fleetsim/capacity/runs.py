"""The runs of a capacity search: one suite entry at a rate, once per order stream seed, on the sweep's
machinery (:mod:`fleetsim.sweep.items`' plain-data runs, :func:`fleetsim.sweep.execute.run_items` on Dask).

Each rate's runs go out together, as one batch, to a Dask client kept open over the search; their rows go
into a results file of the sweep's format (``fleetsim sweep report`` reads it) as they finish, and are
judged by their result documents alone (:func:`fleetsim.capacity.criteria.judge_run`), in seed order, so
neither the workers' layout nor the order runs finish in changes anything.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from fleetsim.capacity.criteria import Criteria, Judgement, judge_run
from fleetsim.errors import FleetsimError, Location
from fleetsim.load.suites.scenario import load_scenario
from fleetsim.load.suites.suite import load_suite
from fleetsim.scenario import Scenario
from fleetsim.sim.record import RunOrigin
from fleetsim.sweep.execute import run_items
from fleetsim.sweep.items import RunItem, scenario_id
from fleetsim.sweep.payload import scenario_payload
from fleetsim.sweep.results import ResultsError, ResultsFile, read_results

__all__ = ["CapacityError", "Runner", "RunsFile", "Target", "load_target", "rate_items"]


class CapacityError(FleetsimError, ValueError):
    """A suite entry whose capacity cannot be searched (no Poisson order stream, say), or a search that
    cannot go on (no run at a rate ran at all); the message names the entry."""


@dataclass(frozen=True, slots=True)
class Target:
    """The suite entry searched: its id (``SUITE::NAME``), its scenario as every run gets it (its ``expect``
    bounds on measures left out), its order stream's own rate and where it is written."""

    id: str
    scenario: Scenario
    rate: float
    origin: Mapping[str, Any]
    where: str  # SUITE:LINE, for messages


def load_target(suite_path: Path, name: str, dispatcher: str | None) -> Target:
    """Entry ``name`` of the suite at ``suite_path`` (loaded completely, as ``fleetsim run`` loads it), with
    ``dispatcher`` (``--dispatcher``) in place of its own when given. Raises :class:`CapacityError` when it
    has no order stream of Poisson arrivals to scale, or no shift to measure."""
    suite = load_suite(suite_path)
    entries = {spec.name: spec for spec in suite.scenarios}
    if name not in entries:
        msg = f"{suite_path} has no scenario {name!r} (its scenarios: {', '.join(entries)})"
        raise CapacityError(msg)
    spec = entries[name]
    where = str(Location(suite_path, spec.line))
    scenario = load_scenario(spec, suite)
    stream = scenario.order_stream
    missing = _missing(scenario)
    if missing:
        msg = f"{where}: scenario {name!r} {missing}; fleetsim capacity scales an order stream's rate"
        raise CapacityError(msg)
    assert stream is not None and stream.arrivals.rate is not None
    expect = dataclasses.replace(scenario.expect, measures=(), overloaded=None)  # capacity judges by its own rules
    scenario = dataclasses.replace(scenario, expect=expect, dispatcher=dispatcher or scenario.dispatcher)
    origin = RunOrigin.of_entry(str(suite_path), spec).keys()
    return Target(scenario_id(suite_path, name), scenario, stream.arrivals.rate, origin, where)


def _missing(scenario: Scenario) -> str:
    """What the scenario lacks for a capacity search, or ``""``."""
    stream = scenario.order_stream
    if stream is None:
        return "has no order stream (order_stream: {arrivals: {poisson: RATE}, stops: ...})"
    if stream.arrivals.process != "poisson" or stream.arrivals.rate is None:
        return f"has {stream.arrivals.process} arrivals, not a Poisson rate (arrivals: {{poisson: RATE}})"
    if stream.limit is not None:
        return f"caps its order stream at limit: {stream.limit} orders, which a higher rate only releases sooner"
    if stream.arrivals.until is not None:
        return f"stops its order stream at until: {stream.arrivals.until:g} s, before the shift ends"
    if scenario.orders:
        return "also has fixed orders (orders.csv), which no rate changes"
    if scenario.shift is None:
        return "has no shift to measure over (shift: {duration: ..., warmup: ...})"
    return ""


def rate_items(
    target: Target, rate: float, seeds: tuple[int, ...], planner: str, timeout: float | None
) -> list[RunItem]:
    """The runs of ``target`` at ``rate`` orders per hour, one per seed: ids ``SUITE::NAME~rRATE~oSEED``."""
    assert target.scenario.order_stream is not None
    stream = target.scenario.order_stream
    items = []
    for seed in seeds:
        arrivals = dataclasses.replace(stream.arrivals, rate=rate)
        scenario = dataclasses.replace(
            target.scenario, order_stream=dataclasses.replace(stream, seed=seed, arrivals=arrivals)
        )
        run_id = f"{target.id}~r{rate:g}~o{seed}"
        item = RunItem(
            key=f"{planner} | {run_id} | 1", id=run_id, planner=planner, source="suite", seed=None,
            repetition=1, vehicles=len(scenario.vehicles), scenario=scenario_payload(scenario),
            origin=dict(target.origin), load_error=None, planner_timeout=timeout, record="none", artifacts=".",
        )  # fmt: skip
        items.append(item)
    return items


class RunsFile(ResultsFile):
    """The search's runs, a sweep results file (``fleetsim sweep report`` reads it), whose rows it keeps.

    With ``resume``, the rows already there are kept and not run again; the file must be of the same
    scenario, planner and dispatcher (its header says them)."""

    def __init__(self, path: Path, header: dict[str, Any], *, resume: bool) -> None:
        if resume and path.exists():
            found, _ = read_results(path)
            about = {key: found.get(key) for key in ("capacity", "planners")}
            if about != {key: header[key] for key in about}:
                msg = f"{path}: the runs of another search ({about}); --resume goes on with the same scenario, planner and dispatcher only"
                raise ResultsError(msg)
        super().__init__(path, header, resume=resume)
        self.rows: dict[str, dict[str, Any]] = {row["key"]: row for row in read_results(path)[1]}

    def __enter__(self) -> RunsFile:
        return self

    def add(self, row: dict[str, Any]) -> bool:
        written = super().add(row)
        if written:
            self.rows[row["key"]] = row
        return written


@dataclass
class Runner:
    """Runs ``target`` at a rate and judges each seed's run: the search's evaluator. The Dask client comes
    from ``open_client``, called once, when the first rate has runs the runs file lacks (a search resumed
    to its end starts no cluster)."""

    target: Target
    planner: str
    seeds: tuple[int, ...]
    criteria: Criteria
    runs: RunsFile
    open_client: Callable[[], Any]
    timeout: float | None = 10.0
    on_rate: Callable[[float, Mapping[int, Judgement]], None] = lambda rate, runs: None
    _client: Any = field(default=None, init=False, repr=False)

    def __call__(self, rate: float) -> dict[int, Judgement]:
        items = rate_items(self.target, rate, self.seeds, self.planner, self.timeout)
        if any(item["key"] not in self.runs.done for item in items):
            self._client = self._client or self.open_client()
            run_items(items, self.runs, client=self._client)
        rows = [self.runs.rows[item["key"]] for item in items]
        if all(row.get("error") for row in rows):
            msg = f"{self.target.where}: no run of {self.target.id} at {rate:g} orders/h ran: {rows[0]['error']}"
            raise CapacityError(msg)
        judged = {seed: judge_run(row, self.criteria) for seed, row in zip(self.seeds, rows, strict=True)}
        self.on_rate(rate, judged)
        return judged

"""Sweeps of shifts on real Dask workers: a scenario with orders runs there as it does here, order stream
seeds vary it, and a throughput gate tells a worse dispatcher from the baseline sweep."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import pytest

pytest.importorskip("distributed")

from sweep_support import planners_on_path, write_pool_project

from fleetsim import load_scenario, load_suite
from fleetsim.cli.main import main
from fleetsim.planners import ReservingPlanner
from fleetsim.sim import run_scenario
from fleetsim.sweep.execute import run_items
from fleetsim.sweep.items import expand
from fleetsim.sweep.results import ResultsFile, read_results
from fleetsim.sweep.spec import load_sweep_spec

ROOT = Path(__file__).resolve().parents[2]
SHIPPED = ROOT / "scenario_suites" / "warehouse.fleetsim.yaml"
PLANNER = "fleetsim.planners:ReservingPlanner"
GATE = "orders_per_hour < baseline - 5%"


def test_a_local_process_sweep_runs_the_shipped_shift_as_it_runs_here(tmp_path: Path) -> None:
    spec_path = tmp_path / "shift.sweep.yaml"
    spec_path.write_text(
        f"fleetsim-sweep: 1\nname: shift\nplanners: [{PLANNER}]\nrecord: none\norder_seeds: [1, 5]\n"
        f"sources:\n  - suite: {SHIPPED}::shift\n",
        encoding="utf-8",
    )
    items = expand(load_sweep_spec(spec_path), tmp_path / "runs")
    for item in items:  # the shift cut to five minutes, as plain data: what a worker gets is all it has
        assert item["scenario"] is not None
        item["scenario"]["shift"] |= {"duration": 300.0, "warmup": 60.0}
    with ResultsFile(tmp_path / "results.jsonl", {"name": "shift"}, resume=False) as results:
        run_items(items, results, workers=1)
    _, rows = read_results(tmp_path / "results.jsonl")
    hashes = {row["id"].rpartition("~o")[2]: row["trace_hash"] for row in rows}

    suite = load_suite(SHIPPED)
    scenario = load_scenario(next(spec for spec in suite.scenarios if spec.name == "shift"), suite)
    assert scenario.shift is not None and scenario.order_stream is not None
    short = dataclasses.replace(scenario, shift=dataclasses.replace(scenario.shift, duration=300, warmup=60))
    here = {
        str(seed): run_scenario(
            dataclasses.replace(short, order_stream=dataclasses.replace(scenario.order_stream, seed=seed)),
            ReservingPlanner(),
        )
        for seed in (1, 5)
    }
    assert hashes == {seed: result.trace_hash for seed, result in here.items()}
    assert hashes["1"] != hashes["5"]  # another seed, other orders
    measured = {row["id"].rpartition("~o")[2]: row["measures"] for row in rows}
    assert measured == {seed: result.measures.to_dict() for seed, result in here.items() if result.measures}


def _sweep(folder: Path, suite: Path, name: str, dispatcher: str | None = None) -> Path:
    """Run the pool suite's shift with four order stream seeds on one local worker; the results file."""
    spec = folder / f"{name}.sweep.yaml"
    spec.write_text(
        f"fleetsim-sweep: 1\nname: {name}\nplanners: [{PLANNER}]\nrecord: none\norder_seeds: [1, 2, 3, 4]\n"
        + (f"dispatcher: {dispatcher}\n" if dispatcher else "")
        + f"sources:\n  - suite: {suite.name}\n",
        encoding="utf-8",
    )
    results = folder / f"{name}.jsonl"
    assert main(["sweep", str(spec), "-o", str(results), "--workers", "1"]) == 0
    return results


def test_a_worse_dispatcher_fails_the_throughput_gate_and_the_baseline_passes_against_itself(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    planners_on_path(monkeypatch)
    suite = write_pool_project(tmp_path)
    base = _sweep(tmp_path, suite, "main")
    worse = _sweep(tmp_path, suite, "branch", dispatcher="sweep_dispatchers:HighestIdleOnly")
    header, rows = read_results(worse)
    assert header["dispatcher"] == "sweep_dispatchers:HighestIdleOnly"  # the rows do not say it; the file does
    assert len(rows) == 4 and all(row["measures"]["orders_per_hour"] > 0 for row in rows)
    capsys.readouterr()

    assert main(["sweep", "report", str(worse), "--compare", str(base), "--fail-if", GATE]) == 1
    out = capsys.readouterr().out
    assert f"FAIL  {PLANNER}: {GATE}: mean difference -" in out and "n=4" in out
    assert f"## ReservingPlanner against ReservingPlanner @ {base.name}" in out
    assert "## Orders" in out and "| orders per hour (orders/h) | 4 |" in out

    assert main(["sweep", "report", str(base), "--compare", str(base), "--fail-if", GATE]) == 0
    out = capsys.readouterr().out
    assert f"ok  {PLANNER}: {GATE}: mean difference +0 orders/h (95% CI +0 .. +0, n=4)" in out


def test_compare_names_a_baseline_planner_the_base_sweep_never_ran(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    results = tmp_path / "r.jsonl"
    results.write_text(json.dumps({"format": "fleetsim-sweep-results/2", "baseline": PLANNER}) + "\n")
    assert main(["sweep", "report", str(results), "--compare", str(results), "--baseline", "other:Planner"]) == 2
    assert f"--baseline='other:Planner' ran no run in {results}; its planners: none" in capsys.readouterr().err

"""One result format: every producer's document satisfies the published schema (schemas/result.schema.json).

``fleetsim run --json`` lines, the ``result.json`` of a run folder and a sweep's records are validated with
jsonschema against the shipped file; a sweep record is the run's ordinary result plus the sweep's keys,
and every reader of sweep records (report, statistics, ``--fleetsim-compare``) reads that shape.
"""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path
from typing import Any

import jsonschema
import pytest
from result_document import SCHEMA, schema_errors

from fleetsim import load_scenario, load_suite, run_scenario
from fleetsim.cli import main
from fleetsim.gating.baseline import BaselineError, ScenarioMetrics, read_metrics
from fleetsim.planners import BFSPlanner, ReservingPlanner
from fleetsim.sim.record import ENTRY_KEYS
from fleetsim.sim.result_schema import result_problem, result_schema
from fleetsim.sweep.items import RunItem, expand
from fleetsim.sweep.results import SWEEP_KEYS, ResultsError, ResultsFile, read_results, record_problem
from fleetsim.sweep.spec import load_sweep_spec
from fleetsim.sweep.stats import METRICS, planner_time_per_call, throughput, waiting_share
from fleetsim.sweep.worker import failed_row, result_row, run_item

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = ROOT / "scenario_suites" / "examples.fleetsim.yaml"
BFS = "fleetsim.planners:BFSPlanner"
RESERVING = "fleetsim.planners:ReservingPlanner"
WALL_CLOCK = ("planner_wall_time", "wall_time", "realtime_factor", "harness_share")

SWEEP = f"""fleetsim-sweep: 1
name: formats
planners: [{RESERVING}, {BFS}]
record: failed
defaults: {{time_limit: 30}}
sources:
  - suite: {EXAMPLES.as_posix()}::crossing
  - name: warehouses
    generate: {{layout: warehouse, size: [1, 2], vehicles: [1, 2], tasks: [1, 1]}}
    count: 2
    seed: 5
"""


def example(name: str):  # type: ignore[no-untyped-def]
    suite = load_suite(EXAMPLES)
    return load_scenario(next(spec for spec in suite.scenarios if spec.name == name), suite)


def example_line(name: str) -> int:
    return next(spec.line for spec in load_suite(EXAMPLES).scenarios if spec.name == name)


def test_the_packaged_schema_is_the_published_one_and_a_valid_schema() -> None:
    packaged = ROOT / "fleetsim" / "schemas" / "result.schema.json"
    assert packaged.read_bytes() == SCHEMA.read_bytes()
    jsonschema.Draft202012Validator.check_schema(json.loads(SCHEMA.read_text(encoding="utf-8")))
    assert result_schema() == json.loads(SCHEMA.read_text(encoding="utf-8"))


# -- the producers ----------------------------------------------------------------------------------


def test_every_line_of_run_json_and_every_result_json_satisfy_the_schema(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    (tmp_path / "broken.fleetsim.yaml").write_text("fleetsim: 1\nname: broken\nscenarios: [\n")
    # BFSPlanner: collisions and rejections; a suite that does not load: a result without a run.
    main(["run", str(EXAMPLES), "broken.fleetsim.yaml", "--planner", BFS, "--json", "--record", "out"])
    lines = [json.loads(line) for line in capsys.readouterr().out.splitlines()]
    assert len(lines) == 5
    assert {line["ended"] for line in lines} >= {"collision", "load-error"}
    for line in lines:
        assert schema_errors(line) == [], line["scenario"]
    folders = sorted((tmp_path / "out").glob("*/*/result.json"))
    assert len(folders) == 4
    for path in folders:
        assert schema_errors(json.loads(path.read_text(encoding="utf-8"))) == [], path
    unloaded = next(line for line in lines if line["ended"] == "load-error")
    assert unloaded["trace_hash"] is None and unloaded["tasks"] == {"total": 0, "completed": 0}


def _items(tmp_path: Path) -> list[RunItem]:
    spec_path = tmp_path / "formats.sweep.yaml"
    spec_path.write_text(SWEEP, encoding="utf-8")
    return expand(load_sweep_spec(spec_path), tmp_path / "runs")


def test_a_sweep_record_is_the_runs_result_plus_the_sweeps_keys(tmp_path: Path) -> None:
    items = _items(tmp_path)
    crossing = next(item for item in items if item["id"].endswith("::crossing") and item["planner"] == BFS)
    record = run_item(crossing)

    assert schema_errors(record) == [] and record_problem(record) is None
    direct = run_scenario(example("crossing"), BFSPlanner(), planner_name=BFS).to_dict()
    assert set(record) - set(direct) == {*SWEEP_KEYS, *ENTRY_KEYS}
    assert (record["suite"], record["line"], record["xfail"], record["planner_options"]) == (
        crossing["id"].rpartition("::")[0],
        example_line("crossing"),
        None,
        {},
    )
    ran = {k: v for k, v in record.items() if k not in (*SWEEP_KEYS, *ENTRY_KEYS)}
    for document in (ran, direct):  # wall-clock figures vary from run to run; artifacts: only the sweep kept any
        document["metrics"] = {k: v for k, v in document["metrics"].items() if k not in WALL_CLOCK}
        document.pop("artifacts")
    assert ran == direct
    assert record["collisions"] and record["failures"][0]["kind"] == "collision"  # what the flat row lacked
    assert (record["key"], record["id"], record["repetition"], record["error"]) == (
        crossing["key"],
        crossing["id"],
        1,
        None,
    )
    assert schema_errors(json.loads(Path(record["artifacts"]["result"]).read_text(encoding="utf-8"))) == []


def test_every_record_of_a_sweep_satisfies_the_schema_failed_runs_included(tmp_path: Path) -> None:
    items = _items(tmp_path)
    records = [run_item(item) for item in items]
    never = failed_row(items[0], "the run's workers died KilledWorker: gone")
    crossing = next(item for item in items if item["id"].endswith("::crossing"))
    gone = {**crossing, "id": crossing["id"] + "~d3@2", "scenario": None, "load_error": "x.csv:2: bad"}
    unloaded = failed_row(gone, "did not load", "load-error")  # type: ignore[arg-type]
    for record in [*records, never, unloaded]:
        assert schema_errors(record) == [], record["key"]
    assert {r["source"] for r in records} == {"suite", "generated"}
    assert (
        never["failures"][0]["kind"] == "planner-error"
        and never["error"] == "the run's workers died KilledWorker: gone"
    )
    assert unloaded["ended"] == "load-error" and unloaded["trace_hash"] is None
    assert unloaded["scenario"] == "crossing"


@pytest.mark.parametrize(
    ("change", "problem"),
    [
        (lambda r: r.pop("status"), "'status' is a required property"),
        (lambda r: r["metrics"].pop("makespan"), "metrics: 'makespan' is a required property"),
        (lambda r: r.update(tasks_completed=2), "Additional properties are not allowed ('tasks_completed'"),
        (lambda r: r.update(trace_hash=""), "trace_hash: '' does not match '^[0-9a-f]{64}$'"),
        (lambda r: r["tasks"].update(completed=-1), "tasks.completed: -1 is less than the minimum of 0"),
    ],
)
def test_a_record_that_breaks_the_schema_is_refused_naming_the_key(change: Any, problem: str) -> None:
    record = run_scenario(example("crossing"), ReservingPlanner()).to_dict()
    assert result_problem(record) is None  # narrowly: the record as written is valid
    change(record)
    assert schema_errors(record) != []
    said = result_problem(record)
    assert said is not None and problem in said, said


def test_a_run_json_document_without_the_sweeps_keys_is_no_sweep_record() -> None:
    document = run_scenario(example("crossing"), ReservingPlanner()).to_dict()
    assert result_problem(document) is None
    assert record_problem(document) == "the sweep's key 'key' is missing"


# -- the readers ------------------------------------------------------------------------------------


def test_sweep_figures_are_worked_out_from_the_result(tmp_path: Path) -> None:
    result = run_scenario(example("corridor-passing-bay"), ReservingPlanner())
    item = next(item for item in _items(tmp_path) if item["id"].endswith("::crossing"))
    record = result_row({**item, "vehicles": 2}, result)
    hours = result.sim_time / 3600
    assert throughput(record) == pytest.approx(result.tasks_completed / hours)
    waited = math.fsum(result.metrics.waiting_time.values())
    assert waiting_share(record) == pytest.approx(waited / (2 * result.sim_time), abs=1e-6)
    assert planner_time_per_call(record) == pytest.approx(
        result.metrics.planner_wall_time / result.metrics.planner_calls, abs=1e-6
    )
    assert METRICS["alerts"].read(record) == 0.0 and METRICS["deadlocks"].read(record) == 0.0
    assert METRICS["makespan"].read(record) == pytest.approx(result.metrics.makespan)
    never = failed_row(item, "gone")
    assert [METRICS[m].read(never) for m in ("throughput", "waiting_share", "makespan")] == [None, None, None]


def test_fleetsim_compare_reads_a_sweeps_records_as_the_runs_metrics(tmp_path: Path) -> None:
    items = [item for item in _items(tmp_path) if item["source"] == "suite"]
    path = tmp_path / "r.jsonl"
    with ResultsFile(path, {"name": "n"}, resume=False) as results:
        for item in items:
            results.add(run_item(item))
    rows = read_metrics(path, planner=BFS)
    [(sid, row)] = rows.items()
    assert sid.endswith("examples.fleetsim.yaml::crossing") and row.planner == BFS
    direct = ScenarioMetrics.from_result(
        sid, "failed", run_scenario(example("crossing"), BFSPlanner(), planner_name=BFS)
    )
    same = (
        "outcome",
        "tasks_total",
        "tasks_completed",
        "makespan",
        "alerts",
        "rejections",
        "planner_calls",
        "trace_hash",
    )
    assert {k: getattr(row, k) for k in same} == {k: getattr(direct, k) for k in same}
    assert row.distance == pytest.approx(direct.distance, abs=1e-5)


def test_a_sweep_row_that_is_not_a_result_is_refused_at_its_line(tmp_path: Path) -> None:
    items = _items(tmp_path)
    path = tmp_path / "r.jsonl"
    with ResultsFile(path, {"name": "n"}, resume=False) as results:
        results.add(run_item(items[0]))
    lines = path.read_text(encoding="utf-8").splitlines()
    broken = json.loads(lines[1])
    del broken["metrics"]
    path.write_text("\n".join([lines[0], json.dumps(broken)]) + "\n", encoding="utf-8")
    with pytest.raises(ResultsError, match=r"r\.jsonl:2: not a sweep record: the result: 'metrics' is a required"):
        read_results(path)
    with pytest.raises(BaselineError, match=r"r\.jsonl:2: not a run's result: the result: 'metrics' is a required"):
        read_metrics(path)


def test_a_results_file_of_the_flat_format_says_it_is_from_another_version(tmp_path: Path) -> None:
    path = tmp_path / "old.jsonl"
    old_row = {"key": "a | b | 1", "id": "b", "tasks_completed": 1, "tasks_total": 1}
    path.write_text(json.dumps({"format": "fleetsim-sweep-results/1"}) + "\n" + json.dumps(old_row) + "\n")
    with pytest.raises(ResultsError, match="written by another fleetsim version"):
        read_results(path)
    with pytest.raises(BaselineError, match="a sweep results file of another fleetsim version"):
        read_metrics(path)


def test_the_sweep_report_of_records_names_the_first_failure(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    items = [item for item in _items(tmp_path) if item["source"] == "suite"]
    path = tmp_path / "r.jsonl"
    with ResultsFile(path, {"name": "formats", "baseline": RESERVING}, resume=False) as results:
        for item in items:
            results.add(run_item(item))
    assert main(["sweep", "report", str(path)]) == 0
    out = capsys.readouterr().out
    assert "| BFSPlanner | 1 | 0 | 0 |" in out and "| ReservingPlanner | 1 | 0 | 100 |" in out
    assert "examples.fleetsim.yaml::crossing`: failed, throughput" in out
    assert "— collision: possible collision on segment 2" in out


if sys.platform == "win32":  # pragma: no cover
    pytestmark = pytest.mark.skip("sweeps run planners as on POSIX")

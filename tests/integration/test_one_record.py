"""One record everywhere: ``fleetsim run --json``, pytest's ``result.json`` and a sweep's results file give
the same run the same record (``fleetsim.sim.record.run_record``): the same keys, but for the producers'
own ones listed in ``PRODUCER_KEYS``, and the same values, all valid against the published schema."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest
from result_document import schema_errors
from sweep_support import TABLE_PLANNER, planners_on_path, write_suite_sweep, write_table_project

from fleetsim.cli import main
from fleetsim.sim.record import ENTRY_KEYS, PRODUCER_KEYS
from fleetsim.sweep.results import read_results

# Imported before the test, not inside it: pytester takes out of sys.modules what a test imported, and
# distributed taken out so leaves the process unable to load pytest plugins in later in-process runs.
pytest.importorskip("distributed")

WALL_CLOCK = ("planner_wall_time", "wall_time", "realtime_factor", "harness_share")


def _shared(record: dict[str, object], producer: str | None) -> dict[str, object]:
    """The record without its producer's own keys, its artifacts (where each producer put files) and its
    wall-clock figures; the suite file as a resolved path."""
    own = PRODUCER_KEYS[producer] if producer is not None else ()
    shared = {key: value for key, value in record.items() if key not in own and key != "artifacts"}
    metrics = shared["metrics"]
    assert isinstance(metrics, dict)
    shared["metrics"] = {key: value for key, value in metrics.items() if key not in WALL_CLOCK}
    shared["suite"] = str(Path(str(record["suite"])).resolve())
    return shared


def test_run_json_result_json_and_a_sweep_record_agree(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str], pytester: pytest.Pytester
) -> None:
    monkeypatch.delenv("CI", raising=False)  # no lock file here: under CI pytest would fail the missing hash
    planners_on_path(monkeypatch)
    suite = write_table_project(tmp_path)

    assert main(["run", str(suite), "--planner", TABLE_PLANNER, "--json"]) == 0
    [line] = capsys.readouterr().out.splitlines()
    run = json.loads(line)

    pytester.runpytest_inprocess(
        str(suite), "--planner", TABLE_PLANNER, "--fleetsim-record", "all", "--fleetsim-artifacts", "out"
    ).assert_outcomes(passed=1)
    [written] = (pytester.path / "out").rglob("result.json")
    under_pytest = json.loads(written.read_text(encoding="utf-8"))

    # The sweep in a process of its own: its Dask cluster changes the process it runs in (environment
    # variables, imports), and a pytest run in this process afterwards would load no plugins.
    results = tmp_path / "sweep" / "results.jsonl"
    spec = write_suite_sweep(tmp_path, suite, [TABLE_PLANNER])
    command = [sys.executable, "-m", "fleetsim", "sweep", str(spec), "-o", str(results), "--workers", "1"]
    assert subprocess.run(command, capture_output=True, text=True, check=False).returncode == 0
    _, [swept] = read_results(results)

    for record in (run, under_pytest, swept):
        assert schema_errors(record) == []
        assert set(ENTRY_KEYS) <= set(record)
    assert set(run) == set(under_pytest) - set(PRODUCER_KEYS["pytest"]) == set(swept) - set(PRODUCER_KEYS["sweep"])
    assert set(PRODUCER_KEYS["pytest"]) <= set(under_pytest) and set(PRODUCER_KEYS["sweep"]) <= set(swept)
    assert _shared(run, None) == _shared(under_pytest, "pytest") == _shared(swept, "sweep")
    assert run["status"] == "passed" and run["trace_hash"] and run["tasks"] == {"total": 2, "completed": 2}
    assert (run["xfail"], run["planner_options"]) == (None, {"table": "data/table.txt"})

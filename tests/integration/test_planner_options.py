"""A suite entry's planner_options and data files reach its planner wherever it runs: ``fleetsim run``,
pytest, an ``exec:`` planner process, and a sweep's workers (other processes, with the files sent to them).

The planner (``sweep_planners:TablePlanner``) cannot start without its data file: it reads the file its
options name from the scenario's folder, which it is given as ``scenario_dir``.
"""

from __future__ import annotations

import json
import shutil
import sys
from pathlib import Path

import pytest
from result_document import schema_errors
from sweep_support import TABLE_PLANNER, planners_on_path, write_suite_sweep, write_table_project

from fleetsim.cli import main
from fleetsim.planners import ReservingPlanner
from fleetsim.sim.loop import run_scenario
from fleetsim.sweep.items import expand
from fleetsim.sweep.results import ResultsFile, read_results
from fleetsim.sweep.spec import load_sweep_spec
from fleetsim.sweep.worker import run_item

OPTIONS = {"table": "data/table.txt"}


@pytest.fixture
def project(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """The table suite in ``tmp_path`` (the working directory), TablePlanner importable here and in
    processes started from here."""
    planners_on_path(monkeypatch)
    monkeypatch.chdir(tmp_path)
    return write_table_project(tmp_path)


def _run_json(suite: Path, planner: str, capsys: pytest.CaptureFixture[str]) -> tuple[int, dict[str, object], str]:
    status = main(["run", str(suite), "--planner", planner, "--json"])
    out, err = capsys.readouterr()
    [line] = out.splitlines()
    return status, json.loads(line), err


def test_fleetsim_run_makes_the_planner_with_its_options_and_records_them(
    project: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    status, record, _ = _run_json(project, TABLE_PLANNER, capsys)
    assert status == 0 and record["status"] == "passed", record["failures"]
    assert record["planner_options"] == OPTIONS and schema_errors(record) == []
    # The options reach the planner, not the trace: the run hashes as the same planner's run without them.
    from fleetsim import load_scenario, load_suite

    suite = load_suite(project)
    plain = run_scenario(load_scenario(suite.scenarios[0], suite), ReservingPlanner())
    assert record["trace_hash"] == plain.trace_hash


def test_an_exec_planner_gets_the_options_and_the_scenario_folder_in_its_init_message(
    project: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    served = f"exec:{sys.executable} -m fleetsim.exec {TABLE_PLANNER}"
    status, record, _ = _run_json(project, served, capsys)
    assert status == 0 and record["status"] == "passed", record["failures"]
    assert record["planner_options"] == OPTIONS


def test_pytest_makes_the_planner_with_its_options_and_result_json_records_them(
    project: Path, pytester: pytest.Pytester, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.delenv("CI", raising=False)  # no lock file here: under CI pytest would fail the missing hash
    result = pytester.runpytest_inprocess(
        str(project), "--planner", TABLE_PLANNER, "--fleetsim-record", "all", "--fleetsim-artifacts", "out"
    )
    result.assert_outcomes(passed=1)
    [written] = (pytester.path / "out").rglob("result.json")
    document = json.loads(written.read_text(encoding="utf-8"))
    assert document["planner_options"] == OPTIONS and schema_errors(document) == []


def test_a_sweep_sends_the_data_files_to_its_workers(project: Path) -> None:
    pytest.importorskip("distributed")
    from fleetsim.sweep.execute import run_items

    items = expand(load_sweep_spec(write_suite_sweep(project.parent, project, [TABLE_PLANNER])), project / "runs")
    # The worker must use what was sent: the planning machine's folder is gone by the time the runs start.
    shutil.rmtree(project.parent / "examples" / "crossing" / "data")
    path = project.parent / "results.jsonl"
    with ResultsFile(path, {"name": "suite"}, resume=False) as results:
        run_items(items, results, workers=1)
    _, [row] = read_results(path)
    assert row["error"] is None and row["status"] == "passed", row["failures"]
    assert row["planner_options"] == OPTIONS and row["suite"] == "table.fleetsim.yaml"


def test_a_planner_that_does_not_take_an_option_fails_its_scenario_saying_where_the_option_is(
    project: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    project.write_text(project.read_text().replace("{table:", "{tabel:"), encoding="utf-8")
    status, record, err = _run_json(project, TABLE_PLANNER, capsys)
    assert status == 1 and record["status"] == "failed" and record["planner_options"] == {"tabel": "data/table.txt"}
    [failure] = record["failures"]
    message = failure["message"]
    assert failure["kind"] == "planner-error"
    assert message.startswith(f"{project}:6:")  # the planner_options of the entry
    assert "does not take the planner option tabel='data/table.txt'" in message and "did you mean 'table'" in message
    assert "Traceback" not in err and schema_errors(record) == []


def test_a_sweep_run_whose_planner_refuses_its_options_fails_alone_with_the_reason(project: Path) -> None:
    spec = load_sweep_spec(write_suite_sweep(project.parent, project, ["fleetsim.planners:ReservingPlanner"]))
    [item] = expand(spec, project / "runs")
    row = run_item(item)
    assert row["status"] == "failed" and row["ended"] == "planner-error"
    assert "does not take the planner option table='data/table.txt'" in row["error"]
    assert "it takes no options" in row["error"] and schema_errors(row) == []


def test_under_pytest_a_refused_option_fails_its_test_saying_where_without_a_traceback(
    project: Path, pytester: pytest.Pytester
) -> None:
    project.write_text(project.read_text().replace("{table:", "{tabel:"), encoding="utf-8")
    result = pytester.runpytest_inprocess(str(project), "--planner", TABLE_PLANNER)
    result.assert_outcomes(failed=1)
    output = result.stdout.str()
    assert f"{project}:6:22: planner spec '{TABLE_PLANNER}'" in output
    assert "does not take the planner option tabel='data/table.txt'" in output and "Traceback" not in output

"""``fleetsim run``, in-process through ``main``: the table, ``--json`` lines, selectors, exit statuses."""

from __future__ import annotations

import io
import json
import os
import re
import shutil
import sys
import xml.etree.ElementTree as ET
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from mcap.reader import make_reader
from result_document import RESULT_KEYS, schema_errors

import fleetsim
from fleetsim.cli import main
from fleetsim.cli.run import _targets
from fleetsim.planners import ReservingPlanner
from fleetsim.sim import run_scenario
from fleetsim.sim.report import SUMMARY_COLUMNS

SUITES = Path(__file__).resolve().parents[2] / "scenario_suites"
EXAMPLES = SUITES / "examples.fleetsim.yaml"
NAMES = ["crossing", "loop-one-way", "corridor-passing-bay", "mixed-shapes"]
RESERVING = "fleetsim.planners:ReservingPlanner"

FAULTY_PLANNERS = """\
import time

from fleetsim.planners import ReservingPlanner


class Raising(ReservingPlanner):
    def plan_routes(self, task, fleet, layout):
        raise ValueError("oops in user code")


class Sleeping(ReservingPlanner):
    def plan_routes(self, task, fleet, layout):
        time.sleep(60)
"""


def run(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    status = main(list(argv))
    out, err = capsys.readouterr()
    return status, out, err


def json_lines(out: str) -> list[dict[str, Any]]:
    return [json.loads(line) for line in out.splitlines()]


@pytest.fixture
def user_project(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[Path]:
    """The current directory holds ``faulty_planners.py``; sys.path and sys.modules are restored."""
    (tmp_path / "faulty_planners.py").write_text(FAULTY_PLANNERS, encoding="utf-8")
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(sys, "path", [p for p in sys.path if p not in ("", os.getcwd())])
    before = set(sys.modules)
    yield tmp_path
    for name in set(sys.modules) - before:
        del sys.modules[name]


def copy_examples(root: Path, *folders: str) -> None:
    shutil.copytree(SUITES / "tiled", root / "tiled")  # the example maps use these templates
    for folder in folders:
        shutil.copytree(SUITES / "examples" / folder, root / "examples" / folder)


# -- the table ------------------------------------------------------------------------------------


def test_the_shipped_suites_pass_with_the_reserving_planner(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.chdir(tmp_path)  # the hunt's counterexample goes to ./fleetsim-results
    status, out, err = run(capsys, "run", str(SUITES), "--planner", RESERVING)
    assert status == 0, out + err
    header, *rows = out.splitlines()[:16]
    assert header.split() == " ".join(SUMMARY_COLUMNS).split()
    expected = [[f"caught-bugs.fleetsim.yaml::{name}", "passed"] for name in ("crossing-collides", "corridor-head-on")]
    # The hunt catches BFSPlanner; its label says what it ran: "(N generated, M shrink runs)".
    expected += [["caught-bugs.fleetsim.yaml::generated-layouts", "generated,", "shrink", "runs)", "xfailed"]]
    expected += [["caught-bugs.fleetsim.yaml::late-crossing-stop", "passed"]]
    expected += [["caught-bugs.fleetsim.yaml::late-crossing-hunt", "generated,", "shrink", "runs)", "xfailed"]]
    expected += [
        [f"disturbances.fleetsim.yaml::{spec.name}", "passed"]
        for spec in fleetsim.load_suite(SUITES / "disturbances.fleetsim.yaml").scenarios
    ]
    expected += [[f"examples.fleetsim.yaml::{name}", "passed"] for name in NAMES]
    assert [
        [cell for cell in row.split() if not cell.lstrip("(").isdigit()][: len(want)]
        for row, want in zip(rows, expected, strict=True)
    ] == expected
    assert (
        tmp_path / "fleetsim-results" / "caught-bugs" / "generated-layouts" / "counterexample" / "map.json"
    ).is_file()
    # The caught-bugs suite is pinned to BFSPlanner, whatever --planner says.
    assert f"24 scenario(s) with fleetsim.planners:BFSPlanner, {RESERVING}: 22 passed, 2 xfailed" in out
    assert "FAILED" not in out


def test_the_bfs_planner_fails_and_the_thesis_collision_alert_is_shown(capsys: pytest.CaptureFixture[str]) -> None:
    status, out, _ = run(capsys, "run", str(EXAMPLES), "--planner", "fleetsim.planners:BFSPlanner")
    assert status == 1
    assert "4 failed" in out
    assert "FAILED crossing" in out
    assert "COLLISION ALERT: Possible collision detected on segment '2'" in out
    assert "Primary reservations" in out and " - vehicle_1" in out


def test_without_a_terminal_each_result_is_one_line_on_stderr(capsys: pytest.CaptureFixture[str]) -> None:
    _, _, err = run(capsys, "run", str(EXAMPLES), "--planner", RESERVING)
    lines = err.splitlines()
    assert len(lines) == 4
    for index, (line, name, tasks) in enumerate(zip(lines, NAMES, (2, 4, 2, 3), strict=True), 1):
        assert re.fullmatch(rf"\[{index}/4\] {name}: passed \(tasks {tasks}/{tasks}, t=\d+\.\d s\)", line), line


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_on_a_terminal_a_live_progress_line_is_drawn_and_cleared(
    capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    terminal = _Terminal()
    monkeypatch.setattr(sys, "stderr", terminal)
    status, out, _ = run(capsys, "run", f"{EXAMPLES}::corridor-passing-bay", "--planner", RESERVING)
    assert status == 0
    shown = terminal.getvalue()
    assert re.search(r"\r\[1/1\] corridor-passing-bay  t=\d+\.\d s  tasks [01]/2", shown)
    assert re.search(r"\r +\r$", shown)  # cleared at the end
    assert "\n" not in shown
    assert "corridor-passing-bay  passed" in out


# -- --json ---------------------------------------------------------------------------------------


def test_json_prints_one_result_per_scenario_per_line_with_the_direct_runs_hash(
    capsys: pytest.CaptureFixture[str],
) -> None:
    status, out, err = run(capsys, "run", str(EXAMPLES), "--planner", RESERVING, "--json")
    assert status == 0
    results = json_lines(out)
    assert [r["scenario"] for r in results] == NAMES
    suite = fleetsim.load_suite(EXAMPLES)
    for result, spec in zip(results, suite.scenarios, strict=True):
        assert result.keys() >= RESULT_KEYS
        assert schema_errors(result) == []
        assert result["status"] == "passed" and result["planner"] == RESERVING
        direct = run_scenario(fleetsim.load_scenario(spec, suite), ReservingPlanner())
        assert result["trace_hash"] == direct.trace_hash
    assert "scenario" in err and "4 passed" in err  # the table moved to stderr


def test_a_selector_runs_one_scenario(capsys: pytest.CaptureFixture[str]) -> None:
    status, out, _ = run(capsys, "run", f"{EXAMPLES}::crossing", "--planner", RESERVING, "--json")
    assert status == 0
    assert [r["scenario"] for r in json_lines(out)] == ["crossing"]


def test_a_scenario_named_twice_runs_once_in_the_order_given(capsys: pytest.CaptureFixture[str]) -> None:
    status, out, _ = run(capsys, "run", f"{EXAMPLES}::mixed-shapes", str(EXAMPLES), "--planner", RESERVING, "--json")
    assert status == 0
    assert [r["scenario"] for r in json_lines(out)] == ["mixed-shapes", *NAMES[:3]]


def test_a_scenario_named_and_in_a_folder_named_after_it_is_taken_once_where_first_named() -> None:
    # (What would run, without running it: the shipped suites take a while.)
    targets = _targets([f"{EXAMPLES}::mixed-shapes", str(SUITES)])
    assert [target.spec.name for target in targets if target.spec is not None] == [
        "mixed-shapes", "crossing-collides", "corridor-head-on", "generated-layouts", "late-crossing-stop", "late-crossing-hunt",
        *(spec.name for spec in fleetsim.load_suite(SUITES / "disturbances.fleetsim.yaml").scenarios),
        "crossing", "loop-one-way", "corridor-passing-bay", "sorting-hall-2024", "sorting-hall-2026", "depot-4",
        "depot-all", "packing-hall-lif", "clinic-rmf",
        *(spec.name for spec in fleetsim.load_suite(SUITES / "warehouse.fleetsim.yaml").scenarios),
    ]  # fmt: skip
    assert len(targets) == len({(target.suite_path.resolve(), target.label) for target in targets})


# -- failures -------------------------------------------------------------------------------------


def test_a_raising_planner_exits_1_and_its_traceback_is_shown(
    user_project: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    status, out, err = run(capsys, "run", f"{EXAMPLES}::crossing", "--planner", "faulty_planners:Raising")
    assert status == 1
    assert "planner-error at t=0.10 s" in out
    assert "plan_routes() for vehicle 1 raised ValueError: oops in user code" in out
    assert "Traceback (most recent call last)" in out
    assert 'raise ValueError("oops in user code")' in out
    assert "faulty_planners.py" in out
    assert "fleetsim/sim/" not in out  # the user's frames only
    assert "Traceback" not in err


def test_the_planner_timeout_option_limits_each_call(user_project: Path, capsys: pytest.CaptureFixture[str]) -> None:
    argv = (
        "run",
        f"{EXAMPLES}::crossing",
        "--planner",
        "faulty_planners:Sleeping",
        "--planner-timeout",
        "0.2",
        "--json",
    )
    status, out, _ = run(capsys, *argv)
    assert status == 1
    [result] = json_lines(out)
    assert result["failures"][0]["kind"] == "planner-error"
    assert "per-call timeout of 0.2 s" in result["failures"][0]["message"]


def test_a_scenario_that_fails_to_load_fails_alone_and_the_others_run(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    copy_examples(tmp_path, "crossing", "corridor")
    (tmp_path / "examples" / "crossing" / "tasks.csv").write_text("vehicle_id,goal_segment_id\n1,4\n2,99\n")
    suite = tmp_path / "two.fleetsim.yaml"
    suite.write_text(
        "fleetsim: 1\nname: two\nscenarios:\n  - name: crossing\n    dir: examples/crossing/\n"
        "  - name: corridor\n    dir: examples/corridor/\n"
    )
    status, out, err = run(capsys, "run", str(suite), "--planner", RESERVING, "--json")
    assert status == 1
    broken, fine = json_lines(out)
    assert broken["status"] == "failed" and fine["status"] == "passed"
    assert broken.keys() == fine.keys()
    [failure] = broken["failures"]
    assert failure["kind"] == "load-error"
    assert "tasks.csv:3" in failure["message"] and "99" in failure["message"]
    assert broken["trace_hash"] is None
    assert "LOAD ERROR crossing" in err and "load-error" in err
    assert "Traceback" not in out + err
    [row] = [line for line in err.splitlines() if line.startswith("crossing ")]
    assert row.split()[1:3] == ["load", "error"] and "2 scenario(s) with" in err
    assert ": 1 passed, 1 load error" in err
    assert "[1/2] crossing: load error\n" in err  # the progress line too


def test_a_suite_that_fails_to_load_is_one_failed_entry(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    suite = tmp_path / "broken.fleetsim.yaml"
    suite.write_text("fleetsim: 1\nname: broken\nscenarios: [\n")
    status, out, err = run(capsys, "run", str(suite), str(EXAMPLES), "--planner", RESERVING, "--json")
    assert status == 1
    results = json_lines(out)
    assert [r["status"] for r in results] == ["failed", "passed", "passed", "passed", "passed"]
    assert results[0]["scenario"] == str(suite)
    assert results[0]["failures"][0]["kind"] == "load-error"
    assert "examples.fleetsim.yaml::crossing" in err  # several suites: rows name their file


def test_an_xfail_scenario_that_fails_does_not_fail_the_run(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    copy_examples(tmp_path, "crossing")
    suite = tmp_path / "known.fleetsim.yaml"
    suite.write_text(
        "fleetsim: 1\nname: known\nscenarios:\n  - name: crossing\n    dir: examples/crossing/\n"
        "    xfail: the BFS planner collides\n"
    )
    status, out, _ = run(capsys, "run", str(suite), "--planner", "fleetsim.planners:BFSPlanner")
    assert status == 0
    assert "crossing  xfailed" in out and "1 xfailed" in out


# -- usage errors ---------------------------------------------------------------------------------


def test_an_unknown_scenario_name_exits_2_listing_the_names(capsys: pytest.CaptureFixture[str]) -> None:
    status, out, err = run(capsys, "run", f"{EXAMPLES}::crosing", "--planner", RESERVING)
    assert status == 2
    assert "has no scenario 'crosing'" in err
    assert ", ".join(NAMES) in err and "did you mean 'crossing'?" in err
    assert out == ""


def test_a_bad_planner_spec_exits_2_without_a_traceback(capsys: pytest.CaptureFixture[str]) -> None:
    status, out, err = run(capsys, "run", str(EXAMPLES), "--planner", "foo")
    assert status == 2
    assert err == (
        "fleetsim: error: planner spec 'foo' must look like module:attribute, e.g. fleetsim.planners:ReservingPlanner\n"
    )
    assert out == ""


def test_a_planner_module_that_does_not_import_exits_2(capsys: pytest.CaptureFixture[str]) -> None:
    status, _, err = run(capsys, "run", str(EXAMPLES), "--planner", "no_such_module_here:Planner")
    assert status == 2
    assert "no module named 'no_such_module_here'" in err and "Traceback" not in err


@pytest.mark.parametrize(
    ("target", "message"),
    [
        ("nowhere/at/all.fleetsim.yaml", "no such file or directory"),
        (f"{SUITES}::crossing", "is a folder"),
        (f"{EXAMPLES}::", "name a scenario after '::'"),
    ],
    ids=["missing-path", "selector-on-folder", "empty-selector"],
)
def test_a_bad_suite_argument_exits_2(target: str, message: str, capsys: pytest.CaptureFixture[str]) -> None:
    status, _, err = run(capsys, "run", target, "--planner", RESERVING)
    assert status == 2
    assert message in err


def test_a_folder_without_suites_exits_2(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    status, _, err = run(capsys, "run", str(tmp_path), "--planner", RESERVING)
    assert status == 2
    assert "no *.fleetsim.yaml files" in err


def test_record_writes_each_runs_artifacts_and_a_picture_for_a_failed_one(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    root = tmp_path / "runs"
    status, out, _ = run(
        capsys, "run", str(EXAMPLES), "--planner", "fleetsim.planners:BFSPlanner", "--record", str(root), "--json"
    )

    assert status == 1
    documents = {document["scenario"]: document for document in json_lines(out)}
    crossing = root / "examples" / "crossing"
    assert documents["crossing"]["status"] == "failed"
    assert documents["crossing"]["artifacts"]["mcap"] == str(crossing / "run.mcap")
    assert sorted(p.name for p in crossing.iterdir()) == [
        "failure.svg",
        "fleetsim.rviz",
        "result.json",
        "run.mcap",
        "trace.jsonl",
        "view.html",
    ]
    with (crossing / "run.mcap").open("rb") as stream:
        summary = make_reader(stream).get_summary()
    assert summary is not None and summary.statistics is not None and summary.statistics.message_count > 0
    caption = "".join(ET.parse(crossing / "failure.svg").getroot().itertext())
    assert "collision" in caption
    for name, document in documents.items():
        folder = root / "examples" / name
        assert (folder / "run.mcap").is_file() and (folder / "result.json").is_file()
        assert (folder / "failure.svg").exists() == (document["status"] == "failed")


def test_record_prints_the_folders_it_wrote_with_their_files(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    argv = [f"{EXAMPLES}::crossing", f"{EXAMPLES}::loop-one-way", "--planner", "fleetsim.planners:BFSPlanner"]
    status, out, _ = run(capsys, "run", *argv, "--record", "out")

    assert status == 1
    listed = out[out.index("\nartifacts: ") + 1 :].splitlines()
    crossing, loop = (tmp_path / "out" / "examples" / name for name in ("crossing", "loop-one-way"))
    expected = [
        f"out/examples/crossing/ ({', '.join(sorted(p.name for p in crossing.iterdir()))})",
        f"out/examples/loop-one-way/ ({', '.join(sorted(p.name for p in loop.iterdir()))})",
    ]
    assert listed == ["artifacts: " + expected[0], "           " + expected[1]]
    assert "<suite>" not in out and "failure.svg" in listed[0]


def test_record_with_nothing_run_says_no_folder_was_written(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    (tmp_path / "broken.fleetsim.yaml").write_text("fleetsim: 1\nname: broken\nscenarios: [\n")
    status, out, _ = run(capsys, "run", "broken.fleetsim.yaml", "--planner", RESERVING, "--record", "out")
    assert status == 1
    assert out.endswith("\nartifacts: none written (no scenario ran)\n") and not (tmp_path / "out").exists()


def test_without_record_no_artifacts_are_written(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    status, out, err = run(capsys, "run", f"{EXAMPLES}::crossing", "--planner", RESERVING, "--json")
    assert status == 0 and json_lines(out)[0]["artifacts"] == {}
    assert list(tmp_path.iterdir()) == []
    assert "artifacts:" not in err


def test_a_record_rate_below_one_step_is_refused(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exit_info:
        main(["run", str(EXAMPLES), "--planner", RESERVING, "--record", "x", "--record-every", "0"])
    assert exit_info.value.code == 2
    assert "--record-every: '0' must be a whole number of steps >= 1" in capsys.readouterr().err

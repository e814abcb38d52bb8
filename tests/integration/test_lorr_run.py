"""A League of Robot Runners problem runs end to end through ``fleetsim run``, with the competition's counts
in its ``--json`` record; a broken one is located lines through ``validate``, never a traceback."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from fleetsim.cli.main import main
from fleetsim.sim.result_schema import result_problem

SHIPPED = Path(__file__).resolve().parents[2] / "scenario_suites"
SUITE = SHIPPED / "lorr.fleetsim.yaml"
PLANNER = "fleetsim.planners:ReservingPlanner"


def test_the_shipped_2026_problem_runs_with_the_league_counts_in_its_json_record() -> None:
    done = subprocess.run(
        [sys.executable, "-m", "fleetsim", "run", f"{SUITE}::sorting-hall-2026", "--planner", PLANNER, "--json"],
        capture_output=True,
        text=True,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    record = json.loads(done.stdout.splitlines()[0])
    assert result_problem(record) is None
    counts = record["lorr"]
    assert (counts["edition"], counts["team_size"], counts["task_pool"], counts["horizon"]) == ("2026", 8, 12, 120)
    finished = sum(1 for order in record["orders"] if order["completed"] is not None)
    assert counts["tasks_finished"] == finished == record["measures"]["completed"] > 0
    assert counts["sum_of_cost"] == sum(counts["cost"]) and counts["makespan"] == max(counts["cost"]) <= 120
    assert record["disturbances"] and all(d["kind"] == "stop" for d in record["disturbances"])  # delayConfig
    assert any("agentCounter" in note for note in counts["not_mapped"])


def test_a_problem_file_runs_on_its_own_and_prints_the_league_table(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    folder = tmp_path / "lorr"
    shutil.copytree(SHIPPED / "lorr", folder)
    problem = json.loads((folder / "sorting-hall-2024.json").read_text())
    problem["teamSize"] = 2
    (folder / "small.json").write_text(json.dumps(problem))
    status = main(["run", str(folder / "small.json"), "--planner", PLANNER])
    out = capsys.readouterr().out
    assert status == 0
    assert "League of Robot Runners counts (timesteps):" in out
    row = next(line for line in out.splitlines() if line.startswith("small ") and "2024" in line)
    assert row.split()[1:5] == ["2024", "2", "3", "5000"]  # edition, robots, pool, horizon
    assert row.split()[5] == "40/40"  # every task finished well within 5000 timesteps


def test_a_broken_problem_is_located_lines_not_a_traceback(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    folder = tmp_path / "lorr"
    shutil.copytree(SHIPPED / "lorr", folder)
    problem = json.loads((folder / "sorting-hall-2024.json").read_text())
    problem["version"] = "2025 LoRR"
    (folder / "broken.json").write_text(json.dumps(problem, indent=2))
    status = main(["validate", str(folder / "broken.json")])
    out = capsys.readouterr().out
    assert status == 1 and "Traceback" not in out
    assert "broken.json:7:3: field '/version': version \"2025 LoRR\" is not a League of Robot Runners edition" in out
    # Location 19 is row 1, column 3: a shelf ('@'); 99999 is off the 16 x 12 map; 4 locations for 3 agents.
    (folder / "sorting-hall.agents").write_text("3\n0\n19\n99999\n4\n")
    status = main(["validate", str(folder / "sorting-hall-2024.json")])
    out = capsys.readouterr().out
    assert status == 1 and "Traceback" not in out
    assert "sorting-hall.agents:5: line 1 says 3 agent(s), but 4 follow; line 5 is one too many" in out
    assert "sorting-hall.agents:3:1: location 19 (row 1, column 3) is on a blocked cell '@'" in out
    assert "sorting-hall.agents:4:1: location 99999 is off the map (16 x 12 cells: locations 0 to 191)" in out

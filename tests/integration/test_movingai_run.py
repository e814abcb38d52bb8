"""A MovingAI scenario file runs as an ordinary scenario: the shipped depot through ``fleetsim run``."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from fleetsim.cli.main import main

SUITE = Path(__file__).resolve().parents[2] / "scenario_suites" / "movingai.fleetsim.yaml"


def test_every_agent_of_the_depot_reaches_its_goal_with_the_reference_planner(
    capsys: pytest.CaptureFixture[str],
) -> None:
    status = main(["run", f"{SUITE}::depot-all", "--planner", "fleetsim.planners:ReservingPlanner", "--json"])
    result = json.loads(capsys.readouterr().out.splitlines()[0])
    assert status == 0
    assert result["status"] == "passed" and result["tasks"] == {"total": 8, "completed": 8}
    assert result["collisions"] == [] and result["rejections"] == []


def test_a_broken_scenario_file_is_one_located_line_not_a_traceback(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    folder = tmp_path / "movingai"
    folder.mkdir()
    (folder / "depot.map").write_text((SUITE.parent / "movingai" / "depot.map").read_text())
    (folder / "depot.scen").write_text("version 1\n0\tdepot.map\t18\t10\t1\t1\t0\t0\t1\n")
    suite = tmp_path / "movingai.fleetsim.yaml"
    suite.write_text("fleetsim: 1\nname: broken\nscenarios:\n  - name: one\n    scen: movingai/depot.scen\n")
    status = main(["validate", str(suite)])
    out = capsys.readouterr().out
    assert status == 1
    assert "depot.scen:2:" in out and "blocked cell '@'" in out and "Traceback" not in out

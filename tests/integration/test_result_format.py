"""Every shipped scenario's result, hunts and disturbances included, in the one published result format."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from result_document import schema_errors

from fleetsim.cli import main

SUITES = Path(__file__).resolve().parents[2] / "scenario_suites"


def test_every_shipped_scenarios_run_json_and_result_json_satisfy_the_schema(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    main(["run", str(SUITES), "--planner", "fleetsim.planners:ReservingPlanner", "--json", "--record", "out"])
    lines = [json.loads(line) for line in capsys.readouterr().out.splitlines()]
    assert any("generated" in line for line in lines), "a generated entry's hunt"
    assert any(line["disturbances"] for line in lines), "a run with disturbances"
    for line in lines:
        assert schema_errors(line) == [], line["scenario"]
    written = sorted((tmp_path / "out").rglob("result.json"))
    assert len(written) >= len(lines) - 1  # a hunt that found nothing leaves no folder
    for path in written:
        assert schema_errors(json.loads(path.read_text(encoding="utf-8"))) == [], path

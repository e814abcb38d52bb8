"""`fleetsim validate` on a folder without a suite: a scenario folder is validated, anything else refused."""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import pytest

from fleetsim.cli.main import main

EXAMPLES = Path(__file__).resolve().parents[2] / "scenario_suites" / "examples"


def test_a_scenario_folder_is_validated_as_one(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["validate", str(EXAMPLES / "corridor")]) == 0
    out = capsys.readouterr().out
    assert "a scenario folder without a suite" in out
    assert "  ok   corridor:" in out
    assert "0 suite(s), 1 scenario folder(s): 1 scenario(s) valid, 0 failed" in out


def test_a_broken_scenario_folder_fails(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    folder = tmp_path / "examples" / "corridor"
    shutil.copytree(EXAMPLES / "corridor", folder)
    shutil.copytree(EXAMPLES.parent / "tiled", tmp_path / "tiled")
    (folder / "tasks.csv").write_text("vehicle_id,goal_segment_id\n1,99\n2,98\n", encoding="utf-8")
    assert main(["validate", str(folder)]) == 1
    out = capsys.readouterr().out
    assert "  FAIL corridor" in out
    assert "tasks.csv:2" in out and "tasks.csv:3" in out


def test_a_folder_that_is_neither_is_a_usage_error(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["validate", str(tmp_path)]) == 2
    assert "no *.fleetsim.yaml files in this folder, and it is no scenario folder" in capsys.readouterr().err


def test_a_folder_of_suites_is_validated_by_its_suites(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["validate", str(EXAMPLES.parent)]) == 0
    out = capsys.readouterr().out
    assert "scenario folder" not in out
    assert re.search(r"\d+ suite\(s\): \d+ scenario\(s\) valid, 0 failed", out)

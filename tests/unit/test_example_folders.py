"""Shipped scenario folders say what they need to be reused: the vehicle types their vehicles.csv names."""

from __future__ import annotations

import csv
import re
from pathlib import Path

import pytest
import yaml

from fleetsim.errors import LoadError
from fleetsim.load.suites.scenario import load_scenario
from fleetsim.load.suites.suite import load_suite

SUITES = Path(__file__).resolve().parents[2] / "scenario_suites"


def named_types(folder: Path) -> set[str]:
    with (folder / "vehicles.csv").open(encoding="utf-8") as rows:
        return {
            row["type"] for row in csv.DictReader(line for line in rows if not line.startswith("#")) if row.get("type")
        }


def folders() -> list[Path]:
    return sorted(path.parent for path in SUITES.glob("*/*/vehicles.csv"))


@pytest.mark.parametrize("folder", folders(), ids=lambda path: path.relative_to(SUITES).as_posix())
def test_a_folder_that_names_types_says_how_to_define_them(folder: Path) -> None:
    types = named_types(folder)
    if not types:
        return  # any suite can use it as it is
    readme = (folder / "README.md").read_text(encoding="utf-8")
    block = re.search(r"```yaml\n(.*?)```", readme, re.DOTALL)
    assert block is not None, f"{folder}/README.md shows no vehicle_types block"
    shown = yaml.safe_load(block.group(1))["vehicle_types"]
    assert set(shown) == types
    defining = [
        suite
        for suite in map(load_suite, sorted(SUITES.glob("*.fleetsim.yaml")))
        if any(spec.map_path.parent == folder for spec in suite.scenarios if spec.generate is None)
    ]
    assert defining, f"no shipped suite uses {folder}"
    for suite in defining:
        raw = yaml.safe_load(suite.path.read_text(encoding="utf-8"))["vehicle_types"]
        assert {name: raw[name] for name in types} == shown, f"{folder}/README.md differs from {suite.path.name}"


def write_suite(tmp_path: Path, vehicle_types: str) -> Path:
    path = tmp_path / "reuse.fleetsim.yaml"
    folder = (SUITES / "examples" / "mixed").as_posix()
    path.write_text(f"fleetsim: 1\nname: reuse\n{vehicle_types}scenarios:\n  - name: mixed\n    dir: {folder}/\n")
    return path


def test_reusing_the_mixed_folder_without_its_types_says_where_types_are_defined(tmp_path: Path) -> None:
    suite = load_suite(write_suite(tmp_path, ""))
    with pytest.raises(LoadError) as caught:
        load_scenario(suite.scenarios[0], suite)
    message = str(caught.value)
    assert "vehicle type 'agv' is not defined" in message
    assert "vehicle type 'tugger' is not defined" in message
    assert "the suite that uses the folder defines them under vehicle_types" in message


def test_reusing_the_mixed_folder_with_its_types_loads(tmp_path: Path) -> None:
    readme = (SUITES / "examples" / "mixed" / "README.md").read_text(encoding="utf-8")
    block = re.search(r"```yaml\n(.*?)```", readme, re.DOTALL)
    assert block is not None
    suite = load_suite(write_suite(tmp_path, block.group(1)))
    scenario = load_scenario(suite.scenarios[0], suite)
    assert sorted(vehicle.type.name for vehicle in scenario.vehicles) == ["agv", "tugger"]

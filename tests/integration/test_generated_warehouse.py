"""A generated warehouse, end to end: written by the command, driven by the reference planner, opened by Tiled."""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING

import pytest

from fleetsim.cli.main import main
from fleetsim.load.common.map_options import MapOptions
from fleetsim.load.maps.site_map import load_site_map

if TYPE_CHECKING:  # the fixture's type; conftest modules are not importable packages
    from conftest import TiledCli

pytestmark = pytest.mark.integration

PLANNER = "fleetsim.planners:ReservingPlanner"


def _results(capsys: pytest.CaptureFixture[str]) -> list[dict[str, object]]:
    return [json.loads(line) for line in capsys.readouterr().out.splitlines() if line.startswith("{")]


@pytest.mark.parametrize("kind", [["--one-way"], ["--two-way"], ["--format", "lif"]], ids=["one-way", "two-way", "lif"])
def test_every_vehicle_drives_pick_drop_park_and_completes(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], kind: list[str]
) -> None:
    folder = tmp_path / "site"
    assert main(["generate", "warehouse", str(folder), "--vehicles", "8", *kind]) == 0
    capsys.readouterr()
    (map_file,) = folder.glob("map.*")
    stations = load_site_map(map_file, MapOptions()).stations
    picks, drops = [s.segment for s in stations["pick"]], [s.segment for s in stations["drop"]]
    parks = [line.split(",")[1] for line in (folder / "vehicles.csv").read_text().splitlines()[1:]]
    # Each vehicle leaves its parking place for a pick station, takes the load to a drop station and
    # parks again where it started; vehicles share stations, so they meet on the way and at the places.
    rows = ["vehicle_id,goal_segment_id,goal_progress_direction"]
    for vehicle, park in enumerate(parks, start=1):
        rows += [f"{vehicle},{picks[3 * vehicle % len(picks)]},", f"{vehicle},{drops[vehicle % len(drops)]},"]
        rows.append(f"{vehicle},{park},")
    (folder / "trips.csv").write_text("\n".join(rows) + "\n", encoding="utf-8")
    (tmp_path / "trips.fleetsim.yaml").write_text(
        "fleetsim: 1\nname: trips\ndefaults: {time_limit: 900}\n"
        "scenarios:\n  - name: trips\n    map: site/" + map_file.name + "\n"
        "    vehicles: site/vehicles.csv\n    tasks: site/trips.csv\n",
        encoding="utf-8",
    )
    assert main(["validate", str(tmp_path / "trips.fleetsim.yaml")]) == 0
    assert "0 lint warning(s)" in capsys.readouterr().out
    assert main(["run", str(tmp_path / "trips.fleetsim.yaml"), "--planner", PLANNER, "--json"]) == 0
    (result,) = _results(capsys)
    assert result["status"] == "passed", result["failures"]
    assert result["tasks"] == {"total": 24, "completed": 24}
    assert result["collisions"] == [] and result["rejections"] == []


def test_the_generated_suite_runs_its_shift_with_the_reference_dispatcher(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    folder = tmp_path / "site"
    assert main(["generate", "warehouse", str(folder)]) == 0
    capsys.readouterr()
    assert main(["validate", str(folder)]) == 0
    assert "1 scenario(s) valid, 0 failed, 0 lint warning(s)" in capsys.readouterr().out
    assert main(["run", str(folder / "warehouse.fleetsim.yaml"), "--planner", PLANNER, "--json"]) == 0
    (result,) = _results(capsys)
    assert result["status"] == "passed", result["failures"]
    assert result["sim_time"] == pytest.approx(3600.0)
    tasks = result["tasks"]
    assert isinstance(tasks, dict) and tasks["completed"] > 0


def test_tiled_opens_the_generated_map_and_resaves_its_segments_and_stations(tiled: TiledCli, tmp_path: Path) -> None:
    folder = tmp_path / "site"
    assert main(["generate", "warehouse", str(folder), "--aisles", "3", "--vehicles", "3"]) == 0
    original = load_site_map(folder / "map.json", MapOptions())
    resaved = load_site_map(tiled.export_map(folder / "map.json", tmp_path / "resaved.tmx"), MapOptions())
    assert [(s.id, s.direction, s.names) for s in resaved.segments] == [
        (s.id, s.direction, s.names) for s in original.segments
    ]
    for got, want in zip(resaved.segments, original.segments, strict=True):  # whole pixels: exact in TMX too
        assert got.waypoints == want.waypoints
    assert dict(resaved.stations) == dict(original.stations)
    assert resaved.meters_per_pixel == pytest.approx(original.meters_per_pixel)

"""Loading (SPEC §3, §5, §13): Tiled maps, scenario CSV files, suites, and whole scenarios."""

from fleetsim.load.suites.scenario import load_scenario, load_scenario_dir
from fleetsim.load.suites.suite import ScenarioSpec, Suite, discover_suites, load_suite
from fleetsim.load.tables.scenario_files import read_tasks, read_vehicles
from fleetsim.load.tiled.reader import TiledMap, load_map
from fleetsim.load.tiled.writer import write_map

__all__ = [
    "ScenarioSpec",
    "Suite",
    "TiledMap",
    "discover_suites",
    "load_map",
    "load_scenario",
    "load_scenario_dir",
    "load_suite",
    "read_tasks",
    "read_vehicles",
    "write_map",
]

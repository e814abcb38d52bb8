"""Writing small sweep specs for the sweep tests."""

from __future__ import annotations

import os
import shutil
from collections.abc import Sequence
from pathlib import Path

import pytest

PLANNERS_DIR = Path(__file__).resolve().parents[1] / "data" / "sweep"
EXAMPLES = Path(__file__).resolve().parents[2] / "scenario_suites" / "examples"
WAREHOUSE = EXAMPLES.parent / "warehouse"
TABLE_PLANNER = "sweep_planners:TablePlanner"  # reads planner_options' table from the scenario's folder


def write_spec(folder: Path, planners: Sequence[str], *, count: int = 20, seed: int = 3, name: str = "small") -> Path:
    """Two planners on ``count`` small generated warehouses, short time limits."""
    listed = "\n".join(f"  - {p!r}" for p in planners)
    spec = folder / f"{name}.sweep.yaml"
    spec.write_text(
        f"fleetsim-sweep: 1\nname: {name}\nplanners:\n{listed}\nrecord: none\n"
        "defaults: {time_limit: 30, stop_on: []}\n"
        "sources:\n"
        f"  - name: warehouses\n    generate: {{layout: warehouse, size: [1, 2], vehicles: [1, 3], tasks: [1, 2]}}\n"
        f"    count: {count}\n    seed: {seed}\n",
        encoding="utf-8",
    )
    return spec


def planners_on_path(monkeypatch: pytest.MonkeyPatch) -> None:
    """Dask workers (new processes) find the test planners through PYTHONPATH, as a user's would."""
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join([str(PLANNERS_DIR), os.environ.get("PYTHONPATH", "")]))
    monkeypatch.syspath_prepend(str(PLANNERS_DIR))


def write_table_project(folder: Path) -> Path:
    """A suite whose one scenario (the crossing) gives TablePlanner its data file: ``planner_options:
    {table: data/table.txt}`` with ``files: [data]``, in ``folder/examples/crossing``; the suite file's path."""
    shutil.copytree(EXAMPLES / "crossing", folder / "examples" / "crossing")
    shutil.copytree(EXAMPLES.parent / "tiled", folder / "tiled")  # the map's object templates
    (folder / "examples" / "crossing" / "data").mkdir()
    (folder / "examples" / "crossing" / "data" / "table.txt").write_text("fleetsim table\n", encoding="utf-8")
    suite = folder / "table.fleetsim.yaml"
    suite.write_text(
        "fleetsim: 1\nname: table\nscenarios:\n"
        "  - name: crossing\n    dir: examples/crossing\n"
        "    planner_options: {table: data/table.txt}\n    files: [data]\n",
        encoding="utf-8",
    )
    return suite


def write_suite_sweep(folder: Path, suite: Path, planners: Sequence[str]) -> Path:
    """A sweep spec running ``planners`` on the scenarios of ``suite``, keeping no run folders."""
    listed = "\n".join(f"  - {p!r}" for p in planners)
    spec = folder / "suite.sweep.yaml"
    spec.write_text(
        f"fleetsim-sweep: 1\nname: suite\nplanners:\n{listed}\nrecord: none\nsources:\n  - suite: {suite.as_posix()}\n",
        encoding="utf-8",
    )
    return spec


def write_pool_project(folder: Path) -> Path:
    """The shipped warehouse under a closed pool of four orders for five minutes (``pool-shift.yaml`` of the
    test data) in ``folder``; the suite file's path."""
    shutil.copytree(WAREHOUSE, folder / "warehouse")
    suite = folder / "pool.fleetsim.yaml"
    shutil.copy(PLANNERS_DIR / "pool-shift.yaml", suite)
    return suite

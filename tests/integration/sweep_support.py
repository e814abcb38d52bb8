"""Writing small sweep specs for the sweep tests."""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path

import pytest

PLANNERS_DIR = Path(__file__).resolve().parents[1] / "data" / "sweep"


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

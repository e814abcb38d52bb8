"""The package type-checks under ``mypy --strict`` (the ``[tool.mypy]`` settings in pyproject.toml).

fleetsim ships ``py.typed``: its type hints are a promise to every planner author whose editor or type
checker reads them, so a wrong or missing hint is a bug like any other.
"""

from __future__ import annotations

from pathlib import Path

from mypy import api

ROOT = Path(__file__).resolve().parents[2]


def test_package_benchmarks_and_plugin_type_check_strictly(tmp_path: Path, monkeypatch) -> None:
    monkeypatch.chdir(ROOT)  # the configuration's file list is relative to the project
    stdout, stderr, status = api.run(["--config-file", str(ROOT / "pyproject.toml"), "--cache-dir", str(tmp_path)])
    assert status == 0, stdout + stderr
    assert stdout.startswith("Success: no issues found in ")

"""fleetsim sweep on real Dask clusters: a local one losing a worker, resuming, a separately started one."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import psutil
import pytest

pytest.importorskip("distributed")

from sweep_support import planners_on_path, write_spec

from fleetsim.sweep.execute import Progress, run_items
from fleetsim.sweep.items import expand
from fleetsim.sweep.results import ResultsFile, read_results
from fleetsim.sweep.spec import load_sweep_spec

SLOW = ("sweep_planners:SlowReserving", "sweep_planners:SlowBFS")


def _keys(path: Path) -> list[str]:
    lines = path.read_text(encoding="utf-8").splitlines()[1:]
    return [json.loads(line)["key"] for line in lines]


def _worker_processes() -> list[psutil.Process]:
    """The local cluster's worker processes: this process's children running Dask's spawned workers."""
    found = []
    for process in psutil.Process().children(recursive=True):
        command = " ".join(process.cmdline())
        if "spawn_main" in command and "resource_tracker" not in command:
            found.append(process)
    return found


def test_local_cluster_losing_a_worker_gives_every_result_exactly_once(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    planners_on_path(monkeypatch)
    spec = load_sweep_spec(write_spec(tmp_path, SLOW, count=20))
    items = expand(spec, tmp_path / "runs")
    assert len(items) == 40
    killed: list[int] = []

    def kill_one_worker(progress: Progress) -> None:
        if progress.done == 6 and not killed:
            victim = _worker_processes()[0]
            killed.append(victim.pid)
            os.kill(victim.pid, signal.SIGKILL)

    results_path = tmp_path / "results.jsonl"
    with ResultsFile(results_path, {"name": "small"}, resume=False) as results:
        progress = run_items(items, results, workers=2, on_progress=kill_one_worker)
    assert killed, "a worker was killed mid-sweep"
    keys = _keys(results_path)
    assert sorted(keys) == sorted(item["key"] for item in items)  # every run, none twice
    assert len(keys) == len(set(keys)) == progress.done == 40
    _, rows = read_results(results_path)
    assert all(row["error"] is None for row in rows), [row["error"] for row in rows if row["error"]]


def test_resume_runs_only_what_is_missing(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    planners_on_path(monkeypatch)
    spec = load_sweep_spec(
        write_spec(tmp_path, ("fleetsim.planners:ReservingPlanner", "fleetsim.planners:BFSPlanner"), count=6)
    )
    items = expand(spec, tmp_path / "runs")
    results_path = tmp_path / "results.jsonl"

    def interrupt(progress: Progress) -> None:
        if progress.done == 5:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt), ResultsFile(results_path, {"name": "small"}, resume=False) as results:
        run_items(items, results, workers=1, on_progress=interrupt)
    first = _keys(results_path)
    assert len(first) == 5
    with results_path.open("a", encoding="utf-8") as file:
        file.write('{"key": "cut short by a ki')  # a sweep killed while writing a row
    with ResultsFile(results_path, {"name": "small"}, resume=True) as results:
        progress = run_items(items, results, workers=1)
    assert progress.total == len(items) - 5  # only the missing runs ran
    keys = _keys(results_path)
    assert keys[:5] == first and sorted(keys) == sorted(item["key"] for item in items)


def test_sweep_on_a_separately_started_scheduler(tmp_path: Path) -> None:
    """`dask scheduler` and `dask worker` as their own processes on loopback; a planner that does not
    import on the worker fails its runs, with the reason, and the sweep goes on."""
    scheduler_file = tmp_path / "scheduler.json"
    env = {**os.environ, "PYTHONPATH": os.environ.get("PYTHONPATH", "")}
    dask = [sys.executable, "-m", "distributed.cli.dask_scheduler"]
    scheduler = subprocess.Popen([*dask, "--host", "127.0.0.1", "--port", "0", "--no-dashboard", "--scheduler-file", str(scheduler_file)],
                                 env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)  # fmt: skip
    worker = None
    try:
        deadline = time.monotonic() + 30
        while not scheduler_file.exists() and time.monotonic() < deadline:
            time.sleep(0.1)
        address = json.loads(scheduler_file.read_text())["address"]
        worker = subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_worker", address, "--nworkers", "1", "--nthreads", "1",
                                   "--no-dashboard", "--host", "127.0.0.1"], env=env, cwd=tmp_path,
                                  stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)  # fmt: skip
        spec = write_spec(tmp_path, ("fleetsim.planners:ReservingPlanner", "only_on_my_laptop:Planner"), count=3)
        out = tmp_path / "results.jsonl"
        done = subprocess.run([sys.executable, "-m", "fleetsim", "sweep", str(spec), "-o", str(out), "--scheduler", address],
                              env=env, capture_output=True, text=True, timeout=120, check=False)  # fmt: skip
        assert done.returncode == 0, done.stderr
        _, rows = read_results(out)
        assert len(rows) == 6
        missing = [row for row in rows if row["planner"] == "only_on_my_laptop:Planner"]
        assert all(row["status"] == "failed" for row in missing)
        assert all(
            "cannot be loaded on this worker" in row["error"] and "only_on_my_laptop" in row["error"] for row in missing
        )
        assert all(row["status"] == "passed" for row in rows if row not in missing)
    finally:
        for process in (worker, scheduler):
            if process is not None:
                process.terminate()
                try:
                    process.wait(timeout=10)
                except subprocess.TimeoutExpired:
                    process.kill()

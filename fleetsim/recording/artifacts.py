"""The artifact folder of a recorded run: what a reviewer opens after a failure.

Each recorded run gets ``ROOT/<suite file stem>/<scenario name>/`` holding ``result.json`` (the
object of ``fleetsim run --json``) and, when the run kept its trace, ``trace.jsonl`` (the canonical
trace whose SHA-256 is the run's hash, one step per line, for diffing two runs). Given the scenario,
the folder also gets ``run.mcap`` (the run for RViz 2 and Foxglove), ``fleetsim.rviz`` (the RViz
layout for it) and, for a failed run, ``failure.svg`` (the fleet at the first failure). A folder is rewritten
as a whole, so stale files from an earlier run never sit next to new ones. Files are written under a
temporary name and renamed, so an interrupted run never leaves a half-written file behind.

A run whose artifacts are kept streams its trace into the folder while it goes
(:func:`start_run_folder`, :class:`fleetsim.sim.trace.TraceFile`), beside ``run.json``, which names the
suite, scenario and planner; so a run killed outright still leaves what ``fleetsim record --trace``
needs to rebuild its picture and recording. When the run ends, the files are written quickest and most
useful first — the picture, ``result.json``, then the recording (slow for a long run) and ``result.json``
again with its path — and ``run.json`` goes, so a second Ctrl-C during the clean-up leaves complete files.

The picture, recording and RViz modules (and the MCAP and ROS 2 message libraries behind them) are
imported when a folder gets those files, so a session whose runs all pass does not load them.
"""

from __future__ import annotations

import json
import re
import shutil
from collections.abc import Callable, Mapping, Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

from fleetsim.load.common.text import write_text_atomically
from fleetsim.scenario import Scenario
from fleetsim.sim.record import RunOrigin, run_record
from fleetsim.sim.result import Failure, RunResult

__all__ = [
    "MCAP_FILE",
    "PICTURE_FILE",
    "RESULT_FILE",
    "RUN_FILE",
    "RVIZ_CONFIG",
    "RVIZ_FILE",
    "TRACE_FILE",
    "artifact_folder",
    "discard_run_folder",
    "start_run_folder",
    "stuck_overlay",
    "write_run_artifacts",
]

RESULT_FILE = "result.json"
RUN_FILE = "run.json"  # what a run in progress is of; replaced by result.json when it ends
TRACE_FILE = "trace.jsonl"
MCAP_FILE = "run.mcap"
PICTURE_FILE = "failure.svg"
RVIZ_FILE = "fleetsim.rviz"
RVIZ_CONFIG = Path(__file__).with_name(RVIZ_FILE)  # shipped with the package
_UNSAFE = re.compile(r"[^A-Za-z0-9._-]+")


def _safe(name: str) -> str:
    """A file-system-safe form of a suite or scenario name (names are checked identifiers, mostly)."""
    cleaned = _UNSAFE.sub("_", name).strip("._")
    return cleaned or "_"


def artifact_folder(root: Path, suite_path: Path, scenario: str) -> Path:
    """``root/<suite stem>/<scenario>``; the stem drops ``.fleetsim.yaml``."""
    stem = suite_path.name.removesuffix(".yaml").removesuffix(".yml").removesuffix(".fleetsim")
    return root / _safe(stem) / _safe(scenario)


def stuck_overlay(failures: Sequence[Failure]) -> dict[str, Any] | None:
    """The details of a run's deadlock, timeout or interruption that explains who waits for whom, with its
    headline, for the recording; None when no failure does."""
    from fleetsim.recording.picture import stuck_details

    for failure in failures:
        details = stuck_details(failure)
        if details is not None:
            return {**details, "headline": f"{failure.kind}: {failure.message}"}
    return None


def start_run_folder(folder: Path, about: Mapping[str, Any]) -> Path:
    """Empty ``folder`` for a run about to start and write its ``run.json`` (``about``: the suite,
    scenario, planner, ...); the path its trace is to be streamed to."""
    if folder.exists():
        shutil.rmtree(folder)
    folder.mkdir(parents=True)
    write_text_atomically(folder / RUN_FILE, json.dumps(dict(about), indent=2, sort_keys=True) + "\n")
    return folder / TRACE_FILE


def discard_run_folder(folder: Path, root: Path) -> None:
    """Remove the folder of a run whose artifacts are not kept (it passed), and the folders above it up to
    ``root`` that it leaves empty."""
    shutil.rmtree(folder, ignore_errors=True)
    for parent in folder.parents:
        if parent == root.parent or not parent.is_relative_to(root):
            break
        try:
            parent.rmdir()
        except OSError:  # not empty (other runs' folders), or gone
            break


def write_run_artifacts(
    folder: Path,
    result: RunResult,
    origin: RunOrigin | None = None,
    *,
    scenario: Scenario | None = None,
    record_every: int = 1,
    streamed: bool = False,
    more: Callable[[Path, Scenario, RunResult, Mapping[str, Any]], Mapping[str, str]] | None = None,
) -> dict[str, str]:
    """Write the run's files into ``folder`` (replacing what was there); their paths by kind.

    ``result.json`` is the run's record (:func:`fleetsim.sim.record.run_record`) from ``origin`` (the
    suite entry, and the producer's own keys: the pytest node id, a sweep's, ...). With the run's
    ``scenario`` and a kept trace, the recording (every ``record_every``-th step) and, for a failed run,
    the failure picture are written too. ``streamed``: the folder was made by :func:`start_run_folder`
    and holds the run's trace already; it is kept. ``more(folder, scenario, result, extra)``: writes
    further files of a run with a trace and a scenario (the viewer page, ``fleetsim.view``) and names them;
    ``extra`` is the origin's keys.
    """
    origin = origin if origin is not None else RunOrigin()
    if not streamed:
        if folder.exists():
            shutil.rmtree(folder)
        folder.mkdir(parents=True)
    paths = {"folder": str(folder), "result": str(folder / RESULT_FILE)}
    lines = result.trace.lines if result.trace is not None else []
    if lines:
        paths["trace"] = str(folder / TRACE_FILE)
        if not streamed:
            write_text_atomically(folder / TRACE_FILE, "\n".join(lines) + "\n")
    if lines and scenario is not None:
        from fleetsim.recording.picture import failure_picture
        from fleetsim.recording.recorder import record_mcap
        from fleetsim.recording.rviz import rviz_config

        picture = failure_picture(scenario, result)
        if picture is not None:
            write_text_atomically(folder / PICTURE_FILE, picture[1])
            paths["picture"] = str(folder / PICTURE_FILE)
        _write_result(folder, result, paths, origin)  # in case the recording is cut short
        paths["mcap"] = str(
            record_mcap(
                folder / MCAP_FILE,
                scenario,
                lines,
                every=record_every,
                stuck=stuck_overlay(result.failures),
                contacts=[c.to_dict() for c in result.contact.contacts] if result.contact is not None else (),
            ).path
        )
        write_text_atomically(folder / RVIZ_FILE, rviz_config(scenario, RVIZ_CONFIG.read_text(encoding="utf-8")))
        paths["rviz"] = str(folder / RVIZ_FILE)
        if more is not None:
            paths.update(more(folder, scenario, result, origin.keys()))
    _write_result(folder, result, paths, origin)
    (folder / RUN_FILE).unlink(missing_ok=True)
    return paths


def _write_result(folder: Path, result: RunResult, paths: Mapping[str, str], origin: RunOrigin) -> None:
    document = run_record(replace(result, artifacts={**result.artifacts, **paths}), origin)
    write_text_atomically(folder / RESULT_FILE, json.dumps(document, indent=2, sort_keys=True) + "\n")

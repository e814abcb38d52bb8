"""The viewer page of a recorded run, and ``view.html`` in a run's artifact folder.

A run folder's ``view.html`` is the run as one self-contained page (open it in any browser: it makes no
request); the summary of ``fleetsim run --record``, the pytest failure report and the sweep report link
to it. It is written by whoever writes the folder (``write_run_artifacts(..., more=write_view_file)``),
so the recording room needs nothing of this one.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from fleetsim.load.common.text import write_text_atomically
from fleetsim.scenario import Scenario
from fleetsim.sim.result import Failure, RunResult
from fleetsim.view.document import outcome_part, view_document
from fleetsim.view.page import recorded_page

__all__ = ["VIEW_FILE", "recorded_view", "write_view_file"]

VIEW_FILE = "view.html"


def recorded_view(
    scenario: Scenario,
    lines: Sequence[str],
    document: Mapping[str, Any],
    failures: Sequence[Failure],
    notes: Sequence[str] = (),
) -> str:
    """The page of a run of ``scenario`` whose trace is ``lines`` (header first) and whose result is
    ``document`` (``result.json``'s object; empty for a run that never ended). Raises ``TraceError`` for a
    trace of another scenario."""
    about = {key: document[key] for key in ("planner", "suite") if isinstance(document.get(key), str)}
    last_step = len(lines) - 2
    outcome = outcome_part(document, failures, scenario.settings.time_step, last_step)
    return recorded_page(view_document(scenario, lines, about, outcome, notes))


def write_view_file(folder: Path, scenario: Scenario, result: RunResult, extra: Mapping[str, Any]) -> dict[str, str]:
    """Write ``view.html`` for a run whose trace was kept into its folder; its path by kind (``view``)."""
    if result.trace is None or not result.trace.lines:
        return {}
    # What the page reads of result.json (the whole document, with every failure's text, is not needed).
    document = {
        "planner": result.planner,
        "status": result.status,
        "ended": result.ended,
        "trace_hash": result.trace_hash,
        "stalls": [stall.to_dict() for stall in result.stalls],
        **extra,
    }
    notes = []
    if result.ended == "interrupted":
        notes.append(f"the run was interrupted at t = {result.sim_time:.2f} s; it ends there")
    write_text_atomically(
        folder / VIEW_FILE, recorded_view(scenario, result.trace.lines, document, result.failures, notes)
    )
    return {"view": str(folder / VIEW_FILE)}

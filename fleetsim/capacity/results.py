"""The results file of a capacity search (format ``fleetsim-capacity/1``): one JSON document.

It holds the capacity and its bracket, each seed's own bracket, why the search stopped, the criteria and
search settings, and every rate tried with each seed's figures. It depends on nothing but the search's
inputs (no times, no host names), so the same search writes the same file byte for byte, and CI keeps it
as the baseline of the next search (``--baseline capacity.json``).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from fleetsim.capacity.criteria import Criteria
from fleetsim.capacity.runs import Target
from fleetsim.capacity.search import SearchResult
from fleetsim.errors import FleetsimError, Location

__all__ = ["CAPACITY_FORMAT", "CapacityResultsError", "capacity_document", "read_capacity", "write_capacity"]

CAPACITY_FORMAT = "fleetsim-capacity/1"


class CapacityResultsError(FleetsimError, ValueError):
    """A capacity results file that cannot be read; the message names the file."""


def capacity_document(
    target: Target, planner: str, criteria: Criteria, result: SearchResult, runs_file: str
) -> dict[str, Any]:
    """The search as its results file holds it."""
    settings = result.settings
    rates = [
        {
            "rate": outcome.rate,
            "step": step,
            "sustained": outcome.sustained,
            "runs": [{"seed": seed, **outcome.runs[seed].to_dict()} for seed in settings.seeds],
        }
        for step, outcome in enumerate(result.tried, start=1)
    ]
    return {
        "format": CAPACITY_FORMAT,
        "scenario": target.id,
        "where": target.where,
        "planner": planner,
        "dispatcher": target.scenario.dispatcher,
        "entry_rate": target.rate,
        "seeds": list(settings.seeds),
        "criteria": criteria.to_dict(),
        "search": {
            "resolution": str(settings.resolution),
            "min_rate": settings.min_rate,
            "max_rate": settings.max_rate,
            "max_runs": settings.max_runs,
        },
        "capacity": result.capacity,
        "sustained": result.sustained,
        "unsustained": result.unsustained,
        "stop": result.stop,
        "why": result.why(),
        "seed_brackets": [
            {"seed": b.seed, "sustained": b.sustained, "unsustained": b.unsustained} for b in result.seed_brackets()
        ],
        "runs": result.runs,
        "rates": sorted(rates, key=lambda rate: float(rate["rate"])),
        "runs_file": runs_file,
    }


def write_capacity(path: Path, document: dict[str, Any]) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(document, indent=2, sort_keys=True) + "\n", encoding="utf-8")


def read_capacity(path: Path) -> dict[str, Any]:
    """A capacity results file written by :func:`write_capacity` (its format and capacity checked)."""
    try:
        document = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise CapacityResultsError(f"{path}: no such capacity results file") from None
    except (OSError, UnicodeDecodeError) as error:
        raise CapacityResultsError(f"{path}: cannot read the capacity results file: {error}") from None
    except json.JSONDecodeError as error:
        raise CapacityResultsError(f"{Location(path, error.lineno, error.colno)}: invalid JSON: {error.msg}") from None
    found = document.get("format") if isinstance(document, dict) else None
    if found != CAPACITY_FORMAT:
        msg = f"{path}: format={found!r}: not a capacity results file (written by fleetsim capacity, format {CAPACITY_FORMAT!r})"
        raise CapacityResultsError(msg)
    capacity = document.get("capacity")
    if isinstance(capacity, bool) or not isinstance(capacity, (int, float)) or capacity < 0:
        raise CapacityResultsError(f"{path}: capacity={capacity!r} must be a number of orders per hour >= 0")
    return dict(document)

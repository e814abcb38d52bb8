"""The results file of a sweep: JSON lines, a header and then one row per finished run.

Rows are appended (and flushed) as runs finish, so a sweep killed at any moment leaves every finished
run on disk; ``--resume`` reads the file, drops a last line cut short, and runs only the keys missing.
Each row is a run's record (``schemas/result.schema.json``: every key ``fleetsim run --json`` prints)
with the sweep's own keys (``key``, ``id``, ``source``, ``seed``, ``repetition``, ``vehicles``,
``error``); ``pytest --fleetsim-compare`` reads the same file. Reading checks every row
against the schema, so a file that is not what this fleetsim writes fails at its line.
"""

from __future__ import annotations

import json
import os
from collections.abc import Iterable
from pathlib import Path
from typing import IO, Any

from fleetsim.errors import FleetsimError, Location
from fleetsim.gating.baseline import SWEEP_RESULTS_FORMAT as RESULTS_FORMAT
from fleetsim.sim.record import PRODUCER_KEYS
from fleetsim.sim.result_schema import result_problem

__all__ = [
    "RESULTS_FORMAT",
    "SWEEP_KEYS",
    "ResultsError",
    "ResultsFile",
    "read_results",
    "record_problem",
    "relabelled",
    "rows_by_key",
]

_FAMILY = RESULTS_FORMAT.rpartition("/")[0] + "/"
SWEEP_KEYS = PRODUCER_KEYS["sweep"]  # a sweep record's own keys, besides the run's and its entry's


class ResultsError(FleetsimError, ValueError):
    """A results file cannot be read or appended to; the message names the file (and line)."""


def read_results(path: Path | str) -> tuple[dict[str, Any], list[dict[str, Any]]]:
    """The header and the rows of a results file; a last line cut short (a killed sweep) is left out.

    A key given twice keeps its first row: every run counts once, whatever happened to the file.
    """
    path = Path(path)
    try:
        lines = path.read_text(encoding="utf-8").split("\n")
    except FileNotFoundError:
        raise ResultsError(f"{path}: no such results file; write one with fleetsim sweep SPEC.yaml -o {path}") from None
    except (OSError, UnicodeDecodeError) as error:
        raise ResultsError(f"{path}: cannot read the results file: {error}") from None
    header = _parse(lines[0], path, 1) if lines and lines[0] else None
    found = header.get("format") if isinstance(header, dict) else None
    if isinstance(found, str) and found != RESULTS_FORMAT and found.startswith(_FAMILY):
        msg = f"{Location(path, 1)}: format={found!r}: written by another fleetsim version (this one reads {RESULTS_FORMAT!r}); run the sweep again into a new results file"
        raise ResultsError(msg)
    if not isinstance(header, dict) or found != RESULTS_FORMAT:
        raise ResultsError(
            f'{Location(path, 1)}: not a sweep results file (its first line must be the header with "format": {RESULTS_FORMAT!r})'
        )
    rows: dict[str, dict[str, Any]] = {}
    # Every row ends with a newline: text after the last one is a row cut short by a kill (not done).
    for number, line in enumerate(lines[1:-1], start=2):
        if not line.strip():
            continue
        row = _parse(line, path, number)
        if not isinstance(row, dict) or not isinstance(row.get("key"), str):
            raise ResultsError(f'{Location(path, number)}: row={line[:80]!r} must be a JSON object with a "key"')
        problem = record_problem(row)
        if problem is not None:
            raise ResultsError(f"{Location(path, number)}: not a sweep record: {problem}")
        rows.setdefault(row["key"], row)
    return header, list(rows.values())


def record_problem(row: Any) -> str | None:
    """``None`` for a sweep record (a run's result with the sweep's keys), else what is wrong with it."""
    problem = result_problem(row)
    if problem is not None:
        return problem
    missing = [key for key in SWEEP_KEYS if key not in row]
    return f"the sweep's key {missing[0]!r} is missing" if missing else None


def _parse(line: str, path: Path, number: int) -> Any:
    try:
        return json.loads(line)
    except json.JSONDecodeError as error:
        raise ResultsError(f"{Location(path, number, error.colno)}: invalid JSON: {error.msg}") from None


class ResultsFile:
    """Appends rows to a results file, one flushed line each; a key is written at most once."""

    def __init__(self, path: Path, header: dict[str, Any], *, resume: bool) -> None:
        self.path = path
        self.done: set[str] = set()
        if resume and path.exists():
            _, rows = read_results(path)
            self.done = {row["key"] for row in rows}
            _cut_partial_line(path)
            self._file: IO[str] = path.open("a", encoding="utf-8")
        elif path.exists():
            raise ResultsError(
                f"{path} exists; pass --resume to run only what it lacks, or choose another file with -o"
            )
        else:
            path.parent.mkdir(parents=True, exist_ok=True)
            self._file = path.open("w", encoding="utf-8")
            self._write({"format": RESULTS_FORMAT, **header})

    def add(self, row: dict[str, Any]) -> bool:
        """Write ``row`` unless its key is done already; True if written."""
        if row["key"] in self.done:
            return False
        self.done.add(row["key"])
        self._write(row)
        return True

    def _write(self, document: dict[str, Any]) -> None:
        self._file.write(json.dumps(document, sort_keys=True) + "\n")
        self._file.flush()
        os.fsync(self._file.fileno())

    def close(self) -> None:
        self._file.close()

    def __enter__(self) -> ResultsFile:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def _cut_partial_line(path: Path) -> None:
    """Drop a last line without its newline (a write cut short), so appending starts on a fresh line."""
    data = path.read_bytes()
    end = data.rfind(b"\n") + 1
    if end < len(data):
        with path.open("r+b") as file:
            file.truncate(end)


def rows_by_key(rows: Iterable[dict[str, Any]]) -> list[dict[str, Any]]:
    """Rows in key order: reports do not depend on the order runs finished in."""
    return sorted(rows, key=lambda row: str(row["key"]))


def relabelled(rows: Iterable[dict[str, Any]], planner: str, label: str) -> list[dict[str, Any]]:
    """``planner``'s rows as ``label``'s (its keys too): another sweep's runs (a baseline saved from the main
    branch, say) beside this sweep's, so a report pairs each of its planners with them by scenario id."""
    return [
        {**row, "planner": label, "key": f"{label} | {row['id']} | {row['repetition']}"}
        for row in rows
        if row["planner"] == planner
    ]

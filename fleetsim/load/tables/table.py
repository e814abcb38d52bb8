"""One of a scenario's CSV tables (``vehicles.csv``, ``tasks.csv``) read into rows, every problem collected.

The conventions are those of :mod:`fleetsim.load.tables.scenario_files`: a header row first (required), blank
and ``#`` comment rows skipped but kept in the file's line numbers, names and values trimmed, column
names case-insensitive, unknown columns and rows of the wrong width refused.

A file that cannot be read as a table at all (missing, not UTF-8, an unclosed quote, a broken header) is
unreadable: its errors are collected and it has no rows, since rows mean nothing without their header.
Every row of the wrong width is its own error, and the other rows are still read. A header that is one
cell separated by ``;`` or tabs is named as such: to a comma reader it is a single unknown column, and
saying only that helps nobody.
"""

from __future__ import annotations

import csv
import difflib
import io
from collections import deque
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path

from fleetsim.errors import LoadError, Location, ScenarioFileError
from fleetsim.load.common.closest import did_you_mean
from fleetsim.load.common.collect import ErrorCollector
from fleetsim.load.common.text import read_text_file

__all__ = ["Columns", "Row", "check_table", "read_table"]

# Separators a spreadsheet may have written instead of commas, and how a message names each.
_OTHER_SEPARATORS = {";": "';'", "\t": "tabs"}


@dataclass(frozen=True, slots=True)
class Columns:
    """A table's columns: the required ones, then the optional ones."""

    required: tuple[str, ...]
    optional: tuple[str, ...]

    @property
    def all(self) -> tuple[str, ...]:
        return self.required + self.optional

    @property
    def header(self) -> str:
        """The header as documented, optional columns in brackets."""
        return ",".join(self.required) + "".join(f"[,{name}]" for name in self.optional)


@dataclass(frozen=True, slots=True)
class Row:
    """One data row: its file line and its trimmed cells by column (absent optional columns read as "")."""

    path: Path
    line: int
    cells: Mapping[str, str]

    def get(self, column: str) -> str:
        return self.cells.get(column, "")

    def error(self, column: str, problem: str) -> ScenarioFileError:
        return ScenarioFileError(problem, Location(self.path, line=self.line, field=column))


def read_table(path: Path, columns: Columns, errors: ErrorCollector) -> Iterator[Row] | None:
    """The data rows of the right width in the CSV file at ``path``, or ``None`` when the file is
    unreadable as a table; every problem is added to ``errors``.

    The rows come one by one and a row of the wrong width is added to ``errors`` when its turn comes,
    so errors the caller finds in the rows stay in file order among them.
    """
    try:
        records = _records(path)
        if not records:
            msg = f"no header: the first row must be {columns.header} (required even with no data rows)"
            raise ScenarioFileError(msg, Location(path, line=1))
        header_line, header_cells = records[0]
        names = _header(path, header_line, header_cells, columns)
    except LoadError as error:  # a LoadErrors when the header has several problems
        errors.add(error)
        return None
    return _rows(path, records[1:], names, errors)


def check_table(path: Path, columns: Columns, errors: ErrorCollector) -> None:
    """Add the problems of the file's structure (readable, header, row widths) to ``errors``."""
    deque(read_table(path, columns, errors) or (), maxlen=0)  # reading each row records its width error


def _rows(
    path: Path, records: list[tuple[int, list[str]]], names: tuple[str, ...], errors: ErrorCollector
) -> Iterator[Row]:
    for line, cells in records:
        if len(cells) != len(names):
            msg = f"row has {len(cells)} values but the header has {len(names)} columns: {cells!r}"
            errors.add(ScenarioFileError(msg, Location(path, line=line)))
            continue
        yield Row(path, line, dict(zip(names, cells, strict=True)))


def _records(path: Path) -> list[tuple[int, list[str]]]:
    """(first file line, trimmed cells) of every row that is neither blank nor a comment."""
    text = read_text_file(path, ScenarioFileError)
    reader = csv.reader(io.StringIO(text, newline=""), strict=True)
    records: list[tuple[int, list[str]]] = []
    line = 1
    try:
        for cells in reader:
            trimmed = [cell.strip() for cell in cells]
            if any(trimmed) and not trimmed[0].startswith("#"):
                records.append((line, trimmed))
            line = reader.line_num + 1  # a quoted cell may span lines: the next row starts after it
    except csv.Error as exc:
        # Point at the row that started it: an unclosed quote only fails at the end of the file.
        raise ScenarioFileError(f"malformed CSV row: {exc}", Location(path, line=line)) from None
    return records


def _header(path: Path, line: int, cells: list[str], columns: Columns) -> tuple[str, ...]:
    """The column names; every problem of the header at once (one error raised as itself, or several)."""
    if cells[0].isdigit():
        # A data row where the header belongs: say that, not "unknown column '1'".
        msg = f"missing header: the first row must be {columns.header}, found data {','.join(cells)!r}"
        raise ScenarioFileError(msg, Location(path, line=line))
    names = tuple(cell.lower() for cell in cells)
    separator = _other_separator(names, columns)
    if separator is not None:
        msg = (
            f"unknown column {names[0]!r}: this file seems to be separated by {_OTHER_SEPARATORS[separator]}; "
            f"fleetsim reads comma-separated files (the header is {columns.header})"
        )
        raise ScenarioFileError(msg, Location(path, line=line, field=names[0]))
    problems = ErrorCollector()
    meant: set[str] = set()  # the columns a misspelt name was taken for: not reported missing as well
    for index, name in enumerate(names):
        where = Location(path, line=line, field=name or None)
        if not name:
            msg = f"header column {index + 1} has no name (a stray comma?); the header is {columns.header}"
            problems.add(ScenarioFileError(msg, where))
        elif name not in columns.all:
            meant.update(difflib.get_close_matches(name, columns.all, n=1))
            msg = f"unknown column {name!r}{did_you_mean(name, columns.all)} (the header is {columns.header})"
            problems.add(ScenarioFileError(msg, where))
        elif name in names[:index]:
            problems.add(ScenarioFileError(f"column {name!r} appears twice in the header", where))
    for name in columns.required:
        if name not in names and name not in meant:
            msg = f"missing required column {name!r} (the header is {columns.header})"
            problems.add(ScenarioFileError(msg, Location(path, line=line, field=name)))
    problems.raise_if_any()
    return names


def _other_separator(names: tuple[str, ...], columns: Columns) -> str | None:
    """The separator a one-cell header was written with, when splitting by it gives known columns."""
    if len(names) != 1:
        return None
    for separator in _OTHER_SEPARATORS:
        parts = [part.strip() for part in names[0].split(separator)]
        if len(parts) > 1 and any(part in columns.all for part in parts):
            return separator
    return None

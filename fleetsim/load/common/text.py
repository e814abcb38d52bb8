"""Text files: reading a user's file (map, template, suite, CSV) with located errors; writing ours whole."""

from __future__ import annotations

import json
import os
import tempfile
from pathlib import Path

from fleetsim.errors import LoadError, Location

__all__ = ["json_problem", "read_text_file", "write_text_atomically"]

# The json module's messages, in the words of someone who edits the file.
_JSON_WORDS = {
    "Unterminated string starting at": "a string that starts here runs to the end of the file (is the file cut short?)",
    "Expecting value": "a value (a number, a string, true/false/null, an object or a list) is expected here",
    "Expecting ',' delimiter": "a ',' between items (or the closing bracket) is expected here",
    "Expecting ':' delimiter": "a ':' after the key is expected here",
    "Expecting property name enclosed in double quotes": "a key in double quotes is expected here",
    "Extra data": "more text follows the end of the JSON document",
    "Invalid control character at": "a control character (a raw newline or tab) is inside a string; write it as \\n or \\t",
    "Invalid \\escape": "a backslash escape here is not valid JSON",
    "Invalid \\uXXXX escape": "a \\u escape here does not have four hex digits",
}


def json_problem(error: json.JSONDecodeError) -> str:
    """What is wrong with a JSON file, as a sentence (its line and column go into the location)."""
    words = _JSON_WORDS.get(error.msg, error.msg[:1].lower() + error.msg[1:])
    if not error.doc[error.pos :].strip() and error.msg not in ("Extra data", "Unterminated string starting at"):
        words += "; the file ends there (is it cut short?)"
    elif error.msg.startswith("Expecting property name") and error.doc[error.pos : error.pos + 1] in "}]":
        words += " (JSON allows no comma after the last item)"
    return f"the file is not valid JSON: {words}"


def read_text_file(path: Path, error_type: type[LoadError], where: Location | None = None) -> str:
    """The file's UTF-8 text (a BOM is dropped); any failure is an ``error_type`` located at ``where``.

    ``where`` defaults to the file itself; a template names the map object that refers to it instead.
    """
    place = where if where is not None else Location(path)
    # The location already names the file unless it points at whoever referred to it.
    name = "" if where is None else f" {str(path)!r}"
    try:
        raw = path.read_bytes()
    except FileNotFoundError:
        raise error_type(f"file{name} not found", place) from None
    except IsADirectoryError:
        raise error_type(f"{name.strip() or 'this'} is a directory, not a file", place) from None
    except (OSError, ValueError) as exc:  # ValueError: a NUL in the path
        raise error_type(f"cannot read{name}: {exc}", place) from None
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = raw.count(b"\n", 0, exc.start) + 1
        msg = f"not UTF-8 text: byte {raw[exc.start : exc.start + 1]!r} cannot be decoded"
        raise error_type(msg, Location(path, line=line) if where is None else place) from None


def write_text_atomically(path: Path, text: str) -> None:
    """Write to a temporary file beside ``path`` and rename, so a reader never sees half a file."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", dir=path.parent)
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as handle:
            handle.write(text)
        os.chmod(tmp, _mode_for(path))  # mkstemp makes it private (0600); a written file should not be
        os.replace(tmp, path)
    except BaseException:
        os.unlink(tmp)
        raise


def _mode_for(path: Path) -> int:
    """The file's current permissions, or what a plain ``open()`` would give a new file."""
    try:
        return path.stat().st_mode & 0o777
    except OSError:
        umask = os.umask(0)
        os.umask(umask)
        return 0o666 & ~umask

"""Lock files: the trace hash each planner produced for each scenario, kept beside the suite file.

A lock file turns "the planner's behaviour did not change" into a check CI can make: the pytest plugin
records ``RunResult.trace_hash`` per planner identity and scenario, and later compares runs against it.
Besides the hash it keeps short prefixes of the running checkpoint digests, so a mismatch can say *when*
the behaviour changed, not only *that* it did. The text is canonical (sorted, one scenario per line) so
that re-recording an unchanged lock writes nothing and a changed scenario is a one-line diff.
"""

from __future__ import annotations

import json
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, NoReturn

from fleetsim.errors import LoadError, Location, MapError
from fleetsim.load.common.text import read_text_file, write_text_atomically
from fleetsim.load.tiled.templates import parse_json
from fleetsim.sim.trace import CHECKPOINT_EVERY, TRACE_FORMAT

__all__ = ["LOCK_FORMAT", "HashLock", "HashMismatch", "LockEntry", "LockFileError", "compare_run", "lock_path_for"]

LOCK_FORMAT = "fleetsim-lock/1"
LOCK_SUFFIX = ".lock.json"
CHECKPOINT_DIGITS = 16  # 64 bits per checkpoint tells runs apart; whole digests would bloat each line
_TOP_KEYS = ("format", "trace_format", "checkpoint_every", "hashes")
_ENTRY_KEYS = ("hash", "steps", "checkpoints")
_HEX_DIGITS = frozenset("0123456789abcdef")


def lock_path_for(suite_path: Path) -> Path:
    """``examples.fleetsim.yaml`` -> ``examples.fleetsim.lock.json`` in the same folder."""
    stem = suite_path.stem if suite_path.suffix.lower() in (".yaml", ".yml") else suite_path.name
    return suite_path.with_name(stem + LOCK_SUFFIX)


class LockFileError(LoadError):
    """A lock file is malformed; it is a ``LoadError`` (so a ``FleetsimError`` and a ``ValueError``)."""


@dataclass(frozen=True, slots=True)
class LockEntry:
    """One recorded run: its trace hash, length, and checkpoint digest prefixes in step order.

    ``checkpoints[i]`` belongs to step ``(i + 1) * CHECKPOINT_EVERY - 1``; it may be empty when the
    recorded checkpoints were taken at another interval and so cannot be compared.
    """

    hash: str
    steps: int
    checkpoints: tuple[str, ...] = ()

    @classmethod
    def from_run(cls, trace_hash: str, steps: int, checkpoints: Sequence[tuple[int, str]]) -> LockEntry:
        return cls(trace_hash, steps, _prefixes(checkpoints))


def _prefixes(checkpoints: Sequence[tuple[int, str]]) -> tuple[str, ...]:
    """Digest prefixes in step order; the steps are checked here because later only positions count."""
    ordered = sorted(checkpoints)
    for index, (step, _) in enumerate(ordered):
        expected = (index + 1) * CHECKPOINT_EVERY - 1
        if step != expected:
            msg = f"checkpoints[{index}] step={step!r} must be {expected} (one every {CHECKPOINT_EVERY} steps)"
            raise ValueError(msg)
    return tuple(digest[:CHECKPOINT_DIGITS] for _, digest in ordered)


class HashLock:
    """The recorded hashes of one lock file, keyed by planner identity and scenario name.

    The trace format is stored once for the whole file, because a format change changes every hash at
    once. A lock recorded under another trace format loads (``trace_format`` says which) so the plugin
    can explain why nothing matches; the first :meth:`set` drops all those entries, since they can never
    match again, and stamps the current ``TRACE_FORMAT``.
    """

    def __init__(self, path: Path | str) -> None:
        self.path = Path(path)
        self.trace_format = TRACE_FORMAT
        self._hashes: dict[str, dict[str, LockEntry]] = {}

    def __repr__(self) -> str:
        return f"HashLock({str(self.path)!r}, {len(self.entries())} entries)"

    @classmethod
    def load(cls, path: Path | str) -> HashLock:
        """The lock at ``path``; a missing file is an empty lock. Any problem raises ``LockFileError``.

        Checkpoints taken at another interval than ``CHECKPOINT_EVERY`` are dropped (the hashes stay):
        their positions would point at the wrong steps.
        """
        lock = cls(path)
        if not lock.path.exists():
            return lock
        text = read_text_file(lock.path, LockFileError)
        try:
            document = parse_json(text, lock.path)
        except MapError as exc:  # the JSON parser's line and column, under this file's error type
            raise LockFileError(exc.problem, exc.location) from None
        lock.trace_format, lock._hashes = _parse(document, lock.path)
        return lock

    def get(self, planner: str, scenario: str) -> LockEntry | None:
        return self._hashes.get(planner, {}).get(scenario)

    def set(self, planner: str, scenario: str, entry: LockEntry) -> None:
        if self.trace_format != TRACE_FORMAT:
            self._hashes.clear()
            self.trace_format = TRACE_FORMAT
        self._hashes.setdefault(planner, {})[scenario] = entry

    def entries(self) -> list[tuple[str, str, LockEntry]]:
        return [(p, s, e) for p, section in sorted(self._hashes.items()) for s, e in sorted(section.items())]

    def scenario_names(self) -> list[str]:
        """Every scenario some planner has an entry for, sorted."""
        return sorted({scenario for section in self._hashes.values() for scenario in section})

    def stale(self, existing_scenarios: Iterable[str]) -> list[tuple[str, str]]:
        """(planner, scenario) of the entries whose scenario is not among ``existing_scenarios``, sorted."""
        existing = frozenset(existing_scenarios)
        return [(planner, scenario) for planner, scenario, _ in self.entries() if scenario not in existing]

    def prune(self, existing_scenarios: Iterable[str]) -> list[tuple[str, str]]:
        """Remove and return the :meth:`stale` entries, so renamed or deleted scenarios leave no trace."""
        removed = self.stale(existing_scenarios)
        for planner, scenario in removed:
            del self._hashes[planner][scenario]
            if not self._hashes[planner]:
                del self._hashes[planner]
        return removed

    def dumps(self) -> str:
        """The canonical text: sorted JSON with one scenario per line, so a change is a one-line diff."""
        sections = []
        for planner, section in sorted(self._hashes.items()):
            rows = ",\n".join(f"      {json.dumps(name)}: {_entry_json(e)}" for name, e in sorted(section.items()))
            sections.append(f"    {json.dumps(planner)}: {{\n{rows}\n    }}")
        hashes = "{\n" + ",\n".join(sections) + "\n  }" if sections else "{}"
        return (
            "{\n"
            f'  "format": {json.dumps(LOCK_FORMAT)},\n'
            f'  "trace_format": {json.dumps(self.trace_format)},\n'
            f'  "checkpoint_every": {CHECKPOINT_EVERY},\n'
            f'  "hashes": {hashes}\n'
            "}\n"
        )

    def save(self) -> bool:
        """Write the lock if its text changed, or delete the file if the lock is empty; say whether it did.

        An unchanged lock is not rewritten, so its mtime (and any tool watching it) is left alone. The
        text goes to a temporary file beside the lock and is renamed over it, so a reader never sees
        half a file.
        """
        try:
            on_disk: str | None = self.path.read_text(encoding="utf-8", errors="replace")
        except FileNotFoundError:
            on_disk = None
        if not self._hashes:
            if on_disk is None:
                return False
            self.path.unlink()
            return True
        text = self.dumps()
        if text == on_disk:
            return False
        write_text_atomically(self.path, text)
        return True


def _entry_json(entry: LockEntry) -> str:
    return json.dumps({"hash": entry.hash, "steps": entry.steps, "checkpoints": list(entry.checkpoints)})


# --- reading ---------------------------------------------------------------------------------------


def _parse(document: object, path: Path) -> tuple[str, dict[str, dict[str, LockEntry]]]:
    """Check the whole document before anything is kept, so a bad file never half-loads."""
    top = _object(path, "the lock file", document)
    if "format" in top and top["format"] != LOCK_FORMAT:  # before the keys: another version has others
        _fail(path, "format", top["format"], f"be {LOCK_FORMAT!r} (the file was written by another fleetsim)")
    _check_keys(path, "the lock file", top, _TOP_KEYS)
    trace_format = top["trace_format"]
    if not isinstance(trace_format, str) or not trace_format:
        _fail(path, "trace_format", trace_format, "be a non-empty string")
    every = top["checkpoint_every"]
    if type(every) is not int or every < 1:
        _fail(path, "checkpoint_every", every, "be a positive integer")
    hashes: dict[str, dict[str, LockEntry]] = {}
    for planner, raw_section in _object(path, "hashes", top["hashes"]).items():
        section = _object(path, f"hashes[{planner!r}]", raw_section)
        entries = {name: _entry(path, f"hashes[{planner!r}][{name!r}]", raw, every) for name, raw in section.items()}
        if entries:
            hashes[planner] = entries
    return trace_format, hashes


def _entry(path: Path, name: str, raw: object, every: int) -> LockEntry:
    fields = _object(path, name, raw)
    _check_keys(path, name, fields, _ENTRY_KEYS)
    trace_hash, steps, checkpoints = (fields[key] for key in _ENTRY_KEYS)
    if not _is_hex(trace_hash, 64):
        _fail(path, f"{name}['hash']", trace_hash, "be 64 lowercase hexadecimal digits (a SHA-256 digest)")
    if type(steps) is not int or steps < 0:
        _fail(path, f"{name}['steps']", steps, "be a non-negative integer")
    if not isinstance(checkpoints, list):
        _fail(path, f"{name}['checkpoints']", checkpoints, "be a list")
    for index, digest in enumerate(checkpoints):
        if not _is_hex(digest, CHECKPOINT_DIGITS):
            _fail(path, f"{name}['checkpoints'][{index}]", digest, "be 16 lowercase hexadecimal digits")
    if checkpoints and len(checkpoints) != steps // every:
        msg = (
            f"{name}['checkpoints'] has {len(checkpoints)} digests; a run of {steps} steps must have "
            f"{steps // every} (one every {every} steps) or none"
        )
        raise LockFileError(msg, Location(path))
    return LockEntry(trace_hash, steps, tuple(checkpoints) if every == CHECKPOINT_EVERY else ())


def _object(path: Path, name: str, value: object) -> dict[str, Any]:
    if not isinstance(value, dict):
        _fail(path, name, value, "be a JSON object")
    return value


def _check_keys(path: Path, name: str, fields: dict[str, Any], keys: tuple[str, ...]) -> None:
    unknown = sorted(fields.keys() - set(keys))
    missing = [key for key in keys if key not in fields]
    if unknown or missing:
        problem = f"has an unknown key {unknown[0]!r}" if unknown else f"lacks the key {missing[0]!r}"
        msg = f"{name} {problem}; the keys are {', '.join(keys)}"
        raise LockFileError(msg, Location(path))


def _is_hex(value: object, digits: int) -> bool:
    return isinstance(value, str) and len(value) == digits and set(value) <= _HEX_DIGITS


def _fail(path: Path, name: str, value: object, must: str) -> NoReturn:
    shown = repr(value)
    if len(shown) > 80:  # a whole section pasted into the message would bury the point
        shown = shown[:76] + " ..."
    raise LockFileError(f"{name} = {shown} must {must}", Location(path))


# --- comparing -------------------------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class HashMismatch:
    """A run whose trace hash differs from the recorded one, and the time window of the divergence.

    ``since_time`` is when the runs were last known to agree and ``until_time`` when they certainly
    differed (seconds of sim time); either is None when the checkpoints cannot tell.
    ``checkpoint_step`` is the step of the first differing checkpoint, if one differs.
    """

    recorded: str
    actual: str
    since_time: float | None
    until_time: float | None
    checkpoint_step: int | None = None
    steps: int = 0
    recorded_steps: int = 0

    @property
    def message(self) -> str:
        text = (
            f"the trace hash {self.actual[:12]} differs from the recorded {self.recorded[:12]}: "
            "the planner's behaviour changed"
        )
        if self.since_time is not None and self.until_time is not None:
            return (
                f"{text} between t = {self.since_time:g} s and t = {self.until_time:g} s "
                f"(the first differing checkpoint is at step {self.checkpoint_step})"
            )
        if self.since_time is not None:
            text += f" after t = {self.since_time:g} s, where every checkpoint both runs share agrees"
        else:
            text += " (no checkpoint both runs have narrows it down)"
        if self.steps != self.recorded_steps:
            text += f"; the run took {self.steps} steps, the recorded one {self.recorded_steps}"
        return text


def compare_run(
    entry: LockEntry, trace_hash: str, steps: int, checkpoints: Sequence[tuple[int, str]], time_step: float
) -> HashMismatch | None:
    """None when the run's hash is the recorded one; otherwise when its behaviour changed, as closely as
    the shared checkpoints tell.

    Checkpoint ``k`` (step ``s = (k + 1) * CHECKPOINT_EVERY - 1``) covers sim time up to
    ``(s + 1) * time_step``. If it is the first to differ, the runs agreed up to the previous checkpoint
    and diverged by ``(s + 1) * time_step``.
    """
    if trace_hash == entry.hash:
        return None
    if not time_step > 0:
        msg = f"time_step={time_step!r} must be positive"
        raise ValueError(msg)
    actual = _prefixes(checkpoints)
    shared = min(len(actual), len(entry.checkpoints))
    mismatch = HashMismatch(entry.hash, trace_hash, None, None, steps=steps, recorded_steps=entry.steps)
    for index in range(shared):
        if actual[index] != entry.checkpoints[index]:
            step = (index + 1) * CHECKPOINT_EVERY - 1
            since, until = index * CHECKPOINT_EVERY * time_step, (step + 1) * time_step
            return replace(mismatch, since_time=since, until_time=until, checkpoint_step=step)
    return replace(mismatch, since_time=shared * CHECKPOINT_EVERY * time_step) if shared else mismatch

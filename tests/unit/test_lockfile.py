"""Lock files: canonical text, saving only on change, strict loading, and locating a hash mismatch."""

from __future__ import annotations

import difflib
import hashlib
import json
import os
from pathlib import Path
from typing import Any

import pytest

from fleetsim.errors import FleetsimError, LoadError
from fleetsim.gating.lockfile import (
    LOCK_FORMAT,
    HashLock,
    HashMismatch,
    LockEntry,
    LockFileError,
    compare_run,
    lock_path_for,
)
from fleetsim.sim.trace import CHECKPOINT_EVERY, TRACE_FORMAT

PLANNER = "fleetsim.planners:ReservingPlanner"
OTHER = "fleetsim.planners:BfsPlanner"


def digest(*parts: object) -> str:
    return hashlib.sha256(repr(parts).encode()).hexdigest()


def run_checkpoints(steps: int, tag: str = "a", diverge_at: int | None = None) -> list[tuple[int, str]]:
    """Checkpoints of a run of ``steps`` steps; from checkpoint index ``diverge_at`` on they differ."""
    count = steps // CHECKPOINT_EVERY
    return [
        ((k + 1) * CHECKPOINT_EVERY - 1, digest(tag if diverge_at is None or k < diverge_at else "b", k))
        for k in range(count)
    ]


def entry(steps: int = 220, tag: str = "a") -> LockEntry:
    return LockEntry.from_run(digest("run", tag, steps), steps, run_checkpoints(steps, tag))


def lock_at(tmp_path: Path, *items: tuple[str, str, LockEntry]) -> HashLock:
    lock = HashLock(tmp_path / "suite.fleetsim.lock.json")
    for planner, scenario, value in items:
        lock.set(planner, scenario, value)
    return lock


# --- paths and entries -----------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("suite", "lock"),
    [
        ("examples.fleetsim.yaml", "examples.fleetsim.lock.json"),
        ("dir/night.fleetsim.yml", "dir/night.fleetsim.lock.json"),
        ("odd.YAML", "odd.lock.json"),
        ("plain", "plain.lock.json"),
    ],
)
def test_lock_path_sits_beside_the_suite_with_yaml_suffix_replaced(suite: str, lock: str) -> None:
    assert lock_path_for(Path(suite)) == Path(lock)


def test_entry_from_run_keeps_16_digit_prefixes_in_step_order() -> None:
    checkpoints = run_checkpoints(350)
    made = LockEntry.from_run("f" * 64, 350, list(reversed(checkpoints)))
    assert made == LockEntry("f" * 64, 350, tuple(d[:16] for _, d in checkpoints))


def test_entry_from_run_rejects_checkpoints_at_unexpected_steps() -> None:
    with pytest.raises(ValueError, match=r"checkpoints\[1\] step=250 must be 199"):
        LockEntry.from_run("f" * 64, 300, [(99, "a" * 64), (250, "b" * 64)])


# --- canonical text and saving ---------------------------------------------------------------------


def test_saved_lock_loads_back_equal(tmp_path: Path) -> None:
    lock = lock_at(tmp_path, (PLANNER, "crossing", entry()), (OTHER, "loop", entry(40)), (PLANNER, "loop", entry(99)))
    assert lock.save()
    loaded = HashLock.load(lock.path)
    assert loaded.entries() == lock.entries()
    assert loaded.trace_format == TRACE_FORMAT
    assert loaded.get(PLANNER, "crossing") == entry()
    assert loaded.get(PLANNER, "missing") is None
    assert loaded.get("nobody", "crossing") is None


def test_text_is_sorted_whatever_the_insertion_order(tmp_path: Path) -> None:
    items = [(PLANNER, "zeta", entry(1)), (OTHER, "alpha", entry(2)), (PLANNER, "alpha", entry(3))]
    forward, backward = lock_at(tmp_path, *items), lock_at(tmp_path, *reversed(items))
    assert forward.dumps() == backward.dumps()
    text = forward.dumps()
    assert text.index(OTHER) < text.index(PLANNER)
    assert text.index('"alpha"', text.index(PLANNER)) < text.index('"zeta"')
    assert [(p, s) for p, s, _ in forward.entries()] == [(OTHER, "alpha"), (PLANNER, "alpha"), (PLANNER, "zeta")]


def test_text_has_fixed_header_and_one_line_per_scenario(tmp_path: Path) -> None:
    recorded = entry(220)
    text = lock_at(tmp_path, (PLANNER, "crossing", recorded)).dumps()
    first, second = recorded.checkpoints
    assert text == (
        "{\n"
        f'  "format": "{LOCK_FORMAT}",\n'
        f'  "trace_format": "{TRACE_FORMAT}",\n'
        f'  "checkpoint_every": {CHECKPOINT_EVERY},\n'
        '  "hashes": {\n'
        f'    "{PLANNER}": {{\n'
        f'      "crossing": {{"hash": "{recorded.hash}", "steps": 220, "checkpoints": ["{first}", "{second}"]}}\n'
        "    }\n"
        "  }\n"
        "}\n"
    )


def test_changing_one_scenario_changes_one_line(tmp_path: Path) -> None:
    lock = lock_at(tmp_path, (PLANNER, "a", entry(1)), (PLANNER, "b", entry(2)), (PLANNER, "c", entry(3)))
    before = lock.dumps().splitlines()
    lock.set(PLANNER, "b", entry(500))
    changed = [line for line in difflib.ndiff(before, lock.dumps().splitlines()) if line[:1] in "+-"]
    assert len(changed) == 2
    assert changed[0].startswith('-       "b": ') and changed[1].startswith('+       "b": ')


def test_names_needing_escapes_stay_valid_json(tmp_path: Path) -> None:
    name = 'quote " backslash \\ newline \n é'
    lock = lock_at(tmp_path, (name, name, entry()))
    assert json.loads(lock.dumps())["hashes"][name][name]["steps"] == 220
    lock.save()
    assert HashLock.load(lock.path).get(name, name) == entry()


def test_empty_lock_text_is_valid_json(tmp_path: Path) -> None:
    assert json.loads(HashLock(tmp_path / "x.lock.json").dumps())["hashes"] == {}


def test_save_of_unchanged_lock_writes_nothing(tmp_path: Path) -> None:
    lock = lock_at(tmp_path, (PLANNER, "crossing", entry()))
    assert lock.save() is True
    os.utime(lock.path, ns=(1_000_000_000, 1_000_000_000))
    reloaded = HashLock.load(lock.path)
    reloaded.set(PLANNER, "crossing", entry())
    assert reloaded.save() is False
    assert lock.path.stat().st_mtime_ns == 1_000_000_000
    reloaded.set(PLANNER, "crossing", entry(300))
    assert reloaded.save() is True
    assert lock.path.stat().st_mtime_ns != 1_000_000_000
    assert HashLock.load(lock.path).get(PLANNER, "crossing") == entry(300)


def test_save_rewrites_a_file_that_is_not_canonical(tmp_path: Path) -> None:
    lock = lock_at(tmp_path, (PLANNER, "crossing", entry()))
    lock.path.write_text(json.dumps(json.loads(lock.dumps())), encoding="utf-8")  # same data, one line
    assert HashLock.load(lock.path).save() is True
    assert lock.path.read_text(encoding="utf-8") == lock.dumps()


def test_save_leaves_no_temporary_file(tmp_path: Path) -> None:
    lock = lock_at(tmp_path, (PLANNER, "crossing", entry()))
    lock.save()
    lock.set(PLANNER, "loop", entry(40))
    lock.save()
    assert [p.name for p in tmp_path.iterdir()] == [lock.path.name]


def test_failed_save_keeps_the_old_file_whole(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    lock = lock_at(tmp_path, (PLANNER, "crossing", entry()))
    lock.save()
    old = lock.path.read_text(encoding="utf-8")

    def fail(*args: object) -> None:
        raise OSError("disk full")

    monkeypatch.setattr(os, "replace", fail)
    lock.set(PLANNER, "loop", entry(40))
    with pytest.raises(OSError, match="disk full"):
        lock.save()
    assert lock.path.read_text(encoding="utf-8") == old
    assert [p.name for p in tmp_path.iterdir()] == [lock.path.name]


def test_save_creates_the_folder(tmp_path: Path) -> None:
    lock = HashLock(tmp_path / "new" / "suite.fleetsim.lock.json")
    lock.set(PLANNER, "crossing", entry())
    assert lock.save() is True
    assert lock.path.is_file()


def test_empty_lock_removes_its_file(tmp_path: Path) -> None:
    lock = lock_at(tmp_path, (PLANNER, "crossing", entry()))
    lock.save()
    lock.prune([])
    assert lock.save() is True
    assert not lock.path.exists()
    assert lock.save() is False
    assert not lock.path.exists()


def test_missing_file_loads_as_empty_lock(tmp_path: Path) -> None:
    lock = HashLock.load(tmp_path / "none.lock.json")
    assert lock.entries() == []
    assert lock.trace_format == TRACE_FORMAT
    assert lock.save() is False
    assert not lock.path.exists()


# --- pruning ---------------------------------------------------------------------------------------


def test_stale_lists_and_prune_removes_entries_of_vanished_scenarios(tmp_path: Path) -> None:
    lock = lock_at(
        tmp_path,
        (PLANNER, "kept", entry(1)),
        (PLANNER, "renamed", entry(2)),
        (OTHER, "renamed", entry(3)),
        (OTHER, "gone", entry(4)),
    )
    assert lock.scenario_names() == ["gone", "kept", "renamed"]
    expected = [(OTHER, "gone"), (OTHER, "renamed"), (PLANNER, "renamed")]
    assert lock.stale(["kept"]) == expected
    assert len(lock.entries()) == 4  # stale() only looks
    assert lock.prune(name for name in ["kept"]) == expected
    assert lock.entries() == [(PLANNER, "kept", entry(1))]
    assert OTHER not in lock.dumps()  # no empty planner section left behind
    assert lock.prune(["kept"]) == []


# --- trace and checkpoint formats ------------------------------------------------------------------


def write_document(path: Path, document: Any) -> Path:
    path.write_text(json.dumps(document, indent=2), encoding="utf-8")
    return path


def document(**top: Any) -> dict[str, Any]:
    recorded = entry(220)
    body = {"hash": recorded.hash, "steps": 220, "checkpoints": list(recorded.checkpoints)}
    base = {
        "format": LOCK_FORMAT,
        "trace_format": TRACE_FORMAT,
        "checkpoint_every": CHECKPOINT_EVERY,
        "hashes": {"X": {"crossing": body}},
    }
    return {**base, **top}


def test_lock_of_another_trace_format_loads_and_is_replaced_on_set(tmp_path: Path) -> None:
    path = write_document(tmp_path / "s.lock.json", document(trace_format="fleetsim-trace/0"))
    lock = HashLock.load(path)
    assert lock.trace_format == "fleetsim-trace/0"
    assert lock.get("X", "crossing") == entry(220)
    lock.set(PLANNER, "loop", entry(40))
    assert lock.trace_format == TRACE_FORMAT
    assert lock.entries() == [(PLANNER, "loop", entry(40))]


def test_checkpoints_of_another_interval_are_dropped_but_the_hash_kept(tmp_path: Path) -> None:
    doc = document(checkpoint_every=50)
    doc["hashes"]["X"]["crossing"]["checkpoints"] = ["0123456789abcdef"] * 4
    lock = HashLock.load(write_document(tmp_path / "s.lock.json", doc))
    assert lock.get("X", "crossing") == LockEntry(entry(220).hash, 220, ())
    lock.save()
    assert HashLock.load(lock.path).get("X", "crossing") == LockEntry(entry(220).hash, 220, ())


# --- loading errors --------------------------------------------------------------------------------


def with_entry(key: str, value: Any) -> dict[str, Any]:
    doc = document()
    doc["hashes"]["X"]["crossing"][key] = value
    return doc


BAD_DOCUMENTS = {
    "not an object": ([1, 2], "the lock file = [1, 2] must be a JSON object"),
    "format": (document(format="fleetsim-lock/2"), "format = 'fleetsim-lock/2' must be 'fleetsim-lock/1'"),
    "unknown key": (document(extra=1), "the lock file has an unknown key 'extra'"),
    "missing key": ({"format": LOCK_FORMAT}, "the lock file lacks the key 'trace_format'"),
    "trace format": (document(trace_format=7), "trace_format = 7 must be a non-empty string"),
    "interval text": (document(checkpoint_every="100"), "checkpoint_every = '100' must be a positive integer"),
    "interval zero": (document(checkpoint_every=0), "checkpoint_every = 0 must be a positive integer"),
    "hashes": (document(hashes=[]), "hashes = [] must be a JSON object"),
    "section": (document(hashes={"X": "abc"}), "hashes['X'] = 'abc' must be a JSON object"),
    "entry": (document(hashes={"X": {"crossing": 3}}), "hashes['X']['crossing'] = 3 must be a JSON object"),
    "entry key": (with_entry("seed", 1), "hashes['X']['crossing'] has an unknown key 'seed'"),
    "steps text": (with_entry("steps", "abc"), "hashes['X']['crossing']['steps'] = 'abc' must be a non-negative"),
    "steps bool": (with_entry("steps", True), "hashes['X']['crossing']['steps'] = True must be a non-negative"),
    "steps negative": (with_entry("steps", -1), "hashes['X']['crossing']['steps'] = -1 must be a non-negative"),
    "hash upper": (with_entry("hash", "A" * 64), f"hashes['X']['crossing']['hash'] = '{'A' * 64}' must be 64"),
    "hash short": (with_entry("hash", "abc"), "hashes['X']['crossing']['hash'] = 'abc' must be 64 lowercase"),
    "checkpoints": (with_entry("checkpoints", "ab"), "hashes['X']['crossing']['checkpoints'] = 'ab' must be a list"),
    "checkpoint hex": (
        with_entry("checkpoints", ["0123456789abcdef", "0123456789abcdeg"]),
        "hashes['X']['crossing']['checkpoints'][1] = '0123456789abcdeg' must be 16 lowercase hexadecimal",
    ),
    "checkpoint count": (
        with_entry("checkpoints", ["0123456789abcdef"] * 3),
        "hashes['X']['crossing']['checkpoints'] has 3 digests; a run of 220 steps must have 2",
    ),
}


@pytest.mark.parametrize("case", sorted(BAD_DOCUMENTS))
def test_bad_document_is_rejected_naming_file_and_value(tmp_path: Path, case: str) -> None:
    bad, expected = BAD_DOCUMENTS[case]
    path = write_document(tmp_path / "s.lock.json", bad)
    with pytest.raises(LockFileError) as caught:
        HashLock.load(path)
    assert str(caught.value).startswith(f"{path}: {expected}")
    assert isinstance(caught.value, ValueError) and isinstance(caught.value, FleetsimError)
    assert isinstance(caught.value, LoadError)


def test_malformed_json_is_reported_with_line_and_column(tmp_path: Path) -> None:
    path = tmp_path / "s.lock.json"
    path.write_text('{\n  "format": "fleetsim-lock/1",\n  "hashes": {,\n}\n', encoding="utf-8")
    with pytest.raises(
        LockFileError, match=r"the file is not valid JSON: a key in double quotes is expected here"
    ) as caught:
        HashLock.load(path)
    assert str(caught.value).startswith(f"{path}:3:14: ")


def test_text_that_is_not_utf8_is_rejected(tmp_path: Path) -> None:
    path = tmp_path / "s.lock.json"
    path.write_bytes(b'{"format": "\xff"}')
    with pytest.raises(LockFileError, match="not UTF-8"):
        HashLock.load(path)


def test_long_bad_value_is_shortened(tmp_path: Path) -> None:
    path = write_document(tmp_path / "s.lock.json", document(hashes=list(range(100))))
    with pytest.raises(LockFileError) as caught:
        HashLock.load(path)
    assert "hashes = [0, 1, 2" in str(caught.value) and " ... must be a JSON object" in str(caught.value)
    assert "99" not in str(caught.value).removeprefix(str(path))  # (the temporary path may hold a 99)


# --- comparing runs --------------------------------------------------------------------------------


def recorded(steps: int = 450) -> LockEntry:
    return LockEntry.from_run("a" * 64, steps, run_checkpoints(steps))


def test_equal_hash_is_no_mismatch() -> None:
    assert compare_run(recorded(), "a" * 64, 450, run_checkpoints(450, diverge_at=0), 0.1) is None


def test_first_checkpoint_differing_places_the_change_in_the_first_window() -> None:
    mismatch = compare_run(recorded(), "b" * 64, 450, run_checkpoints(450, diverge_at=0), 0.1)
    assert isinstance(mismatch, HashMismatch)
    assert mismatch.since_time == 0.0 and mismatch.until_time == pytest.approx(10.0)
    assert mismatch.checkpoint_step == 99
    assert mismatch.message == (
        "the trace hash bbbbbbbbbbbb differs from the recorded aaaaaaaaaaaa: the planner's behaviour changed "
        "between t = 0 s and t = 10 s (the first differing checkpoint is at step 99)"
    )


def test_later_checkpoint_differing_places_the_change_after_the_previous_one() -> None:
    mismatch = compare_run(recorded(), "b" * 64, 470, run_checkpoints(470, diverge_at=2), 0.05)
    assert mismatch is not None
    assert mismatch.checkpoint_step == 299
    assert mismatch.since_time == pytest.approx(10.0) and mismatch.until_time == pytest.approx(15.0)
    assert "between t = 10 s and t = 15 s (the first differing checkpoint is at step 299)" in mismatch.message
    assert "took" not in mismatch.message  # the window says enough; the lengths are not mentioned


def test_all_shared_checkpoints_equal_places_the_change_after_the_last_and_names_the_lengths() -> None:
    mismatch = compare_run(recorded(450), "b" * 64, 230, run_checkpoints(230), 0.1)
    assert mismatch is not None
    assert mismatch.until_time is None and mismatch.checkpoint_step is None
    assert mismatch.since_time == pytest.approx(20.0)
    assert mismatch.message.endswith(
        "changed after t = 20 s, where every checkpoint both runs share agrees; "
        "the run took 230 steps, the recorded one 450"
    )


def test_same_length_with_equal_checkpoints_does_not_mention_lengths() -> None:
    mismatch = compare_run(recorded(450), "b" * 64, 450, run_checkpoints(450), 0.1)
    assert mismatch is not None
    assert mismatch.message.endswith("changed after t = 40 s, where every checkpoint both runs share agrees")


def test_runs_without_checkpoints_give_no_window() -> None:
    mismatch = compare_run(recorded(60), "b" * 64, 80, [], 0.1)
    assert mismatch is not None
    assert (mismatch.since_time, mismatch.until_time, mismatch.checkpoint_step) == (None, None, None)
    assert mismatch.message.endswith(
        "changed (no checkpoint both runs have narrows it down); the run took 80 steps, the recorded one 60"
    )


def test_compare_rejects_a_non_positive_time_step() -> None:
    with pytest.raises(ValueError, match=r"time_step=0 must be positive"):
        compare_run(recorded(), "b" * 64, 450, [], 0)

"""A League of Robot Runners problem file (JSON) read into a :class:`LorrProblem`, with located errors.

The keys, by edition (paths relative to the problem file):

- every edition: ``mapFile`` (a MovingAI-style ``.map``), ``agentFile`` (early 2023 files: ``robotFile``),
  ``taskFile``, ``teamSize`` (robots: the first ``teamSize`` agents of the agent file) and
  ``numTasksReveal`` (optional, default 1: a whole number in 2023, a multiplier from 2024 on; the pool of
  revealed tasks holds ``numTasksReveal × teamSize`` of them);
- ``version``: absent in 2023 files; ``"2024 LoRR"`` or ``"2026 LoRR"`` after (``"2023 LoRR"`` is taken too);
- 2023: ``taskAssignmentStrategy`` (``greedy``, ``roundrobin``, ``roundrobin_fixed``);
- 2026: ``agentSize`` (a robot's side in cells), ``agentCounter`` and ``delayConfig`` (random delays,
  :mod:`.delays`).

Every problem is a :class:`~fleetsim.errors.ScenarioFileError` at the file, with the line and column of the
key when the file has it where a person would look, and the JSON pointer (``/teamSize``): a file that is
not JSON (line and column of the fault), a key missing or unknown, a value of the wrong type or range, a
version the reader does not know, a referenced file that does not exist. All are reported at once.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

from fleetsim.errors import Location, ScenarioFileError
from fleetsim.load.common.closest import did_you_mean
from fleetsim.load.common.collect import ErrorCollector
from fleetsim.load.common.text import json_problem, read_text_file
from fleetsim.load.lorr.delays import DelayConfig, parse_delays
from fleetsim.load.lorr.places import KeyPlaces

__all__ = ["EDITIONS", "PROBLEM_KEYS", "LorrProblem", "read_problem"]

EDITIONS = {"2023 lorr": "2023", "2024 lorr": "2024", "2026 lorr": "2026"}
PROBLEM_KEYS = (
    "mapFile",
    "agentFile",
    "robotFile",
    "taskFile",
    "teamSize",
    "numTasksReveal",
    "version",
    "taskAssignmentStrategy",
    "agentSize",
    "agentCounter",
    "delayConfig",
)
STRATEGIES = ("greedy", "roundrobin", "roundrobin_fixed")


@dataclass(frozen=True, slots=True)
class LorrProblem:
    """A League of Robot Runners problem, its values checked (not yet its files' contents).

    Attributes:
        path: The problem file.
        edition: ``"2023"``, ``"2024"`` or ``"2026"`` (from ``version``; none is 2023).
        map_path, agent_path, task_path: The files it names, resolved against its folder (each exists).
        team_size: ``teamSize``: how many robots.
        reveal: ``numTasksReveal`` (default 1).
        strategy: 2023's ``taskAssignmentStrategy``, or ``None``.
        agent_size: 2026's ``agentSize`` (cells), or ``None``.
        agent_counter: 2026's ``agentCounter``, or ``None``.
        delays: 2026's ``delayConfig``, or ``None``.
        places: Where each key is written (for errors found later: a team larger than the agent file).
    """

    path: Path
    edition: str
    map_path: Path
    agent_path: Path
    task_path: Path
    team_size: int
    reveal: float
    strategy: str | None
    agent_size: float | None
    agent_counter: int | None
    delays: DelayConfig | None
    places: KeyPlaces


def read_problem(path: Path) -> LorrProblem:
    """Read and check the problem file at ``path`` (see the module docstring)."""
    text = read_text_file(path, ScenarioFileError)
    try:
        raw = json.loads(text)
    except json.JSONDecodeError as exc:
        raise ScenarioFileError(json_problem(exc), Location(path, line=exc.lineno, column=exc.colno)) from None
    if not isinstance(raw, dict):
        msg = f"a League of Robot Runners problem is a JSON object (mapFile, agentFile, taskFile, teamSize, ...), not {_kind(raw)}"
        raise ScenarioFileError(msg, Location(path, line=1, column=1, field="/"))
    places = KeyPlaces(path, text)
    errors = ErrorCollector()
    for key in raw:
        if key not in PROBLEM_KEYS:
            known = ", ".join(k for k in PROBLEM_KEYS if k != "robotFile")
            msg = f"unknown key {key!r}{did_you_mean(key, PROBLEM_KEYS)} (a problem's keys: {known})"
            errors.add(ScenarioFileError(msg, places.at(key)))
    edition: str | None = None  # a version the reader does not know: no edition's rules apply
    with errors.collecting():
        edition = _edition(raw, places)
    files: dict[str, Path] = {}
    for key in ("mapFile", "agentFile", "taskFile"):
        with errors.collecting():
            files[key] = _file(raw, key, path, places)
    team = reveal = None
    with errors.collecting():
        team = _whole(raw, "teamSize", places, minimum=1, required=True)
    with errors.collecting():
        reveal = _reveal(raw, edition, places)
    strategy = agent_size = counter = delays = None
    with errors.collecting():
        strategy = _strategy(raw, places)
    with errors.collecting():
        agent_size = _positive(raw, "agentSize", places)
    with errors.collecting():
        counter = _whole(raw, "agentCounter", places, minimum=0)
    if "delayConfig" in raw:
        with errors.collecting():
            delays = parse_delays(raw["delayConfig"], places)
    errors.raise_if_any()
    assert team is not None and reveal is not None and edition is not None
    return LorrProblem(
        path, edition, files["mapFile"], files["agentFile"], files["taskFile"], team, reveal, strategy,
        agent_size, counter, delays, places,
    )  # fmt: skip


def _kind(value: object) -> str:
    names = {bool: "a boolean", int: "a number", float: "a number", str: "a string", list: "a list", dict: "an object"}
    return "null" if value is None else names.get(type(value), type(value).__name__)


def _shown(value: object) -> str:
    text = json.dumps(value)
    return text if len(text) <= 40 else text[:37] + "..."


def _edition(raw: dict[str, object], places: KeyPlaces) -> str:
    if "version" not in raw:
        return "2023"
    value = raw["version"]
    if isinstance(value, str) and " ".join(value.split()).lower() in EDITIONS:
        return EDITIONS[" ".join(value.split()).lower()]
    msg = (
        f"version {_shown(value)} is not a League of Robot Runners edition fleetsim reads: "
        "'2024 LoRR' or '2026 LoRR' (a 2023 problem has no version)"
    )
    raise ScenarioFileError(msg, places.at("version"))


def _file(raw: dict[str, object], key: str, path: Path, places: KeyPlaces) -> Path:
    name = key
    if key == "agentFile" and key not in raw and "robotFile" in raw:
        name = "robotFile"  # early 2023 problems
    if name not in raw:
        also = " (or robotFile)" if key == "agentFile" else ""
        raise ScenarioFileError(f"required key {key!r}{also} is missing", Location(path, field="/"))
    value = raw[name]
    if not isinstance(value, str) or not value.strip():
        raise ScenarioFileError(f"{name}={_shown(value)} must be a file name (a string)", places.at(name))
    target = path.parent / value.replace("\\", "/")
    if not target.is_file():
        msg = f"{name}: no such file {value!r} (looked for {str(target)!r}, relative to the problem file)"
        raise ScenarioFileError(msg, places.at(name))
    return target


def _whole(raw: dict[str, object], key: str, places: KeyPlaces, *, minimum: int, required: bool = False) -> int | None:
    if key not in raw:
        if required:
            raise ScenarioFileError(f"required key {key!r} is missing", Location(places.path, field="/"))
        return None
    value = raw[key]
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not float(value).is_integer():
        raise ScenarioFileError(f"{key}={_shown(value)} must be a whole number", places.at(key))
    if value < minimum:
        raise ScenarioFileError(f"{key}={_shown(value)} must be >= {minimum}", places.at(key))
    return int(value)


def _positive(raw: dict[str, object], key: str, places: KeyPlaces) -> float | None:
    if key not in raw:
        return None
    value = raw[key]
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) or value <= 0:
        raise ScenarioFileError(f"{key}={_shown(value)} must be a number > 0", places.at(key))
    return float(value)


def _reveal(raw: dict[str, object], edition: str | None, places: KeyPlaces) -> float:
    if "numTasksReveal" not in raw:
        return 1.0
    if edition == "2023":
        whole = _whole(raw, "numTasksReveal", places, minimum=1)
        assert whole is not None
        return float(whole)
    reveal = _positive(raw, "numTasksReveal", places)
    assert reveal is not None
    return reveal


def _strategy(raw: dict[str, object], places: KeyPlaces) -> str | None:
    if "taskAssignmentStrategy" not in raw:
        return None
    value = raw["taskAssignmentStrategy"]
    word = value.strip().lower().replace("-", "_") if isinstance(value, str) else None
    if word not in STRATEGIES:
        msg = f"taskAssignmentStrategy={_shown(value)} must be one of {', '.join(STRATEGIES)}"
        raise ScenarioFileError(msg, places.at("taskAssignmentStrategy"))
    return word

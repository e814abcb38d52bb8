"""Independent judges of VDA 5050 documents for the tests: validators fleetsim did not write.

- 2.1: the official JSON Schemas (draft 2020-12) as the PyPI package vda5050-sdk 0.2.0 bundles them,
  checked with jsonschema, formats included (:func:`validate_21`).
- 2.0: vda-5050-lib 1.4.0's validators (npm, in ``tests/vda5050/node/node_modules``), compiled from the
  2.0 schemas, run by ``node/validate.js``: one long-lived node process per test session, so thousands
  of documents take a second (:func:`validate_20`). It is skipped when node or the package is missing,
  and fails instead under FLEETSIM_REQUIRE_TOOLS=1.

The official schemas disagree with the text in places. Each disagreement fleetsim follows the text on is
in :data:`KNOWN_DEFECTS` with its reason; :func:`validate_21` forgives exactly those findings (and
:func:`validate_20` adapts the document around vda-5050-lib's), and a test
shows each still exists (so an entry goes stale loudly, when a fixed schema ships).

What was found in vda-5050-lib 1.4.0's compiled 2.0 validators (``vda-5050-validators-2.0.js``) and in
the official 2.0.0-era schema files of the VDA5050 repository:

- the official ``instantActions.schema`` requires ``actionName`` where the text and ``order.schema`` say
  ``actionType`` (and lists no top-level required keys at all). vda-5050-lib's validator does not repeat
  that: an instant action needs ``actionType``; one with only ``actionName`` is rejected.
- vda-5050-lib's validator (and its types, and so its master controller) wants the instant actions under
  the key ``instantActions``; the text's key is ``actions``. A document that follows the text fails it with
  ``#/instantActions: #/allOf/1/required``. :data:`KNOWN_DEFECTS` holds the adaptation (the key renamed
  before the document is shown to it).
- vda-5050-lib lists PAUSED among the ``actionStatus`` values, which the 2.1 schema lacks.
- vda-5050-lib spells the node position's ``allowedDeviationXY`` as ``allowedDeviationXy`` (validators and
  types); its validator ignores the text's spelling as an unknown key. fleetsim writes the text's and
  names vda-5050-lib's as a validationError (it would otherwise be dropped silently).
- 2.0 (vda-5050-lib) types ``batteryHealth`` as an integer, as the text's table does (int8); the 2.1 schema
  takes any number. fleetsim's model holds an int.

In the 2.1 schemas (vda5050-sdk 0.2.0): ``actionStatus`` lacks PAUSED, and the factsheet's
``blockingTypes`` carries its enum on the array instead of its items (no array can pass); both are in
:data:`KNOWN_DEFECTS`. The 2.1 ``state`` schema does not require ``maps``; fleetsim writes it in 2.1
always (empty when no map is known), which both readings of the text allow.

The compiled validators stop at their first finding, so a 2.0 defect is adapted around, not forgiven.
"""

from __future__ import annotations

import atexit
import json
import re
import shutil
import subprocess
import threading
from collections.abc import Callable
from dataclasses import dataclass
from functools import cache
from importlib import resources
from pathlib import Path
from typing import Any

import jsonschema
from tooling import missing

__all__ = ["KNOWN_DEFECTS", "NODE_DIR", "KnownDefect", "node_validator", "validate", "validate_20", "validate_21"]

NODE_DIR = Path(__file__).resolve().parent / "node"
_VALIDATORS_20 = NODE_DIR / "node_modules" / "vda-5050-lib" / "common" / "vda-5050-validators-2.0.js"
_TOPICS = ("order", "instantActions", "state", "visualization", "connection", "factsheet")


@dataclass(frozen=True)
class KnownDefect:
    """An official schema's finding fleetsim overrules, with why: ``path`` (a regular expression over the
    finding's JSON pointer, e.g. ``actionStates/0/actionStatus``) and ``keyword`` (``enum``...) in ``topic``."""

    name: str
    version: str
    topic: str
    path: str
    keyword: str
    reason: str
    instance: Callable[[Any], bool] = lambda _value: True
    adapt: Callable[[Any], Any] | None = None  # 2.0: the document as the defective validator wants it

    def forgives(self, topic: str, error: jsonschema.ValidationError) -> bool:
        pointer = "/".join(str(part) for part in error.absolute_path)
        return (
            topic == self.topic
            and error.validator == self.keyword
            and re.fullmatch(self.path, pointer) is not None
            and self.instance(error.instance)
        )


def _actions_as_instant_actions(document: Any) -> Any:
    if not isinstance(document, dict) or "actions" not in document or "instantActions" in document:
        return document
    return {("instantActions" if key == "actions" else key): value for key, value in document.items()}


KNOWN_DEFECTS = (
    KnownDefect(
        name="vda-5050-lib-instantActions-key",
        version="2.0",
        topic="instantActions",
        path="instantActions",
        keyword="required",
        adapt=_actions_as_instant_actions,
        reason="vda-5050-lib 1.4.0's 2.0 validator requires the key 'instantActions' for the array of "
        "actions; the text (6.7) names it 'actions', as does the 2.1 schema.",
    ),
    KnownDefect(
        name="state-actionStatus-PAUSED",
        version="2.1",
        topic="state",
        path=r"actionStates/\d+/actionStatus",
        keyword="enum",
        instance=lambda value: value == "PAUSED",
        reason="The text's actionStatus table (6.10.5) and the startPause/stopPause actions use PAUSED; the "
        "2.1 state schema's enum lists WAITING, INITIALIZING, RUNNING, FINISHED and FAILED only.",
    ),
    KnownDefect(
        name="factsheet-blockingTypes-enum-on-array",
        version="2.1",
        topic="factsheet",
        path=r"protocolFeatures/agvActions/\d+/blockingTypes",
        keyword="enum",
        reason="The 2.1 factsheet schema puts the enum NONE/SOFT/HARD on the array blockingTypes itself, not "
        "on its items, so no array (the text: an array of the blocking types the action supports) can pass.",
    ),
)


@cache
def _schema_validator_21(topic: str) -> jsonschema.protocols.Validator:
    if topic not in _TOPICS:
        msg = f"topic={topic!r} must be one of {_TOPICS}"
        raise ValueError(msg)
    path = resources.files("vda5050") / "validation" / "schemas" / f"{topic}.json"
    schema = json.loads(path.read_text(encoding="utf-8"))
    cls = jsonschema.validators.validator_for(schema)
    cls.check_schema(schema)
    return cls(schema, format_checker=cls.FORMAT_CHECKER)


def validate_21(topic: str, document: Any, *, forgive_known_defects: bool = True) -> list[str]:
    """The 2.1 schema's findings on ``document`` (empty when valid), each ``pointer: message``; those in
    :data:`KNOWN_DEFECTS` are left out unless ``forgive_known_defects`` is False."""
    defects = [d for d in KNOWN_DEFECTS if d.version == "2.1" and d.adapt is None] if forgive_known_defects else []
    return [
        f"{'/'.join(str(part) for part in error.absolute_path) or '(document)'}: {error.message}"
        for error in _schema_validator_21(topic).iter_errors(document)
        if not any(defect.forgives(topic, error) for defect in defects)
    ]


class NodeValidator:
    """``node validate.js``, started once: one request line, one answer line, under a lock."""

    def __init__(self, node: str) -> None:
        self._lock = threading.Lock()
        self._process = subprocess.Popen(
            [node, str(NODE_DIR / "validate.js")],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            encoding="utf-8",
        )
        atexit.register(self.close)

    def validate(self, topic: str, document: Any) -> list[str]:
        with self._lock:
            assert self._process.stdin is not None and self._process.stdout is not None
            self._process.stdin.write(json.dumps({"topic": topic, "document": document}) + "\n")
            self._process.stdin.flush()
            line = self._process.stdout.readline()
        if not line:
            stderr = self._process.stderr.read() if self._process.stderr else ""
            msg = f"validate.js ended without answering (exit {self._process.poll()}): {stderr[-2000:]}"
            raise RuntimeError(msg)
        answer = json.loads(line)
        if "fatal" in answer:
            raise ValueError(answer["fatal"])
        return list(answer["errors"])

    def close(self) -> None:
        if self._process.poll() is None:
            assert self._process.stdin is not None
            self._process.stdin.close()
            try:
                self._process.wait(timeout=5)
            except subprocess.TimeoutExpired:
                self._process.kill()
                self._process.wait()


_node_validator: NodeValidator | None = None


def node_validator() -> NodeValidator:
    """The session's 2.0 validator process (started on first use); skips or fails when it cannot run."""
    global _node_validator
    if _node_validator is None:
        node = shutil.which("node")
        if node is None:
            missing("Node.js 'node' is not on PATH (Debian/Ubuntu: apt install nodejs)")
        if not _VALIDATORS_20.is_file():
            missing(f"vda-5050-lib is not installed in {NODE_DIR} (npm ci --prefix tests/vda5050/node)")
        assert node is not None
        _node_validator = NodeValidator(node)
    return _node_validator


def validate_20(topic: str, document: Any, *, adapt_known_defects: bool = True) -> list[str]:
    """vda-5050-lib's 2.0 findings on ``document`` (empty when valid; the first finding only), shown the
    document as the :data:`KNOWN_DEFECTS` of 2.0 adapt it unless ``adapt_known_defects`` is False."""
    for defect in KNOWN_DEFECTS:
        if adapt_known_defects and defect.version == "2.0" and defect.topic == topic and defect.adapt is not None:
            document = defect.adapt(document)
    return node_validator().validate(topic, document)


def validate(version: str, topic: str, document: Any) -> list[str]:
    """The independent findings on ``document`` for ``version`` ("2.0" or "2.1")."""
    if version == "2.0":
        return validate_20(topic, document)
    if version == "2.1":
        return validate_21(topic, document)
    msg = f"version={version!r} must be '2.0' or '2.1'"
    raise ValueError(msg)

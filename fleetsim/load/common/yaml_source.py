"""Safe YAML loading that remembers where every value came from.

Suite errors must point at ``file:line:column`` of the offending value, so the loader keeps the node
marks that PyYAML normally throws away. Only :class:`yaml.SafeLoader` is used: a suite file can never
construct arbitrary Python objects.
"""

from __future__ import annotations

from collections.abc import Hashable
from pathlib import Path
from typing import Any, Protocol

import yaml

from fleetsim.errors import LoadError, Location, SuiteError
from fleetsim.load.common.text import read_text_file

__all__ = ["Locate", "YamlPath", "load_yaml_with_marks"]

YamlPath = tuple[Hashable, ...]
_Pairs = dict[int, dict[Hashable, tuple[yaml.Node, yaml.Node]]]  # id(mapping node) → key → (key, value)
_MERGE_TAG = "tag:yaml.org,2002:merge"


class Locate(Protocol):
    """Where a value (or, with ``key=True``, its key) was written; see :func:`load_yaml_with_marks`."""

    def __call__(self, path: YamlPath, *, key: bool = False) -> Location: ...


class _MarkedLoader(yaml.SafeLoader):
    """A safe loader that rejects duplicate keys and records each mapping's key → (key node, value node)."""

    def __init__(self, stream: str, error_type: type[LoadError], path: Path) -> None:
        super().__init__(stream)
        self.error_type = error_type
        self.path = path
        self.pairs: _Pairs = {}

    def construct_mapping(self, node: yaml.MappingNode, deep: bool = False) -> dict[Hashable, Any]:
        # Check before flattening: keys brought in by a `<<` merge may legitimately be overridden.
        self._reject_duplicate_keys(node)
        mapping = super().construct_mapping(node, deep=deep)
        pairs: dict[Hashable, tuple[yaml.Node, yaml.Node]] = {}
        for key_node, value_node in node.value:  # flattened: later pairs win, as in the mapping
            pairs[self.construct_object(key_node, deep=True)] = (key_node, value_node)
        self.pairs[id(node)] = pairs
        return mapping

    def _reject_duplicate_keys(self, node: yaml.MappingNode) -> None:
        seen: dict[Hashable, yaml.Node] = {}
        for key_node, _ in node.value:
            if key_node.tag == _MERGE_TAG:
                continue
            key = self.construct_object(key_node, deep=True)
            if not isinstance(key, Hashable):
                continue  # the base constructor reports unhashable keys with their mark
            if key in seen:
                first = seen[key].start_mark.line + 1
                msg = f"duplicate key {key!r} (first given on line {first})"
                raise self.error_type(msg, _location(self.path, key_node.start_mark))
            seen[key] = key_node


def _location(path: Path, mark: yaml.Mark | None) -> Location:
    if mark is None:
        return Location(path)
    return Location(path, line=mark.line + 1, column=mark.column + 1)


def _syntax_error(exc: yaml.YAMLError, text: str, path: Path, error_type: type[LoadError]) -> LoadError:
    """Turn a PyYAML error into a located error that keeps the parser's own words."""
    if isinstance(exc, yaml.MarkedYAMLError):
        problem = exc.problem or "invalid YAML"
        if exc.context:  # PyYAML's own order: "while parsing X at line L, column C: <problem>"
            where = ""
            if exc.context_mark is not None and exc.context_mark is not exc.problem_mark:
                where = f" at line {exc.context_mark.line + 1}, column {exc.context_mark.column + 1}"
            problem = f"{exc.context}{where}: {problem}"
        return error_type(f"invalid YAML: {problem}", _location(path, exc.problem_mark or exc.context_mark))
    if isinstance(exc, yaml.reader.ReaderError):
        line = text.count("\n", 0, exc.position) + 1
        column = exc.position - text.rfind("\n", 0, exc.position)
        code = exc.character if isinstance(exc.character, int) else ord(exc.character)
        return error_type(f"invalid YAML: {exc.reason}: #x{code:04x}", Location(path, line, column))
    return error_type(f"invalid YAML: {exc}", Location(path))


def load_yaml_with_marks(path: Path | str, *, error_type: type[LoadError] = SuiteError) -> tuple[Any, Locate]:
    """Load one YAML document safely; return the data and ``locate(path, *, key=False) -> Location``.

    ``locate(("scenarios", 2, "expect", "tasks"))`` gives the line and column of that value;
    ``key=True`` gives the position of the last key instead (where an unknown key is written). A path
    that leads nowhere stops at the deepest node that exists, so a missing key points at its parent.
    """
    path = Path(path)
    text = read_text_file(path, error_type)
    try:
        loader = _MarkedLoader(text, error_type, path)  # the reader rejects control characters here
        try:
            root = loader.get_single_node()
            data = None if root is None else loader.construct_document(root)
        finally:
            loader.dispose()
    except yaml.YAMLError as exc:
        raise _syntax_error(exc, text, path, error_type) from None
    return data, _locator(path, root, loader.pairs)


def _locator(file: Path, root: yaml.Node | None, pairs: _Pairs) -> Locate:
    def locate(path: YamlPath, *, key: bool = False) -> Location:
        node, mark = root, None if root is None else root.start_mark
        for index, step in enumerate(path):
            child = _child(node, step, pairs)
            if child is None:
                break
            key_node, node = child
            shown = key_node if key and key_node is not None and index == len(path) - 1 else node
            mark = shown.start_mark
        return _location(file, mark)

    return locate


def _child(node: yaml.Node | None, step: Hashable, pairs: _Pairs) -> tuple[yaml.Node | None, yaml.Node] | None:
    """(key node, value node) one step down, or None; sequence items have no key node."""
    if isinstance(node, yaml.MappingNode):
        return pairs.get(id(node), {}).get(step)
    if isinstance(node, yaml.SequenceNode) and isinstance(step, int) and 0 <= step < len(node.value):
        return None, node.value[step]
    return None

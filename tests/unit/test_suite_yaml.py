"""Safe YAML loading with marks: values are located, duplicates and syntax errors are located errors."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from fleetsim.errors import ScenarioFileError, SuiteError
from fleetsim.load.common.yaml_source import Locate, load_yaml_with_marks

DOCUMENT = """\
name: demo
scenarios:
  - name: a
    expect: {tasks: 3}
  - name: b
    expect:
      tasks: all
base: &base {k: 1, m: 2}
derived:
  <<: *base
  k: 5
"""


def load(tmp_path: Path, text: str | bytes) -> tuple[Any, Locate]:
    path = tmp_path / "suite.fleetsim.yaml"
    if isinstance(text, bytes):
        path.write_bytes(text)
    else:
        path.write_text(text, encoding="utf-8")
    return load_yaml_with_marks(path)


def test_values_load_with_safe_types_and_merge_keys(tmp_path: Path) -> None:
    data, _ = load(tmp_path, DOCUMENT)
    assert data["scenarios"][1]["expect"] == {"tasks": "all"}
    assert data["derived"] == {"k": 5, "m": 2}


@pytest.mark.parametrize(
    ("path", "key", "line_column"),
    [
        (("scenarios", 1, "expect", "tasks"), False, (7, 14)),
        (("scenarios", 1, "expect", "tasks"), True, (7, 7)),
        (("scenarios", 0, "expect", "tasks"), False, (4, 21)),
        (("scenarios", 1), False, (5, 5)),
        (("derived", "k"), False, (11, 6)),
        (("derived", "m"), False, (8, 23)),  # brought in by the merge: located at the anchor
        (("scenarios", 1, "no_such_key"), False, (5, 5)),  # a missing key points at its parent
        ((), False, (1, 1)),
    ],
)
def test_locate_gives_line_and_column_of_a_value_or_its_key(
    tmp_path: Path, path: tuple[object, ...], key: bool, line_column: tuple[int, int]
) -> None:
    _, locate = load(tmp_path, DOCUMENT)
    location = locate(path, key=key)
    assert (location.line, location.column) == line_column


def test_duplicate_key_is_an_error_naming_both_lines(tmp_path: Path) -> None:
    with pytest.raises(SuiteError, match=r"yaml:4:3: duplicate key 'name' \(first given on line 2\)"):
        load(tmp_path, "scenarios:\n- name: a\n  dir: x\n  name: b\n")


def test_a_merge_key_overridden_locally_is_not_a_duplicate(tmp_path: Path) -> None:
    data, _ = load(tmp_path, "a: &a {x: 1}\nb:\n  <<: *a\n  x: 2\n")
    assert data["b"] == {"x": 2}


def test_syntax_error_has_line_column_and_the_parsers_words(tmp_path: Path) -> None:
    with pytest.raises(SuiteError, match=r"yaml:3:2: invalid YAML: .*flow sequence.*expected ',' or ']'"):
        load(tmp_path, "a: 1\nb: [1, 2\nc: 3\n")


def test_python_tags_are_refused_by_the_safe_loader(tmp_path: Path) -> None:
    with pytest.raises(SuiteError, match=r"yaml:1:4: invalid YAML: could not determine a constructor"):
        load(tmp_path, "a: !!python/object/apply:os.system [echo hi]\n")


def test_control_characters_are_a_located_error(tmp_path: Path) -> None:
    with pytest.raises(SuiteError, match=r"yaml:2:4: invalid YAML: special characters .* #x0001"):
        load(tmp_path, "a: 1\nb: \x01\n")


def test_undecodable_bytes_are_a_located_error(tmp_path: Path) -> None:
    with pytest.raises(SuiteError, match=r"yaml:2: not UTF-8 text"):
        load(tmp_path, b"a: 1\nb: \xff\n")


def test_two_documents_are_an_error(tmp_path: Path) -> None:
    with pytest.raises(SuiteError, match=r"yaml:2:1: invalid YAML: expected a single document"):
        load(tmp_path, "a: 1\n---\nb: 2\n")


def test_empty_file_loads_as_none(tmp_path: Path) -> None:
    data, locate = load(tmp_path, "# nothing here\n")
    assert data is None
    assert locate(("a",)).line is None


def test_missing_file_is_a_located_error(tmp_path: Path) -> None:
    with pytest.raises(SuiteError, match=r"nope\.yaml: file not found"):
        load_yaml_with_marks(tmp_path / "nope.yaml")


def test_the_error_class_can_be_chosen(tmp_path: Path) -> None:
    path = tmp_path / "x.yaml"
    path.write_text("a: [\n", encoding="utf-8")
    with pytest.raises(ScenarioFileError):
        load_yaml_with_marks(path, error_type=ScenarioFileError)

"""The example runner itself: what it accepts, and that a drifted example fails."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.docs.examples import PageRun, blocks, commands, normalise, output_pattern


def test_blocks_reads_titles_indentation_and_lines() -> None:
    text = 'text\n\n```python title="a.py"\nx = 1\n```\n\n- item\n\n    ```yaml\n    scenarios: []\n    ```\n'
    found = list(blocks(text))
    assert [(b.lang, b.title, b.text, b.line) for b in found] == [
        ("python", "a.py", "x = 1\n", 4),
        ("yaml", None, "scenarios: []\n", 10),
    ]


def test_console_blocks_split_into_commands_and_outputs() -> None:
    (block,) = blocks("```console\n$ echo a \\\n  b\na b\n$ true\n```\n")
    assert list(commands(block)) == [("echo a \\\n  b", "a b"), ("true", "")]


@pytest.mark.parametrize(
    ("expected", "actual", "matches"),
    [
        ("a\nb", "a\nb", True),
        ("a\n...\nd", "a\nb\nc\nd", True),
        ("a\n...\nd", "a\nd", True),
        ("passed in ...s", "passed in 1.23s", True),
        ("a\nb", "a\nc", False),
        ("a\n...\nd", "a\nb\nc", False),
        ("passed in ...s", "passed in 1.23s\nmore", False),
        ("a.b", "axb", False),  # a dot is a dot, not any character
    ],
)
def test_output_patterns(expected: str, actual: str, matches: bool) -> None:
    assert bool(output_pattern(normalise(expected)).fullmatch(normalise(actual))) is matches


def run_page(folder: Path, markdown: str) -> int:
    """Run the examples of a page holding ``markdown``, in a working folder of its own under ``folder``."""
    folder.mkdir()
    page = folder / "page.md"
    page.write_text(markdown)
    return PageRun(page, folder / "work").run()


@pytest.mark.parametrize(
    ("markdown", "raised", "message"),
    [
        ("```console\n$ echo actual\nshown\n```\n", AssertionError, "printed"),  # output drifted
        ("```yaml\nscenarios:\n  - name: x\n    dir: no/such/folder\n```\n", Exception, "no/such/folder"),
        ("```python\nimport fleetsim\nfleetsim.no_such_name\n```\n", AttributeError, "no_such_name"),
        ("```pycon\n>>> 1 + 1\n3\n```\n", AssertionError, "doctest failed"),  # a shown result drifted
    ],
    ids=["console", "yaml", "python", "pycon"],
)
def test_an_example_that_no_longer_holds_fails(
    tmp_path: Path, markdown: str, raised: type[BaseException], message: str
) -> None:
    with pytest.raises(raised, match=message):
        run_page(tmp_path / "page", markdown)


def test_titled_blocks_are_written_and_suites_loaded(tmp_path: Path) -> None:
    markdown = (
        '```yaml title="mine.fleetsim.yaml"\nfleetsim: 1\nname: mine\nscenarios:\n'
        "  - {name: c, dir: scenario_suites/examples/crossing}\n```\n"
        "```console\n$ ls mine.fleetsim.yaml\nmine.fleetsim.yaml\n```\n"
    )
    assert run_page(tmp_path / "page", markdown) == 2


def test_a_broken_suite_is_checked_by_the_command_that_shows_its_error(tmp_path: Path) -> None:
    suite = '```yaml title="bad.fleetsim.yaml"\nfleetsim: 1\nname: bad\nscenarios:\n  - {name: c, dir: nowhere}\n```\n'
    with pytest.raises(Exception, match="nowhere"):  # loaded, and it does not load
        run_page(tmp_path / "alone", suite)
    shown = suite + "```console\n$ fleetsim validate bad.fleetsim.yaml\n...\n```\n"
    assert run_page(tmp_path / "shown", shown) == 2

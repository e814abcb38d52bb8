"""Every example in the documentation and the README runs (tests/docs/examples.py says how)."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.docs.examples import REPO, PageRun, blocks

PAGES = sorted([REPO / "README.md", *(REPO / "docs").rglob("*.md")])
RUN = ("python", "pycon", "yaml", "console")


@pytest.mark.parametrize("page", PAGES, ids=[str(page.relative_to(REPO)) for page in PAGES])
def test_examples_on_the_page_run(page: Path, tmp_path: Path) -> None:
    expected = sum(1 for block in blocks(page.read_text(encoding="utf-8")) if block.title or block.lang in RUN)
    assert PageRun(page, tmp_path).run() == expected


def test_every_python_and_yaml_example_is_run_or_loaded() -> None:
    # An example in a block the runner does not know (```py, ```yml) would silently go untested.
    for page in PAGES:
        for block in blocks(page.read_text(encoding="utf-8")):
            assert block.lang not in {"py", "yml", "python3", "shell-session"}, block.where(page)

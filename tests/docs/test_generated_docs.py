"""The documentation reads whole as plain Markdown (GitHub, an editor), and its generated parts are current.

The reference entries, the code blocks that show a repository file and the protocol transcript are
written into the pages by ``python -m scripts.gen_docs``; these tests fail when a page differs from what
the generator gives (a docstring, a shown file or the protocol changed and the page was not regenerated),
and when a page holds a directive that only MkDocs would fill in.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from scripts import docs_exchange, gen_docs
from tests.docs.examples import REPO, blocks

PAGES = sorted((REPO / "docs").rglob("*.md"))
# What shows nothing outside MkDocs: a mkdocstrings directive, a snippet include.
_DIRECTIVE = re.compile(r'^\s*(?::::\s+[\w.]+|--8<--\s+"[^"]+")\s*$', re.M)
_THESIS_WORD = re.compile(r"(?i)(?<![\w\[])thesis(?:['’]s)?(?!\w)")
_LINKED_THESIS = re.compile(r"(?i)\[(?:the )?thesis(?:['’]s)?\]\((?:\.\./)?index\.md#background\)")
_CODE = re.compile(r"```.*?```|`[^`\n]*`", re.S)


def empty_directives(text: str) -> list[str]:
    """The lines of a page that only MkDocs would fill in (they show nothing on GitHub or in an editor)."""
    return [match[0].strip() for match in _DIRECTIVE.finditer(text)]


def unlinked_thesis_mentions(text: str) -> list[str]:
    """Mentions of the thesis, outside code, that are not a link to its reference on the home page."""
    prose = _LINKED_THESIS.sub("", _CODE.sub("", text))
    return [prose[max(0, m.start() - 30) : m.end() + 10] for m in _THESIS_WORD.finditer(prose)]


def test_the_generated_parts_of_every_page_are_current() -> None:
    stale = [str(page.relative_to(REPO)) for page in gen_docs.stale()]
    assert stale == [], f"stale pages (run `{gen_docs.COMMAND}`): {stale}"


def test_a_changed_shown_file_makes_its_page_stale() -> None:
    page = '```csv title="scenario_suites/examples/crossing/vehicles.csv"\nid,old\n```\n'
    shown = gen_docs.show_files(page)
    assert shown != page
    assert shown == gen_docs.show_files(shown)  # current once regenerated
    assert (REPO / "scenario_suites/examples/crossing/vehicles.csv").read_text(encoding="utf-8") in shown
    # A title that is not a repository file (a file the reader writes) is left as the page has it.
    mine = '```python title="my_planner.py"\nclass Planner: ...\n```\n'
    assert gen_docs.show_files(mine) == mine


@pytest.mark.parametrize("page", PAGES, ids=lambda page: str(page.relative_to(REPO)))
def test_the_page_holds_its_content_as_plain_markdown(page: Path) -> None:
    text = page.read_text(encoding="utf-8")
    assert empty_directives(text) == []
    for block in blocks(text):
        assert block.text.strip(), f"{block.where(page)}: an empty code block"
    prose = _CODE.sub("", text)
    assert len(re.findall(r"[A-Za-z]{3,}", prose)) >= 30, "a page with next to no text of its own"


def test_the_reference_pages_show_every_entry_in_full() -> None:
    for page in sorted((REPO / "docs" / "reference").glob("*.md")):
        text = page.read_text(encoding="utf-8")
        for entry in re.finditer(
            r"<!-- reference: (?P<path>[\w.]+)[^\n]*-->\n(?P<body>.*?)<!-- end reference -->", text, re.S
        ):
            body = entry["body"]
            assert f'<a id="{entry["path"]}"></a>' in body, entry["path"]
            assert "```pyi" in body and len(body.splitlines()) >= 5, entry["path"]


def test_what_only_mkdocs_fills_in_is_found() -> None:
    assert empty_directives("# Layout\n\n::: fleetsim.layout.layout.Layout\n    options:\n") == [
        "::: fleetsim.layout.layout.Layout"
    ]
    assert empty_directives('```yaml\n--8<-- "examples/sweep/reserving-vs-bfs.sweep.yaml"\n```\n') != []
    # A definition list or an admonition is Markdown that reads as text.
    assert empty_directives("Term\n:   its definition\n\n!!! note\n    text\n") == []


def test_the_thesis_is_named_once_and_every_other_mention_links_to_it() -> None:
    home = (REPO / "docs" / "index.md").read_text(encoding="utf-8")
    background = home.split("## Background", 1)[1]
    assert "Santeri Kangas" in background and "Routing Simulation of a Robot Vehicle Fleet" in background
    assert "Tampere University" in background and "2024" in background
    named = [page for page in [*PAGES, REPO / "README.md"] if "Santeri Kangas" in page.read_text(encoding="utf-8")]
    assert named == [REPO / "docs" / "index.md"]
    for page in [*PAGES, REPO / "README.md"]:
        text = page.read_text(encoding="utf-8")
        if page == REPO / "docs" / "index.md":
            text = text.split("## Background", 1)[0]
        assert unlinked_thesis_mentions(text) == [], page.relative_to(REPO)


def test_an_unlinked_mention_of_the_thesis_is_found() -> None:
    assert unlinked_thesis_mentions("the thesis's figure 24") != []
    assert unlinked_thesis_mentions("[the thesis's](index.md#background) figure 24") == []
    assert unlinked_thesis_mentions("[thesis](../index.md#background) words") == []
    assert unlinked_thesis_mentions("Hypothesis generates layouts; `thesis` in code") == []


def test_the_exchange_page_shows_a_real_run_with_init_a_request_an_answer_and_a_rejection() -> None:
    text = (REPO / "docs" / "protocol-exchange.md").read_text(encoding="utf-8")
    section = docs_exchange.SECTION.search(text)
    assert section is not None
    shown = section[0]
    for what in ("`init`", "`ready`", "`plan_routes`", "the answer to", "**rejects**", "closes the planner's stdin"):
        assert what in shown, what
    assert '"protocol": "fleetsim-planner/' in shown
    assert "illegal-progress-change" in shown

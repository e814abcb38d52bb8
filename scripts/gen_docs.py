"""Regenerate the generated parts of docs/: ``python -m scripts.gen_docs`` (``--check``: change nothing,
list the stale pages and exit 1).

The pages are plain Markdown that read whole on GitHub and in an editor; three kinds of text in them are
generated, each in the page it belongs to, and tests/docs/test_generated_docs.py fails when any is stale:

- the API reference entries of docs/reference/*.md, rendered from the docstrings (scripts/docs_reference.py);
- a code block titled with a repository file's path (```` ```json title="schemas/planner-ready.schema.json" ````)
  shows that file as it is: the file is the one source, the page a copy kept equal to it;
- the transcript of docs/protocol-exchange.md, recorded from a real run with a planner process
  (scripts/docs_exchange.py).
"""

from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path

from scripts import docs_exchange, docs_reference

REPO = Path(__file__).resolve().parents[1]
DOCS = REPO / "docs"
COMMAND = "python -m scripts.gen_docs"
_FENCE = re.compile(
    r'^(?P<indent> *)(?P<open>```\w*[^\n]*?title="(?P<title>[^"]+)"[^\n]*)\n(?P<body>.*?)^(?P=indent)```[ \t]*$',
    re.M | re.S,
)


def pages() -> list[Path]:
    """Every documentation page: docs/**/*.md and the README."""
    return sorted([REPO / "README.md", *DOCS.rglob("*.md")])


def shown_file(title: str) -> Path | None:
    """The repository file a code block's title names, if it is one (a tracked path, not a new file)."""
    path = REPO / title
    return path if path.is_file() and path.resolve().is_relative_to(REPO) else None


def show_files(text: str) -> str:
    """The text with every code block titled with a repository file's path showing that file."""

    def replace(match: re.Match[str]) -> str:
        path = shown_file(match["title"])
        if path is None:
            return match[0]
        indent = match["indent"]
        content = path.read_text(encoding="utf-8")
        body = "".join(f"{indent}{line}\n" if line.strip() else "\n" for line in content.splitlines())
        return f"{indent}{match['open']}\n{body}{indent}```"

    return _FENCE.sub(replace, text)


def generate() -> dict[Path, str]:
    """Every page's text as it should be (unchanged pages included)."""
    texts = {page: page.read_text(encoding="utf-8") for page in pages()}
    texts = {page: show_files(text) for page, text in texts.items()}
    reference = {page: text for page, text in texts.items() if page.parent == DOCS / "reference"}
    rendered, unresolved = docs_reference.render_pages(reference, docs_reference.load_package(REPO))
    for broken in unresolved:
        print(f"warning: a cross-reference no reference page shows (shown as plain text): {broken}", file=sys.stderr)
    texts.update(rendered)
    exchange = DOCS / "protocol-exchange.md"
    texts[exchange] = docs_exchange.fill(texts[exchange], docs_exchange.record(REPO))
    return texts


def stale() -> list[Path]:
    """The pages whose committed text differs from what the generator gives."""
    return [page for page, text in generate().items() if page.read_text(encoding="utf-8") != text]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog=COMMAND, description=__doc__.splitlines()[0] if __doc__ else None)
    parser.add_argument("--check", action="store_true", help="write nothing; exit 1 if a page is stale")
    options = parser.parse_args(argv)
    changed = []
    for page, text in generate().items():
        if page.read_text(encoding="utf-8") != text:
            changed.append(page.relative_to(REPO))
            if not options.check:
                page.write_text(text, encoding="utf-8")
    for path in changed:
        print(f"{'stale' if options.check else 'regenerated'}: {path}")
    return 1 if options.check and changed else 0


if __name__ == "__main__":
    sys.exit(main())

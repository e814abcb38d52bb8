"""Run the examples of a Markdown page, so that the documentation cannot drift from the code.

A page is read as a sequence of fenced code blocks, handled in order in a working folder of its own
that holds a copy of the repository's `scenario_suites/`, `examples/` and `schemas/`:

- a block with a title (```` ```python title="my_planner.py" ````, Material's code-block title) is
  written to that path; Python files are imported and suites loaded completely once the page's files
  are all written — unless a console command on the page names the suite, which then shows what
  loading it gives (a broken suite's error, say);
- an untitled ```` ```python ```` block is executed (the page's blocks share one namespace, as in a
  tutorial read top to bottom), ```` ```pycon ```` blocks are run as doctests;
- an untitled ```` ```yaml ```` block is loaded as what it shows: a suite (a mapping with `scenarios`;
  `fleetsim: 1` may be left out), scenario entries (a list) or a sweep (`fleetsim-sweep: 1`);
- a ```` ```console ```` block's `$ COMMAND` lines are run with bash in the working folder, and the lines
  after each are the output it must print. In expected output a line that is only `...` stands for any
  number of lines, and `...` inside a line for any text.

`sh`, `text` and other blocks are not run: install commands, usage synopses and output shown without its
command.
"""

from __future__ import annotations

import doctest
import importlib.util
import io
import os
import re
import shutil
import subprocess
import sys
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import yaml

REPO = Path(__file__).resolve().parents[2]
COPIED = ("scenario_suites", "examples", "schemas")
_FENCE = re.compile(r"^(?P<indent> *)```(?P<info>[^\n`]*)\n(?P<body>.*?)^(?P=indent)```[ \t]*$", re.M | re.S)
_TITLE = re.compile(r'title="([^"]+)"')


@dataclass(frozen=True)
class Block:
    """One fenced code block of a page: its language, title (a file path) and text, and where it starts."""

    lang: str
    title: str | None
    text: str
    line: int

    def where(self, page: Path) -> str:
        shown = page.relative_to(REPO) if page.is_relative_to(REPO) else page
        return f"{shown}:{self.line}"


def blocks(text: str) -> Iterator[Block]:
    """The fenced code blocks of a Markdown text, in order (indented ones, in list items, included)."""
    for match in _FENCE.finditer(text):
        info = match.group("info").strip()
        lang = info.split()[0] if info else ""
        title = _TITLE.search(info)
        indent = len(match.group("indent"))
        body = "".join(line[indent:] for line in match.group("body").splitlines(keepends=True))
        line = text.count("\n", 0, match.start()) + 2  # the first line inside the fence
        yield Block(lang, title.group(1) if title else None, body, line)


def output_pattern(expected: str) -> re.Pattern[str]:
    """A pattern for a command's output: `...` alone on a line is any lines, within a line any text."""
    parts = []
    for line in expected.splitlines():
        if line.strip() == "...":
            parts.append(r"(?:[^\n]*\n)*?")
        else:
            pieces = [re.escape(piece) for piece in line.rstrip().split("...")]
            parts.append("[^\n]*".join(pieces) + r"\n")
    return re.compile("".join(parts))


def normalise(output: str) -> str:
    """Trailing spaces and blank lines at the end removed; a newline at the end."""
    lines = [line.rstrip() for line in output.splitlines()]
    while lines and not lines[-1]:
        lines.pop()
    return "\n".join(lines) + "\n"


def commands(block: Block) -> Iterator[tuple[str, str]]:
    """The (command, expected output) pairs of a console block; `\\` at a line's end continues the command."""
    command: list[str] = []
    output: list[str] = []
    continuing = False
    for line in block.text.splitlines():
        if continuing:
            command.append(line)
            continuing = line.endswith("\\")
        elif line.startswith("$ "):
            if command:
                yield "\n".join(command), "\n".join(output)
            command, output = [line[2:]], []
            continuing = line.endswith("\\")
        else:
            output.append(line)
    if command:
        yield "\n".join(command), "\n".join(output)


class PageRun:
    """The examples of one page, run in order in `work`."""

    def __init__(self, page: Path, work: Path) -> None:
        self.page = page
        self.work = work
        self.namespace: dict[str, object] = {"__name__": "__docs_example__"}
        self.suites: list[tuple[Block, Path]] = []
        self.modules: list[tuple[Block, Path]] = []
        self.sweeps: list[Path] = []
        self.commands: list[str] = []
        for name in COPIED:
            shutil.copytree(REPO / name, work / name)

    def run(self) -> int:
        """Run every block; the number of blocks that ran or were loaded."""
        count = 0
        previous = Path.cwd()
        os.chdir(self.work)
        sys.path.insert(0, str(self.work))
        try:
            for block in blocks(self.page.read_text(encoding="utf-8")):
                count += self.handle(block)
            for block, path in self.modules:
                self.import_module(block, path)
            for block, path in self.suites:
                if not any(block.title in command for command in self.commands):
                    load_suite_fully(block, path, self.page)
            for path in self.sweeps:
                load_sweep(path)
        finally:
            sys.path.remove(str(self.work))
            os.chdir(previous)
        return count

    def handle(self, block: Block) -> int:
        if block.title is not None:
            path = self.work / block.title
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(block.text, encoding="utf-8")
            if block.title.endswith(".sweep.yaml"):
                self.sweeps.append(path)
            elif block.title.endswith(".fleetsim.yaml"):
                self.suites.append((block, path))
            elif block.title.endswith(".py"):
                self.modules.append((block, path))
            elif block.title.endswith((".yaml", ".yml")):
                yaml.safe_load(block.text)
            return 1
        if block.lang == "python":
            code = compile(block.text, block.where(self.page), "exec")
            exec(code, self.namespace)
            return 1
        if block.lang == "pycon":
            self.doctest(block)
            return 1
        if block.lang == "yaml":
            self.load_yaml(block)
            return 1
        if block.lang == "console":
            for command, expected in commands(block):
                self.commands.append(command)
                self.check_command(block, command, expected)
            return 1
        return 0

    def doctest(self, block: Block) -> None:
        parser = doctest.DocTestParser()
        test = parser.get_doctest(block.text, self.namespace, block.where(self.page), str(self.page), block.line - 1)
        runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
        report = io.StringIO()
        runner.run(test, out=report.write)
        if runner.failures:
            raise AssertionError(f"{block.where(self.page)}: doctest failed\n{report.getvalue()}")

    def load_yaml(self, block: Block) -> None:
        document = yaml.safe_load(block.text)
        if isinstance(document, dict) and "fleetsim-sweep" in document:
            path = self.work / f"_example_{block.line}.sweep.yaml"
            path.write_text(block.text, encoding="utf-8")
            load_sweep(path)
            return
        if isinstance(document, list):
            document = {"scenarios": document}
        if not isinstance(document, dict) or "scenarios" not in document:
            raise AssertionError(
                f"{block.where(self.page)}: a YAML example must be a suite, scenario entries or a sweep, "
                f"or have a title (a file it is written to); got {type(document).__name__}"
            )
        document.setdefault("fleetsim", 1)
        document.setdefault("name", f"example-{block.line}")
        path = self.work / f"_example_{block.line}.fleetsim.yaml"
        path.write_text(yaml.safe_dump(document, sort_keys=False), encoding="utf-8")
        load_suite_fully(block, path, self.page)

    def import_module(self, block: Block, path: Path) -> None:
        name = f"_docs_example_{path.stem}_{block.line}"
        spec = importlib.util.spec_from_file_location(name, path)
        assert spec is not None and spec.loader is not None
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)

    def check_command(self, block: Block, command: str, expected: str) -> None:
        env = dict(os.environ)
        env["PYTHONPATH"] = os.pathsep.join([str(self.work), str(REPO), env.get("PYTHONPATH", "")]).rstrip(os.pathsep)
        env["COLUMNS"] = "80"  # as the pages show it
        env.pop("PYTEST_ADDOPTS", None)
        env.pop("PYTEST_XDIST_WORKER", None)
        env.pop("CI", None)  # the pages show a developer's machine; CI's stricter rules are described, not shown
        done = subprocess.run(
            ["bash", "-c", command],
            cwd=self.work,
            env=env,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,  # one stream, in the order a terminal shows them
            text=True,
            timeout=600,
        )
        actual = normalise(done.stdout)
        if not output_pattern(normalise(expected)).fullmatch(actual):
            raise AssertionError(
                f"{block.where(self.page)}: `{command}` printed (exit {done.returncode}):\n{actual}\n"
                f"the page shows:\n{normalise(expected)}"
            )


def load_suite_fully(block: Block, path: Path, page: Path) -> None:
    """Load a suite and every scenario in it, as `fleetsim validate` does."""
    from fleetsim import load_scenario, load_suite
    from fleetsim.gating.generated import check_generate_block

    suite = load_suite(path)
    for spec in suite.scenarios:
        if spec.generate is None:
            load_scenario(spec, suite)
        else:  # a generate entry has no files of its own: its settings are checked, as validate does
            check_generate_block(spec, suite)
    assert suite.scenarios, f"{block.where(page)}: the suite has no scenarios"


def load_sweep(path: Path) -> None:
    from fleetsim.sweep.spec import load_sweep_spec

    load_sweep_spec(path)

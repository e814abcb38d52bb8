"""The promises the repository makes about itself: README commands, CI script, shipped files."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def test_ci_runs_exactly_the_readme_test_command() -> None:
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    match = re.search(r"The test command is `([^`]+)`", readme)
    assert match, "README must name its test command"
    ci_commands = [line.strip() for line in (ROOT / ".ci" / "run").read_text().splitlines()]
    assert ci_commands[-1] == match.group(1)


def test_readme_opens_with_the_main_job_and_the_test_commands() -> None:
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    blocks = re.findall(r"```sh\n(.+?)\n```", readme, flags=re.S)
    assert blocks[0] == "pip install -e . && pytest scenario_suites --planner fleetsim.planners:ReservingPlanner"
    assert blocks[1].endswith("pip install -e '.[test]' && python -m pytest -n 2")


def test_packaged_schema_is_the_top_level_schema() -> None:
    packaged = ROOT / "fleetsim" / "schemas" / "suite.schema.json"
    assert packaged.read_bytes() == (ROOT / "schemas" / "suite.schema.json").read_bytes()


def test_readme_fits_on_two_screens_and_links_into_the_docs() -> None:
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    assert len(readme) <= 10_000
    for target in re.findall(r"\]\((docs/[^)#]+)", readme):
        assert (ROOT / target).is_file(), target

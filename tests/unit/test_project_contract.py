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
    assert blocks[1] == "bash scripts/install-test-tools.sh && python -m pytest -n 2"


INSTALL_SCRIPT = ROOT / "scripts" / "install-test-tools.sh"


def test_ci_installs_with_the_script_the_readme_names() -> None:
    ci_lines = [line.strip() for line in (ROOT / ".ci" / "run").read_text(encoding="utf-8").splitlines()]
    assert "bash scripts/install-test-tools.sh" in ci_lines
    assert not any(line.startswith(("apt-get install", "npm ci", "python -m pip install")) for line in ci_lines)


def _skip_hints() -> str:
    """Every install hint in the tests' skip reasons (tests/tooling.py's ``missing``, ``required_tool``)."""
    return "\n".join(path.read_text(encoding="utf-8") for path in sorted((ROOT / "tests").rglob("*.py")))


def test_the_install_script_installs_every_tool_a_test_would_skip_without() -> None:
    """A newcomer's run skips nothing: each Debian package, npm folder and Python package that a skip
    reason asks for is installed by the one script."""
    script = INSTALL_SCRIPT.read_text(encoding="utf-8")
    hints = _skip_hints()
    debian = set(re.findall(r"apt install ([a-z0-9][a-z0-9.+-]*)", hints))
    assert {"tiled", "nodejs", "chromium", "mosquitto"} <= debian
    for package in sorted(debian):
        assert re.search(rf"packages\+=\({re.escape(package)}\)", script), f"the script does not install {package}"
    for folder in sorted(set(re.findall(r"npm ci --prefix ([\w/.-]+)", hints))):
        assert f"npm ci --prefix {folder}" in script, folder
    assert "pip install -q --disable-pip-version-check -e '.[test]'" in script
    pyproject = (ROOT / "pyproject.toml").read_text(encoding="utf-8")
    test_extra = pyproject.split("test = [", 1)[1].split("]\n", 1)[0]
    for package in sorted(set(re.findall(r"pip install ([A-Za-z][\w-]*)", hints))):
        assert f'"{package}' in test_extra, f"{package} is not in the test extra"


def test_packaged_schema_is_the_top_level_schema() -> None:
    packaged = ROOT / "fleetsim" / "schemas" / "suite.schema.json"
    assert packaged.read_bytes() == (ROOT / "schemas" / "suite.schema.json").read_bytes()


def test_readme_fits_on_two_screens_and_links_into_the_docs() -> None:
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    assert len(readme) <= 10_000
    for target in re.findall(r"\]\((docs/[^)#]+)", readme):
        assert (ROOT / target).is_file(), target

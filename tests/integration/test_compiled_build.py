"""The optional compiled build (setup.py, fleetsim/compiled.py): built for real with mypyc in a copy of this
tree, it must give every recorded trace hash and pass the tests that judge runs end to end.

The test suite runs pure Python; this test builds the compiled build (``scripts/compiled_copy.py``, about a
minute; ``FLEETSIM_COMPILED_TREE`` may name one built beforehand from this same tree, as .ci/run does) and
runs, with it first on the path, the main job over every shipped suite (each run gated by its
lock file's hash) and the test modules below, in processes of their own.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from importlib.machinery import EXTENSION_SUFFIXES
from pathlib import Path

import pytest

from fleetsim.compiled import COMPILED_MODULES, compiled_modules
from fleetsim.version import __version__
from scripts.compiled_copy import build_compiled_copy, is_compiled_copy_of
from tests.tooling import missing

ROOT = Path(__file__).resolve().parents[2]

# Test modules that judge whole runs, their hashes and the motion: run against the compiled build.
END_TO_END = (
    "tests/contact",
    "tests/property/test_batched_motion.py",
    "tests/property/test_quiet_runs.py",
    "tests/unit/test_checks.py",
    "tests/unit/test_controller.py",
    "tests/unit/test_loop.py",
    "tests/unit/test_motion.py",
    "tests/unit/test_planner_faults.py",
    "tests/unit/test_planners.py",
    "tests/unit/test_profile.py",
    "tests/unit/test_reachability.py",
    "tests/unit/test_reference_planner_regressions.py",
    "tests/unit/test_reservations.py",
    "tests/unit/test_verify.py",
)


@pytest.fixture(scope="module")
def compiled(tmp_path_factory: pytest.TempPathFactory) -> Path:
    if shutil.which("cc") is None and shutil.which("gcc") is None:
        missing("the compiled build needs a C compiler (Debian/Ubuntu: apt install gcc)")
    try:
        import mypyc  # noqa: F401
    except ImportError:
        missing("the compiled build needs mypyc, which comes with mypy (pip install mypy)")
    ready = os.environ.get("FLEETSIM_COMPILED_TREE")
    if ready and is_compiled_copy_of(Path(ready), ROOT):
        return Path(ready)  # built beforehand from this very tree (.ci/run builds it beside its other steps)
    return build_compiled_copy(tmp_path_factory.mktemp("compiled") / "tree", ROOT)


def _python(tree: Path, *arguments: str, timeout: float) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "PYTHONPATH": str(tree), "PYTHONHASHSEED": "0"}
    env.pop("PYTEST_XDIST_WORKER", None)
    return subprocess.run(
        [sys.executable, *arguments], cwd=tree, env=env, capture_output=True, text=True, timeout=timeout, check=False
    )


def test_the_pure_python_install_compiles_nothing() -> None:
    assert compiled_modules() == []
    version = subprocess.run(
        [sys.executable, "-m", "fleetsim", "--version"], capture_output=True, text=True, timeout=60, check=True
    )
    assert version.stdout.strip() == f"fleetsim {__version__} (pure Python)"


def test_every_listed_module_is_compiled_in_the_compiled_build(compiled: Path) -> None:
    code = (
        "import importlib; from fleetsim.compiled import compiled_modules\n"
        "for name in compiled_modules(): print(name, importlib.import_module(name).__file__)"
    )
    done = _python(compiled, "-c", code, timeout=60)
    assert done.returncode == 0, done.stderr
    found = dict(line.split(" ", 1) for line in done.stdout.splitlines())
    assert list(found) == list(COMPILED_MODULES)
    assert all(
        Path(origin).is_relative_to(compiled) and origin.endswith(tuple(EXTENSION_SUFFIXES))
        for origin in found.values()
    )
    version = _python(compiled, "-m", "fleetsim", "--version", timeout=60)
    assert (
        version.stdout.strip()
        == f"fleetsim {__version__} (compiled: {len(COMPILED_MODULES)} of {len(COMPILED_MODULES)} hot-path modules)"
    )


def test_the_compiled_build_gives_every_recorded_hash(compiled: Path) -> None:
    done = _python(
        compiled,
        "-m", "pytest", "scenario_suites", "--planner", "fleetsim.planners:ReservingPlanner",
        "-p", "no:cacheprovider", "-p", "no:randomly", "-q",
        timeout=600,
    )  # fmt: skip
    assert done.returncode == 0, done.stdout[-6000:] + done.stderr[-2000:]
    assert "22 passed, 2 xfailed" in done.stdout


def test_the_compiled_build_passes_the_end_to_end_tests(compiled: Path) -> None:
    done = _python(
        compiled,
        "-m", "pytest", *END_TO_END, "-p", "no:cacheprovider", "-p", "no:randomly", "-q", "-n", "0",
        timeout=900,
    )  # fmt: skip
    assert done.returncode == 0, done.stdout[-6000:] + done.stderr[-2000:]
    assert " passed" in done.stdout and "skipped" not in done.stdout


def test_the_compiled_build_refuses_an_editable_install() -> None:
    """Its compiled modules would be imported instead of the sources a developer edits."""
    done = subprocess.run(
        [sys.executable, "setup.py", "editable_wheel"],
        cwd=ROOT,
        env={**os.environ, "FLEETSIM_COMPILE": "1"},
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    assert done.returncode != 0
    assert "does not make an editable install" in done.stderr
    assert "python -m scripts.compiled_copy DEST" in done.stderr

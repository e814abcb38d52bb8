"""The viewer in a real headless Chromium (Debian's ``chromium``, driven by Playwright for Python through
``executable_path``: no browser of Playwright's own is downloaded). Skipped where Chromium or Playwright
is missing, and failed instead under FLEETSIM_REQUIRE_TOOLS=1 (CI must not pass by skipping)."""

from __future__ import annotations

import os
import shutil
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

REPO = Path(__file__).resolve().parents[2]
EXAMPLES = REPO / "scenario_suites" / "examples.fleetsim.yaml"


def _missing(reason: str) -> None:
    if os.environ.get("FLEETSIM_REQUIRE_TOOLS") == "1":
        pytest.fail(reason + "; FLEETSIM_REQUIRE_TOOLS=1 requires it", pytrace=False)
    pytest.skip(reason)


@pytest.fixture(scope="session")
def chromium_path() -> str:
    path = shutil.which("chromium")
    if path is None:
        _missing("Chromium 'chromium' is not on PATH (Debian/Ubuntu: apt install chromium)")
    assert path is not None
    return path


@pytest.fixture(scope="module")
def browser(chromium_path: str) -> Iterator[Any]:
    try:
        from playwright.sync_api import sync_playwright
    except ImportError:
        _missing("Playwright for Python is not installed (pip install playwright)")
    with sync_playwright() as playwright:
        launched = playwright.chromium.launch(
            executable_path=chromium_path, args=["--no-sandbox", "--disable-gpu", "--disable-background-networking"]
        )
        yield launched
        launched.close()


@pytest.fixture
def page(browser: Any) -> Iterator[Any]:
    """A fresh page; any script error on it fails the test."""
    context = browser.new_context(viewport={"width": 1200, "height": 760})
    opened = context.new_page()
    errors: list[str] = []
    opened.on("pageerror", lambda error: errors.append(str(error)))
    opened.errors = errors
    yield opened
    context.close()
    assert errors == [], errors


def ready(page: Any, timeout: float = 15_000) -> None:
    page.wait_for_function("() => window.fleetsimView && window.fleetsimView.ready", timeout=timeout)


def state(page: Any) -> dict[str, Any]:
    result: dict[str, Any] = page.evaluate("fleetsimView.state()")
    return result


def drawn(page: Any) -> dict[str, Any]:
    """What the last drawn frame showed: its step and each vehicle's (x, y, heading)."""
    result: dict[str, Any] = page.evaluate("fleetsimView.drawnPoses()")
    return result


def wait_drawn(page: Any, step: int) -> dict[str, Any]:
    page.wait_for_function(f"() => fleetsimView.drawnPoses().step === {step}", timeout=10_000)
    return drawn(page)


def short_suite(folder: Path, time_limit: float, name: str = "watched") -> Path:
    """A suite of one scenario (the shipped mixed-shapes example) that ends at ``time_limit``."""
    text = EXAMPLES.read_text(encoding="utf-8")
    head = text[: text.index("scenarios:")].replace("time_limit: 300", f"time_limit: {time_limit}")
    mixed = REPO / "scenario_suites" / "examples" / "mixed"
    suite = folder / f"{name}.fleetsim.yaml"
    suite.write_text(
        head.replace("name: examples", f"name: {name}") + f"scenarios:\n  - name: mixed\n    dir: {mixed}/\n",
        encoding="utf-8",
    )
    return suite

"""The viewer in a real headless Chromium (Debian's ``chromium``, driven by Playwright for Python through
``executable_path``: no browser of Playwright's own is downloaded). Skipped where Chromium or Playwright
is missing, and failed instead under FLEETSIM_REQUIRE_TOOLS=1 (CI must not pass by skipping)."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import pytest
from tooling import missing, required_tool


@pytest.fixture(scope="session")
def chromium_path() -> str:
    return required_tool("chromium", "Chromium 'chromium'", "apt install chromium")


@pytest.fixture(scope="module")
def browser(chromium_path: str) -> Iterator[Any]:
    try:
        from playwright.sync_api import sync_playwright
    except ImportError:
        missing("Playwright for Python is not installed (pip install playwright)")
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

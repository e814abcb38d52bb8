"""The viewer in a real headless Chromium (Debian's ``chromium``, driven by Playwright for Python through
``executable_path``: no browser of Playwright's own is downloaded). Skipped where Chromium or Playwright
is missing, and failed instead under FLEETSIM_REQUIRE_TOOLS=1 (CI must not pass by skipping)."""

from __future__ import annotations

import os
import shutil
from collections.abc import Iterator
from typing import Any

import pytest


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

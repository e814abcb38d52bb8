"""The pytest11 entry point of fleetsim. It stays thin and imports little: hooks call into :mod:`fleetsim`."""

from __future__ import annotations

from importlib.metadata import PackageNotFoundError, version

import pytest


def pytest_report_header(config: pytest.Config) -> str:
    try:
        return f"fleetsim: {version('fleetsim')}"
    except PackageNotFoundError:  # running from a source tree that was never installed
        return "fleetsim: (not installed)"

"""The pytest11 entry point of fleetsim. It stays thin: hooks call into :mod:`fleetsim`."""

from __future__ import annotations

import pytest

import fleetsim


def pytest_report_header(config: pytest.Config) -> str:
    return f"fleetsim: {fleetsim.__version__}"

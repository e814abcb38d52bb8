"""Where a pytest session keeps fleetsim's state; a module of its own so that the plugin can ask whether
the state exists without importing the harness."""

from __future__ import annotations

from typing import TYPE_CHECKING

import pytest

if TYPE_CHECKING:
    from pytest_fleetsim._state import FleetsimState  # noqa: F401 (named in the string StashKey[...] below)

__all__ = ["STATE_KEY"]

STATE_KEY = pytest.StashKey["FleetsimState"]()

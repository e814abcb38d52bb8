"""Tests that need an external tool (Tiled, Chromium, Node.js, mosquitto, a package): skipped where it is missing,
failed instead under FLEETSIM_REQUIRE_TOOLS=1, so that CI cannot pass by skipping them."""

from __future__ import annotations

import os
import shutil
from typing import NoReturn

import pytest


def missing(reason: str, *, module_level: bool = False) -> NoReturn:
    """Skip (the test, or with ``module_level`` the module), or fail when FLEETSIM_REQUIRE_TOOLS=1."""
    if os.environ.get("FLEETSIM_REQUIRE_TOOLS") == "1":
        pytest.fail(reason + "; FLEETSIM_REQUIRE_TOOLS=1 requires it", pytrace=False)
    pytest.skip(reason, allow_module_level=module_level)


def required_tool(program: str, what: str, install: str) -> str:
    """The path of ``program``; missing, the test is skipped (or failed, see :func:`missing`)."""
    executable = shutil.which(program)
    if executable is None:
        missing(f"{what} is not on PATH (Debian/Ubuntu: {install})")
    return executable


def mosquitto_executable() -> str:
    """Debian's MQTT broker ``mosquitto`` (on PATH or in /usr/sbin); missing, see :func:`missing`."""
    from fleetsim.vda5050.broker import find_mosquitto

    executable = find_mosquitto()
    if executable is None:
        missing("the MQTT broker 'mosquitto' is not installed (Debian/Ubuntu: apt install mosquitto)")
    return executable

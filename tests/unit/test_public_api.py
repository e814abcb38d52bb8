"""The public surface: what ``fleetsim`` exports, and what importing it costs."""

from __future__ import annotations

import subprocess
import sys

import fleetsim


def test_every_exported_name_exists() -> None:
    missing = [name for name in fleetsim.__all__ if not hasattr(fleetsim, name)]
    assert missing == []


def test_core_library_never_imports_pytest() -> None:
    code = "import sys, fleetsim, fleetsim.cli; sys.exit('pytest' in sys.modules)"
    assert subprocess.run([sys.executable, "-c", code], check=False).returncode == 0


def test_errors_are_also_the_builtin_they_resemble() -> None:
    for error in (fleetsim.MapError, fleetsim.ScenarioFileError, fleetsim.SuiteError, fleetsim.LayoutError):
        assert issubclass(error, fleetsim.FleetsimError)
        assert issubclass(error, ValueError)


def test_str_enums_equal_and_hash_like_their_file_words() -> None:
    assert {"forward": 1}[fleetsim.Traverse.FORWARD] == 1
    assert {fleetsim.Progress.REVERSE: 2}["reverse"] == 2
    assert fleetsim.JointKind.TURN_IN_PLACE == "turn_in_place"

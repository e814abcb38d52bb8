"""Fixtures for tests that drive real external tools (here: the Tiled command line)."""

from __future__ import annotations

import os
import subprocess
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import pytest
from tooling import required_tool

__all__ = ["TiledCli", "required_tool"]


@dataclass(frozen=True, slots=True)
class TiledCli:
    """Runs the ``tiled`` executable headless, isolated from the user's Tiled settings."""

    executable: str
    config_home: Path
    timeout: float = 60.0

    def run(self, *args: str | os.PathLike[str]) -> subprocess.CompletedProcess[str]:
        # offscreen: no display needed; a private XDG config home keeps the user's Tiled session
        # (and any project it would load) out of the test and keeps the test out of it.
        env = {
            **os.environ,
            "QT_QPA_PLATFORM": "offscreen",
            "XDG_CONFIG_HOME": str(self.config_home),
            "XDG_RUNTIME_DIR": str(self.config_home),
        }
        command = [self.executable, *map(str, args)]
        try:
            result = subprocess.run(command, env=env, capture_output=True, text=True, timeout=self.timeout, check=False)
        except subprocess.TimeoutExpired as exc:
            msg = f"{' '.join(command)} did not finish within {self.timeout} s"
            raise RuntimeError(msg) from exc
        if result.returncode != 0:
            msg = f"{' '.join(command)} exited with {result.returncode}:\n{result.stderr}"
            raise RuntimeError(msg)
        return result

    def export_map(
        self, source: Path, target: Path, *, detach_templates: bool = False, extra: Sequence[str] = ()
    ) -> Path:
        """Let Tiled load ``source`` and write it as ``target`` (format from the target's suffix)."""
        file_format = "tmx" if target.suffix == ".tmx" else "json"
        options = ["--detach-templates"] if detach_templates else []
        self.run(*options, *extra, "--export-map", file_format, source, target)
        if not target.is_file():
            raise RuntimeError(f"tiled reported success but wrote no {target}")
        return target


@pytest.fixture(scope="session")
def tiled(tmp_path_factory: pytest.TempPathFactory) -> TiledCli:
    """The Tiled CLI; tests using it are skipped when Tiled is not installed."""
    executable = required_tool("tiled", "the Tiled editor's CLI 'tiled'", "apt install tiled")
    config_home = tmp_path_factory.mktemp("tiled-config")
    config_home.chmod(0o700)  # Qt refuses an XDG_RUNTIME_DIR others can read
    return TiledCli(executable, config_home)


@pytest.fixture(scope="module")
def node() -> str:
    """The ``node`` executable; skipped when missing, unless FLEETSIM_REQUIRE_TOOLS=1 (as for tiled)."""
    return required_tool("node", "Node.js 'node'", "apt install nodejs")

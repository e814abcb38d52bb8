"""The picture of a generated warehouse in docs/generate.md is what `fleetsim render` draws of it today."""

from __future__ import annotations

from pathlib import Path

import pytest

from fleetsim.cli.main import main
from tests.docs.examples import REPO


def test_the_generated_warehouse_picture_is_up_to_date(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    # Redraw it with: cd "$(mktemp -d)" && fleetsim generate warehouse site && fleetsim render site/map.json \
    #   -o REPO/docs/images/generated-warehouse.svg
    monkeypatch.chdir(tmp_path)
    assert main(["generate", "warehouse", "site"]) == 0
    assert main(["render", "site/map.json", "-o", "warehouse.svg"]) == 0
    picture = REPO / "docs" / "images" / "generated-warehouse.svg"
    assert Path("warehouse.svg").read_text(encoding="utf-8") == picture.read_text(encoding="utf-8")

"""The documentation site, built as CI builds it and opened in a real headless Chromium."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest
from browser import chromium_run, requested
from tooling import required_tool

REPO = Path(__file__).resolve().parents[2]
# What a planner reads (docs/reference/planner.md): each type, and attributes that must be in its table.
PLANNER_FACING = {
    "fleetsim.scenario.Task": ("id", "vehicle_id", "goal_segment", "goal_progress"),
    "fleetsim.planning.snapshot.FleetSnapshot": ("time", "vehicles", "plans", "tasks"),
    "fleetsim.planning.snapshot.VehicleState": ("segment", "traverse", "progress", "distance", "speed", "type"),
    "fleetsim.scenario.VehicleType": ("turn_capability", "max_speed", "acceleration", "length"),
    "fleetsim.planning.plans.FleetPlan": ("vehicle_id", "legs"),
    "fleetsim.planning.plans.FleetLeg": ("segment", "traverse", "progress", "fixed", "goal_for_task"),
    "fleetsim.planning.plans.RouteError": ("vehicle_id", "message"),
}


@pytest.fixture(scope="module")
def site(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("site")
    env = {**os.environ, "NO_MKDOCS_2_WARNING": "1"}
    done = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(folder)],
        cwd=REPO,
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )
    assert done.returncode == 0, done.stderr[-3000:]
    return folder


def test_every_page_of_the_navigation_is_built(site: Path) -> None:
    nav = re.findall(r":\s+([\w/-]+)\.md$", (REPO / "mkdocs.yml").read_text(encoding="utf-8"), flags=re.M)
    assert len(nav) >= 20
    for page in nav:
        folder = page.removesuffix("index").rstrip("/")
        built = site / folder / "index.html"
        assert built.is_file(), page


def test_the_planner_reference_renders_every_attribute_a_planner_reads(site: Path, tmp_path: Path) -> None:
    chromium = required_tool("chromium", "Chromium 'chromium'", "apt install chromium")
    page = site / "reference" / "planner" / "index.html"
    shot = tmp_path / "planner.png"
    netlog = tmp_path / "net.json"
    chromium_run(chromium, page, tmp_path, f"--screenshot={shot}", "--window-size=1300,2000", f"--log-net-log={netlog}")
    assert shot.is_file() and shot.stat().st_size > 20_000
    dom = chromium_run(chromium, page, tmp_path, "--dump-dom").stdout
    for identifier, attributes in PLANNER_FACING.items():
        assert f'id="{identifier}"' in dom, identifier
        # The entry runs from its heading to the next anchor (a member's or the next entry's); each
        # attribute is an item of its Attributes list.
        entry = dom.split(f'id="{identifier}"', 1)[1].split("</h", 1)[1].split('<a id="fleetsim.', 1)[0]
        assert "<strong>Attributes</strong>" in entry, identifier
        for attribute in attributes:
            assert f"<li><code>{attribute}</code>" in entry, f"{identifier}.{attribute}"
    text = re.sub(r"<[^>]+>", "", dom)
    # Sphinx roles and unresolved cross-references ([`X`][path]) would show as raw text.
    assert ":class:" not in text and ":meth:" not in text
    assert not re.search(r"\]\[[\w.]*\]", text)
    assert {url for url in requested(netlog) if not url.startswith("file://")} == set()


def test_the_site_asks_nothing_of_other_hosts(site: Path) -> None:
    for html in site.rglob("*.html"):
        assert "fonts.googleapis.com" not in html.read_text(encoding="utf-8"), html

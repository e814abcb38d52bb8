"""A real headless Chromium for tests of HTML that fleetsim writes (the sweep report, the documentation site)."""

from __future__ import annotations

import subprocess
from pathlib import Path
from urllib.parse import urlsplit

FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run", "--disable-background-networking",
         "--disable-component-update", "--disable-sync", "--hide-scrollbars"]  # fmt: skip


def chromium_run(executable: str, page: Path, work: Path, *extra: str) -> subprocess.CompletedProcess[str]:
    profile = work / f"profile-{len(list(work.glob('profile-*')))}"
    command = [executable, *FLAGS, f"--user-data-dir={profile}", *extra, page.as_uri()]
    return subprocess.run(command, capture_output=True, text=True, timeout=90, check=False)


# Chromium's own service calls (time, accounts, search prefetch), made whatever page is open.
BROWSER_SERVICES = (".google.com", ".googleapis.com", ".gvt1.com", ".gstatic.com")


def requested(netlog: Path) -> set[str]:
    """Every URL the browser's network stack was asked for on the page's behalf, from its net log."""
    text = netlog.read_text(encoding="utf-8", errors="replace")
    urls = set()
    for marker in ('"url":"', '"original_url":"'):
        for piece in text.split(marker)[1:]:
            urls.add(piece.split('"', 1)[0])
    return {url for url in urls if not urlsplit(url).hostname or not urlsplit(url).hostname.endswith(BROWSER_SERVICES)}

"""Helpers of the viewer's tests: waiting for the page, reading its state hook, a short scenario."""

from __future__ import annotations

from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[2]
EXAMPLES = REPO / "scenario_suites" / "examples.fleetsim.yaml"


def ready(page: Any, timeout: float = 15_000) -> None:
    page.wait_for_function("() => window.fleetsimView && window.fleetsimView.ready", timeout=timeout)


def state(page: Any) -> dict[str, Any]:
    result: dict[str, Any] = page.evaluate("fleetsimView.state()")
    return result


def drawn(page: Any) -> dict[str, Any]:
    """What the last drawn frame showed: its step and each vehicle's (x, y, heading)."""
    result: dict[str, Any] = page.evaluate("fleetsimView.drawnPoses()")
    return result


def wait_drawn(page: Any, step: int) -> dict[str, Any]:
    page.wait_for_function(f"() => fleetsimView.drawnPoses().step === {step}", timeout=10_000)
    return drawn(page)


def short_suite(folder: Path, time_limit: float, name: str = "watched") -> Path:
    """A suite of one scenario (the shipped mixed-shapes example) that ends at ``time_limit``."""
    text = EXAMPLES.read_text(encoding="utf-8")
    head = text[: text.index("scenarios:")].replace("time_limit: 300", f"time_limit: {time_limit}")
    mixed = REPO / "scenario_suites" / "examples" / "mixed"
    suite = folder / f"{name}.fleetsim.yaml"
    suite.write_text(
        head.replace("name: examples", f"name: {name}") + f"scenarios:\n  - name: mixed\n    dir: {mixed}/\n",
        encoding="utf-8",
    )
    return suite

"""Test-wide settings. Hypothesis runs derandomised in CI, so a CI failure reproduces exactly."""

from __future__ import annotations

import os

# numpy cannot be loaded twice in one process, and pytester's in-process runs forget the modules
# imported inside them: loaded here, every in-process run of the plugin reuses it.
import numpy  # noqa: F401
from hypothesis import settings

settings.register_profile("ci", derandomize=True, print_blob=True)
settings.register_profile("dev", print_blob=True)  # a random failure prints how to reproduce it
settings.load_profile("ci" if os.environ.get("CI") else os.environ.get("HYPOTHESIS_PROFILE", "dev"))

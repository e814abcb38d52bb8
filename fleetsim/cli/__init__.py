"""The ``fleetsim`` command line."""

from fleetsim.cli.main import main

__all__ = ["main"]

"""fleetsim's version (``pyproject.toml``'s), in a module of its own so that what records it (the MCAP
recordings, ``fleetsim --version``) does not import the package's public facade."""

__version__ = "0.1.0"

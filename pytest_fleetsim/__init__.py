"""pytest plugin for fleetsim: hooks and reporting only; behaviour lives in :mod:`fleetsim`."""

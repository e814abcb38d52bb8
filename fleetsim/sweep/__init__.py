"""Planner comparison at scale: ``fleetsim sweep`` runs planners × scenarios on Dask and reports on them.

Layout follows a sweep's flow: :mod:`~fleetsim.sweep.spec` (the YAML), :mod:`~fleetsim.sweep.items`
(runs as plain data), :mod:`~fleetsim.sweep.worker` (one run on a worker), :mod:`~fleetsim.sweep.execute`
(Dask), :mod:`~fleetsim.sweep.results` (the JSON-lines file), :mod:`~fleetsim.sweep.stats` and
:mod:`~fleetsim.sweep.gate` (bootstrap comparisons, ``--fail-if``), :mod:`~fleetsim.sweep.report`,
:mod:`~fleetsim.sweep.report_html` and :mod:`~fleetsim.sweep.plots`. Dask is imported only when a sweep runs.
"""

from fleetsim.sweep.results import RESULTS_FORMAT, ResultsError, read_results
from fleetsim.sweep.spec import SweepSpec, SweepSpecError, load_sweep_spec

__all__ = ["RESULTS_FORMAT", "ResultsError", "SweepSpec", "SweepSpecError", "load_sweep_spec", "read_results"]

"""A fleet's capacity: ``fleetsim capacity`` finds the highest order arrival rate a fleet sustains.

Layout follows a search's flow: :mod:`~fleetsim.capacity.criteria` (whether one run sustained its rate,
from its result document), :mod:`~fleetsim.capacity.search` (bracketing and bisection over rates, each
tried with several order stream seeds), :mod:`~fleetsim.capacity.runs` (a rate's runs on the sweep's
Dask machinery), :mod:`~fleetsim.capacity.results` (the JSON results file, a CI baseline),
:mod:`~fleetsim.capacity.gate` (``--fail-if``), :mod:`~fleetsim.capacity.report` and
:mod:`~fleetsim.capacity.plots`. Dask is imported only when a search runs.
"""

from fleetsim.capacity.criteria import Criteria, Judgement, judge_run
from fleetsim.capacity.search import Resolution, SearchResult, SearchSettings, search

__all__ = ["Criteria", "Judgement", "Resolution", "SearchResult", "SearchSettings", "judge_run", "search"]

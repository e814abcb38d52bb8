"""Running a sweep's items on Dask: a local cluster by default, or any scheduler by address.

Items go to the workers as plain data; rows come back as runs finish and are appended to the results
file at once. Dask reschedules the runs of a worker that dies (``distributed.scheduler.allowed-failures``
times); a run whose workers keep dying fails with a row saying so, and the sweep goes on. The results
file writes each key once, so a run Dask happened to finish twice still counts once.
"""

from __future__ import annotations

import contextlib
import os
import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from typing import Any

from fleetsim.errors import FleetsimError
from fleetsim.sweep.items import RunItem
from fleetsim.sweep.results import ResultsFile
from fleetsim.sweep.worker import failed_row, run_item

__all__ = ["DaskMissingError", "Progress", "dask_client", "run_items"]


class DaskMissingError(FleetsimError, ImportError):
    """``fleetsim sweep`` needs Dask, an optional dependency."""


@dataclass(frozen=True, slots=True)
class Progress:
    """How far a sweep is: shown as it goes."""

    done: int
    failing: int
    total: int
    elapsed: float  # seconds since the first run was sent

    @property
    def eta(self) -> float | None:
        """Seconds left at the pace so far; None before the first run finished."""
        return None if self.done == 0 else self.elapsed / self.done * (self.total - self.done)


def _distributed() -> Any:
    try:
        import distributed
    except ImportError:
        msg = "fleetsim sweep runs on Dask, which is not installed: pip install 'fleetsim[sweep]' (dask[distributed])"
        raise DaskMissingError(msg) from None
    return distributed


@contextlib.contextmanager
def dask_client(scheduler: str | None = None, workers: int | None = None) -> Iterator[Any]:
    """A Dask client: of the scheduler at ``scheduler``, else of a local cluster of ``workers`` processes
    (default: one per core), closed (with the local cluster) on leaving. ``fleetsim capacity`` keeps one
    open over the rounds of its search."""
    distributed = _distributed()
    if scheduler is not None:
        client = distributed.Client(scheduler, timeout="20s")
        cluster = None
    else:
        count = workers or os.cpu_count() or 1
        cluster = distributed.LocalCluster(
            n_workers=count, threads_per_worker=1, processes=True, dashboard_address=None, silence_logs=40
        )
        client = distributed.Client(cluster)
    try:
        yield client
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


def run_items(
    items: Sequence[RunItem],
    results: ResultsFile,
    *,
    scheduler: str | None = None,
    workers: int | None = None,
    on_progress: Callable[[Progress], None] = lambda progress: None,
    client: Any = None,
) -> Progress:
    """Run the items not yet in ``results`` on Dask; every finished run's row goes into ``results`` once.

    On ``client`` when given (an open :func:`dask_client`), else on a client opened for these items alone."""
    todo = [item for item in items if item["key"] not in results.done]
    if not todo:
        return Progress(0, 0, 0, 0.0)
    if client is None:
        with dask_client(scheduler, workers) as opened:
            return _run_on(opened, todo, results, on_progress)
    return _run_on(client, todo, results, on_progress)


def _run_on(
    client: Any, todo: Sequence[RunItem], results: ResultsFile, on_progress: Callable[[Progress], None]
) -> Progress:
    distributed = _distributed()
    start = time.monotonic()
    progress = Progress(0, 0, len(todo), 0.0)
    futures = {client.submit(run_item, item, key=_task_key(item), pure=False): item for item in todo}
    failing = 0
    for done, future in enumerate(distributed.as_completed(futures), start=1):
        item = futures[future]
        try:
            row = future.result()
        except Exception as error:
            row = failed_row(item, f"the run's workers died {type(error).__name__}: {error}")
        results.add(row)
        failing += row["status"] != "passed"
        progress = Progress(done, failing, len(todo), time.monotonic() - start)
        on_progress(progress)
    return progress


def _task_key(item: RunItem) -> str:
    """Dask task keys must be unique per scheduler: the run's key plus this process, so two sweeps on one
    cluster do not share futures."""
    return f"fleetsim-run-{os.getpid()}-{item['key']}"

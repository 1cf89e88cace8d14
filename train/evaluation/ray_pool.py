"""Sets too large for one machine, on Ray: ``--address auto`` (as ``dwr-gym sweep`` joins a cluster), ``--address
local`` for a Ray cluster started here; without ``--address``, local processes.

:class:`RayPool` has the part of :class:`concurrent.futures.ProcessPoolExecutor` that the optimum cache uses
(``map`` with a chunk size, ``shutdown``): each chunk is one task, so a task is a few seconds of solves; and
:meth:`RayPool.run_each`, one task per call, with which ``evaluate`` runs each policy's rollout on a set (the
evaluation's shards: one per policy and set, the same batched rollout as a local run's, so the same numbers).
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterable, Iterator
from typing import Any


def _solve_chunk(function: Callable[[Any], Any], items: list[Any]) -> list[Any]:
    return [function(item) for item in items]


def _timed_call(function: Callable[..., Any], args: tuple[Any, ...]) -> tuple[Any, float]:
    began = time.perf_counter()
    return function(*args), time.perf_counter() - began


class RayPool:
    """Chunks of ``map`` as Ray tasks on the cluster at ``address`` (joined here; a cluster this process started is
    stopped by :meth:`shutdown`)."""

    def __init__(self, address: str) -> None:
        try:
            import ray
        except ImportError as error:
            raise ImportError('--address needs Ray: pip install "dwr-gym[sweep]"') from error
        self._ray = ray
        self._started = not ray.is_initialized()
        if self._started:
            ray.init(address=address, include_dashboard=False, configure_logging=False, log_to_driver=False)
        self._task = ray.remote(num_cpus=1)(_solve_chunk)
        self._call = ray.remote(num_cpus=1)(_timed_call)
        self.workers = max(1, int(ray.cluster_resources().get("CPU", 1)))

    def map(self, function: Callable[[Any], Any], items: Iterable[Any], chunksize: int = 1) -> Iterator[Any]:
        """``function`` of each item, in order; each chunk of ``chunksize`` items is one task."""
        items = list(items)
        chunks = [items[i : i + chunksize] for i in range(0, len(items), max(chunksize, 1))]
        futures = [self._task.remote(function, chunk) for chunk in chunks]
        try:
            for future in futures:
                yield from self._ray.get(future)
        finally:
            for future in futures:  # an interruption cancels what has not run
                self._ray.cancel(future)

    def run_each(self, function: Callable[..., Any], calls: list[tuple[Any, ...]]) -> list[tuple[Any, float]]:
        """``function(*args)`` for each ``args`` of ``calls``, each one task, all submitted at once: (result, its wall
        seconds on its worker) in order; an error in one is raised here, and what has not run is cancelled."""
        futures = [self._call.remote(function, args) for args in calls]
        try:
            return [self._ray.get(future) for future in futures]
        finally:
            for future in futures:
                self._ray.cancel(future)

    def shutdown(self, wait: bool = True, cancel_futures: bool = False) -> None:
        if self._started:
            self._ray.shutdown()
            self._started = False


__all__ = ["RayPool"]

"""The optima of a set too large for one machine, solved as Ray tasks: ``--address auto`` (as ``dwr-gym sweep`` joins a
cluster), ``--address local`` for a Ray cluster started here; without ``--address``, local processes.

:class:`RayPool` has the part of :class:`concurrent.futures.ProcessPoolExecutor` that the optimum cache uses
(``map`` with a chunk size, ``shutdown``): each chunk is one task, so a task is a few seconds of solves.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator
from typing import Any


def _solve_chunk(function: Callable[[Any], Any], items: list[Any]) -> list[Any]:
    return [function(item) for item in items]


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

    def shutdown(self, wait: bool = True, cancel_futures: bool = False) -> None:
        if self._started:
            self._ray.shutdown()
            self._started = False


__all__ = ["RayPool"]

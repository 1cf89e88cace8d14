"""The second process of ``compare`` and ``evaluate``: policies' rollouts in a forked process beside the command's.

Most of ``compare``'s wall time goes to the three policies that solve CasADi problems while they drive (``optimal``,
``robust-pt`` and the ``robust`` agent: ``PLANNERS``); the others (the laws, the agents) take one batched rollout each.
:class:`SideProcess` runs jobs in one forked process, from the first on, while the command's process takes those not
started yet (:meth:`SideProcess.take`, the last or the next), so that both cores work to the end:
:func:`train.evaluation.evaluate.evaluate_sets` puts every (set, policy) rollout of every set in one queue that both
processes take from, :func:`train.evaluation.evaluate.evaluate` a set's policies but its costliest planner. The same
rollouts with the same seeds in either process, so the same numbers to the last digit; each job returns its result
and its own wall time, and the plans a planner solves there go to the plan store in files of that process's own
(:meth:`baselines.plan_store.PlanStore.adopt`). Where a fork is not safe (not Linux, JAX's threads in the process) or
the machine has one core, :func:`side_process_usable` says no and everything runs in turn.
"""

from __future__ import annotations

import multiprocessing
import os
import signal
import sys
import threading
import time
from collections import deque
from collections.abc import Container
from typing import Any

#: The policies that plan with CasADi while they drive (their labels in ``compare``): first in a set's queue, the
#: costliest in the command's process.
PLANNERS = frozenset({"optimal", "robust-pt", "robust"})
#: ``DWR_GYM_SIDE_PROCESS=0`` evaluates every policy in the command's process, one after the other.
SWITCH = "DWR_GYM_SIDE_PROCESS"

#: What the forked process evaluates: set by the parent before it forks, read by the child (never pickled).
_JOBS: dict[str, Any] = {}


def side_process_usable() -> bool:
    """Whether a second process may run policies: Linux (fork), no JAX threads to fork, two cores, not turned off."""
    return (
        os.environ.get(SWITCH, "1") != "0"
        and sys.platform.startswith("linux")
        and "jax" not in sys.modules
        and (os.cpu_count() or 1) >= 2
    )


def _start_child() -> None:
    """Ctrl-C goes to the command's process, which ends this one; the planners' plans solved here go to the plan store
    in files of this process's own (:mod:`baselines.plan_store`)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    from baselines import plan_store

    store = plan_store.current()
    if store is not None:
        store.adopt()


def _run(label: str) -> tuple[Any, float]:
    from baselines import plan_store

    began = time.perf_counter()
    function, args = _JOBS[label]
    result = function(*args)
    store = plan_store.current()
    if store is not None:
        store.flush()
    return result, time.perf_counter() - began


class SideProcess:
    """One forked process that runs ``function(*args)`` for the labels given at construction, from the first on, while
    this process may take the others from the last on (:meth:`take`) to run them itself once its own work is done:
    whichever process is free runs the next job, so both cores stay busy to the end. Results by label with their wall
    seconds (:meth:`results`); :meth:`close` ends the process."""

    def __init__(self, jobs: dict[str, tuple[Any, tuple[Any, ...]]]):
        _JOBS.clear()
        _JOBS.update(jobs)
        self._pool = multiprocessing.get_context("fork").Pool(1, initializer=_start_child)
        _JOBS.clear()  # the child has its copy: the parent keeps no reference to the jobs
        self._lock = threading.Lock()
        self._waiting = deque(jobs)  # not started yet
        self._pending: dict[str, Any] = {}
        self._closed = False
        self._next()

    def _next(self, _: Any = None) -> None:
        """Start the next waiting job in the process (as the one before ends: called by the pool's result thread)."""
        with self._lock:
            if self._waiting and not self._closed:
                label = self._waiting.popleft()
                self._pending[label] = self._pool.apply_async(_run, (label,), callback=self._next)

    def take(self, first: bool = False) -> Any:
        """A job the process has not started, which the caller runs itself instead (the last waiting; with ``first``
        the first, the one the process would start next), or None."""
        with self._lock:
            if not self._waiting:
                return None
            return self._waiting.popleft() if first else self._waiting.pop()

    def finished(self) -> dict[str, tuple[Any, float]]:
        """The result and wall seconds of each job that ended in the process since the last call (an error in one is
        raised here), without waiting: :meth:`results` returns the others."""
        with self._lock:
            ready = {label: result for label, result in self._pending.items() if result.ready()}
            for label in ready:
                del self._pending[label]
        return {label: result.get() for label, result in ready.items()}

    def results(self, labels: Container[Any] | None = None) -> dict[str, tuple[Any, float]]:
        """The result and wall seconds of each job the process ran or runs that :meth:`finished` has not returned (of
        those in ``labels`` only, if given), waiting for those not done (an error in one is raised here); without
        ``labels`` call it once :meth:`take` has returned None (no job waits: none will start any more)."""
        with self._lock:
            pending = {label: result for label, result in self._pending.items() if labels is None or label in labels}
            for label in pending:
                del self._pending[label]
        return {label: result.get() for label, result in pending.items()}

    def started(self) -> frozenset[Any]:
        """The jobs started in the process whose results :meth:`finished` or :meth:`results` has not returned."""
        with self._lock:
            return frozenset(self._pending)

    def close(self) -> None:
        """End the process (at once: what it still runs is not wanted after an error or Ctrl-C)."""
        with self._lock:
            self._closed = True
        self._pool.terminate()
        self._pool.join()


__all__ = ["PLANNERS", "SWITCH", "SideProcess", "side_process_usable"]

"""The policies without a planner, evaluated in a second process while the planners run in the command's own.

``compare`` evaluates each policy on each scenario set in turn. Most of its wall time goes to the three policies that
solve CasADi problems while they drive (``optimal``, ``robust-pt`` and the ``robust`` agent: ``PLANNERS``), and the
others (the laws, the agents: one batched rollout each) wait for them on one core. :class:`SideProcess` runs those
others in one forked process at the same time, on the second core, and the command's process takes those the side
process has not started once its planners are done (their plans solved before, :mod:`baselines.plan_store`, leave it
little to do): the same rollouts with the same seeds in either process, so the same numbers to the last digit; each
returns its result and its own wall time. Where a fork is not safe (not Linux,
JAX's threads in the process) or the machine has one core, :func:`side_process_usable` says no and everything runs in
turn, as before.
"""

from __future__ import annotations

import multiprocessing
import os
import signal
import sys
import threading
import time
from collections import deque
from typing import Any

#: The policies that plan with CasADi while they drive (their labels in ``compare``): they stay in the command's process.
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


def _ignore_interrupts() -> None:
    """Ctrl-C goes to the command's process, which ends this one."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def _run(label: str) -> tuple[Any, float]:
    began = time.perf_counter()
    function, args = _JOBS[label]
    return function(*args), time.perf_counter() - began


class SideProcess:
    """One forked process that runs ``function(*args)`` for the labels given at construction, from the first on, while
    this process may take the others from the last on (:meth:`take`) to run them itself once its own work is done:
    whichever process is free runs the next job, so both cores stay busy to the end. Results by label with their wall
    seconds (:meth:`results`); :meth:`close` ends the process."""

    def __init__(self, jobs: dict[str, tuple[Any, tuple[Any, ...]]]):
        _JOBS.clear()
        _JOBS.update(jobs)
        self._pool = multiprocessing.get_context("fork").Pool(1, initializer=_ignore_interrupts)
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

    def take(self) -> str | None:
        """A job the process has not started, which the caller runs itself instead (the last waiting), or None."""
        with self._lock:
            return self._waiting.pop() if self._waiting else None

    def finished(self) -> dict[str, tuple[Any, float]]:
        """The result and wall seconds of each job that ended in the process since the last call (an error in one is
        raised here), without waiting: :meth:`results` returns the others."""
        with self._lock:
            ready = {label: result for label, result in self._pending.items() if result.ready()}
            for label in ready:
                del self._pending[label]
        return {label: result.get() for label, result in ready.items()}

    def results(self) -> dict[str, tuple[Any, float]]:
        """The result and wall seconds of each job the process ran or runs that :meth:`finished` has not returned,
        waiting for those not done (an error in one is raised here); call it once :meth:`take` has returned None (no
        job waits: none will start any more)."""
        with self._lock:
            pending = dict(self._pending)
            self._pending.clear()
        return {label: result.get() for label, result in pending.items()}

    def close(self) -> None:
        """End the process (at once: what it still runs is not wanted after an error or Ctrl-C)."""
        with self._lock:
            self._closed = True
        self._pool.terminate()
        self._pool.join()


__all__ = ["PLANNERS", "SWITCH", "SideProcess", "side_process_usable"]

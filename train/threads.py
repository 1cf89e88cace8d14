"""torch's thread count for the duration of one of our commands, restored afterwards.

The networks trained and evaluated here are small (two hidden layers of 64 by default): one of their matrix
products is microseconds of work. torch's intra-op pool (OpenMP) splits such an operation across the cores, and
on a busy machine a worker of the pool has often been set aside by the scheduler when the operation starts, so
the join waits up to a time slice (milliseconds) for microseconds of work; idle workers also spin before they
sleep, taking CPU time from the rest of the process. With two busy processes beside it on two cores, SAC ran
at a fraction of its speed on one thread (docs/training/threads.json, docs/training-speed.md). So ``train``,
``sweep``, ``imitate``, DAgger, ``evaluate``, ``compare`` and ``robustness`` run torch on ``threads`` threads
(default 1, the ``--threads`` option), set on entry and restored on exit: a Python session that calls them
gets its own setting back.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager

DEFAULT_THREADS = 1
"""torch threads of our commands when ``--threads`` is not given."""
MAX_THREADS = 1024


def check_threads(threads: int | None) -> int:
    """``threads`` (None: the default) as the count to use; anything but an integer in [1, 1024] is a ValueError
    naming ``--threads``."""
    if threads is None:
        return DEFAULT_THREADS
    if isinstance(threads, bool) or not isinstance(threads, int) or not 1 <= threads <= MAX_THREADS:
        raise ValueError(f"--threads {threads!r} is invalid: expected an integer in [1, {MAX_THREADS}]")
    return threads


@contextmanager
def torch_threads(threads: int | None = None) -> Iterator[int]:
    """Run the block with torch's intra-op thread count at ``threads`` (None: :data:`DEFAULT_THREADS`), then put
    the caller's count back, also after an error or Ctrl-C. Yields the count used. Without torch, does nothing.

    The count is torch's intra-op pool, OpenMP's and MKL's (``torch.set_num_threads`` sets all three).
    torch's inter-op pool is left alone: it can be sized only once per process, before its first use, and the
    measurement found nothing to gain from it (docs/training.md).
    """
    count = check_threads(threads)
    try:
        import torch
    except ImportError:
        yield count
        return
    before = torch.get_num_threads()
    if before != count:
        torch.set_num_threads(count)
    try:
        yield count
    finally:
        if torch.get_num_threads() != before:
            torch.set_num_threads(before)


__all__ = ["DEFAULT_THREADS", "check_threads", "torch_threads"]

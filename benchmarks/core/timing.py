"""Timing on a shared machine: medians over repeats, the candidates taking turns with a reference in the same run
(so that a drift in the machine's load hits both sides of a ratio), and busy background processes as a load."""

from __future__ import annotations

import contextlib
import os
import platform
import signal
import statistics
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator
from typing import Any

#: A busy loop, ended by itself after argv[1] seconds (if its parent cannot end it).
BUSY_LOOP = "import sys, time\nend = time.monotonic() + float(sys.argv[1])\nwhile time.monotonic() < end:\n    pass\n"

Stepper = tuple[Callable[[], Any], Callable[[], contextlib.AbstractContextManager[Any]]]


@contextlib.contextmanager
def background_load(processes: int, seconds: float) -> Iterator[list[subprocess.Popen[bytes]]]:
    """``processes`` CPU-bound Python processes (yielded) running while the block runs; each ends by itself
    after ``seconds`` at the latest, and all are killed when the block ends (on errors, Ctrl-C and SIGTERM too)."""
    busy: list[subprocess.Popen[bytes]] = []
    if processes < 1:
        yield busy
        return
    main_thread = threading.current_thread() is threading.main_thread()  # (only it may set signal handlers)
    previous = signal.getsignal(signal.SIGTERM)
    if main_thread:
        signal.signal(signal.SIGTERM, lambda *_: sys.exit(143))  # a SIGTERM runs the finally below
    try:
        for _ in range(processes):
            busy.append(subprocess.Popen([sys.executable, "-c", BUSY_LOOP, str(seconds)]))
        time.sleep(0.5)  # until they run
        yield busy
    finally:
        for process in busy:
            process.kill()
        for process in busy:
            process.wait()
        if main_thread:
            signal.signal(signal.SIGTERM, previous)


def median_seconds(fn: Callable[[], Any], number: int, repeats: int) -> float:
    """Median over ``repeats`` of the time per call of ``fn`` (called ``number`` times per repeat)."""
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        for _ in range(number):
            fn()
        times.append((time.perf_counter() - start) / number)
    return statistics.median(times)


def interleaved(steppers: dict[str, Stepper], repeats: int, number: int) -> dict[str, list[float]]:
    """Seconds per call of each stepper in each repeat, the steppers taking turns within a repeat, each
    inside its context (a setting it needs, entered and left around its turn). A turn starts with one
    untimed call: each stepper is timed with its data in the caches, as in a loop of its own, not as
    the previous stepper left them. The order rotates from one repeat to the next, so that no stepper
    always follows the same one."""
    times: dict[str, list[float]] = {name: [] for name in steppers}
    names = list(steppers)
    for repeat in range(repeats):
        for name in names[repeat % len(names) :] + names[: repeat % len(names)]:
            step, context = steppers[name]
            with context():
                step()
                times[name].append(median_seconds(step, number, 1))
    return times


def paired_ratio(times: dict[str, list[float]], name: str, reference: str) -> float:
    """Median over the repeats of the speed of ``name`` relative to ``reference`` in the same repeat."""
    return statistics.median(ref / own for own, ref in zip(times[name], times[reference], strict=True))


def median_ratio(rounds: list[dict[str, float]], name: str, reference: str) -> float:
    """Median over alternating rounds of ``name``'s rate over ``reference``'s in the same round."""
    return statistics.median(r[name] / r[reference] for r in rounds)


def medians(rounds: list[dict[str, float]]) -> dict[str, float]:
    """The median of each key over the rounds."""
    return {key: statistics.median(r[key] for r in rounds) for key in rounds[0]}


def jax_timed(run: Callable[[], Any]) -> tuple[float, float, Any]:
    """(wall s, process CPU s, result) of ``run()``, its (jax) result waited for."""
    import jax

    wall, cpu = time.perf_counter(), time.process_time()
    result = jax.block_until_ready(run())
    return time.perf_counter() - wall, time.process_time() - cpu, result


def jax_machine() -> str:
    """The machine and what jax runs on: its backend, device kind and device count."""
    import jax

    return (f"{platform.machine()}, {os.cpu_count()} cores, jax {jax.__version__} ({jax.default_backend()}: "
            f"{jax.devices()[0].device_kind}, {len(jax.devices())} devices)")  # fmt: skip

"""Memory stays flat: the resident set size over 100,000 single-env steps (random actions, autoreset by hand).

    python -m benchmarks run memory

It prints the RSS after a warm-up and every 20,000 steps, and the growth from the warm-up to the end;
the line ends "flat" when the growth is under 5 MiB (a leak of even 100 bytes a step would show 9.5 MiB).
"""

from __future__ import annotations

import resource

import gymnasium as gym
import numpy as np

import dwr_gym  # noqa: F401
from benchmarks.core.commands import parser_for


def rss_mib() -> float:
    """The current resident set size [MiB] (Linux: /proc; elsewhere the peak from getrusage)."""
    try:
        with open("/proc/self/statm") as handle:
            return int(handle.read().split()[1]) * resource.getpagesize() / 2**20
    except OSError:
        return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**10


def main(argv: list[str] | None = None) -> int:
    parser = parser_for("memory", __doc__)
    parser.add_argument("--steps", type=int, default=100_000, help="steps after the warm-up (default 100000)")
    steps = parser.parse_args(argv).steps
    if steps < 20_000:
        parser.error(f"--steps {steps} is invalid: expected at least 20000 (the RSS is printed every 20000)")
    env = gym.make("DWRPointStabilization-v0", render_mode=None)
    env.reset(seed=0)
    rng = np.random.default_rng(0)
    actions = rng.uniform(-1, 1, (steps + 5_000, 2)).astype(np.float32)
    for k in range(5_000):  # warm-up: caches, allocator pools
        if any(env.step(actions[k])[2:4]):
            env.reset()
    start = rss_mib()
    print(f"after warm-up: {start:.1f} MiB")
    for k in range(steps):
        if any(env.step(actions[5_000 + k])[2:4]):
            env.reset()
        if (k + 1) % 20_000 == 0:
            print(f"{k + 1:>7} steps: {rss_mib():.1f} MiB")
    growth = rss_mib() - start
    print(f"growth over {steps:,} steps: {growth:+.2f} MiB: {'flat' if growth < 5.0 else 'NOT flat'}")
    return 0 if growth < 5.0 else 1

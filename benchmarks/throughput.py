"""Throughput of DWRPointStabilization-v0 against Gymnasium's CartPole, measured in the same run.

    python benchmarks/throughput.py            # everything (about 2 minutes on 2 cores)
    python benchmarks/throughput.py --quick    # fewer repeats and sizes

Prints, as medians of several repeats: the cost of one step of our single env and of CartPole-v1
(both through gym.make, and both unwrapped); env-steps per second of our vector env (float64, the
default, and dtype="float32"), of Gymnasium's
SyncVectorEnv over our single env, and of Gymnasium's CartPoleVectorEnv at N = 1, 64, 1024, 4096,
16384; the ratios; our vector env in each autoreset mode on short episodes (many resets); and the time
to evaluate the PTC law on the `random` set of 10,000 start poses.
Timings on shared machines are noisy: compare ratios measured in one run, not absolute numbers.
"""

from __future__ import annotations

import argparse
import statistics
import time
from collections.abc import Callable
from typing import Any

import gymnasium as gym
import numpy as np

import dwr_gym  # noqa: F401

SIZES = (1, 64, 1024, 4096, 16384)


def median_seconds(fn: Callable[[], Any], number: int, repeats: int) -> float:
    """Median over ``repeats`` of the time per call of ``fn`` (called ``number`` times per repeat)."""
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        for _ in range(number):
            fn()
        times.append((time.perf_counter() - start) / number)
    return statistics.median(times)


def single_step_costs(env_ids: tuple[str, str], wrapped: bool, repeats: int) -> tuple[float, float, float]:
    """Median step cost of two envs, measured alternately (so drifts in machine load hit both), and the
    median of the per-repeat ratios."""
    steppers = []
    for env_id in env_ids:
        env = gym.make(env_id)
        target = env if wrapped else env.unwrapped
        env.reset(seed=0)
        action = env.action_space.sample()

        def step(target: Any = target, action: Any = action) -> None:
            _, _, terminated, truncated, _ = target.step(action)
            if terminated or truncated:
                target.reset()

        step()
        steppers.append(step)
    costs: list[list[float]] = [[], []]
    for _ in range(repeats):
        for i, step in enumerate(steppers):
            costs[i].append(median_seconds(step, 2000, 1))
    ratios = [a / b for a, b in zip(costs[0], costs[1], strict=True)]
    return statistics.median(costs[0]), statistics.median(costs[1]), statistics.median(ratios)


def vector_rate(envs: Any, n: int, repeats: int, steps: int) -> float:
    envs.reset(seed=0)
    rng = np.random.default_rng(0)
    sample = envs.action_space.sample()
    actions = rng.uniform(-1, 1, size=np.shape(sample)).astype(np.float32) if sample.dtype.kind == "f" else sample
    envs.step(actions)
    return n / median_seconds(lambda: envs.step(actions), steps, repeats)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer repeats and sizes")
    args = parser.parse_args()
    repeats = 3 if args.quick else 7
    sizes = (1, 1024, 4096) if args.quick else SIZES

    print("== one step of a single env (median of", repeats, "repeats) ==")
    for wrapped in (True, False):
        ours, cart, ratio = single_step_costs(("DWRPointStabilization-v0", "CartPole-v1"), wrapped, 3 * repeats)
        label = "gym.make" if wrapped else "unwrapped"
        print(f"{label:>10}: ours {ours * 1e6:7.1f} us, CartPole-v1 {cart * 1e6:7.1f} us, ratio {ratio:5.2f}x")

    print("\n== vector envs: env-steps per second (median) ==")
    print(f"{'N':>6} {'ours float64':>13} {'ours float32':>13} {'Sync(ours)':>11} {'CartPoleVec':>12} "
          f"{'f64/CartPole':>13} {'f32/CartPole':>13} {'f64/Sync':>9}")  # fmt: skip
    for n in sizes:
        steps = max(10, min(300, 400_000 // n))
        ours = vector_rate(gym.make_vec("DWRPointStabilization-v0", num_envs=n), n, repeats, steps)
        fast = vector_rate(gym.make_vec("DWRPointStabilization-v0", num_envs=n, dtype="float32"), n, repeats, steps)
        sync_steps = max(3, min(100, 20_000 // n))
        sync = vector_rate(
            gym.make_vec("DWRPointStabilization-v0", num_envs=n, vectorization_mode="sync"), n, 3, sync_steps
        )
        cart = vector_rate(gym.make_vec("CartPole-v1", num_envs=n, vectorization_mode="vector_entry_point"), n,
                           repeats, steps)  # fmt: skip
        print(f"{n:>6} {ours / 1e6:>11.2f} M {fast / 1e6:>11.2f} M {sync / 1e6:>9.3f} M {cart / 1e6:>10.2f} M "
              f"{ours / cart:>13.2f} {fast / cart:>13.2f} {ours / sync:>9.1f}")  # fmt: skip

    print("\n== autoreset modes: N = 4096, T_con = 2 s and dt = 0.1 s, so every episode ends within 30 steps ==")
    rates = {}
    for mode in ("next_step", "same_step"):
        for dtype in ("float64", "float32"):
            envs = gym.make_vec("DWRPointStabilization-v0", num_envs=4096, dtype=dtype, autoreset_mode=mode,
                                T_con=2.0, dt=0.1)  # fmt: skip
            rates[mode, dtype] = vector_rate(envs, 4096, repeats, 100)
    for dtype in ("float64", "float32"):
        next_step, same_step = rates["next_step", dtype], rates["same_step", dtype]
        print(
            f"{dtype}: NEXT_STEP (default) {next_step / 1e6:.2f} M, SAME_STEP {same_step / 1e6:.2f} M, "
            f"ratio {next_step / same_step:.2f}"
        )

    print("\n== PTC law on the `random` scenario set (10,000 start poses, default T_con and dt) ==")
    from train.evaluation import evaluate, make_scenario

    scenario = make_scenario("random", n=10_000, seed=0)
    times = []
    for _ in range(3):
        start = time.perf_counter()
        result = evaluate({"ptc": "ptc"}, scenario)["ptc"]
        times.append(time.perf_counter() - start)
    print(f"median {statistics.median(times):.2f} s, success rate {result.success.mean():.4f}")


if __name__ == "__main__":
    main()

"""Throughput of DWRPointStabilization-v0 against Gymnasium's CartPole, measured in the same run.

    python benchmarks/throughput.py            # everything (about 3 minutes on 2 cores)
    python benchmarks/throughput.py --quick    # fewer repeats and sizes
    python benchmarks/throughput.py --readme   # everything, written into docs/throughput.md

Prints, as medians of several repeats: the cost of one step of our single env and of CartPole-v1
(both through gym.make, and both unwrapped); env-steps per second of our vector env (float64, the
default, the same with the numpy-only math of DWR_GYM_TORCH=0, and dtype="float32"), of Gymnasium's
SyncVectorEnv over our single env, and of Gymnasium's CartPoleVectorEnv at N = 1, 64, 1024, 4096,
16384; the ratios (each the median of the ratios within one repeat, so that load drifts hit both sides);
our vector env in each autoreset mode on short episodes (many resets); and the time
to evaluate the PTC law on the `random` set of 10,000 start poses; then the issue's goals, met or not, and
the machine and library versions it ran on.
Timings on shared machines are noisy: compare ratios measured in one run, not absolute numbers, and
compare two versions of the code with ``instructions.py`` (instruction counts, which do not vary).
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

import dwr_gym  # noqa: F401
from dwr_gym import model

SIZES = (1, 64, 1024, 4096, 16384)
README = Path(__file__).resolve().parents[1] / "docs" / "throughput.md"  # the page of the throughput block
BEGIN, END = "<!-- throughput:begin -->", "<!-- throughput:end -->"


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


def vector_stepper(envs: Any, n: int) -> Callable[[], Any]:
    """A function doing one step of ``envs`` with fixed random actions."""
    envs.reset(seed=0)
    rng = np.random.default_rng(0)
    sample = envs.action_space.sample()
    actions = rng.uniform(-1, 1, size=np.shape(sample)).astype(np.float32) if sample.dtype.kind == "f" else sample
    envs.step(actions)
    return lambda: envs.step(actions)


def vector_times(steppers: dict[str, Callable[[], Any]], repeats: int, steps: int) -> dict[str, list[float]]:
    """Seconds per step of each stepper in each repeat, measured in turn within a repeat (load drifts hit all)."""
    times: dict[str, list[float]] = {name: [] for name in steppers}
    for _ in range(repeats):
        for name, step in steppers.items():
            times[name].append(median_seconds(step, steps, 1))
    return times


def vector_rates(steppers: dict[str, Callable[[], Any]], n: int, repeats: int, steps: int) -> dict[str, float]:
    """Median env-steps per second of each stepper."""
    return {name: n / statistics.median(values) for name, values in vector_times(steppers, repeats, steps).items()}


def paired_ratio(times: dict[str, list[float]], name: str, reference: str) -> float:
    """Median over the repeats of the speed of ``name`` relative to ``reference`` in the same repeat."""
    return statistics.median(ref / own for own, ref in zip(times[name], times[reference], strict=True))


def machine() -> str:
    """The machine and the libraries the numbers were measured with."""
    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as info:
            cpu = next(line.split(":", 1)[1].strip() for line in info if line.startswith("model name"))
    except (OSError, StopIteration):
        pass
    torch = model._torch_module()
    return (
        f"{cpu}, {os.cpu_count()} cores; Python {platform.python_version()}, numpy {np.__version__}, "
        f"gymnasium {gym.__version__}, torch {torch.__version__ if torch else 'absent'}"
    )


def run(quick: bool) -> list[str]:
    """Every measurement, as the lines the benchmark prints."""
    repeats = 3 if quick else 7
    sizes = (1, 1024, 4096) if quick else SIZES
    lines = [f"machine: {machine()}", "", f"== one step of a single env (median of {3 * repeats} repeats) =="]
    single = {}
    for wrapped in (True, False):
        ours, cart, ratio = single_step_costs(("DWRPointStabilization-v0", "CartPole-v1"), wrapped, 3 * repeats)
        single[wrapped] = ratio
        label = "gym.make" if wrapped else "unwrapped"
        lines.append(f"{label:>10}: ours {ours * 1e6:7.1f} us, CartPole-v1 {cart * 1e6:7.1f} us, ratio {ratio:5.2f}x")

    lines += [
        "",
        "== vector envs: env-steps per second (median); numpy-only is float64 with DWR_GYM_TORCH=0; ratios paired ==",
    ]
    lines.append(f"{'N':>6} {'ours float64':>13} {'numpy-only':>11} {'ours float32':>13} {'Sync(ours)':>11} "
                 f"{'CartPoleVec':>12} {'f64/CartPole':>13} {'f32/CartPole':>13} {'f64/Sync':>9}")  # fmt: skip
    at_4096: dict[str, float] = {}
    for n in sizes:
        steps = max(10, min(100, 200_000 // n))
        make = gym.make_vec
        steppers = {
            "f64": vector_stepper(make("DWRPointStabilization-v0", num_envs=n), n),
            "f32": vector_stepper(make("DWRPointStabilization-v0", num_envs=n, dtype="float32"), n),
            "cart": vector_stepper(make("CartPole-v1", num_envs=n, vectorization_mode="vector_entry_point"), n),
        }
        times = vector_times(steppers, 3 * repeats, max(5, steps // 3))  # short, interleaved repeats
        rates = {name: n / statistics.median(values) for name, values in times.items()}
        ratios = {name: paired_ratio(times, name, "cart") for name in ("f64", "f32")}
        saved = model._torch
        model._torch = False  # the numpy-only path, as without torch or with DWR_GYM_TORCH=0
        try:
            rates.update(vector_rates({"numpy": steppers["f64"]}, n, repeats, steps))
        finally:
            model._torch = saved
        sync_env = make("DWRPointStabilization-v0", num_envs=n, vectorization_mode="sync")
        rates.update(vector_rates({"sync": vector_stepper(sync_env, n)}, n, 3, max(3, min(100, 20_000 // n))))
        if n == 4096:
            at_4096 = {**rates, "f64/cart": ratios["f64"]}
        lines.append(
            f"{n:>6} {rates['f64'] / 1e6:>11.2f} M {rates['numpy'] / 1e6:>9.2f} M {rates['f32'] / 1e6:>11.2f} M "
            f"{rates['sync'] / 1e6:>9.3f} M {rates['cart'] / 1e6:>10.2f} M {ratios['f64']:>13.2f} "
            f"{ratios['f32']:>13.2f} {rates['f64'] / rates['sync']:>9.1f}"
        )

    lines += ["", "== autoreset modes: N = 4096, T_con = 2 s and dt = 0.1 s, so every episode ends within 30 steps =="]
    steppers = {}
    for mode in ("next_step", "same_step"):
        for dtype in ("float64", "float32"):
            envs = gym.make_vec("DWRPointStabilization-v0", num_envs=4096, dtype=dtype, autoreset_mode=mode,
                                T_con=2.0, dt=0.1)  # fmt: skip
            steppers[mode, dtype] = vector_stepper(envs, 4096)
    rates = vector_rates(steppers, 4096, repeats, 50)  # type: ignore[arg-type]
    for dtype in ("float64", "float32"):
        next_step, same_step = rates["next_step", dtype], rates["same_step", dtype]  # type: ignore[index]
        lines.append(f"{dtype}: NEXT_STEP (default) {next_step / 1e6:.2f} M, SAME_STEP {same_step / 1e6:.2f} M, "
                     f"ratio {next_step / same_step:.2f}")  # fmt: skip

    lines += ["", "== PTC law on the `random` scenario set (10,000 start poses, default T_con and dt) =="]
    from train.evaluation.evaluate import evaluate
    from train.evaluation.scenarios import make_scenario

    scenario = make_scenario("random", n=10_000, seed=0)
    times = []
    for _ in range(3):
        start = time.perf_counter()
        result = evaluate({"ptc": "ptc"}, scenario)["ptc"]
        times.append(time.perf_counter() - start)
    lines.append(f"median {statistics.median(times):.2f} s, success rate {result.success.mean():.4f}")

    if at_4096:
        f64, ratio = at_4096["f64"], at_4096["f64/cart"]
        lines += [
            "",
            "== the goals of issue 14 ==",
            f"vector env, float64, N = 4096, >= 10 M env-steps/s: {f64 / 1e6:.2f} M -> {'met' if f64 >= 1e7 else 'not met'}",
            f"vector env, float64, N = 4096, >= 0.5x CartPoleVectorEnv: {ratio:.2f}x -> "
            f"{'met' if ratio >= 0.5 else 'not met'}",
            f"single env step through gym.make <= 1.5x CartPole-v1's: {single[True]:.2f}x -> "
            f"{'met' if single[True] <= 1.5 else 'not met'}",
        ]
    return lines


def write_readme(lines: list[str]) -> None:
    """Replace the README's block between the throughput markers with ``lines``."""
    text = README.read_text()
    begin, end = text.index(BEGIN) + len(BEGIN), text.index(END)
    README.write_text(text[:begin] + "\n```\n" + "\n".join(lines) + "\n```\n" + text[end:])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer repeats and sizes")
    parser.add_argument("--readme", action="store_true", help="write the output into README.md's throughput block")
    args = parser.parse_args()
    lines = run(args.quick)
    print("\n".join(lines))
    if args.readme:
        write_readme(lines)
        print(f"wrote {README}")


if __name__ == "__main__":
    main()

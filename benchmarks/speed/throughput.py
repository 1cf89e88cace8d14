"""Throughput of DWRPointStabilization-v0 against Gymnasium's CartPole, on a quiet and on a busy machine.

    python -m benchmarks run throughput              # quiet, then loaded by 2 busy processes (5-10 min on 2 cores)
    python -m benchmarks run throughput --quick      # fewer repeats and sizes (2-4 minutes)
    python -m benchmarks run throughput --load 0     # quiet only
    python -m benchmarks run throughput --docs       # also write docs/throughput/throughput.json and render its block

Each measurement runs twice: on the machine as it is ("quiet"), and while ``--load`` background processes (default
2) run busy loops, as other work would on a user's machine ("loaded"); they end after ``--load-seconds`` at the
latest, and are killed when their measurement ends. Measured, as medians of interleaved repeats (so that drifts in
the machine's load hit both sides of a ratio):

- the float64 kernels at N = 4096 that numpy evaluates one element at a time, by numpy, by torch on the calling
  thread (as dwr_gym runs them) and by torch on its thread pool (as torch runs them by default);
- one step of our single env and of CartPole-v1 (gym.make'd, and unwrapped), one fixed seeded action, resetting;
- env-steps per second of our vector env (float64, the default; float64 with torch's thread count set to
  1 by the user; the numpy-only path of DWR_GYM_TORCH=0; float32), of Gymnasium's SyncVectorEnv over our
  single env, and of Gymnasium's CartPoleVectorEnv, at N = 1, 64, 1024, 4096, 16384, and the default
  float64 path against the numpy-only one step by step (see :func:`alternating_ratio`);
- quiet only: our vector env in each autoreset mode on short episodes; the PTC law on 10,000 starts; and
  the float64 step with torch computing at every size against the numpy-only path, at 1024 to 4096 robots,
  on this CPU and (on a CPU with AVX512) in a process with numpy's and torch's AVX512 switched off: where
  torch starts to pay, which is what ``dwr_gym.model.TORCH_MIN_SIZE`` is.

Then the env-speed and busy-machine goals, met or not, and the machine and library versions. ``--docs`` writes every
figure into the JSON, which renders docs/throughput.md's block (:mod:`train.reporting.throughput_tables`).
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import platform
import statistics
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

import dwr_gym  # noqa: F401
from benchmarks.core.commands import parser_for
from benchmarks.core.docs import Schema, fenced
from benchmarks.core.record import cpu_model, report
from benchmarks.core.timing import Stepper, background_load, interleaved, median_seconds, paired_ratio
from dwr_gym import model
from train.reporting.throughput_tables import render

ROOT = Path(__file__).resolve().parents[2]
JSON_PATH = ROOT / "docs" / "throughput" / "throughput.json"
SIZES = (1, 64, 1024, 4096, 16384)
QUICK_SIZES = (1, 1024, 4096)
CROSSOVER_SIZES = (1024, 1536, 2048, 3072, 4096)
KERNELS = ("sin", "cos", "tanh", "arcsin", "arctan2")


@contextlib.contextmanager
def numpy_only() -> Iterator[None]:
    """dwr_gym's math without torch, as without torch installed or with DWR_GYM_TORCH=0."""
    saved, model._torch = model._torch, False
    try:
        yield
    finally:
        model._torch = saved


@contextlib.contextmanager
def torch_threads(threads: int | None) -> Iterator[None]:
    """torch's thread count set to ``threads`` (None: left as it is), as a user would set it."""
    torch = model._torch_module()
    if not torch or threads is None:
        yield
        return
    saved = torch.get_num_threads()
    torch.set_num_threads(threads)
    try:
        yield
    finally:
        torch.set_num_threads(saved)


def kernel_costs(repeats: int, n: int = 4096) -> dict[str, dict[str, float]]:
    """Per float64 kernel at ``n`` elements and per backend (numpy, torch on the calling thread as dwr_gym runs
    it, torch on its thread pool as torch runs it by default): microseconds per call, as the median of calls
    timed one by one (the typical call) and as the mean (total time over calls: what a loop of calls takes,
    waits included), and the process's CPU seconds per wall second over the calls (above 1: other threads
    worked or spun; below 1: the process waited)."""
    torch = model._torch_module()
    rng = np.random.default_rng(0)
    x, y = rng.uniform(-0.9, 0.9, n), rng.uniform(0.1, 2.0, n)
    calls: dict[str, tuple[Callable[..., Any], tuple[Any, ...], Callable[[], Any]]] = {}
    for name in KERNELS:
        args = (x, y) if name == "arctan2" else (x,)
        calls[f"{name}/numpy"] = (getattr(np, name), args, contextlib.nullcontext)
        if torch:
            torch_fn = getattr(torch, {"arctan2": "atan2", "arcsin": "asin"}.get(name, name))
            tensors = tuple(map(torch.from_numpy, args))
            calls[f"{name}/torch, calling thread"] = (torch_fn, tensors, lambda: torch_threads(1))
            calls[f"{name}/torch, thread pool"] = (torch_fn, tensors, contextlib.nullcontext)
    times: dict[str, list[float]] = {key: [] for key in calls}
    cpu: dict[str, list[float]] = {key: [] for key in calls}
    wall: dict[str, list[float]] = {key: [] for key in calls}
    clock, cpu_clock = time.perf_counter, time.process_time
    for _ in range(repeats):
        for key, (fn, args, context) in calls.items():
            with context():
                wall_start, cpu_start = clock(), cpu_clock()
                for _ in range(20):
                    start = clock()
                    fn(*args)
                    times[key].append(clock() - start)
                wall[key].append(clock() - wall_start)
                cpu[key].append(cpu_clock() - cpu_start)
    costs: dict[str, dict[str, float]] = {}
    for key in calls:
        name, backend = key.split("/")
        costs.setdefault(name, {})[f"{backend}: median"] = statistics.median(times[key]) * 1e6
        costs[name][f"{backend}: mean"] = sum(wall[key]) / len(times[key]) * 1e6
        costs[name][f"{backend}: cpu/wall"] = sum(cpu[key]) / sum(wall[key])
    return costs


def single_step_costs(wrapped: bool, repeats: int) -> dict[str, float]:
    """Median step cost [us] of our single env and of CartPole-v1, measured alternately, their median
    per-repeat ratio, and how many steps an episode of each lasted under its fixed action."""
    steppers: dict[str, Stepper] = {}
    episodes: dict[str, list[int]] = {}
    for key, env_id in (("ours", "DWRPointStabilization-v0"), ("cartpole", "CartPole-v1")):
        env = gym.make(env_id)
        target = env if wrapped else env.unwrapped
        env.reset(seed=0)
        env.action_space.seed(0)
        action = env.action_space.sample()
        counts = episodes[key] = [0, 0]  # steps, episodes ended

        def step(target: Any = target, action: Any = action, counts: list[int] = counts) -> None:
            _, _, terminated, truncated, _ = target.step(action)
            counts[0] += 1
            if terminated or truncated:
                counts[1] += 1
                target.reset()

        step()
        steppers[key] = (step, contextlib.nullcontext)
    times = interleaved(steppers, 5 * repeats, 100)  # turns of 100 steps: a pair sees the same load
    return {
        "ours_us": statistics.median(times["ours"]) * 1e6,
        "cartpole_us": statistics.median(times["cartpole"]) * 1e6,
        "ratio": 1.0 / paired_ratio(times, "ours", "cartpole"),
        "ours_episode_steps": episodes["ours"][0] / max(1, episodes["ours"][1]),
        "cartpole_episode_steps": episodes["cartpole"][0] / max(1, episodes["cartpole"][1]),
    }


def vector_stepper(envs: Any) -> Callable[[], Any]:
    """A function doing one step of ``envs`` with fixed random actions."""
    envs.reset(seed=0)
    rng = np.random.default_rng(0)
    sample = envs.action_space.sample()
    actions = rng.uniform(-1, 1, size=np.shape(sample)).astype(np.float32) if sample.dtype.kind == "f" else sample
    envs.step(actions)
    return lambda: envs.step(actions)


def alternating_ratio(step: Callable[[], Any], pairs: int) -> float:
    """The speed of dwr_gym's default math relative to its numpy-only path, stepping one env alternately on
    each, step by step: the median over pairs of adjacent steps (which goes first alternates) of the
    numpy-only step's time over the default's. Adjacent steps see the same load, which turns of many
    steps do not on a shared machine, and the robots' autoresets fall on both paths alike."""
    clock, ratios = time.perf_counter, []
    for pair in range(pairs):
        seconds = {}
        for path in ("numpy", "default") if pair % 2 else ("default", "numpy"):
            with numpy_only() if path == "numpy" else contextlib.nullcontext():
                start = clock()
                step()
                seconds[path] = clock() - start
        ratios.append(seconds["numpy"] / seconds["default"])
    return statistics.median(ratios)


def torch_crossover(sizes: tuple[int, ...] = CROSSOVER_SIZES, pairs: int = 400) -> dict[str, float]:
    """:func:`alternating_ratio` with torch computing at every size (``TORCH_MIN_SIZE`` lowered to 1): the step's
    speed with torch's functions relative to numpy's alone, per number of robots (what ``TORCH_MIN_SIZE`` is)."""
    saved, model.TORCH_MIN_SIZE = model.TORCH_MIN_SIZE, 1
    try:
        return {
            str(n): alternating_ratio(vector_stepper(gym.make_vec("DWRPointStabilization-v0", num_envs=n)), pairs)
            for n in sizes
        }
    finally:
        model.TORCH_MIN_SIZE = saved


def crossover_without_avx512() -> dict[str, Any] | None:
    """:func:`torch_crossover` in a process whose numpy and torch do not use AVX512 (as on CPUs without it):
    numpy's float64 tanh, arcsin and arctan2 are then scalar loops too, and torch computes all five functions.
    None on a CPU without AVX512 (the crossover measured in this process is that one)."""
    if not model._numpy_has_simd_float64():
        return None
    off = "X86_V4 AVX512_SKX AVX512_CLX AVX512_CNL AVX512_ICL AVX512_SPR"
    env = {**os.environ, "NPY_DISABLE_CPU_FEATURES": off, "ATEN_CPU_CAPABILITY": "avx2", "PYTHONWARNINGS": "ignore"}
    result = subprocess.run([sys.executable, "-m", "benchmarks", "run", "throughput", "--crossover-child"], env=env,
                            capture_output=True, text=True, check=True, cwd=ROOT)  # fmt: skip
    return json.loads(result.stdout.splitlines()[-1])


def vector_rates(n: int, repeats: int) -> dict[str, float]:
    """Env-steps per second of each vector env at ``n`` robots (each stepper its own env, all seeded alike, so
    that each sees the same steps), ratios to CartPoleVectorEnv paired within repeats, and the default path
    against the numpy-only one on adjacent steps."""

    def ours(**kwargs: Any) -> Callable[[], Any]:
        return vector_stepper(gym.make_vec("DWRPointStabilization-v0", num_envs=n, **kwargs))

    steppers: dict[str, Stepper] = {
        "f64": (ours(), contextlib.nullcontext),
        "f64_torch1": (ours(), lambda: torch_threads(1)),
        "numpy": (ours(), numpy_only),
        "f32": (ours(dtype="float32"), contextlib.nullcontext),
        "cart": (vector_stepper(gym.make_vec("CartPole-v1", num_envs=n, vectorization_mode="vector_entry_point")),
                 contextlib.nullcontext),
    }  # fmt: skip
    times = interleaved(steppers, repeats, max(5, min(40, 60_000 // n)))
    rates = {name: n / statistics.median(values) for name, values in times.items()}
    for name in ("f64", "f64_torch1", "numpy", "f32"):
        rates[f"{name}/cart"] = paired_ratio(times, name, "cart")
    rates["f64/numpy"] = alternating_ratio(ours(), max(100, min(1000, 2_000_000 // n)))
    sync = ours(vectorization_mode="sync")
    rates["sync"] = n / median_seconds(sync, max(3, min(100, 20_000 // n)), 3)
    return rates


def measure_condition(quick: bool) -> dict[str, Any]:
    """The measurements made both quiet and loaded."""
    repeats = 15 if quick else 41  # short turns, many of them: medians that a busy machine's pauses barely move
    return {
        "kernels": kernel_costs(repeats),
        "single": {
            "gym.make": single_step_costs(True, repeats),
            "unwrapped": single_step_costs(False, repeats),
        },
        "vector": {str(n): vector_rates(n, repeats) for n in (QUICK_SIZES if quick else SIZES)},
    }


def measure_quiet_only(quick: bool) -> dict[str, Any]:
    """The autoreset modes and the PTC law's evaluation, measured on the quiet machine only."""
    repeats = 3 if quick else 7
    steppers: dict[str, Stepper] = {}
    for mode in ("next_step", "same_step"):
        for dtype in ("float64", "float32"):
            envs = gym.make_vec("DWRPointStabilization-v0", num_envs=4096, dtype=dtype, autoreset_mode=mode,
                                T_con=2.0, dt=0.1)  # fmt: skip
            steppers[f"{mode}/{dtype}"] = (vector_stepper(envs), contextlib.nullcontext)
    times = interleaved(steppers, repeats, 50)
    autoreset = {name: 4096 / statistics.median(values) for name, values in times.items()}

    from train.evaluation.evaluate import evaluate
    from train.evaluation.scenarios import make_scenario

    scenario = make_scenario("random", n=10_000, seed=0)
    seconds = []
    for _ in range(3):
        start = time.perf_counter()
        result = evaluate({"ptc": "ptc"}, scenario)["ptc"]
        seconds.append(time.perf_counter() - start)
    ptc = {"seconds": statistics.median(seconds), "success_rate": float(result.success.mean())}
    crossover = {"this_cpu": torch_crossover(), "without_avx512": crossover_without_avx512()}
    return {"autoreset": autoreset, "ptc": ptc, "crossover": crossover}


def machine() -> dict[str, Any]:
    """The machine and the libraries the numbers were measured with."""
    torch = model._torch_module()
    return {
        "cpu": cpu_model(),
        "cores": os.cpu_count(),
        "python": platform.python_version(),
        "numpy": np.__version__,
        "gymnasium": gym.__version__,
        "torch": torch.__version__ if torch else None,
        "torch_threads": torch.get_num_threads() if torch else None,
        "torch_functions": sorted(model.TORCH_FUNCTIONS) if torch else [],
        "torch_min_size": model.TORCH_MIN_SIZE,
    }


def run(quick: bool, load: int, load_seconds: float) -> dict[str, Any]:
    """Every measurement, as the JSON the benchmark writes."""
    results: dict[str, Any] = {"machine": machine(), "quick": quick, "load_processes": load}
    print("measuring on the quiet machine ...", file=sys.stderr, flush=True)
    results["quiet"] = measure_condition(quick)
    results.update(measure_quiet_only(quick))
    if load > 0:
        print(f"measuring with {load} busy background processes ...", file=sys.stderr, flush=True)
        with background_load(load, load_seconds) as busy:
            results["loaded"] = measure_condition(quick)
            if any(process.poll() is not None for process in busy):
                sys.exit(
                    f"the background processes ended before the measurements did: raise --load-seconds={load_seconds:g}"
                )
    return results


#: The results block of docs/throughput.md.
BLOCKS = (fenced("throughput", "docs/throughput/throughput.json", render,
                 Schema({"machine": dict, "quick": bool, "load_processes": int, "quiet": dict, "autoreset": dict,
                         "ptc": dict, "crossover": dict})),)  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    parser = parser_for("throughput", __doc__)
    parser.add_argument("--quick", action="store_true", help="fewer repeats and sizes")
    parser.add_argument("--load", type=int, default=2, help="busy background processes of the loaded run (0: none)")
    parser.add_argument("--load-seconds", type=float, default=1200.0,
                        help="the longest the background processes run, if they cannot be ended (default 1200)")  # fmt: skip
    parser.add_argument("--docs", action="store_true", help=f"write {JSON_PATH.relative_to(ROOT)} and render its block")
    parser.add_argument("--crossover-child", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if not 0 <= args.load <= 64:
        parser.error(f"--load={args.load} is invalid: expected 0 to 64 background processes")
    if args.load_seconds <= 0:
        parser.error(f"--load-seconds={args.load_seconds} is invalid: expected a positive number of seconds")
    if args.crossover_child:
        print(json.dumps({"torch_functions": sorted(model.TORCH_FUNCTIONS), "ratios": torch_crossover()}))
        return 0
    results = run(args.quick, args.load, args.load_seconds)
    return report(render(results), results, JSON_PATH if args.docs else None)

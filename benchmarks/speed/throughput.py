"""Throughput of DWRPointStabilization-v0 against Gymnasium's CartPole, on a quiet and on a busy machine.

    python benchmarks/throughput.py              # quiet, then loaded by 2 busy processes (5-10 minutes on 2 cores)
    python benchmarks/throughput.py --quick      # fewer repeats and sizes (2-4 minutes)
    python benchmarks/throughput.py --load 0     # quiet only
    python benchmarks/throughput.py --docs       # also write docs/throughput/throughput.json and docs/throughput.md's block
    python benchmarks/throughput.py --render     # rewrite docs/throughput.md's block from the JSON (no measuring)

Each measurement runs twice: on the machine as it is ("quiet"), and while ``--load`` background processes
(default 2) run busy loops, as other work would on a user's machine ("loaded"). The background processes
are started here, end by themselves after ``--load-seconds`` at the latest, and are killed when their
measurement ends, whatever happens. Measured, as medians of interleaved repeats (so that drifts in the
machine's load hit both sides of a ratio):

- the float64 kernels at N = 4096 that numpy evaluates one element at a time, by numpy, by torch on the
  calling thread (as dwr_gym runs them) and by torch on its thread pool (as torch runs them by default);
- one step of our single env and of CartPole-v1 (through gym.make, and unwrapped), each with one fixed
  seeded action, resetting when an episode ends;
- env-steps per second of our vector env (float64, the default; float64 with torch's thread count set to
  1 by the user; the numpy-only path of DWR_GYM_TORCH=0; float32), of Gymnasium's SyncVectorEnv over our
  single env, and of Gymnasium's CartPoleVectorEnv, at N = 1, 64, 1024, 4096, 16384, and the default
  float64 path against the numpy-only one step by step (see :func:`alternating_ratio`);
- quiet only: our vector env in each autoreset mode on short episodes; the PTC law on 10,000 starts; and
  the float64 step with torch computing at every size against the numpy-only path, at 1024 to 4096 robots,
  on this CPU and (on a CPU with AVX512) in a process with numpy's and torch's AVX512 switched off: where
  torch starts to pay, which is what ``dwr_gym.model.TORCH_MIN_SIZE`` is.

Then the goals of issues 14 and 23, met or not, and the machine and library versions. ``--docs`` writes
every figure into the JSON and renders the results block of docs/throughput.md from that JSON alone, and
the blocks of the JSON files that ``compare_commits.py --json`` and ``instructions.py --json`` wrote into
docs/throughput/. Compare two versions of the code with ``compare_commits.py`` (alternating runs) or
``instructions.py`` (counts).
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import platform
import signal
import statistics
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

import dwr_gym  # noqa: F401
from dwr_gym import model

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs" / "throughput.md"
JSON_PATH = ROOT / "docs" / "throughput" / "throughput.json"
SIZES = (1, 64, 1024, 4096, 16384)
QUICK_SIZES = (1, 1024, 4096)
CROSSOVER_SIZES = (1024, 1536, 2048, 3072, 4096)
KERNELS = ("sin", "cos", "tanh", "arcsin", "arctan2")
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
    result = subprocess.run([sys.executable, __file__, "--crossover-child"], env=env, capture_output=True, text=True,
                            check=True)  # fmt: skip
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
    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as info:
            cpu = next(line.split(":", 1)[1].strip() for line in info if line.startswith("model name"))
    except (OSError, StopIteration):
        pass
    torch = model._torch_module()
    return {
        "cpu": cpu,
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


def verdict(ok: bool) -> str:
    return "met" if ok else "not met"


def goals(results: dict[str, Any]) -> list[str]:
    """The goals of issues 14 and 23, each with the measured figure."""
    lines = []
    quiet = results["quiet"]
    if "4096" in quiet["vector"]:
        rates = quiet["vector"]["4096"]
        lines += [
            f"issue 14: vector env, float64, N = 4096, >= 10 M env-steps/s: {rates['f64'] / 1e6:.2f} M -> "
            f"{verdict(rates['f64'] >= 1e7)}",
            f"issue 23: vector env, float64, N = 4096, quiet, >= 0.5x CartPoleVectorEnv: {rates['f64/cart']:.2f}x -> "
            f"{verdict(rates['f64/cart'] >= 0.5)}",
        ]
        if "loaded" in results:
            loaded = results["loaded"]["vector"]["4096"]["f64/cart"]
            lines.append(
                f"issue 23: vector env, float64, N = 4096, {results['load_processes']} busy processes, >= 0.4x "
                f"CartPoleVectorEnv: {loaded:.2f}x -> {verdict(loaded >= 0.4)}"
            )
    single = quiet["single"]["gym.make"]["ratio"]
    lines.append(f"issue 23: single env step through gym.make, quiet, <= 1.5x CartPole-v1's: {single:.2f}x -> "
                 f"{verdict(single <= 1.5)}")  # fmt: skip
    threshold = results["machine"]["torch_min_size"]
    for condition in ("quiet", "loaded"):
        if condition not in results:
            continue
        ratios = {int(n): rates["f64/numpy"] for n, rates in results[condition]["vector"].items()}
        same = [r for n, r in ratios.items() if n < threshold]  # the same code runs on both paths: the noise
        floor = min([1.0, *same])
        worst = min((n for n in ratios if n >= threshold), key=ratios.__getitem__, default=None)
        if worst is not None:
            noise = (
                f"; below N = {threshold} both run the same code and measure {min(same):.2f}x-{max(same):.2f}x"
                if same
                else ""
            )
            lines.append(
                f"issue 23: vector env not slower than its numpy-only path, {condition}: slowest float64/numpy-only "
                f"ratio {ratios[worst]:.2f}x (N = {worst}){noise} -> {verdict(ratios[worst] >= floor)}"
            )
    return lines


def render(results: dict[str, Any]) -> list[str]:
    """The lines of the report, from the JSON alone."""
    m = results["machine"]
    torch = f"torch {m['torch']} ({m['torch_threads']} threads by default)" if m["torch"] else "no torch"
    conditions = ["quiet"] + (["loaded"] if "loaded" in results else [])
    load = results["load_processes"]
    label = {"quiet": "quiet", "loaded": f"loaded ({load} busy processes)"}
    lines = [
        f"machine: {m['cpu']}, {m['cores']} cores; Python {m['python']}, numpy {m['numpy']}, "
        f"gymnasium {m['gymnasium']}, {torch}",
        f"computed by torch for large float64 arrays: {', '.join(m['torch_functions']) or 'none'}"
        + (" (quick run)" if results["quick"] else ""),
        "",
        "== summary: " + " | ".join(label[c] for c in conditions) + " ==",
    ]
    rows = [
        ("single env step / CartPole-v1's (gym.make)", lambda r: r["single"]["gym.make"]["ratio"], "x"),
        ("single env step / CartPole-v1's (unwrapped)", lambda r: r["single"]["unwrapped"]["ratio"], "x"),
        ("vector float64, N = 4096 / CartPoleVectorEnv", lambda r: r["vector"]["4096"]["f64/cart"], "x"),
        ("vector float64, N = 4096 / numpy-only path", lambda r: r["vector"]["4096"]["f64/numpy"], "x"),
        ("vector float64, N = 4096 [M env-steps/s]", lambda r: r["vector"]["4096"]["f64"] / 1e6, " M"),
        ("CartPoleVectorEnv, N = 4096 [M env-steps/s]", lambda r: r["vector"]["4096"]["cart"] / 1e6, " M"),
    ]
    for title, get, unit in rows:
        lines.append(f"{title:<46}" + "".join(f"{get(results[c]):>12.2f}{unit:<2}" for c in conditions))

    for condition in conditions:
        r = results[condition]
        lines += [
            "",
            f"== {label[condition]}: float64 kernels at N = 4096: us per call (median of single calls, mean over "
            "all), process CPU s per wall s ==",
        ]
        backends = [b[: -len(": median")] for b in next(iter(r["kernels"].values())) if b.endswith(": median")]
        lines.append(f"{'':<8}" + "".join(f"{b:>26}" for b in backends))
        lines.append(f"{'':<8}" + "   median     mean cpu/wall" * len(backends))
        for name, costs in r["kernels"].items():
            cells = (f"{costs[b + ': median']:>9.1f}{costs[b + ': mean']:>9.1f}{costs[b + ': cpu/wall']:>8.2f}"
                     for b in backends)  # fmt: skip
            lines.append(f"{name:<8}" + " ".join(cells))

        lines += ["", f"== {label[condition]}: one step of a single env, fixed seeded action, reset at episode ends =="]
        for kind, s in r["single"].items():
            lines.append(f"{kind:>10}: ours {s['ours_us']:6.1f} us, CartPole-v1 {s['cartpole_us']:6.1f} us, ratio "
                         f"{s['ratio']:5.2f}x (episodes of {s['ours_episode_steps']:.0f} and "
                         f"{s['cartpole_episode_steps']:.1f} steps)")  # fmt: skip

        lines += [
            "",
            f"== {label[condition]}: vector envs, M env-steps/s (median); numpy-only: DWR_GYM_TORCH=0; "
            "torch 1 thr: torch.set_num_threads(1); ratios paired (f64/numpy: adjacent steps) ==",
            f"{'N':>6} {'float64':>8} {'torch 1 thr':>11} {'numpy-only':>10} {'float32':>8} {'Sync(ours)':>10} "
            f"{'CartPoleVec':>11} {'f64/Cart':>8} {'f64/numpy':>9} {'f32/Cart':>8}",
        ]
        for n, v in r["vector"].items():
            lines.append(
                f"{n:>6} {v['f64'] / 1e6:>8.2f} {v['f64_torch1'] / 1e6:>11.2f} {v['numpy'] / 1e6:>10.2f} "
                f"{v['f32'] / 1e6:>8.2f} {v['sync'] / 1e6:>10.3f} {v['cart'] / 1e6:>11.2f} {v['f64/cart']:>8.2f} "
                f"{v['f64/numpy']:>9.2f} {v['f32/cart']:>8.2f}"
            )

    a = results["autoreset"]
    lines += [
        "",
        "== quiet: autoreset modes, N = 4096, T_con = 2 s and dt = 0.1 s (every episode ends within 30 steps) ==",
    ]
    for dtype in ("float64", "float32"):
        next_step, same_step = a[f"next_step/{dtype}"], a[f"same_step/{dtype}"]
        lines.append(f"{dtype}: NEXT_STEP (default) {next_step / 1e6:.2f} M, SAME_STEP {same_step / 1e6:.2f} M, "
                     f"ratio {next_step / same_step:.2f}")  # fmt: skip
    c = results["crossover"]
    lines += [
        "",
        "== quiet: float64 step with torch's functions at every size / numpy-only, adjacent steps (TORCH_MIN_SIZE) ==",
        f"{'N':>24}" + "".join(f"{n:>7}" for n in c["this_cpu"]),
        f"{'this CPU':>24}" + "".join(f"{r:>7.2f}" for r in c["this_cpu"].values()),
    ]
    if c["without_avx512"]:
        ratios = c["without_avx512"]["ratios"]
        lines.append(f"{'AVX512 switched off':>24}" + "".join(f"{r:>7.2f}" for r in ratios.values())
                     + f"   (torch computes {', '.join(c['without_avx512']['torch_functions'])})")  # fmt: skip
    p = results["ptc"]
    lines += [
        "",
        "== quiet: PTC law on the `random` scenario set (10,000 start poses, default T_con and dt) ==",
        f"median {p['seconds']:.2f} s, success rate {p['success_rate']:.4f}",
        "",
        "== goals ==",
        *goals(results),
    ]
    return lines


def render_compare(record: dict[str, Any]) -> list[str]:
    """The lines of the block of ``compare_commits.py --json``'s record."""
    (old, new), load = record["commits"], record["load_processes"]
    threads = record.get("omp_num_threads")
    setting = f"OMP_NUM_THREADS={threads}" if threads else "default threads"
    lines = [f"float64 vector env at N = {record['num_envs']}, {load} busy background processes, {setting}; speed "
             "relative to CartPoleVectorEnv in the same process, per round:"]  # fmt: skip
    for commit, ratios in zip(record["commits"], record["ratios"], strict=True):
        lines.append(f"{commit:>8}: " + "  ".join(f"{r:.3f}x" for r in ratios))
    old_median, new_median = record["median_ratios"]
    lines.append(
        f"median: {old} {old_median:.3f}x, {new} {new_median:.3f}x ({new_median / old_median:.1f} times as fast)"
    )
    return lines


def render_instructions(record: dict[str, Any]) -> list[str]:
    """The lines of the block of ``instructions.py --json``'s record."""
    lines = [
        f"{label:<40} {count:>12,.0f} instructions per step" for label, count in record["instructions_per_step"].items()
    ]
    lines += [f"ratio, {kind}: {ratio:.2f}x CartPole's" for kind, ratio in record["ratios"].items()]
    return lines


#: The generated blocks of docs/throughput.md: marker name -> (the JSON they are rendered from, the renderer).
BLOCKS: dict[str, tuple[Path, Callable[[dict[str, Any]], list[str]]]] = {
    "throughput": (JSON_PATH, render),
    "compare": (JSON_PATH.parent / "compare_loaded.json", render_compare),
    "compare_quiet": (JSON_PATH.parent / "compare_quiet_one_thread.json", render_compare),
    "instructions": (JSON_PATH.parent / "instructions.json", render_instructions),
}


def rendered_block(name: str) -> str:
    """The block ``name`` as rendered from its JSON file."""
    path, renderer = BLOCKS[name]
    return "\n```\n" + "\n".join(renderer(json.loads(path.read_text()))) + "\n```\n"


def docs_block(name: str) -> str:
    """The text between the markers of block ``name`` in docs/throughput.md."""
    from train.reporting.doc_tables import block

    return block(DOCS.read_text(), name)


def write_docs() -> None:
    """Render every block of docs/throughput.md whose JSON file exists from that file."""
    from train.reporting.doc_tables import with_block

    text = DOCS.read_text()
    for name, (path, _) in BLOCKS.items():
        if path.exists():
            text = with_block(text, name, rendered_block(name))
    DOCS.write_text(text)
    print(f"wrote {DOCS}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer repeats and sizes")
    parser.add_argument("--load", type=int, default=2, help="busy background processes of the loaded run (0: none)")
    parser.add_argument("--load-seconds", type=float, default=1200.0,
                        help="the longest the background processes run, if they cannot be ended (default 1200)")  # fmt: skip
    parser.add_argument("--docs", action="store_true", help=f"write {JSON_PATH.relative_to(ROOT)} and render the "
                        f"blocks of {DOCS.relative_to(ROOT)} from the JSON files")  # fmt: skip
    parser.add_argument("--crossover-child", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--render", action="store_true", help=f"only render the blocks of {DOCS.relative_to(ROOT)} "
                        "from the JSON files (of this benchmark, compare_commits.py and instructions.py)")  # fmt: skip
    args = parser.parse_args()
    if not 0 <= args.load <= 64:
        parser.error(f"--load={args.load} is invalid: expected 0 to 64 background processes")
    if args.load_seconds <= 0:
        parser.error(f"--load-seconds={args.load_seconds} is invalid: expected a positive number of seconds")
    if args.crossover_child:
        print(json.dumps({"torch_functions": sorted(model.TORCH_FUNCTIONS), "ratios": torch_crossover()}))
        return
    if args.render:
        if not JSON_PATH.exists():
            sys.exit(f"{JSON_PATH} does not exist: run `python benchmarks/throughput.py --docs` first")
        write_docs()
        return
    results = run(args.quick, args.load, args.load_seconds)
    print("\n".join(render(results)))
    if args.docs:
        JSON_PATH.parent.mkdir(parents=True, exist_ok=True)
        JSON_PATH.write_text(json.dumps(results, indent=1) + "\n")
        print(f"wrote {JSON_PATH}")
        write_docs()  # the blocks from the JSON files as written


if __name__ == "__main__":
    main()

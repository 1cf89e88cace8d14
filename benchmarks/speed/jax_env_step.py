"""The functional (JAX) env's step alone against the native numpy vector env, N = 4096, on one thread budget.

    python -m benchmarks run jax-env-step                # measure and print (2-4 minutes on 2 cores)
    python -m benchmarks run jax-env-step --threads 2    # both sides may use 2 threads (XLA's; numpy's step uses one)
    python -m benchmarks run jax-env-step --docs         # also write docs/jax/env_step.json, render its table

Env-steps per second, medians of interleaved repeats in one process (so drifts in the machine's load hit every
case), each with the same fixed random actions (as ``throughput``), episodes ending and restarting as they do:

- the native vector env (``gymnasium.make_vec("DWRPointStabilization-v1", num_envs=N)``), float64 and float32;
- the gymnax adapter's step with auto-reset, ``jax.jit(jax.vmap(env.step))``, one Python call per step
  (dispatch included, what a Python training loop over the JAX env pays), float64 (``jax_enable_x64``) and float32;
- the same step inside ``jax.lax.scan`` over ``--scan`` steps in one compiled call (how PureJaxRL runs an env),
  the same with optimistic resets (``OptimisticResetVecEnv``: ``N // --reset-ratio`` new episodes per step), and
  the FuncEnv's ``transition`` alone so (no auto-reset: gymnax's computes a new episode for every robot each step).

``--threads`` sets OMP_NUM_THREADS, torch's threads and XLA's CPU thread pool before anything is imported.
"""

from __future__ import annotations

import os
import platform
import statistics
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from benchmarks.core.commands import parser_for
from benchmarks.core.docs import Schema, table
from benchmarks.core.record import write_json

ROOT = Path(__file__).resolve().parents[2]
JSON_PATH = ROOT / "docs" / "jax" / "env_step.json"
ENV_ID = "DWRPointStabilization-v1"


def limit_threads(threads: int) -> None:
    """One thread budget for numpy (OpenMP, BLAS), torch and XLA's CPU client; call before importing them."""
    for name in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ[name] = str(threads)
    flags = f"--xla_cpu_multi_thread_eigen={'true' if threads > 1 else 'false'} intra_op_parallelism_threads={threads}"
    os.environ["XLA_FLAGS"] = f"{os.environ.get('XLA_FLAGS', '')} {flags}".strip()


def native_case(num_envs: int, dtype: str, actions: Any) -> Callable[[int], None]:
    import gymnasium as gym

    env = gym.make_vec(ENV_ID, num_envs=num_envs, vectorization_mode="vector_entry_point", dtype=dtype)
    env.reset(seed=0)

    def run(steps: int) -> None:
        for _ in range(steps):
            env.step(actions)

    return run


def jax_cases(num_envs: int, dtype: str, actions: Any, scan: int, reset_ratio: int) -> dict[str, Callable[[int], None]]:
    """(one call per step, ``scan`` steps per call) for the gymnax adapter in ``dtype`` (x64 already set)."""
    import jax
    import jax.numpy as jnp

    from dwr_gym.jax_env import make_gymnax_env
    from dwr_gym.jax_env.autoreset import OptimisticResetVecEnv

    env, params = make_gymnax_env(ENV_ID, dtype)
    optimistic = OptimisticResetVecEnv(env, num_envs, reset_ratio)
    action = jnp.asarray(actions)
    vmapped = jax.vmap(env.step, in_axes=(0, 0, 0, None))

    @jax.jit
    def step(state: Any, key: jax.Array) -> tuple[Any, jax.Array]:
        """One step of every robot, the keys split inside: one compiled call."""
        key, step_key = jax.random.split(key)
        _, state, _reward, _, _ = vmapped(jax.random.split(step_key, num_envs), state, action, params)
        return state, key

    def optimistic_step(state: Any, key: jax.Array) -> tuple[Any, jax.Array]:
        """:func:`step` with optimistic resets: ``num_envs // reset_ratio`` new episodes per step."""
        key, step_key = jax.random.split(key)
        _, state, _reward, _, _ = optimistic.step(step_key, state, action, params)
        return state, key

    transition = jax.vmap(env.func_env.transition, in_axes=(0, 0, 0, None))

    @jax.jit
    def transition_only(state: Any, key: jax.Array) -> tuple[Any, jax.Array]:
        """:func:`step` without the auto-reset (which computes a new episode for every robot at every step)."""
        key, step_key = jax.random.split(key)
        return transition(state, action, jax.random.split(step_key, num_envs), params), key

    def scanned_call(advance: Callable[..., Any]) -> Callable[..., Any]:
        @jax.jit
        def rollout(state: Any, key: jax.Array) -> tuple[Any, jax.Array]:
            (state, key), _ = jax.lax.scan(lambda carry, _: (advance(*carry), None), (state, key), None, length=scan)
            return state, key

        return rollout

    keys = jax.random.split(jax.random.PRNGKey(0), num_envs)
    _, state = jax.jit(jax.vmap(env.reset, in_axes=(0, None)))(keys, params)
    carry = {"state": state, "key": jax.random.PRNGKey(1)}
    rollouts = {"scan": scanned_call(step), f"scan, optimistic auto-reset, reset_ratio {reset_ratio}":
                scanned_call(optimistic_step), "scan, no auto-reset": scanned_call(transition_only)}  # fmt: skip
    jax.block_until_ready(step(state, carry["key"]))  # compile them
    for rollout in rollouts.values():
        jax.block_until_ready(rollout(state, carry["key"]))

    def per_call(steps: int) -> None:
        state, key = carry["state"], carry["key"]
        for _ in range(steps):
            state, key = step(state, key)
        carry["state"], carry["key"] = jax.block_until_ready((state, key))

    def scanned(rollout: Callable[..., Any]) -> Callable[[int], None]:
        def run(steps: int) -> None:
            state, key = carry["state"], carry["key"]
            for _ in range(max(1, steps // scan)):
                state, key = rollout(state, key)
            jax.block_until_ready((state, key))  # (the state without resets is not kept: its episodes would not end)

        return run

    return {"per call": per_call, **{name: scanned(rollout) for name, rollout in rollouts.items()}}


def measure(cases: dict[str, tuple[Callable[[int], None], int]], repeats: int) -> dict[str, tuple[float, float]]:
    """Median (wall-clock seconds, CPU seconds of this process) per step of each case, in interleaved repeats.

    On a machine busy with other work the wall clock counts the time this process waits for a core; the CPU time
    counts what it computed (all its threads), which varies far less with the load.
    """
    times: dict[str, list[tuple[float, float]]] = {name: [] for name in cases}
    for _ in range(repeats):
        for name, (run, steps) in cases.items():
            wall, cpu = time.perf_counter(), time.process_time()
            run(steps)
            times[name].append(((time.perf_counter() - wall) / steps, (time.process_time() - cpu) / steps))
    return {name: (statistics.median(w for w, _ in v), statistics.median(c for _, c in v)) for name, v in times.items()}


def main(argv: list[str] | None = None) -> None:
    parser = parser_for("jax-env-step", __doc__)
    parser.add_argument("--num-envs", type=int, default=4096, help="robots per step (default 4096)")
    parser.add_argument("--threads", type=int, default=1, help="thread budget of both sides (default 1)")
    parser.add_argument("--repeats", type=int, default=7, help="interleaved repeats (default 7)")
    parser.add_argument("--steps", type=int, default=40, help="steps per repeat of the native env (default 40)")
    parser.add_argument("--scan", type=int, default=200, help="steps per compiled call in the scan case (default 200)")
    parser.add_argument("--reset-ratio", type=int, default=16, help="robots per new episode, optimistic case (16)")
    parser.add_argument("--docs", action="store_true", help="write docs/jax/env_step.json (and render docs/jax.md)")
    args = parser.parse_args(argv)
    if min(args.num_envs, args.threads, args.repeats, args.steps, args.scan, args.reset_ratio) < 1:
        parser.error("--num-envs, --threads, --repeats, --steps, --scan and --reset-ratio must be positive integers")
    if args.reset_ratio > args.num_envs:
        parser.error(f"--reset-ratio {args.reset_ratio} is invalid: expected at most --num-envs ({args.num_envs})")
    limit_threads(args.threads)
    import jax
    import numpy as np

    import dwr_gym  # noqa: F401

    actions = np.random.default_rng(0).uniform(-1, 1, (args.num_envs, 2)).astype(np.float32)
    load_before = os.getloadavg()[0]
    seconds: dict[str, tuple[float, float]] = {}
    for dtype in ("float64", "float32"):  # x64 set for the whole block: toggling it per call costs a re-trace check
        jax.config.update("jax_enable_x64", dtype == "float64")
        cases = {f"numpy vector env, {dtype}": (native_case(args.num_envs, dtype, actions), args.steps)}
        for how, run in jax_cases(args.num_envs, dtype, actions, args.scan, args.reset_ratio).items():
            steps = args.scan * max(1, 2 * args.steps // args.scan) if how.startswith("scan") else args.steps
            cases[f"JAX env {how}, {dtype}"] = (run, steps)
        seconds.update(measure(cases, args.repeats))
    reference = {dtype: seconds[f"numpy vector env, {dtype}"] for dtype in ("float64", "float32")}
    rows = []
    for name, (wall, cpu) in seconds.items():
        ref_wall, ref_cpu = reference[name.rsplit(", ", 1)[1]]
        rows.append({"case": name, "us_per_step": wall * 1e6, "env_steps_per_second": args.num_envs / wall,
                     "speedup": ref_wall / wall, "cpu_us_per_step": cpu * 1e6, "cpu_speedup": ref_cpu / cpu})  # fmt: skip
        print(f"{name:<36} {wall * 1e6:9.1f} us/step {args.num_envs / wall:13,.0f} env-steps/s {ref_wall / wall:6.2f}x "
              f"the numpy env's; CPU {cpu * 1e6:9.1f} us/step, {ref_cpu / cpu:6.2f}x")  # fmt: skip
    record = {"num_envs": args.num_envs, "threads": args.threads, "repeats": args.repeats, "scan": args.scan,
              "reset_ratio": args.reset_ratio,
              "env_id": ENV_ID, "rows": rows, "machine": f"{platform.machine()}, {os.cpu_count()} cores",
              "jax": jax.__version__, "numpy": np.__version__, "device": str(jax.devices()[0].platform),
              "load_average": [round(load_before, 1), round(os.getloadavg()[0], 1)]}  # fmt: skip
    if args.docs:
        write_json(JSON_PATH, record)


#: The table of docs/jax.md.
BLOCKS = (table("jax-env-step", Schema({"num_envs": int, "threads": int, "repeats": int, "env_id": str, "rows": list,
                                        "machine": str, "jax": str, "device": str, "load_average": list})),)  # fmt: skip

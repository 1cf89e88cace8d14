"""The jitted PPO of `dwr-gym train --backend jax` against `dwr-gym train`'s stable-baselines3 PPO.

    nice -n 10 python -m benchmarks run jax-training --threads 1 --docs   # docs/jax/training_speed_1thread.json
    nice -n 10 python -m benchmarks run jax-training --threads 2 --docs   # docs/jax/training_speed_2thread.json

Env steps per second including the updates, on DWRPointStabilization-v1 with the defaults of
train/hyperparams/ppo.yml (256 robots, rollouts of 64 steps, 4 epochs over minibatches of 1024), in one process
on one thread budget (``--threads``: XLA's and torch's threads, OMP_NUM_THREADS), alternating rounds so that the
ratios hold on a busy machine: SB3 PPO's ``learn`` on the native vector env (what `dwr-gym train` runs between
its evaluations), the jitted PPO on one seed, five seeds under ``vmap``, and the jitted rollout alone (the
functional env and the policy, no update: what limits the rest). Compilation is timed apart.
"""

from __future__ import annotations

import itertools
import os
import platform
import statistics
import time
from pathlib import Path
from typing import Any

from benchmarks.core.commands import parser_for
from benchmarks.core.docs import Schema, fenced
from benchmarks.core.record import report

ROOT = Path(__file__).resolve().parents[2]
OUT = ROOT / "docs" / "jax"
SPEED_GOALS = {"ratio_to_sb3": 10.0, "steps_per_second": 200_000.0, "vmap_ratio": 3.0}


def make_config() -> Any:
    """The TrainConfig of `dwr-gym train --backend jax` with the shipped PPO defaults."""
    from train.learning.config import TrainConfig
    from train.learning.hyperparams import resolve_hyperparams

    config = TrainConfig(backend="jax", progress=False)
    config.validate()
    return resolve_hyperparams(config, set())


def setup(config: Any) -> tuple[Any, Any, Any]:
    """(config, settings, JaxPPO) of ``config``."""
    from train.learning.jitted.policy import PPOSettings
    from train.learning.jitted.ppo import JaxPPO
    from train.learning.jitted.trainer import make_jax_env

    settings = PPOSettings.from_algo_kwargs(config.algo_kwargs, int(config.num_envs or 0))
    env, env_params = make_jax_env(config)
    return config, settings, JaxPPO(settings, env, env_params)


def timed(fn: Any, *args: Any) -> tuple[Any, float]:
    import jax

    began = time.perf_counter()
    out = jax.block_until_ready(fn(*args))
    return out, time.perf_counter() - began


def machine(threads: int) -> str:
    import jax
    import torch

    return (f"{platform.machine()}, {os.cpu_count()} cores, jax {jax.__version__} ({jax.default_backend()}), "
            f"torch {torch.__version__}; {threads} thread(s) each (XLA_FLAGS={os.environ.get('XLA_FLAGS', '')!r}, "
            f"torch threads {torch.get_num_threads()})")  # fmt: skip


def speed(threads: int, repeats: int, updates: int, seeds: int) -> dict[str, Any]:
    """Alternating rounds of SB3 PPO, the jitted PPO (one seed, ``seeds`` under vmap) and the jitted rollout."""
    import jax
    import numpy as np
    import torch
    from stable_baselines3 import PPO

    from train.learning.jitted.export import sb3_policy_kwargs
    from train.learning.training_env import make_training_env

    torch.set_num_threads(threads)
    config, settings, ppo = setup(make_config())
    per_update = settings.steps_per_update
    total = 1e9
    sb3 = PPO("MlpPolicy", make_training_env(config), seed=0, device="cpu", verbose=0,
              **sb3_policy_kwargs(config.algo_kwargs))  # fmt: skip
    sb3.learn(per_update)  # warm-up: the first rollout's allocations
    compile_s: dict[str, float] = {}
    (runner, _), compile_s["one_seed"] = timed(lambda: ppo.run(ppo.init(0), 1, total))
    keys = jax.random.split(jax.random.PRNGKey(0), seeds)
    (many, _), compile_s[f"{seeds}_seeds_vmap"] = timed(lambda: ppo.run_seeds(ppo.init_seeds(keys), 1, total))
    collect = jax.jit(ppo.collect)
    _, compile_s["rollout_only"] = timed(collect, runner)
    rounds = []
    for index in range(repeats):
        began = time.perf_counter()
        sb3.learn(updates * per_update, reset_num_timesteps=False)
        entry = {"sb3_ppo": updates * per_update / (time.perf_counter() - began)}
        (runner, _), elapsed = timed(ppo.run, runner, updates, total)
        entry["jax_one_seed"] = updates * per_update / elapsed
        (many, _), elapsed = timed(ppo.run_seeds, many, updates, total)
        entry[f"jax_{seeds}_seeds_vmap"] = seeds * updates * per_update / elapsed
        state = runner
        began = time.perf_counter()
        for _ in range(updates):
            state, _, _ = jax.block_until_ready(collect(state))
        entry["jax_rollout_only"] = updates * per_update / (time.perf_counter() - began)
        rounds.append(entry)
        print(f"round {index + 1}/{repeats}: " + ", ".join(f"{k} {v:,.0f}" for k, v in entry.items()), flush=True)
    median = {key: statistics.median(r[key] for r in rounds) for key in rounds[0]}
    ratio = statistics.median(r["jax_one_seed"] / r["sb3_ppo"] for r in rounds)
    vmap_ratio = statistics.median(r[f"jax_{seeds}_seeds_vmap"] / r["jax_one_seed"] for r in rounds)
    return {
        "machine": machine(threads), "threads": threads, "load_average_1min_at_end": round(os.getloadavg()[0], 2),
        "settings": settings.as_dict(), "steps_per_round": updates * per_update, "seeds": seeds,
        "compile_seconds": {k: round(v, 1) for k, v in compile_s.items()}, "rounds": rounds, "median_fps": median,
        "ratio_to_sb3": ratio, "vmap_ratio_to_sequential": vmap_ratio,
        "update_share": float(np.clip(1.0 - median["jax_one_seed"] / median["jax_rollout_only"], 0.0, 1.0)),
        "goals": SPEED_GOALS,
        "met": {"ratio_to_sb3": ratio >= SPEED_GOALS["ratio_to_sb3"],
                "steps_per_second": median["jax_one_seed"] >= SPEED_GOALS["steps_per_second"],
                "vmap_ratio": vmap_ratio >= SPEED_GOALS["vmap_ratio"]},
    }  # fmt: skip


def update_flops(settings: dict[str, Any], observation_size: int = 10, action_size: int = 2) -> float:
    """Floating-point operations of the updates per env step: n_epochs passes of a forward and a backward pass
    (taken as 3 forward passes) of the actor and the critic, 2 FLOP per multiply-add."""
    sizes = [observation_size, *settings["net_arch"]]
    hidden = sum(a * b for a, b in itertools.pairwise(sizes))  # multiply-adds of one MLP's hidden layers
    forward = 2 * hidden + sizes[-1] * (action_size + 1)  # actor and critic, their heads
    return float(settings["n_epochs"] * 3 * 2 * forward)


def render_speed(data: dict[str, Any]) -> list[str]:
    fps, seeds = data["median_fps"], data["seeds"]
    names = {"sb3_ppo": "dwr-gym train (SB3 PPO, torch, native vector env)",
             "jax_one_seed": "--backend jax, one seed", f"jax_{seeds}_seeds_vmap": f"--backend jax, {seeds} seeds "
             "under vmap (total)", "jax_rollout_only": "jitted rollout alone (env + policy, no update)"}  # fmt: skip
    lines = [data["machine"], f"load average {data['load_average_1min_at_end']} (1 min, at the end); "
             f"{len(data['rounds'])} alternating rounds of {data['steps_per_round']:,} steps; medians", "",
             f"{'run':<58}{'env steps/s':>12}{'/ SB3':>8}"]  # fmt: skip
    for key, name in names.items():
        lines.append(f"{name:<58}{fps[key]:>12,.0f}{fps[key] / fps['sb3_ppo']:>7.1f}x")
    compile_s = ", ".join(f"{k} {v:.0f} s" for k, v in data["compile_seconds"].items())
    met = {k: "met" if v else "NOT met" for k, v in data["met"].items()}
    lines += ["", f"compilation (apart from the rates): {compile_s}",
              f"updates' share of the one-seed time: {data['update_share']:.0%}; their arithmetic: "
              f"{update_flops(data['settings']) / 1e6:.2f} MFLOP per env step",
              f"goal >= {data['goals']['ratio_to_sb3']:.0f}x SB3: {data['ratio_to_sb3']:.1f}x, {met['ratio_to_sb3']}",
              f"goal >= {data['goals']['steps_per_second']:,.0f} steps/s: {fps['jax_one_seed']:,.0f}, "
              f"{met['steps_per_second']}",
              f"goal {seeds} seeds under vmap >= {data['goals']['vmap_ratio']:.0f}x {seeds} sequential runs: "
              f"{data['vmap_ratio_to_sequential']:.1f}x, {met['vmap_ratio']}"]  # fmt: skip
    return lines


SPEED = Schema(
    {
        "machine": str,
        "load_average_1min_at_end": (int, float),
        "settings": dict,
        "steps_per_round": int,
        "seeds": int,
        "compile_seconds": dict,
        "rounds": list,
        "median_fps": dict,
        "ratio_to_sb3": (int, float),
        "vmap_ratio_to_sequential": (int, float),
        "update_share": (int, float),
        "goals": dict,
        "met": dict,
    }
)
#: The blocks of docs/jax-training.md.
BLOCKS = (fenced("jax-training-speed", "docs/jax/training_speed_1thread.json", render_speed, SPEED),
          fenced("jax-training-speed-2threads", "docs/jax/training_speed_2thread.json", render_speed, SPEED))  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    parser = parser_for("jax-training", __doc__)
    parser.add_argument("--threads", type=int, default=1, help="XLA and torch threads (default: 1)")
    parser.add_argument("--repeats", type=int, default=3, help="speed: alternating rounds (default: 3)")
    parser.add_argument("--updates", type=int, default=8, help="speed: PPO updates per round (default: 8)")
    parser.add_argument("--seeds", type=int, default=5, help="seeds under vmap (default: 5)")
    parser.add_argument(
        "--docs", action="store_true", help="write docs/jax/*.json and render docs/jax-training.md's blocks"
    )
    args = parser.parse_args(argv)
    for name in ("threads", "repeats", "updates", "seeds"):
        if getattr(args, name) < 1:
            parser.error(f"--{name.replace('_', '-')}={getattr(args, name)} is invalid: expected a positive integer")
    from train.learning.jitted.setup import configure_threads

    # one thread budget for XLA and torch, before either is imported: one thread (XLA without its Eigen pool), or
    # XLA's default pool (every core) beside torch on --threads threads
    os.environ["OMP_NUM_THREADS"] = str(args.threads)
    configure_threads(args.threads)
    data = speed(args.threads, args.repeats, args.updates, args.seeds)
    return report(render_speed(data), data, OUT / f"training_speed_{args.threads}thread.json" if args.docs else None)

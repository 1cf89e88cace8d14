"""The jitted PPO of `dwr-gym train --backend jax` against `dwr-gym train`'s stable-baselines3 PPO.

    nice -n 10 python -m benchmarks run jax-training speed --threads 1 --docs   # docs/jax/training_speed_1thread.json
    nice -n 10 python -m benchmarks run jax-training speed --threads 2 --docs   # docs/jax/training_speed_2thread.json
    nice -n 5 python -m benchmarks run jax-training learn --budget 1380 --eval-every 30 --docs \
        --hyperparams "policy_kwargs=dict(net_arch=[64, 64], normalize_observations=True)"  # time_to_criteria.json

``speed``: env steps per second including the updates, on DWRPointStabilization-v1 with the defaults of
train/hyperparams/ppo.yml (256 robots, rollouts of 64 steps, 4 epochs over minibatches of 1024), in one process
on one thread budget (``--threads``: XLA's and torch's threads, OMP_NUM_THREADS), alternating rounds so that the
ratios hold on a busy machine: SB3 PPO's ``learn`` on the native vector env (what `dwr-gym train` runs between
its evaluations), the jitted PPO on one seed, five seeds under ``vmap``, and the jitted rollout alone (the
functional env and the policy, no update: what limits the rest). Compilation is timed apart.

``learn``: wall-clock time from scratch (compilation included) until each of five seeds, trained together under
``vmap``, meets the RL benchmark's criteria on `dwr-gym train`'s fixed evaluation set (100 starts of v1, seed 12345):
in time >= 99 %, energy / optimum <= 1.5 (mean over the episodes in time), mean final heading error <= 0.1 rad.
Each evaluation exports each seed's policy into an SB3 model and runs the SB3 path's rollout on the numpy env;
the time it takes counts. Process CPU time is recorded beside wall time, since the machine is shared.
"""

from __future__ import annotations

import itertools
import math
import os
import platform
import statistics
import time
from pathlib import Path
from typing import Any

from benchmarks.core.commands import parser_for
from benchmarks.core.docs import Schema, fenced
from benchmarks.core.record import write_json


def set_threads(threads: int) -> None:
    """One thread budget for XLA and torch, before either is imported: one thread (XLA without its Eigen pool),
    or XLA's default pool (every core: 2 here) beside torch on ``threads`` threads."""
    os.environ["OMP_NUM_THREADS"] = str(threads)
    if threads == 1:
        flags = "--xla_cpu_multi_thread_eigen=false intra_op_parallelism_threads=1"
        os.environ["XLA_FLAGS"] = f"{os.environ.get('XLA_FLAGS', '')} {flags}".strip()


ROOT = Path(__file__).resolve().parents[2]
OUT = ROOT / "docs" / "jax"
SPEED_GOALS = {"ratio_to_sb3": 10.0, "steps_per_second": 200_000.0, "vmap_ratio": 3.0}
CRITERIA = {"in_time": 0.99, "energy_ratio": 1.5, "final_heading": 0.1}
TIME_GOAL_S = 300.0


def make_config(overrides: dict[str, Any] | None = None) -> Any:
    """The TrainConfig of `dwr-gym train --backend jax` with the shipped PPO defaults and ``overrides``."""
    from train.learning.config import TrainConfig
    from train.learning.hyperparams import resolve_hyperparams

    config = TrainConfig(backend="jax", progress=False, hyperparam_overrides=dict(overrides or {}))
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


def meets(row: dict[str, Any]) -> bool:
    ratio = row["energy_ratio"]
    return (row["in_time"] >= CRITERIA["in_time"] and ratio is not None and ratio <= CRITERIA["energy_ratio"]
            and row["final_heading"] <= CRITERIA["final_heading"])  # fmt: skip


def learn(seeds: int, eval_every: int, budget_s: float, overrides: dict[str, Any]) -> dict[str, Any]:
    """Train ``seeds`` seeds together under vmap, evaluating every ``eval_every`` updates, until all meet the
    criteria or ``budget_s`` seconds of wall clock pass."""
    from train.evaluation.evaluate import evaluate
    from train.evaluation.scenarios import make_scenario

    config = make_config(overrides)
    scenario = make_scenario("random", n=config.eval_episodes, seed=config.eval_seed, env_kwargs=config.env_keywords())
    evaluate({"ptc": "ptc"}, scenario, optimum="pose")  # the optimum's energies, solved (or cached) before jax starts
    import jax
    import numpy as np

    from train.learning.jitted.export import SB3Exporter
    from train.learning.jitted.trainer import export_runner
    from train.learning.training_env import make_training_env

    config, settings, ppo = setup(config)
    exporter = SB3Exporter(make_training_env(config), config.algo_kwargs)
    keys = jax.random.split(jax.random.PRNGKey(config.seed), seeds)
    wall0, cpu0 = time.perf_counter(), time.process_time()
    runners = ppo.init_seeds(keys)
    curves: list[list[dict[str, Any]]] = [[] for _ in range(seeds)]
    reached: list[dict[str, Any] | None] = [None] * seeds
    compile_s = None
    while time.perf_counter() - wall0 < budget_s and not all(reached):
        runners, _ = ppo.run_seeds(runners, eval_every, 1e9)
        jax.block_until_ready(runners)
        compile_s = compile_s or time.perf_counter() - wall0
        steps = int(runners.updates[0]) * settings.steps_per_update
        for seed in range(seeds):
            one = jax.tree.map(lambda x, i=seed: x[i], runners)
            model = export_runner(exporter, ppo, one, steps)
            result = evaluate({"agent": model}, scenario, optimum="pose", record=True)["agent"]
            summary, path = result.summary(), result.trajectory or {}
            turning = float(np.sum(np.square(path["angular_velocity"])))
            row = {"steps": steps, "wall_s": round(time.perf_counter() - wall0, 1),
                   "cpu_s": round(time.process_time() - cpu0, 1), "in_time": summary["success_rate"],
                   "energy_ratio": None if math.isnan(summary["energy_ratio_mean"]) else summary["energy_ratio_mean"],
                   "final_heading": summary["final_heading_error_mean"], "energy": summary["energy_mean"],
                   "optimal_energy": summary["optimal_energy_mean"],
                   "arrival_fraction": summary["arrival_fraction_mean"],
                   "turning_share": turning / max(turning + float(np.sum(np.square(path["linear_velocity"]))), 1e-12)}  # fmt: skip
            curves[seed].append(row)
            if reached[seed] is None and meets(row):
                reached[seed] = row
        print(f"{steps:>10,} steps {curves[0][-1]['wall_s']:>7.0f} s: " + "; ".join(
            f"{c[-1]['in_time']:.2f} {c[-1]['energy_ratio'] or math.nan:.2f} {c[-1]['final_heading']:.2f}"
            for c in curves), flush=True)  # fmt: skip
    times = [r["wall_s"] if r else None for r in reached]
    return {
        "machine": machine(int(os.environ.get("OMP_NUM_THREADS", "1"))),
        "load_average_1min_at_end": round(os.getloadavg()[0], 2), "settings": settings.as_dict(),
        "overrides": overrides, "seeds": seeds, "eval_every_steps": eval_every * settings.steps_per_update,
        "evaluation_set": f"random, {config.eval_episodes} starts, seed {config.eval_seed} ({config.env_id})",
        "criteria": CRITERIA, "budget_s": budget_s, "compile_and_first_chunk_s": round(compile_s or 0.0, 1),
        "reached": reached, "curves": curves, "goal_s": TIME_GOAL_S,
        "met": all(t is not None and t <= TIME_GOAL_S for t in times),
        "median_time_s": statistics.median(t if t is not None else math.inf for t in times),
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


def render_learn(data: dict[str, Any]) -> list[str]:
    c = data["criteria"]
    lines = [data["machine"], f"load average {data['load_average_1min_at_end']} (1 min, at the end); "
             f"{data['seeds']} seeds under vmap; overrides {data['overrides'] or 'none'}",
             f"criteria on {data['evaluation_set']}: in time >= {c['in_time']:.0%}, E/opt <= {c['energy_ratio']}, "
             f"final heading <= {c['final_heading']} rad; evaluated every {data['eval_every_steps']:,} steps",
             f"compilation and first chunk: {data['compile_and_first_chunk_s']:.0f} s", "",
             f"{'seed':<6}{'reached at steps':>17}{'wall s':>9}{'CPU s':>9}{'in time':>9}{'E/opt':>7}{'heading':>9}"]  # fmt: skip
    for seed, (row, curve) in enumerate(zip(data["reached"], data["curves"], strict=True)):
        last = row or curve[-1]
        steps = f"{row['steps']:,}" if row else f"not by {last['steps']:,}"
        lines.append(f"{seed:<6}{steps:>17}{last['wall_s']:>9.0f}{last['cpu_s']:>9.0f}{last['in_time']:>9.0%}"
                     f"{last['energy_ratio'] or math.nan:>7.2f}{last['final_heading']:>9.3f}")  # fmt: skip
    first = [next((r for r in curve if r["in_time"] >= c["in_time"]), None) for curve in data["curves"]]
    lines += ["", f"in time >= {c['in_time']:.0%} alone, first reached (steps, wall s): " + "; ".join(
        f"seed {i}: {r['steps']:,}, {r['wall_s']:.0f} s" if r else f"seed {i}: not reached" for i, r in enumerate(first))]  # fmt: skip
    last = [curve[-1] for curve in data["curves"]]
    lines += ["", "at the last evaluation, median over seeds: energy "
              f"{statistics.median(r['energy'] for r in last):.2f} (optimum {last[0]['optimal_energy']:.2f}), arrival at "
              f"{statistics.median(r['arrival_fraction'] for r in last):.0%} of T_con, "
              f"{statistics.median(r['turning_share'] for r in last):.0%} of the squared commands from turning"]  # fmt: skip
    verdict = "met" if data["met"] else "NOT met"
    lines += ["", f"goal <= {data['goal_s']:.0f} s each: median {data['median_time_s']:.0f} s, {verdict}"]
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
          fenced("jax-training-speed-2threads", "docs/jax/training_speed_2thread.json", render_speed, SPEED),
          fenced("jax-time-to-criteria", "docs/jax/time_to_criteria.json", render_learn,
                 Schema({"machine": str, "settings": dict, "seeds": int, "criteria": dict, "reached": list,
                         "curves": list, "goal_s": (int, float), "met": bool, "median_time_s": (int, float)})))  # fmt: skip


def main(argv: list[str] | None = None) -> None:
    parser = parser_for("jax-training", __doc__)
    parser.add_argument("what", nargs="?", choices=("speed", "learn"), help="the measurement to run")
    parser.add_argument("--threads", type=int, default=1, help="XLA and torch threads (default: 1)")
    parser.add_argument("--repeats", type=int, default=3, help="speed: alternating rounds (default: 3)")
    parser.add_argument("--updates", type=int, default=8, help="speed: PPO updates per round (default: 8)")
    parser.add_argument("--seeds", type=int, default=5, help="seeds under vmap (default: 5)")
    parser.add_argument("--eval-every", type=int, default=10, help="learn: updates between evaluations (default: 10)")
    parser.add_argument("--budget", type=float, default=1800.0, help="learn: wall-clock budget, s (default: 1800)")
    parser.add_argument("--hyperparams", nargs="*", default=[], metavar="KEY=VALUE", help="learn: overrides")
    parser.add_argument(
        "--docs", action="store_true", help="write docs/jax/*.json and render docs/jax-training.md's blocks"
    )
    args = parser.parse_args(argv)
    if args.what is None:
        parser.error("expected speed or learn")
    for name in ("threads", "repeats", "updates", "seeds", "eval_every"):
        if getattr(args, name) < 1:
            parser.error(f"--{name.replace('_', '-')}={getattr(args, name)} is invalid: expected a positive integer")
    set_threads(args.threads)  # before jax and torch are imported
    if args.what == "speed":
        data, file = (
            speed(args.threads, args.repeats, args.updates, args.seeds),
            f"training_speed_{args.threads}thread.json",
        )
        lines = render_speed(data)
    else:
        from train.learning.hyperparams import parse_overrides

        data = learn(args.seeds, args.eval_every, args.budget, parse_overrides(args.hyperparams))
        file, lines = "time_to_criteria.json", render_learn(data)
    print("\n".join(lines))
    if args.docs:
        write_json(OUT / file, data)

"""`dwr-gym train` with its defaults against stable-baselines3's PPO with its defaults on CartPole-v1, in one run.

    OMP_NUM_THREADS=1 nice -n 10 python -m benchmarks run training-speed --docs   # docs/training/speed.json, its block

The busy-machine goal: `dwr-gym train` with its defaults (PPO on DWRPointStabilization-v1, evaluations and
checkpoints included) runs at >= 20x the env steps per second of ``PPO("MlpPolicy", "CartPole-v1")``,
both on one thread. Both are timed alternately in this process (``--repeats`` rounds), with the old
defaults of `dwr-gym train` (16 robots, n_steps 256, batch 512, 10 epochs, evaluations every 20,000 and
checkpoints every 50,000 steps) as a third entry, so that the ratios hold on a busy machine: each is a median
of per-round ratios against CartPole measured minutes apart. The absolute rates depend on the machine's load,
which is recorded (``os.getloadavg``).
"""

from __future__ import annotations

import os

os.environ.setdefault("OMP_NUM_THREADS", "1")  # before torch is imported: one thread, as the goal says

import platform
import tempfile
import time
from pathlib import Path
from typing import Any

from benchmarks.core.commands import parser_for
from benchmarks.core.docs import NUMBER, Schema, fenced
from benchmarks.core.record import load_average, report
from benchmarks.core.timing import median_ratio, medians

ROOT = Path(__file__).resolve().parents[2]
JSON_PATH = ROOT / "docs" / "training" / "speed.json"
GOAL = 20.0
OLD_DEFAULTS = {"num_envs": 16, "eval_freq": 20_000, "checkpoint_freq": 50_000,
                "hyperparam_overrides": {"n_steps": 256, "batch_size": 512, "n_epochs": 10}}  # fmt: skip
"""`dwr-gym train`'s defaults before the batch-sized defaults (PPO; the rest of train/hyperparams/ppo.yml unchanged)."""


def cartpole_fps(steps: int) -> float:
    """Env steps per second of stable-baselines3's PPO with its defaults on CartPole-v1."""
    from stable_baselines3 import PPO

    model = PPO("MlpPolicy", "CartPole-v1", seed=0, device="cpu", verbose=0)
    began = time.perf_counter()
    model.learn(steps)
    return model.num_timesteps / (time.perf_counter() - began)


def train_fps(steps: int, old: bool) -> float:
    """Env steps per second of `dwr-gym train` with its defaults (or the old ones), evaluations and
    checkpoints included, timed around the whole of ``train`` as the CLI runs it."""
    from train.learning.config import TrainConfig
    from train.learning.hyperparams import resolve_hyperparams
    from train.learning.runs import read_state
    from train.learning.training import train

    with tempfile.TemporaryDirectory() as tmp:
        extra: dict[str, Any] = dict(OLD_DEFAULTS) if old else {}
        config = TrainConfig(total_timesteps=steps, run_dir=f"{tmp}/run", progress=False, **extra)
        config.validate()
        explicit = {"total_timesteps", *extra}
        resolve_hyperparams(config, explicit)
        began = time.perf_counter()
        run_dir = train(config, command=["python", "-m", "benchmarks", "run", "training-speed"])
        elapsed = time.perf_counter() - began
        return int(read_state(run_dir)["timesteps"]) / elapsed


def run(repeats: int, cartpole_steps: int, new_steps: int, old_steps: int) -> dict[str, Any]:
    """Alternate the three measurements ``repeats`` times; the medians and the per-round ratios."""
    import torch

    torch.set_num_threads(1)
    rounds = []
    for index in range(repeats):
        entry = {"cartpole_sb3_ppo": cartpole_fps(cartpole_steps), "train_defaults": train_fps(new_steps, old=False),
                 "train_old_defaults": train_fps(old_steps, old=True)}  # fmt: skip
        rounds.append(entry)
        print(
            f"round {index + 1}/{repeats}: " + ", ".join(f"{k} {v:,.0f} steps/s" for k, v in entry.items()), flush=True
        )
    ratio = median_ratio(rounds, "train_defaults", "cartpole_sb3_ppo")
    return {
        "machine": f"{platform.machine()}, {os.cpu_count()} cores, torch {torch.__version__}, "
        f"OMP_NUM_THREADS={os.environ.get('OMP_NUM_THREADS')}, torch threads {torch.get_num_threads()}",
        "load_average_1min_at_end": load_average(),
        "steps": {"cartpole_sb3_ppo": cartpole_steps, "train_defaults": new_steps, "train_old_defaults": old_steps},
        "rounds": rounds,
        "median_fps": medians(rounds),
        "ratio_train_defaults_to_cartpole": ratio,
        "ratio_train_old_defaults_to_cartpole": median_ratio(rounds, "train_old_defaults", "cartpole_sb3_ppo"),
        "ratio_new_to_old_defaults": median_ratio(rounds, "train_defaults", "train_old_defaults"),
        "goal": GOAL,
        "met": ratio >= GOAL,
    }


def render(results: dict[str, Any]) -> list[str]:
    """The docs block: rates, ratios and the goal, from the JSON."""
    fps, steps = results["median_fps"], results["steps"]
    names = {"cartpole_sb3_ppo": 'SB3 PPO("MlpPolicy", "CartPole-v1"), its defaults',
             "train_defaults": "dwr-gym train, defaults (256 robots, evals + checkpoints)",
             "train_old_defaults": "dwr-gym train, old defaults (16 robots, evals + checkpoints)"}  # fmt: skip
    lines = [f"{results['machine']}; load average {results['load_average_1min_at_end']} (1 min, at the end)",
             f"{len(results['rounds'])} rounds, alternating; medians", "",
             f"{'run':<62}{'env steps':>11}{'steps/s':>10}{'/ CartPole':>12}"]  # fmt: skip
    for key, name in names.items():
        ratio = median_ratio(results["rounds"], key, "cartpole_sb3_ppo")
        lines.append(f"{name:<62}{steps[key]:>11,}{fps[key]:>10,.0f}{ratio:>11.1f}x")
    verdict = "met" if results["met"] else "NOT met"
    per_round = ", ".join(f"{r['train_defaults'] / r['cartpole_sb3_ppo']:.1f}x" for r in results["rounds"])
    lines += ["", f"dwr-gym train defaults / CartPole, per round: {per_round}",
              f"new defaults / old defaults: {results['ratio_new_to_old_defaults']:.1f}x",
              f"the busy-machine goal, dwr-gym train defaults >= {results['goal']:.0f}x SB3 PPO on CartPole-v1: "
              f"{results['ratio_train_defaults_to_cartpole']:.1f}x, {verdict}"]  # fmt: skip
    return lines


def main(argv: list[str] | None = None) -> int:
    parser = parser_for("training-speed", __doc__)
    parser.add_argument("--repeats", type=int, default=3, help="alternating rounds (default: 3)")
    parser.add_argument("--cartpole-steps", type=int, default=16_384, help="SB3 PPO on CartPole (default: 16384)")
    parser.add_argument("--steps", type=int, default=524_288,
                        help="dwr-gym train with its defaults (default: 524288: 2 evaluations, 1 checkpoint)")  # fmt: skip
    parser.add_argument("--old-steps", type=int, default=65_536, help="dwr-gym train, old defaults (default: 65536)")
    parser.add_argument("--docs", action="store_true", help=f"write {JSON_PATH.relative_to(ROOT)} and render its block")
    args = parser.parse_args(argv)
    for name in ("repeats", "cartpole_steps", "steps", "old_steps"):
        if getattr(args, name) < 1:
            parser.error(f"--{name.replace('_', '-')}={getattr(args, name)} is invalid: expected a positive integer")
    results = run(args.repeats, args.cartpole_steps, args.steps, args.old_steps)
    return report(render(results), results, JSON_PATH if args.docs else None)


#: The block of docs/training.md.
BLOCKS = (fenced("training-speed", "docs/training/speed.json", render,
                 Schema({"machine": str, "load_average_1min_at_end": NUMBER, "steps": dict, "rounds": list,
                         "median_fps": dict, "ratio_train_defaults_to_cartpole": NUMBER,
                         "ratio_new_to_old_defaults": NUMBER, "goal": NUMBER, "met": bool})),)  # fmt: skip

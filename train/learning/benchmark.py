"""``dwr-gym benchmark``: train every agent x seed from v1's reward, evaluate, and keep the results.

An *entry* is a name and either the options of ``dwr-gym train`` (:data:`ENTRIES`, or ``NAME:KEY=VALUE,...``
on the command line) or, from Python, any function ``make(seed, run_dir) -> policy`` whose policy has
stable-baselines3's ``predict`` (:class:`Entry`). Each (entry, seed) trains in ``<out>/runs/<name>-seed<seed>``
(its learning curve: ``evaluations.csv`` on the benchmark's nominal set) and is evaluated once finished on the
nominal and disturbed sets (:mod:`train.evaluation.benchmark`); the result is ``<out>/results/<name>-seed<seed>.json``.
A run whose result exists is not run again, so an interrupted benchmark continues where it stopped.
:mod:`train.reporting.rl_benchmark` aggregates the results over seeds.
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from train.env_ids import TASK_ENV_ID
from train.evaluation.benchmark import (
    DISTURBED_EPISODES,
    EVAL_EPISODES,
    EVAL_SEED,
    OPTIMUM_EPISODES,
    PER_T_CON_EPISODES,
    evaluate_policy,
)
from train.learning.config import ConfigError, TrainConfig
from train.learning.hyperparams import HYPERPARAMS_DIR

V2 = "DWRPointStabilization-v2"
#: The env of an entry that names none: v1, whose reward the benchmark's first entries (ppo, sac, ...) learned from
#: and whose published tables they are; the entries of v2 name it.
ENTRY_ENV_ID = TASK_ENV_ID


def apg_teacher_time_scaled(total_timesteps: int, **overrides: Any) -> dict[str, Any]:
    """An entry of APG from its open-loop teacher (train/hyperparams/apg_teacher.yml, ``overrides`` on top) with
    time-scaled actions on v2, for ``total_timesteps`` env steps, its curve evaluated 14 times."""
    entry: dict[str, Any] = {"algo": "apg", "backend": "jax", "env_id": V2,
                             "hyperparams": str(HYPERPARAMS_DIR / "apg_teacher.yml")}  # fmt: skip
    if overrides:
        entry["hyperparam_overrides"] = overrides
    every = total_timesteps // 14
    return {**entry, "action_time_scale": 10.0, "total_timesteps": total_timesteps, "eval_freq": every,
            "checkpoint_freq": every}  # fmt: skip


#: The shipped entries: the options of ``dwr-gym train`` each one trains with (on top of train/hyperparams/).
ENTRIES: dict[str, dict[str, Any]] = {
    "ppo": {"algo": "ppo"},
    "ppo-jax": {"algo": "ppo", "backend": "jax"},
    # evolution strategies on the JAX env (train/hyperparams/es.yml): a generation is some 500,000 env steps, so
    # its curve is evaluated every 5 M of them rather than at the benchmark's --eval-freq
    "es": {"algo": "es", "backend": "jax", "eval_freq": 5_000_000, "checkpoint_freq": 5_000_000},
    # the same on v1 with an arena of 50 m: leaving v1's 5 m arena ends an episode at a cost (-10 + the start's
    # potential) that a policy which cannot yet arrive prefers to the late penalty, a trap ES falls into
    # (docs/evolution.md); the evaluation is on v1 as registered
    "es-arena50": {
        "algo": "es",
        "backend": "jax",
        "eval_freq": 5_000_000,
        "checkpoint_freq": 5_000_000,
        "env_kwargs": {"arena_radius": 50.0},
    },
    "es-v2": {"algo": "es", "backend": "jax", "env_id": V2, "eval_freq": 5_000_000, "checkpoint_freq": 5_000_000},
    # the same with time-scaled actions (train.learning.time_scale): the action times min(1, 10 s / T_con), so that one
    # behaviour in the time fraction serves every T_con, as the optimum's commands scale
    "es-time-scaled-v2": {
        "algo": "es",
        "backend": "jax",
        "env_id": V2,
        "action_time_scale": 10.0,
        "eval_freq": 5_000_000,
        "checkpoint_freq": 5_000_000,
    },
    "sac": {"algo": "sac"},
    "td3": {"algo": "td3"},
    "tqc": {"algo": "tqc"},
    "crossq": {"algo": "crossq"},
    "residual-ppo": {"algo": "ppo", "residual": True, "expert": "ptc"},
    "residual-ppo-astolfi": {"algo": "ppo", "residual": True, "expert": "pt-astolfi"},
    # the residual inside the jitted PPO's compiled loop (train.learning.jitted.residual): millions of steps per run
    "residual-ppo-jax": {"algo": "ppo", "backend": "jax", "residual": True, "expert": "ptc"},
    "residual-ppo-jax-astolfi": {"algo": "ppo", "backend": "jax", "residual": True, "expert": "pt-astolfi"},
    "residual-ppo-jax-v2": {
        "algo": "ppo",
        "backend": "jax",
        "residual": True,
        "expert": "ptc",
        "env_id": "DWRPointStabilization-v2",
    },
    "residual-ppo-jax-astolfi-v2": {
        "algo": "ppo",
        "backend": "jax",
        "residual": True,
        "expert": "pt-astolfi",
        "env_id": "DWRPointStabilization-v2",
    },
    # sbx-rl, the JAX stable-baselines: the same algorithms and settings, compiled by XLA
    "sac-sbx": {"algo": "sac", "backend": "sbx"},
    "tqc-sbx": {"algo": "tqc", "backend": "sbx"},
    "crossq-sbx": {"algo": "crossq", "backend": "sbx"},
    # the task held to T_con: gamma 1 (the v2 sections of train/hyperparams/), the jitted PPO with its
    # exploration noise on a fixed schedule, the off-policy learners of sbx
    "ppo-jax-v2": {"algo": "ppo", "backend": "jax", "env_id": V2},
    "ppo-jax-fixed-noise-v2": {
        "algo": "ppo",
        "backend": "jax",
        "env_id": V2,
        "hyperparams": str(HYPERPARAMS_DIR / "ppo_jax_v2.yml"),
    },
    # ES on a residual (train/hyperparams/residual_es.yml): the search starts at the expert and pays nothing for
    # exploring; a generation is about 1 M env steps (sigma 0.02 and a step of 0.002: from the expert, larger steps
    # first lose the arrival, measured on one seed)
    "es-residual-v2": {
        "algo": "es",
        "backend": "jax",
        "env_id": V2,
        "residual": True,
        "expert": "ptc",
        "eval_freq": 5_000_000,
        "checkpoint_freq": 5_000_000,
    },
    "es-residual-astolfi-v2": {
        "algo": "es",
        "backend": "jax",
        "env_id": V2,
        "residual": True,
        "expert": "pt-astolfi",
        "eval_freq": 5_000_000,
        "checkpoint_freq": 5_000_000,
    },
    # analytic policy gradients through the JAX env (train/hyperparams/apg.yml): an update is some 45,000 env steps
    # (64 episodes); from scratch (the curve evaluated every 25 M), and as a residual on PTC (every 10 M)
    "apg-v2": {
        "algo": "apg",
        "backend": "jax",
        "env_id": V2,
        "eval_freq": 25_000_000,
        "checkpoint_freq": 25_000_000,
    },
    # the residual on PTC by APG (train/hyperparams/residual_apg.yml): the shipped apg_residual_ptc_v2's entry
    "apg-residual-v2": {
        "algo": "apg",
        "backend": "jax",
        "env_id": V2,
        "residual": True,
        "expert": "ptc",
        "eval_freq": 10_000_000,
        "checkpoint_freq": 10_000_000,
    },
    # the same, its policy first cloned from an open-loop teacher (train/hyperparams/apg_teacher.yml)
    "apg-teacher-v2": {
        "algo": "apg",
        "backend": "jax",
        "env_id": V2,
        "hyperparams": str(HYPERPARAMS_DIR / "apg_teacher.yml"),
        "eval_freq": 25_000_000,
        "checkpoint_freq": 25_000_000,
    },
    # and with time-scaled actions (the action times min(1, 10 s / T_con): one behaviour for every T_con)
    "apg-teacher-time-scaled-v2": {
        "algo": "apg",
        "backend": "jax",
        "env_id": V2,
        "hyperparams": str(HYPERPARAMS_DIR / "apg_teacher.yml"),
        "action_time_scale": 10.0,
        "eval_freq": 25_000_000,
        "checkpoint_freq": 25_000_000,
    },
    # and the same for the goal's whole 30 minutes a seed: 700 M env steps (the 400 M runs took about 15 minutes of a
    # core alone and were still climbing when their rate reached 0), its rate decaying over them
    "apg-teacher-time-scaled-30min-v2": apg_teacher_time_scaled(700_000_000),
    # the lesson fitted 4x longer (clone_steps 16000: the clone 23 % in time, not 9 %) and the episodes that end near the
    # goal but outside its tolerance clipped at 16 (near_miss_clip: the arrival bonus, a step, has no gradient);
    # 560 M env steps, the goal's 30 minutes of a core
    "apg-near-miss-time-scaled-30min-v2": apg_teacher_time_scaled(560_000_000, clone_steps=16000, near_miss_clip=16.0),
    # and the miss over the last 20 control periods (1 s) before T_con in the gradient too (hold_steps: at the goal
    # a little early and still there, the robot is within the tolerance at T_con whatever the timing of its last steps)
    "apg-hold-time-scaled-30min-v2": apg_teacher_time_scaled(
        560_000_000, clone_steps=16000, near_miss_clip=16.0, hold_steps=20
    ),
    # and the heading's error over the same window, 5 per radian, linear near 0 (hold_heading_weight: v2's 5 (cos psi - 1)
    # has a vanishing gradient there, and the updates after the clone trade the heading for the arrival)
    "apg-hold-heading-time-scaled-30min-v2": apg_teacher_time_scaled(
        560_000_000, clone_steps=16000, near_miss_clip=16.0, hold_steps=20, hold_heading_weight=5.0
    ),
    # and twice that weight (10 per radian): at 5 the heading ends at 0.13 rad (IQM of 5 seeds), at 20 at 0.026 rad but
    # in time on 87.5 % (one seed)
    "apg-hold-heading10-time-scaled-30min-v2": apg_teacher_time_scaled(
        560_000_000, clone_steps=16000, near_miss_clip=16.0, hold_steps=20, hold_heading_weight=10.0
    ),
    # the deadline and the heading as constraints (train.learning.jitted.lagrangian): multipliers per T_con bin in
    # place of the hand-set weights (hold_weight, hold_heading_weight), over the same window of 20 control periods
    # before T_con, the near misses' clip kept (without it the deadline's multipliers sit at their ceiling and 20-30 %
    # of episodes stay late: docs/rl-constrained.md); 560 M env steps, the 30 minutes of one core a seed
    "apg-lagrangian-v2": apg_teacher_time_scaled(
        560_000_000, clone_steps=16000, near_miss_clip=16.0, hold_steps=20, lagrangian=1
    ),
    # and the weights' moving average (weight_average: Polyak averaging over some 200 updates) validated and exported
    # in place of the last network: late in a run the network's in-time rate swings by 5-10 points at T_con 10 s from
    # one evaluation to the next, the step's swing, and the average sits inside it
    "apg-lagrangian-averaged-v2": apg_teacher_time_scaled(
        560_000_000, clone_steps=16000, near_miss_clip=16.0, hold_steps=20, lagrangian=1, weight_average=0.995
    ),
    "apg-lagrangian-residual-ptc-v2": {
        "algo": "apg",
        "backend": "jax",
        "env_id": V2,
        "residual": True,
        "expert": "ptc",
        "hyperparam_overrides": {"lagrangian": 1, "hold_steps": 20},
        "total_timesteps": 30_000_000,
        "eval_freq": 5_000_000,
        "checkpoint_freq": 5_000_000,
    },
    # PPO-Lagrangian (train.learning.jitted.ppo_lagrangian), the on-policy reference of constrained RL: the v2 recipe
    # of the jitted PPO (gamma 1, the noise on its fixed schedule) with a cost critic and the same multipliers per
    # T_con bin as the Lagrangian APG
    "ppo-lagrangian-v2": {
        "algo": "ppo",
        "backend": "jax",
        "env_id": V2,
        "hyperparams": str(HYPERPARAMS_DIR / "ppo_jax_v2.yml"),
        "hyperparam_overrides": {"lagrangian": 1},
    },
    "sac-sbx-v2": {"algo": "sac", "backend": "sbx", "env_id": V2},
    "tqc-sbx-v2": {"algo": "tqc", "backend": "sbx", "env_id": V2},
    "crossq-sbx-v2": {"algo": "crossq", "backend": "sbx", "env_id": V2},
}
# PPO-Lagrangian for the 30 minutes of one core a seed (60 M env steps at its 33,000 a second), its schedules over them
ENTRIES["ppo-lagrangian-30min-v2"] = {**ENTRIES["ppo-lagrangian-v2"], "total_timesteps": 60_000_000,
                                      "eval_freq": 6_000_000, "checkpoint_freq": 6_000_000}  # fmt: skip
RESULTS_DIR, RUNS_DIR = "results", "runs"


@dataclass
class Entry:
    """One agent of the benchmark: ``options`` of ``dwr-gym train``, or ``make(seed, run_dir) -> policy``."""

    name: str
    options: dict[str, Any] = field(default_factory=dict)
    make: Callable[[int, Path], Any] | None = None
    learned_from: str = "reward"


def parse_entry(text: str) -> Entry:
    """``NAME`` (one of :data:`ENTRIES`) or ``NAME:KEY=VALUE,KEY=VALUE`` (options of ``dwr-gym train`` on top of
    NAME's, or on plain PPO when NAME is new), e.g. ``ppo-rep5:action_repeat=5,normalize_obs=true``."""
    import yaml

    name, _, rest = text.partition(":")
    base = name if name in ENTRIES else name.split("-")[0] if name.split("-")[0] in ENTRIES else None
    if not rest and name not in ENTRIES:
        raise ConfigError(f"agent {text!r} is invalid: expected one of {', '.join(ENTRIES)}, or NAME:KEY=VALUE,...")
    options = dict(ENTRIES[base]) if base else {}
    for item in filter(None, _split_top_level(rest)):
        key, sep, value = item.partition("=")
        if not sep or key not in TrainConfig.__dataclass_fields__:
            raise ConfigError(f"agent {text!r}: {item!r} is invalid: expected KEY=VALUE with KEY a train option")
        try:
            options[key] = yaml.safe_load(value)
        except yaml.YAMLError:
            raise ConfigError(f"agent {text!r}: {item!r} is invalid: its value is not YAML") from None
    return Entry(name, options)


def _split_top_level(text: str) -> list[str]:
    """``text`` split at the commas outside brackets and braces."""
    items, depth, current = [], 0, ""
    for char in text:
        depth += (char in "[{(") - (char in "]})")
        if char == "," and depth == 0:
            items.append(current)
            current = ""
        else:
            current += char
    return [*items, current]


def train_config(entry: Entry, seed: int, run_dir: Path, budget: dict[str, Any]) -> TrainConfig:
    """The TrainConfig of one run: the entry's options, the budget, the seed, and evaluation on the nominal set.

    ``budget``: ``env_steps`` (env steps; with an action repeat of K the agent decides env_steps / K times),
    ``time_limit`` (seconds), ``eval_freq`` (env steps) and ``eval_episodes``.
    """
    from train.learning.hyperparams import resolve_hyperparams

    options = {**entry.options}
    overrides = options.pop("hyperparams", None)
    repeat = int(options.get("action_repeat", 1))
    options.setdefault("env_id", ENTRY_ENV_ID)
    config = TrainConfig(**options, seed=seed, run_dir=str(run_dir), progress=False,
                         eval_seed=EVAL_SEED, eval_episodes=int(budget.get("eval_episodes", EVAL_EPISODES)))  # fmt: skip
    if budget.get("env_steps") and "total_timesteps" not in entry.options:  # an entry's own budget wins
        config.total_timesteps = max(1, int(budget["env_steps"]) // repeat)
    if budget.get("eval_freq") and "eval_freq" not in entry.options:
        config.eval_freq = max(1, int(budget["eval_freq"]) // repeat)
        config.checkpoint_freq = config.eval_freq
    if budget.get("time_limit") is not None and "time_limit" not in entry.options:  # as the budget above
        config.time_limit = budget["time_limit"]
    if isinstance(overrides, str):  # hyperparams=PATH: an rl-zoo3 YAML file, as dwr-gym train --hyperparams
        config.hyperparams = overrides
    elif isinstance(overrides, dict):
        config.hyperparam_overrides = dict(overrides)
    elif overrides is not None:
        raise ConfigError(f"agent {entry.name!r}: hyperparams={overrides!r} is invalid: expected a YAML file's path or "
                          "a mapping such as {learning_rate: 1e-4}")  # fmt: skip
    config.validate()
    explicit = {"total_timesteps"} if budget.get("env_steps") or "total_timesteps" in entry.options else set()
    return resolve_hyperparams(config, explicit)


def train_command(entry: Entry, config: TrainConfig) -> list[str]:
    """The ``dwr-gym train`` command that trains this run alone (config.yaml's recipe, which
    ``python -m benchmarks run retrain-pretrained`` runs again)."""
    command = ["dwr-gym", "train", "--seed", str(config.seed), "--total-timesteps", str(config.total_timesteps),
               "--eval-freq", str(config.eval_freq), "--checkpoint-freq", str(config.checkpoint_freq),
               "--eval-episodes", str(config.eval_episodes), "--eval-seed", str(config.eval_seed),
               "--env", config.env_id]  # fmt: skip
    if config.time_limit is not None:
        command += ["--time-limit", str(config.time_limit)]
    files: list[str] = []  # one --hyperparams (the CLI's only form): the YAML file, then the KEY=VALUE overrides
    overrides: list[str] = []
    for key, value in entry.options.items():
        flag = "--" + key.replace("_", "-")
        if key in ("total_timesteps", "eval_freq", "checkpoint_freq", "eval_episodes", "eval_seed", "time_limit",
                   "env_id"):  # fmt: skip
            continue  # given above, from the config
        if key in ("hyperparams", "hyperparam_overrides") and isinstance(value, dict):
            overrides += [f"{k}={_cli_value(v)}" for k, v in value.items()]
        elif key == "hyperparams":
            files.append(str(value))
        elif key == "env_kwargs" and isinstance(value, dict):
            command += [flag, *(f"{k}={_cli_value(v)}" for k, v in value.items())]
        elif isinstance(value, bool):
            command += [flag] if value else []
        else:
            command += [flag, str(value)]
    if files or overrides:
        command += ["--hyperparams", *files, *overrides]
    return [*command, "--run-dir", str(config.run_dir)]


def _cli_value(value: Any) -> str:
    """A value as ``KEY=VALUE`` of the command line reads it back (YAML; JSON is YAML): a string as itself."""
    return value if isinstance(value, str) else json.dumps(value)


def run_one(entry: Entry, seed: int, out: Path, budget: dict[str, Any], progress: bool = False) -> dict[str, Any]:
    """Train (or make) and evaluate one (entry, seed); returns and writes its result JSON."""
    result_path = out / RESULTS_DIR / f"{entry.name}-seed{seed}.json"
    if result_path.is_file():
        return json.loads(result_path.read_text())
    run_dir = out / RUNS_DIR / f"{entry.name}-seed{seed}"
    start = time.time()
    if entry.make is not None:
        run_dir.mkdir(parents=True, exist_ok=True)
        policy, repeat, config_dict = entry.make(seed, run_dir), 1, {}
    else:
        import torch

        from train.learning.agents import load_agent
        from train.learning.runs import MODEL_FILE
        from train.learning.training import train

        config = train_config(entry, seed, run_dir, budget)
        torch.set_num_threads(config.threads or 1)
        state = run_dir / "run_state.json"
        saved = json.loads(state.read_text()) if state.is_file() else None
        if saved is not None and not saved.get("finished") and (run_dir / MODEL_FILE).is_file():
            config.resume = str(run_dir / MODEL_FILE)  # an interrupted run continues from its last checkpoint
            # its seconds: the training's wall time until that checkpoint, then this process's
            start -= float(saved.get("wall_time", 0.0))
        elif saved is None or not saved.get("finished"):  # (interrupted before its first checkpoint: from the start)
            config.overwrite = True
        if not (saved is not None and saved.get("finished")):
            train(config, command=train_command(entry, config))  # a missing extra: a ConfigError naming it
        _, policy = load_agent(run_dir)
        repeat, config_dict = config.action_repeat, config.to_dict()
    train_seconds = time.time() - start
    env_id = config_dict.get("env_id", ENTRY_ENV_ID)  # each agent on its own env id: v1's or v2's episode end
    n_eval = int(budget.get("eval_episodes", EVAL_EPISODES))
    sets = evaluate_policy(policy, env_id=env_id, n=n_eval, n_per_T_con=min(PER_T_CON_EPISODES, n_eval),
                           n_disturbed=int(budget.get("disturbed_episodes", DISTURBED_EPISODES)),
                           n_optimum=budget.get("optimum_episodes", OPTIMUM_EPISODES) or None, progress=progress)  # fmt: skip
    state_path = run_dir / "run_state.json"
    steps = json.loads(state_path.read_text()).get("timesteps", 0) * repeat if state_path.is_file() else None
    result = {"entry": entry.name, "seed": seed, "learned_from": entry.learned_from, "action_repeat": repeat,
              "env_id": env_id,
              "env_steps": steps,
              "seconds": round(train_seconds, 1), "sets": sets, "curve": read_curve(run_dir, repeat),
              "config": config_dict}  # fmt: skip
    result_path.parent.mkdir(parents=True, exist_ok=True)
    result_path.write_text(json.dumps(result, indent=1, default=str))
    return result


def read_curve(run_dir: Path, repeat: int = 1) -> list[dict[str, float]]:
    """A run's learning curve (evaluations.csv) as rows of env steps, wall seconds and the benchmark's metrics."""
    import csv

    path = run_dir / "evaluations.csv"
    if not path.is_file():
        return []
    with path.open() as handle:
        rows = list(csv.DictReader(handle))
    return [{"env_steps": int(row["timesteps"]) * repeat, "wall_time": float(row["wall_time"]),
             "in_time": float(row["success_rate"]), "final_heading": float(row["final_heading_error_mean"]),
             "energy": float(row["energy_mean"])} for row in rows]  # fmt: skip


def run_benchmark(
    entries: list[Entry], seeds: list[int], out: Path, budget: dict[str, Any], jobs: int = 1, progress: bool = False,
    ray: bool = False, address: str | None = None, resources: dict[str, float] | None = None,
) -> list[dict[str, Any]]:  # fmt: skip
    """Every (entry, seed), in ``jobs`` processes, or as Ray tasks of ``resources`` with ``ray`` or an ``address``
    (:mod:`train.learning.ray_grid`: a local Ray, or the cluster at ``address``); the results in the order of
    entries then seeds."""
    out.mkdir(parents=True, exist_ok=True)
    work = [(entry, seed) for entry in entries for seed in seeds]
    if ray or address is not None:
        from train.learning.ray_grid import run_on_ray

        out = out.resolve()  # the workers' working directory is not the driver's
        results = run_on_ray(run_one, [(entry, seed, out, budget) for entry, seed in work], address, resources)
        for result in results:  # where a worker on another machine wrote its result to a disk the driver lacks
            path = out / RESULTS_DIR / f"{result['entry']}-seed{result['seed']}.json"
            if not path.is_file():
                path.parent.mkdir(parents=True, exist_ok=True)
                path.write_text(json.dumps(result, indent=1, default=str))
        return results
    if jobs <= 1 or any(entry.make is not None for entry in entries):
        return [run_one(entry, seed, out, budget, progress) for entry, seed in work]
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor

    with ProcessPoolExecutor(jobs, mp_context=multiprocessing.get_context("spawn")) as pool:
        futures = [pool.submit(run_one, entry, seed, out, budget) for entry, seed in work]
        return [future.result() for future in futures]


__all__ = ["ENTRIES", "Entry", "parse_entry", "read_curve", "run_benchmark", "run_one", "train_command", "train_config"]

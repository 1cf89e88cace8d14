"""Every benchmark of the suite: its name -> its module. The group is the module's package (what it measures); the
one-line summary is the first line of the module's docstring. Adding a benchmark is its module and one line here."""

from __future__ import annotations

import ast
import importlib
from pathlib import Path
from types import ModuleType

ROOT = Path(__file__).resolve().parents[1]

SUITE: dict[str, str] = {
    # speed: the env's step, against CartPole and the numpy path, in time and in instructions
    "throughput": "benchmarks.speed.throughput",
    "instructions": "benchmarks.speed.instructions",
    "memory": "benchmarks.speed.memory",
    "jax-env-step": "benchmarks.speed.jax_env_step",
    "compare-time": "benchmarks.speed.compare_time",
    "compare-cpu-paths": "benchmarks.quality.cpu_paths",
    "optimum-speed": "benchmarks.speed.optimum_speed",
    "env-versions": "benchmarks.speed.env_versions",
    # training: how fast `dwr-gym train` and the JAX learners run, and what a run costs
    "training-speed": "benchmarks.training.training_speed",
    "training-threads": "benchmarks.training.training_threads",
    "readme-training": "benchmarks.training.readme_training",
    "retrain-pretrained": "benchmarks.training.retrain_pretrained",
    "jax-training": "benchmarks.training.jax_training",
    "es-speed": "benchmarks.training.es_speed",
    "apg-speed": "benchmarks.training.apg_speed",
    "sbx-speed": "benchmarks.training.sbx_speed",
    # learning: what the learned agents reach, and the archived record of what was tried (archive)
    "archive": "benchmarks.learning.archive",
    "constraint-log": "benchmarks.learning.constraint_log",
    "ship-rl-agents": "benchmarks.learning.ship_rl_agents",
    "per-t-con": "benchmarks.learning.per_t_con",
    "prescribed-time-goal": "benchmarks.learning.prescribed_time_goal",
    "sbx-learn": "benchmarks.learning.sbx_learn",
    # robustness: the deadline under disturbances
    "robustness": "benchmarks.robustness.robustness",
    "robust-goal": "benchmarks.robustness.robust_goal",
    # quality: the controllers and agents against the paper and the optimum
    "compare": "benchmarks.quality.compare",
    "leaderboard": "benchmarks.quality.leaderboard",
    "reproduce": "benchmarks.quality.reproduce",
    "optimal": "benchmarks.quality.optimal",
    "ship-optima": "benchmarks.quality.ship_optima",
    # testing: how good the tests are
    "fuzz": "benchmarks.testing.fuzz",
    "reliability": "benchmarks.testing.reliability",
    "golden-rollouts": "benchmarks.testing.golden_rollouts",
    "mutation": "benchmarks.testing.mutation",
    "planted-bugs": "benchmarks.testing.planted_bugs",
    # datasets: the offline suite and how fast it is made
    "datasets-suite": "benchmarks.datasets.suite",
    "dataset-speed": "benchmarks.datasets.speed",
    "offline-d3rlpy": "benchmarks.datasets.offline_d3rlpy",
    # recipes: the trainings behind the shipped agents and the docs' tables (long: hours)
    "agents-v0": "benchmarks.recipes.agents_v0",
    "dagger-agents": "benchmarks.recipes.dagger_agents",
    "prescribed-time-agents": "benchmarks.recipes.prescribed_time_agents",
    "rl-agents": "benchmarks.recipes.rl_agents",
    "rl-v2": "benchmarks.recipes.rl_v2",
    "rl-time-scale": "benchmarks.recipes.rl_time_scale",
    "rl-apg": "benchmarks.recipes.rl_apg",
    "rl-apg-scratch": "benchmarks.recipes.rl_apg_scratch",
    "rl-apg-teacher": "benchmarks.recipes.rl_apg_teacher",
    "rl-apg-teacher-30min": "benchmarks.recipes.rl_apg_teacher_30min",
    "rl-apg-near-miss": "benchmarks.recipes.rl_apg_near_miss",
    "rl-apg-hold": "benchmarks.recipes.rl_apg_hold",
    "rl-apg-hold-heading10": "benchmarks.recipes.rl_apg_hold_heading10",
    "rl-constrained": "benchmarks.recipes.rl_constrained",
    "robust-rl": "benchmarks.recipes.robust_rl",
}


def check(name: str) -> str:
    """``name`` if it is an entry of the suite, else a one-line error naming the entries."""
    if name not in SUITE:
        raise SystemExit(
            f"benchmark {name!r} is unknown: expected one of {', '.join(SUITE)} (python -m benchmarks list)"
        )
    return name


def load(name: str) -> ModuleType:
    """The module of entry ``name``."""
    return importlib.import_module(SUITE[check(name)])


def group(name: str) -> str:
    """What entry ``name`` measures: its module's package."""
    return SUITE[check(name)].split(".")[1]


def source(name: str) -> Path:
    """The file of entry ``name``'s module."""
    return ROOT.joinpath(*SUITE[check(name)].split(".")).with_suffix(".py")


def summary(name: str) -> str:
    """The first line of entry ``name``'s docstring, read without importing the module (so listing is instant)."""
    doc = ast.get_docstring(ast.parse(source(name).read_text())) or ""
    return doc.splitlines()[0] if doc else ""

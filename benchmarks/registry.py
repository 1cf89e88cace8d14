"""Every benchmark of the suite: its name -> its module, or the shell script of a recipe. The group is the package
(what it measures); the one-line summary is the first line of the module's docstring or of the script's header.
Adding a benchmark is its module (or script) and one line here."""

from __future__ import annotations

import ast
import importlib
from pathlib import Path
from types import ModuleType, SimpleNamespace

ROOT = Path(__file__).resolve().parents[1]

SUITE: dict[str, str] = {
    # speed: the env's step, against CartPole and the numpy path, in time and in instructions
    "throughput": "benchmarks.speed.throughput",
    "instructions": "benchmarks.speed.instructions",
    "memory": "benchmarks.speed.memory",
    "jax-env-step": "benchmarks.speed.jax_env_step",
    "compare-time": "benchmarks.speed.compare_time",
    "optimum-speed": "benchmarks.speed.optimum_speed",
    "env-versions": "benchmarks.speed.env_versions",
    # training: how fast `dwr-gym train` and the JAX learners run, and what a run costs
    "training-speed": "benchmarks.training.training_speed",
    "readme-training": "benchmarks.training.readme_training",
    "retrain-pretrained": "benchmarks.training.retrain_pretrained",
    "jax-training": "benchmarks.training.jax_training",
    "apg-speed": "benchmarks.training.apg_speed",
    # learning: what the learned agents reach, and the archived record of what was tried (archive)
    "archive": "benchmarks.learning.archive",
    "constraint-log": "benchmarks.learning.constraint_log",
    "ship-rl-agents": "benchmarks.learning.ship_rl_agents",
    "per-t-con": "benchmarks.learning.per_t_con",
    "constraint-misses": "benchmarks.learning.misses",
    # robustness: the deadline under disturbances
    "robustness": "benchmarks.robustness.robustness",
    "robust-goal": "benchmarks.robustness.robust_goal",
    # quality: the controllers and agents against the paper and the optimum
    "compare": "benchmarks.quality.compare",
    "compare-cpu-paths": "benchmarks.quality.cpu_paths",
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
    "agents-v0": "benchmarks/recipes/agents_v0.sh",
    "dagger-agents": "benchmarks/recipes/dagger_agents.sh",
    "rl-agents": "benchmarks/recipes/rl_agents.sh",
    "rl-v2": "benchmarks/recipes/rl_v2.sh",
    "rl-time-scale": "benchmarks/recipes/rl_time_scale.sh",
    "rl-apg": "benchmarks/recipes/rl_apg.sh",
    "rl-apg-scratch": "benchmarks/recipes/rl_apg_scratch.sh",
    "rl-apg-teacher": "benchmarks/recipes/rl_apg_teacher.sh",
    "rl-apg-teacher-30min": "benchmarks/recipes/rl_apg_teacher_30min.sh",
    "rl-apg-near-miss": "benchmarks/recipes/rl_apg_near_miss.sh",
    "rl-apg-hold": "benchmarks/recipes/rl_apg_hold.sh",
    "rl-apg-hold-heading10": "benchmarks/recipes/rl_apg_hold_heading10.sh",
    "rl-constrained": "benchmarks/recipes/rl_constrained.sh",
    "sbx-tqc-v2": "benchmarks/recipes/sbx_tqc_v2.sh",
    "robust-rl": "benchmarks/recipes/robust_rl.sh",
}


def check(name: str) -> str:
    """``name`` if it is an entry of the suite, else a one-line error naming the entries."""
    if name not in SUITE:
        raise SystemExit(
            f"benchmark {name!r} is unknown: expected one of {', '.join(SUITE)} (python -m benchmarks list)"
        )
    return name


def load(name: str) -> ModuleType | SimpleNamespace:
    """The module of entry ``name``; a recipe's ``main`` and ``BLOCKS`` (:func:`benchmarks.recipes.entry`)."""
    target = SUITE[check(name)]
    if target.endswith(".sh"):  # (loaded by name as every entry is: the recipes' blocks use benchmarks.core.docs)
        return importlib.import_module("benchmarks.recipes").entry(name, ROOT / target)  # type: ignore[no-any-return]
    return importlib.import_module(target)


def group(name: str) -> str:
    """What entry ``name`` measures: its package."""
    return SUITE[check(name)].replace("/", ".").split(".")[1]


def source(name: str) -> Path:
    """The file of entry ``name``: its module, or a recipe's script."""
    target = SUITE[check(name)]
    return ROOT / target if target.endswith(".sh") else ROOT.joinpath(*target.split(".")).with_suffix(".py")


def summary(name: str) -> str:
    """The first line of entry ``name``'s docstring or script header, read without importing (so listing is instant)."""
    path = source(name)
    if path.suffix == ".sh":
        return path.read_text().splitlines()[1].removeprefix("# ")
    doc = ast.get_docstring(ast.parse(path.read_text())) or ""
    return doc.splitlines()[0] if doc else ""

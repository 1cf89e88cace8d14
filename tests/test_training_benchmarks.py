"""The training entries of the suite (benchmarks/training/: training-speed, retrain-pretrained and readme-training;
the archived old-vs-new and training-threads): the blocks of docs/training.md and the README are what they render from
their JSON, and the retraining replays each shipped agent's recorded recipe."""

from __future__ import annotations

import importlib
import importlib.util
import json
from pathlib import Path
from types import ModuleType

import pytest

from benchmarks.core import docs


def load(name: str) -> ModuleType:
    return importlib.import_module(f"benchmarks.training.{name}")


@pytest.mark.parametrize("block", ["training-speed", "old-vs-new", "retrain", "training-threads"])
def test_each_docs_block_is_what_its_benchmark_renders_from_its_json(block: str) -> None:
    assert docs.written(block) == docs.rendered(block)


def test_the_speed_verdict_follows_the_measured_ratio() -> None:
    module = load("training_speed")
    results = json.loads(module.JSON_PATH.read_text())
    assert results["met"] == (results["ratio_train_defaults_to_cartpole"] >= 20)
    assert ("20x SB3 PPO on CartPole-v1" in module.render(results)[-1]) and module.render(results)[-1].endswith(
        ", met" if results["met"] else "NOT met"
    )


def test_the_readmes_training_example_is_what_its_benchmark_measured() -> None:
    module = load("readme_training")
    results = json.loads(module.JSON_PATH.read_text())
    assert docs.written("readme-training") == module.render(results)
    best = max(results["curve"], key=lambda row: (row["success_rate"], -row["energy_mean"], row["return_mean"]))
    assert results["command"] in docs.written("readme-training").replace(" \\\n  ", " ")  # (a long one is folded)
    assert results["best"]["timesteps"] == best["timesteps"]  # the most episodes in time, then the least energy


def test_a_recipe_is_replayed_with_only_seed_run_dir_and_budget_changed(tmp_path: Path) -> None:
    module = load("retrain_pretrained")
    recorded = ["dwr-gym", "train", "--env", "DWRPointStabilization-v0", "--seed", "0", "--run-dir", "runs/ppo_s0",
                "--total-timesteps", "1500000", "--env-kwargs", "heading_weight=5", "--no-progress"]  # fmt: skip
    args = module.runnable(recorded, 2, tmp_path / "r", 0.5)[1:]
    assert args == ["-m", "train.cli", "train", "--env", "DWRPointStabilization-v0", "--seed", "2", "--run-dir",
                    str(tmp_path / "r"), "--total-timesteps", "750000", "--env-kwargs", "heading_weight=5",
                    "--no-progress"]  # fmt: skip
    dagger = module.runnable(["python", "-m", "train.learning.imitation.dagger", "--run-dir", "x", "--episodes", "250"],
                             1, tmp_path / "d", 1.0)[1:]  # fmt: skip
    assert dagger == ["-m", "train.learning.imitation.dagger", "--run-dir", str(tmp_path / "d"), "--episodes", "250"]
    with pytest.raises(ValueError, match="not dwr-gym or python"):
        module.runnable(["bash", "train.sh"], 0, tmp_path, 1.0)


def test_every_shipped_agent_has_a_recipe_this_checkout_can_run(tmp_path: Path) -> None:
    module = load("retrain_pretrained")
    agents = sorted(path.parent for path in module.PRETRAINED.glob("*/config.yaml"))
    assert {"ppo", "residual_ppo", "robust", "apg_v2"} <= {agent.name for agent in agents}
    for agent in agents:
        steps, dirs = module.moved_run_dirs(module.recipe(agent), tmp_path / agent.name)
        assert dirs[-1] == tmp_path / agent.name
        for step, run_dir in zip(steps, dirs, strict=True):
            command = module.runnable(step, 1, run_dir, 1.0)
            assert importlib.util.find_spec(command[command.index("-m") + 1]) is not None
            assert command[command.index("--run-dir") + 1] == str(run_dir)
    # robust: the DAgger hand-over network first, in a directory of its own, then robust DAgger starting from it
    steps, dirs = module.moved_run_dirs(module.recipe(module.PRETRAINED / "robust"), tmp_path / "robust")
    assert len(steps) == 2 and dirs[0] != dirs[1] and "train.learning.imitation.dagger" in steps[0]
    assert steps[1][steps[1].index("--init-from") + 1] == str(dirs[0])

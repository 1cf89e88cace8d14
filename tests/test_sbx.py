"""``dwr-gym train --backend sbx``: sbx-rl's SAC, TQC and CrossQ on the SB3 training path, loaded wherever agents
load, resumed as the uninterrupted run; a missing sbx-rl names the extra."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest
import yaml

from train.cli import main
from train.learning.config import ConfigError, TrainConfig

pytest.importorskip("sbx")

TINY = ["--num-envs", "4", "--hyperparams", "learning_starts=16", "batch_size=16", "buffer_size=1000",
        "--eval-freq", "1000", "--eval-episodes", "2", "--no-progress"]  # fmt: skip


def actor_parameters(run_dir: Path, algo: str) -> list[np.ndarray]:
    import jax

    from train.learning.hyperparams import algorithm_class

    model = algorithm_class(algo, "sbx").load(run_dir / "model.zip")
    return [np.asarray(leaf) for leaf in jax.tree_util.tree_leaves(model.policy.actor_state.params)]


@pytest.mark.parametrize("algo", ["sac", pytest.param("tqc", marks=pytest.mark.slow),
                                  pytest.param("crossq", marks=pytest.mark.slow)])  # fmt: skip
def test_each_algorithm_trains_saves_an_sbx_model_and_loads_as_an_agent(algo: str, tmp_path: Path) -> None:
    """TQC and CrossQ are marked slow: each compiles its own update (tens of seconds on 2 shared cores)."""
    import sbx

    from train.learning.agents import load_agent

    run = tmp_path / algo
    assert main(["train", "--algo", algo, "--backend", "sbx", "--total-timesteps", "64", *TINY,
                 "--run-dir", str(run)]) == 0  # fmt: skip
    assert yaml.safe_load((run / "config.yaml").read_text())["config"]["backend"] == "sbx"
    assert (run / "best_model.zip").is_file() and (run / "evaluations.csv").read_text().count("\n") == 3
    _label, policy = load_agent(run)
    assert isinstance(policy, getattr(sbx, {"sac": "SAC", "tqc": "TQC", "crossq": "CrossQ"}[algo]))
    actions = policy.predict(np.zeros((3, 10), dtype=np.float32), deterministic=True)[0]
    assert actions.shape == (3, 2) and np.all(np.abs(actions) <= 1.0)


@pytest.mark.slow
def test_a_resumed_sbx_run_equals_the_uninterrupted_one(tmp_path: Path) -> None:
    """Marked slow (three runs, each compiling sbx's update: over a minute on 2 shared cores); .ci/run runs it."""
    from train.learning.hyperparams import resolve_hyperparams
    from train.learning.runs import resume_config
    from train.learning.training import train

    def tiny(run_dir: Path, total: int) -> TrainConfig:
        config = TrainConfig(algo="sac", backend="sbx", total_timesteps=total, num_envs=4, eval_freq=1000,
                             eval_episodes=2, checkpoint_freq=32, run_dir=str(run_dir), progress=False)  # fmt: skip
        config.validate()
        resolve_hyperparams(config, set())
        config.algo_kwargs.update(learning_starts=16, buffer_size=1000, batch_size=16)
        return config

    train(tiny(tmp_path / "whole", 96))
    train(tiny(tmp_path / "split", 48))  # stops after a checkpoint, as Ctrl-C does
    train(resume_config({"resume": str(tmp_path / "split"), "total_timesteps": 96, "progress": False}))
    whole, split = actor_parameters(tmp_path / "whole", "sac"), actor_parameters(tmp_path / "split", "sac")
    assert len(whole) == len(split) > 0
    for a, b in zip(whole, split, strict=True):
        np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize(
    ("args", "message"),
    [(["--algo", "ppo"], "--algo 'ppo' is invalid with --backend sbx"),
     (["--algo", "sac", "--residual"], "--residual is invalid with --backend sbx"),
     (["--algo", "sac", "--hyperparams", "target_update_interval=2"], "are not accepted by SAC of sbx")],
)  # fmt: skip
def test_what_sbx_does_not_train_is_refused_in_one_line_before_training(
    args: list[str], message: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["train", "--backend", "sbx", *args, "--run-dir", str(tmp_path / "run"), "--no-progress"]) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and len(err.splitlines()) == 1
    assert not (tmp_path / "run" / "model.zip").exists()


def test_a_missing_sbx_names_the_extra(monkeypatch: pytest.MonkeyPatch) -> None:
    from train.learning.hyperparams import algorithm_class

    monkeypatch.setitem(sys.modules, "sbx", None)  # import sbx now raises ImportError, as where it is not installed
    with pytest.raises(ConfigError, match=r'needs sbx, .*pip install "dwr-gym\[sbx\]"'):
        algorithm_class("sac", "sbx")
    assert algorithm_class("sac").__module__.startswith("stable_baselines3")  # the other backends need no sbx

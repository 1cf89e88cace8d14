"""rl-zoo3 trains DWRPointStabilization-v1 (and v0) with the shipped train/hyperparams/, which are also dwr-gym train's
defaults."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from train.learning.config import BUDGET_HELP, TrainConfig
from train.learning.hyperparams import HYPERPARAMS_DIR, resolve_hyperparams

ROOT = Path(__file__).resolve().parents[1]


def stated_defaults(text: str) -> dict[str, int]:
    """{"PPO": 256, "SAC": 64, "TD3": 64} from "...: 256 for PPO, 64 for SAC and TD3"."""
    return {algo: int(number) for number, algos in re.findall(r"(\d+) for ([A-Z0-9 and]+)", text)
            for algo in algos.split(" and ")}  # fmt: skip


@pytest.mark.parametrize("env_id", ["DWRPointStabilization-v1", "DWRPointStabilization-v0"])
@pytest.mark.parametrize("name", ["ppo", "sac", "td3", "residual_ppo", "residual_sac", "residual_td3"])
def test_shipped_yaml_is_rl_zoo3_format_and_matches_train_defaults(name: str, env_id: str, tmp_path: Path) -> None:
    """rl-zoo3's own loader reads each shipped file, and the model `dwr-gym train` builds by default has exactly
    the hyperparameters rl-zoo3 read (n_envs and n_timesteps are the trainer's defaults)."""
    pytest.importorskip("rl_zoo3")
    import argparse

    from rl_zoo3.exp_manager import ExperimentManager
    from stable_baselines3 import PPO, SAC, TD3

    from train.learning.training import train

    algo, residual = name.removeprefix("residual_"), name.startswith("residual_")
    manager = ExperimentManager(argparse.Namespace(), algo, env_id, str(tmp_path / "zoo"),
                                config=str(HYPERPARAMS_DIR / f"{name}.yml"), verbose=0)  # fmt: skip
    zoo, _, _, _ = manager._preprocess_hyperparams(manager.read_hyperparameters()[0])
    defaults = resolve_hyperparams(TrainConfig(algo=algo, residual=residual, env_id=env_id), set())
    assert (manager.n_envs, manager.n_timesteps) == (defaults.num_envs, defaults.total_timesteps)
    assert stated_defaults(BUDGET_HELP["n_envs"])[algo.upper()] == manager.n_envs  # as the CLI's help says
    assert stated_defaults(BUDGET_HELP["n_timesteps"])[algo.upper()] == manager.n_timesteps

    config = TrainConfig(algo=algo, residual=residual, env_id=env_id, total_timesteps=1, eval_freq=10**9, eval_episodes=1,
                         checkpoint_freq=10**9, run_dir=str(tmp_path / "run"), progress=False)  # fmt: skip
    resolve_hyperparams(config, set())
    cls = {"ppo": PPO, "sac": SAC, "td3": TD3}[algo]
    model = cls.load(train(config) / "model.zip", device="cpu")
    assert model.n_envs == manager.n_envs
    assert model.policy_class is cls.policy_aliases[zoo.pop("policy")]
    schedule = zoo.pop("learning_rate")
    assert [model.lr_schedule(p) for p in (1.0, 0.5, 0.0)] == [schedule(p) for p in (1.0, 0.5, 0.0)]
    for key, value in zoo.pop("policy_kwargs").items():
        assert model.policy_kwargs[key] == value, key
    if zoo.pop("noise_type", None) is not None:  # rl-zoo3's normal noise of noise_std on each action
        noise = getattr(model.action_noise, "base_noise", model.action_noise)  # SB3 vectorises it over the envs
        np.testing.assert_array_equal(noise._sigma, np.full(2, zoo.pop("noise_std")))
    if "train_freq" in zoo:
        assert model.train_freq.frequency == zoo.pop("train_freq")
    for key, value in zoo.items():
        assert getattr(model, key) == value, key
    # v1 charges energy over episodes of up to 90 s: its discount is the README's 0.999, v0 keeps its tuned 0.99
    assert model.gamma == (0.999 if env_id.endswith("v1") else 0.99)


def test_dwr_gym_train_reads_an_rl_zoo3_yaml_with_noise(tmp_path: Path) -> None:
    path = tmp_path / "td3.yml"
    path.write_text("DWRPointStabilization-v0:\n  n_timesteps: 5000\n  noise_type: normal\n  noise_std: 0.3\n")
    config = resolve_hyperparams(
        TrainConfig(algo="td3", env_id="DWRPointStabilization-v0", hyperparams=str(path)), explicit=set()
    )
    assert config.total_timesteps == 5000 and config.algo_kwargs["action_noise_sigma"] == 0.3


def test_rl_zoo3_trains_the_env(tmp_path: Path) -> None:
    """The issue's command as it is (no --conf-file: dwr_gym points rl-zoo3 at train/hyperparams/), tiny budget."""
    pytest.importorskip("rl_zoo3")
    command = [sys.executable, "-m", "rl_zoo3.train", "--algo", "ppo", "--env", "DWRPointStabilization-v1",
               "--gym-packages", "dwr_gym", "-n", "128",
               "--hyperparams", "n_envs:2", "n_steps:64", "batch_size:64", "--eval-freq", "-1", "--seed", "0",
               "-f", str(tmp_path)]  # fmt: skip
    result = subprocess.run(command, capture_output=True, text=True, timeout=300, cwd=ROOT)
    assert result.returncode == 0, result.stderr[-2000:]
    saved = list(tmp_path.glob("ppo/DWRPointStabilization-v1_*/DWRPointStabilization-v1.zip"))
    assert len(saved) == 1
    config = next(tmp_path.glob("ppo/*/DWRPointStabilization-v1/config.yml")).read_text()
    assert "dict(net_arch=[64, 64])" in config and "0.999" in config  # our YAML's v1 section was the one used


def test_rl_zoo3_steps_our_ids_on_one_native_vector_env(tmp_path: Path) -> None:
    """rl-zoo3's n_envs robots are those of one native vector env (not n_envs single envs in a DummyVecEnv), with
    the env kwargs it was given; other env ids keep rl-zoo3's own env."""
    pytest.importorskip("rl_zoo3")
    import argparse

    from rl_zoo3.exp_manager import ExperimentManager
    from stable_baselines3.common.vec_env import DummyVecEnv

    from dwr_gym.sb3 import SB3VecEnv
    from dwr_gym.zoo import use_our_hyperparameters

    use_our_hyperparameters()
    ours = ExperimentManager(argparse.Namespace(), "ppo", "DWRPointStabilization-v1", str(tmp_path / "a"),
                             env_kwargs={"T_con": 30.0}, verbose=0)  # fmt: skip
    ours.read_hyperparameters()
    env = ours.create_envs(8)
    assert isinstance(env, SB3VecEnv) and env.num_envs == 8 and env.params.T_con == 30.0
    env.close()
    other = ExperimentManager(argparse.Namespace(), "ppo", "CartPole-v1", str(tmp_path / "b"), verbose=0)
    other.read_hyperparameters()
    env = other.create_envs(2)
    assert isinstance(env, DummyVecEnv)
    env.close()

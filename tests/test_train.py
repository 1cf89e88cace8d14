"""Training: short runs of every algorithm, the residual wrapper, save/load/resume, and the CLI."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

from baselines import ExpertPolicy, PTCController
from train.learning.agents import load_agent, pretrained_paths
from train.learning.config import ConfigError, TrainConfig
from train.learning.hyperparams import parse_policy_kwargs, resolve_hyperparams
from train.learning.residual import ResidualActionWrapper, ResidualVecEnv, residual_action
from train.learning.training import train

ROOT = Path(__file__).resolve().parent.parent


def dwr_gym(*args: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "MPLBACKEND": "Agg", "OMP_NUM_THREADS": "1"}
    return subprocess.run([sys.executable, "-m", "train.cli", *args], capture_output=True, text=True, cwd=cwd,
                          env=env, timeout=600)  # fmt: skip


def tiny(algo: str, residual: bool, run_dir: Path, **overrides: object) -> TrainConfig:
    config = TrainConfig(algo=algo, residual=residual, total_timesteps=300, num_envs=4, eval_freq=200,
                         eval_episodes=8, checkpoint_freq=200, run_dir=str(run_dir), progress=False)  # fmt: skip
    for key, value in overrides.items():
        setattr(config, key, value)
    resolve_hyperparams(config, set())
    if algo == "ppo":
        config.algo_kwargs.update(n_steps=32, batch_size=64)
    else:
        config.algo_kwargs.update(learning_starts=50, buffer_size=1000, batch_size=32)
    return config


@pytest.mark.parametrize("residual", [False, True], ids=["plain", "residual"])
@pytest.mark.parametrize("algo", ["ppo", "sac", "td3"])
def test_short_training_run_of_each_algorithm(algo: str, residual: bool, tmp_path: Path) -> None:
    run_dir = train(tiny(algo, residual, tmp_path / "run"))
    for name in ("model.zip", "config.yaml", "evaluations.csv", "best_model.zip"):
        assert (run_dir / name).is_file(), name
    assert any((run_dir / "checkpoints").iterdir())
    assert any((run_dir / "tb").rglob("events.out.tfevents.*"))
    _label, policy = load_agent(run_dir)
    obs = np.zeros((3, 10), dtype=np.float32)
    obs[:, 0], obs[:, 1], obs[:, 3], obs[:, 7], obs[:, 8] = 0.5, 1.0, 1.0, 20.0, 0.5
    actions, _ = policy.predict(obs)
    assert actions.shape == (3, 2) and np.all(np.abs(actions) <= 1.0)


def test_ppo_log_std_final_anneals_the_exploration_noise_to_its_value(tmp_path: Path) -> None:
    config = tiny("ppo", False, tmp_path / "run")
    config.algo_kwargs.update(log_std_final=-3.0, policy_kwargs={"log_std_init": -1.0})
    run_dir = train(config)
    from stable_baselines3 import PPO

    # the cap reaches log_std_final at the end of the budget, from log_std_init: far below what 10 updates learn
    np.testing.assert_allclose(PPO.load(run_dir / "model.zip").policy.log_std.detach().numpy(), -3.0, atol=1e-6)
    with pytest.raises(ConfigError, match=r"\['log_std_final'\] are not accepted by SAC"):
        resolve_hyperparams(TrainConfig(algo="sac", hyperparam_overrides={"log_std_final": -3.0}), {"hyperparams"})


def test_init_from_starts_at_the_saved_network_and_the_warmup_trains_only_the_critic(tmp_path: Path) -> None:
    import torch
    import yaml
    from stable_baselines3 import PPO

    robust = ROOT / "train" / "pretrained" / "robust"
    config = tiny("ppo", False, tmp_path / "run", init_from=str(robust), critic_warmup=10**6)
    config.validate()
    run_dir = train(config)
    saved, tuned = PPO.load(robust / "model.zip").policy, PPO.load(run_dir / "model.zip").policy
    actor = ("mlp_extractor.policy_net", "action_net", "log_std")
    for name, value in saved.state_dict().items():  # the architecture adopted; the actor frozen; the critic learned
        same = torch.equal(value, tuned.state_dict()[name])
        assert same == name.startswith(actor), name
    record = yaml.safe_load((run_dir / "config.yaml").read_text())
    assert record["learned_from"] == "expert, then reward" and record["config"]["init_from"] == str(robust)
    with pytest.raises(ConfigError, match=r"--init-from .* not a SAC model"):
        train(tiny("sac", False, tmp_path / "sac", init_from=str(robust)))
    with pytest.raises(ConfigError, match="--critic-warmup 5 is invalid: it needs --init-from"):
        TrainConfig(critic_warmup=5).validate()


def test_env_kwargs_take_the_json_form_of_a_disturbance_distribution_as_config_yaml_keeps_it() -> None:
    from dwr_gym.randomization import DisturbanceDistribution

    config = TrainConfig(env_kwargs={"disturbance_distribution": {"probability": 0.3}})
    config.validate()  # the env's parameters accept it
    distribution = config.env_keywords()["disturbance_distribution"]
    assert isinstance(distribution, DisturbanceDistribution) and distribution.probability == 0.3
    assert config.to_dict()["env_kwargs"] == {"disturbance_distribution": {"probability": 0.3}}


def test_residual_action_arithmetic_and_clipping() -> None:
    expert = np.array([[0.2, -0.5], [0.9, 0.9], [-0.9, 0.0]], dtype=np.float32)
    residual = np.array([[0.4, 0.2], [1.0, -1.0], [-1.0, 0.5]], dtype=np.float32)
    out = residual_action(expert, residual, 0.5)
    np.testing.assert_allclose(out, [[0.4, -0.4], [1.0, 0.4], [-1.0, 0.25]], atol=1e-7)
    assert out.dtype == np.float32


def test_residual_wrapper_logs_expert_and_residual_parts() -> None:
    base = gym.make("DWRPointStabilization-v1")
    expert = ExpertPolicy.from_env(base, PTCController())
    env = ResidualActionWrapper(base, expert, scale=0.5)
    obs, _ = env.reset(seed=0)
    expected_expert, _ = expert.predict(obs)
    _, _, _, _, info = env.step(np.array([3.0, -0.2], dtype=np.float32))  # the residual itself is clipped to [-1, 1]
    np.testing.assert_allclose(info["expert_action"], expected_expert)
    np.testing.assert_allclose(info["residual_action"], [0.5, -0.1], atol=1e-7)
    applied = np.clip(expected_expert + np.array([0.5, -0.1]), -1, 1)
    assert info["linear_velocity"] == pytest.approx(applied[0] * 0.5, abs=1e-6)
    with pytest.raises(ValueError, match="residual_scale"):
        ResidualActionWrapper(base, expert, scale=0.0)


def test_residual_vec_env_with_zero_residual_is_the_expert() -> None:
    from dwr_gym.sb3 import make_sb3_vec_env

    plain = make_sb3_vec_env(4, seed=3)
    venv = ResidualVecEnv(make_sb3_vec_env(4, seed=3), ExpertPolicy(PTCController(), 0.5, 2.0), scale=0.5)
    obs_p, obs_r = plain.reset(), venv.reset()
    expert = ExpertPolicy(PTCController(), 0.5, 2.0)
    for _ in range(20):
        obs_p, _, _, _ = plain.step(expert.predict(obs_p)[0])
        obs_r, _, _, infos = venv.step(np.zeros((4, 2), dtype=np.float32))
        np.testing.assert_array_equal(obs_p, obs_r)
    assert infos[0]["residual_action"].tolist() == [0.0, 0.0]


def test_residual_training_starts_from_the_expert(tmp_path: Path) -> None:
    from train.learning.residual import ResidualPolicy, zero_init_last_layer
    from train.learning.training_env import make_training_env

    config = tiny("ppo", True, tmp_path / "r")
    from stable_baselines3 import PPO

    from train.learning.hyperparams import build_algo_kwargs

    model = PPO(env=make_training_env(config), seed=0, **build_algo_kwargs(config.algo_kwargs))
    zero_init_last_layer(model)
    expert = ExpertPolicy(PTCController(), 0.5, 2.0)
    obs, _ = gym.make_vec("DWRPointStabilization-v1", num_envs=64).reset(seed=0)
    combined, _ = ResidualPolicy(model, expert, 0.5).predict(obs)
    np.testing.assert_allclose(combined, expert.predict(obs)[0], atol=1e-4)  # 1e-3 of a residual in [-1, 1], halved


@pytest.mark.parametrize("algo", ["ppo", "sac", "td3"])
def test_zero_init_scales_the_last_layer_to_gain_and_zeroes_its_bias(algo: str) -> None:
    """The layer that outputs the action: its weights become exactly gain x their initial values, its bias 0."""
    import torch
    from stable_baselines3 import PPO, SAC, TD3

    from train.learning.residual import zero_init_last_layer

    cls = {"ppo": PPO, "sac": SAC, "td3": TD3}[algo]
    model = cls("MlpPolicy", gym.make("DWRPointStabilization-v0"), seed=0, device="cpu")

    # found by its shape, not by the name the function uses: the first Linear with 2 outputs (PPO's action_net,
    # SAC's and TD3's mu; SAC's log_std comes after it)
    actor = model.policy if algo == "ppo" else model.actor
    layer = next(m for m in actor.modules() if isinstance(m, torch.nn.Linear) and m.out_features == 2)
    initial = layer.weight.detach().clone()
    assert torch.count_nonzero(initial) == initial.numel()  # so that scaling it shows
    zero_init_last_layer(model, gain=1e-3)
    assert torch.equal(layer.weight.detach(), initial * 1e-3)
    assert torch.count_nonzero(layer.bias.detach()) == 0
    if algo == "td3":  # the target actor starts as the actor
        for a, b in zip(model.actor.parameters(), model.actor_target.parameters(), strict=True):
            assert torch.equal(a, b)


def test_save_load_and_resume_round_trip(tmp_path: Path) -> None:
    from stable_baselines3 import PPO

    config = tiny("ppo", False, tmp_path / "run", total_timesteps=256, checkpoint_freq=128)
    run_dir = train(config)
    model = PPO.load(run_dir / "model.zip")
    _, policy = load_agent(run_dir / "model.zip")
    obs = np.random.default_rng(0).uniform(-1, 1, (5, 10)).astype(np.float32)
    np.testing.assert_array_equal(policy.predict(obs, deterministic=True)[0], model.predict(obs, deterministic=True)[0])
    resumed = tiny("ppo", False, run_dir, total_timesteps=512, resume=str(run_dir / "model.zip"))
    train(resumed)
    assert PPO.load(run_dir / "model.zip").num_timesteps >= 512
    rows = (run_dir / "evaluations.csv").read_text().splitlines()
    assert rows[0].startswith("timesteps") and len(rows) > 3  # the resumed run appended to the same curve


def test_zoo_yaml_hyperparameters(tmp_path: Path) -> None:
    yaml_path = tmp_path / "ppo.yml"
    yaml_path.write_text(
        "DWRPointStabilization-v2:\n  n_timesteps: !!float 1e3\n  n_envs: 2\n  policy: 'MlpPolicy'\n"
        '  n_steps: 64\n  learning_rate: lin_1e-3\n  policy_kwargs: "dict(net_arch=[32, 32], activation_fn=nn.Tanh)"\n'
    )
    config = resolve_hyperparams(TrainConfig(hyperparams=str(yaml_path)), set())
    assert config.total_timesteps == 1000 and config.num_envs == 2
    assert config.algo_kwargs["policy_kwargs"] == {"net_arch": [32, 32], "activation_fn": "nn.Tanh"}
    explicit = resolve_hyperparams(TrainConfig(hyperparams=str(yaml_path), total_timesteps=77), {"total_timesteps"})
    assert explicit.total_timesteps == 77
    yaml_path.write_text("DWRPointStabilization-v2:\n  n_stepz: 64\n")
    with pytest.raises(ConfigError, match="n_stepz"):
        resolve_hyperparams(TrainConfig(hyperparams=str(yaml_path)), set())
    with pytest.raises(ConfigError, match="policy_kwargs"):
        parse_policy_kwargs("__import__('os').system('true')")


@pytest.mark.parametrize(
    "args, message",
    [
        (["--algo", "dqn"], "--algo 'dqn' is invalid"),
        (["--hyperparams", "missing.yml"], "--hyperparams 'missing.yml' is invalid: no such file"),
        (["--resume", "missing.zip"], "--resume 'missing.zip' is invalid"),
        (["--env-kwargs", "dt=-1"], "dt=-1"),
        (["--env-kwargs", "T_conn=5"], "unknown parameter"),
        (["--total-timesteps", "-5"], "--total-timesteps -5 is invalid"),
        (["--num-envs", "0"], "--num-envs 0 is invalid"),
        (["--residual-scale", "9"], "--residual-scale 9.0 is invalid"),
        (["--expert", "pid"], "--expert 'pid' is invalid"),
        (["--device", "gpu"], "--device 'gpu' is invalid"),
        (["--total-timesteps", "1e5", "--seed", "-1"], "--seed -1 is invalid"),
    ],
)
def test_train_bad_input_exits_2_before_training(args: list[str], message: str, tmp_path: Path) -> None:
    result = dwr_gym("train", *args, "--run-dir", "run", cwd=tmp_path)
    assert result.returncode == 2, result.stderr
    assert message in result.stderr and len(result.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "run").exists()


def test_train_cli_end_to_end_and_refuses_to_overwrite(tmp_path: Path) -> None:
    yaml_path = tmp_path / "hp.yml"
    yaml_path.write_text("DWRPointStabilization-v2:\n  n_steps: 32\n  batch_size: 64\n")
    args = ["train", "--residual", "--total-timesteps", "256", "--num-envs", "4", "--eval-freq", "128",
            "--eval-episodes", "8", "--hyperparams", str(yaml_path), "--run-dir", "run", "--no-progress"]  # fmt: skip
    result = dwr_gym(*args, cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert "saved run/model.zip" in result.stdout
    assert "n_steps: 32" in (tmp_path / "run" / "config.yaml").read_text()
    again = dwr_gym(*args, cwd=tmp_path)
    assert again.returncode == 2 and "already holds a run" in again.stderr


def test_ctrl_c_saves_the_current_model(tmp_path: Path) -> None:
    env = {**os.environ, "OMP_NUM_THREADS": "1"}
    process = subprocess.Popen(
        [sys.executable, "-m", "train.cli", "train", "--total-timesteps", "10000000", "--num-envs", "4",
         "--eval-freq", "100000", "--eval-episodes", "4", "--run-dir", "run", "--no-progress"],
        cwd=tmp_path, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    deadline = time.time() + 120
    while not (tmp_path / "run" / "evaluations.csv").exists() and time.time() < deadline:
        time.sleep(0.2)
    time.sleep(2.0)  # let it train a little
    process.send_signal(signal.SIGINT)
    _, stderr = process.communicate(timeout=120)
    assert process.returncode == 130, stderr
    assert "interrupted at" in stderr
    assert (tmp_path / "run" / "model.zip").is_file()


@pytest.mark.skipif(not pretrained_paths(), reason="no pretrained agent in this checkout")
def test_compare_on_the_shipped_agents_each_on_its_own_env(tmp_path: Path) -> None:
    """By default the leaderboard's agents, each on the env id it was trained on; the paper's reward's only by name."""
    from train.learning.agents import PAPER_AGENTS, default_agents, trained_env_id

    result = dwr_gym("compare", "--scenarios", "paper-fig5", "random", "--n", "50", "--controllers", "ptc",
                     "--out", "out", "--no-progress", cwd=tmp_path)  # fmt: skip
    assert result.returncode == 0, result.stderr
    envs = {row["policy"]: row["env_id"] for row in json.loads((tmp_path / "out" / "comparison.json").read_text())}
    assert envs == {"ptc": "DWRPointStabilization-v2", **{label: trained_env_id(path)
                                                          for label, path in default_agents().items()}}  # fmt: skip
    assert len(set(envs.values())) > 1 and not set(PAPER_AGENTS) & set(envs)
    for name in ("comparison.csv", "comparison.json", "trajectories.png", "time_series.png", "learning_curves.png"):
        assert (tmp_path / "out" / name).is_file(), name


def test_compare_bad_input(tmp_path: Path) -> None:
    result = dwr_gym("compare", "--agents", "nowhere", cwd=tmp_path)
    assert result.returncode == 2 and "nowhere" in result.stderr

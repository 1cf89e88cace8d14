"""Time-scaled actions (``--action-time-scale``): the action, or a residual agent's residual, times
min(1, T_REF / T_con), the same in the SB3 VecEnv, the jitted trainers' functional env and a saved agent at run time."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from train.learning.config import ConfigError, TrainConfig
from train.learning.time_scale import T_CON_INDEX, TimeScaledPolicy, TimeScaledVecEnv, time_scaled_action

ROOT = Path(__file__).resolve().parent.parent


def observations(T_cons: list[float]) -> np.ndarray:
    """One observation per T_con (the other features of a robot 1.2 m away, a tenth of the way in)."""
    obs = np.tile(np.asarray([1.2, 0.6, 0.8, 1.0, 0.0, 0.9, 0.1, 20.0, 1.5, 0.9], np.float32), (len(T_cons), 1))
    obs[:, T_CON_INDEX] = T_cons
    return obs


def test_the_action_shrinks_as_one_over_T_con_above_the_reference_and_is_clipped_first() -> None:
    action = np.asarray([[0.8, -0.4], [0.8, -0.4], [0.8, -0.4], [3.0, -2.0]], np.float32)
    got = time_scaled_action(action, observations([5.0, 10.0, 40.0, 20.0]), 10.0)
    assert got.dtype == np.float32
    np.testing.assert_allclose(got, [[0.8, -0.4], [0.8, -0.4], [0.2, -0.1], [0.5, -0.5]], rtol=1e-6)


def test_the_scaled_commands_drive_the_same_path_in_proportion_to_T_con() -> None:
    """The invariance the option rests on: the same normalised output at T_con and 2 T_con, run for T_con and 2 T_con,
    ends at the same pose (a constant command is an arc) with half the energy."""
    from dwr_gym import model

    reference, action = 10.0, np.asarray([[0.6, 0.3]], np.float32)
    poses, energies = [], []
    for T_con in (20.0, 40.0):
        u, omega = time_scaled_action(action, observations([T_con]), reference)[0] * np.asarray([0.5, 2.0])
        steps = round(T_con / 0.05)
        x = y = psi = np.zeros(1)
        for _ in range(steps):
            x, y, psi = model.unicycle_step_exact(x, y, psi, np.full(1, u), np.full(1, omega), 0.05)
        poses.append(np.concatenate([x, y, np.unwrap(psi)]))
        energies.append((u * u + omega * omega) * T_con)
    np.testing.assert_allclose(poses[0], poses[1], atol=1e-9)
    np.testing.assert_allclose(energies[1], energies[0] / 2, rtol=1e-6)


def test_the_vec_env_steps_with_the_scaled_action() -> None:
    from dwr_gym.sb3 import make_sb3_vec_env

    actions = np.asarray([[0.9, -0.7]] * 4, np.float32)
    plain = make_sb3_vec_env(4, seed=5, T_con_range=(30.0, 60.0))
    scaled = TimeScaledVecEnv(make_sb3_vec_env(4, seed=5, T_con_range=(30.0, 60.0)), 10.0)
    obs, obs_scaled = plain.reset(), scaled.reset()
    np.testing.assert_array_equal(obs, obs_scaled)
    for _ in range(3):
        want = plain.step(time_scaled_action(actions, obs, 10.0))
        got = scaled.step(actions)
        obs = want[0]
        np.testing.assert_array_equal(got[0], want[0])
        np.testing.assert_array_equal(got[1], want[1])
    assert 0.0 < np.min(obs[:, T_CON_INDEX]) and np.max(10.0 / obs[:, T_CON_INDEX]) < 0.34  # all scaled down


def test_a_saved_agent_acts_time_scaled_and_a_residual_agent_scales_only_its_residual() -> None:
    from stable_baselines3 import PPO

    from baselines.expert import ExpertPolicy
    from baselines.registry import make_controller
    from dwr_gym.sb3 import make_sb3_vec_env
    from train.learning.training_env import as_policy

    model = PPO("MlpPolicy", make_sb3_vec_env(2, seed=0), n_steps=8, batch_size=16, seed=0)
    obs = observations([5.0, 20.0, 60.0])
    raw = np.clip(as_policy(model, TrainConfig()).predict(obs, deterministic=True)[0], -1, 1)
    factor = np.minimum(1.0, 10.0 / obs[:, T_CON_INDEX : T_CON_INDEX + 1])
    policy = as_policy(model, TrainConfig(action_time_scale=10.0))
    np.testing.assert_allclose(policy.predict(obs)[0], raw * factor, rtol=1e-6)
    residual = as_policy(model, TrainConfig(action_time_scale=10.0, residual=True, expert="ptc"))
    expert = ExpertPolicy(make_controller("ptc"), 0.5, 2.0).predict(obs)[0]
    np.testing.assert_allclose(residual.predict(obs)[0], np.clip(expert + 0.5 * raw * factor, -1, 1), atol=1e-6)
    assert isinstance(policy, TimeScaledPolicy)


@pytest.mark.parametrize("value", [-1.0, 1e9, "ten"])
def test_a_bad_time_scale_is_refused_in_one_line_naming_the_option(value: object) -> None:
    config = TrainConfig(action_time_scale=value)  # type: ignore[arg-type]
    with pytest.raises(ConfigError, match="--action-time-scale") as error:
        config.validate()
    assert "\n" not in str(error.value)


def test_the_jax_env_steps_with_the_numpy_scaled_action() -> None:
    jax = pytest.importorskip("jax")
    pytest.importorskip("flax")
    import jax.numpy as jnp

    import dwr_gym
    from dwr_gym.jax_env import make_gymnax_env
    from train.learning.time_scale import TimeScaledGymnaxEnv

    env, params = make_gymnax_env(dwr_gym.ENV_ID_V2)
    scaled_env = TimeScaledGymnaxEnv(env, 10.0)
    keys = jax.random.split(jax.random.PRNGKey(3), 32)
    obs, state = jax.vmap(env.reset_env, in_axes=(0, None))(keys, params)
    action = jax.random.uniform(jax.random.PRNGKey(4), (32, 2), jnp.float32, -1.5, 1.5)
    got = jax.vmap(scaled_env.step_env, in_axes=(0, 0, 0, None))(keys, state, action, params)[0]
    want_action = jnp.asarray(time_scaled_action(np.asarray(action), np.asarray(obs), 10.0))
    want = jax.vmap(env.step_env, in_axes=(0, 0, 0, None))(keys, state, want_action, params)[0]
    np.testing.assert_allclose(np.asarray(got), np.asarray(want), rtol=1e-6, atol=1e-6)


def test_cli_trains_a_time_scaled_es_agent_that_load_agent_runs_time_scaled(tmp_path: Path) -> None:
    pytest.importorskip("jax")
    pytest.importorskip("evosax")
    import yaml

    from train.learning.agents import load_agent

    run_dir = tmp_path / "run"
    env = {**os.environ, "PYTHONPATH": str(ROOT), "OMP_NUM_THREADS": "1"}
    command = [sys.executable, "-m", "train.cli", "train", "--backend", "jax", "--algo", "es", "--action-time-scale",
               "10", "--env", "DWRPointStabilization-v2", "--env-kwargs", "T_con_range=[20,30]",
               "--eval-episodes", "3", "--no-progress", "--total-timesteps", "3000", "--eval-freq", "2000",
               "--hyperparams", "population_size=4", "episodes=2", "policy_kwargs=dict(net_arch=[16])",
               "--run-dir", str(run_dir)]  # fmt: skip
    done = subprocess.run(command, cwd=ROOT, env=env, text=True, capture_output=True, timeout=600)
    assert done.returncode == 0, done.stderr
    saved = yaml.safe_load((run_dir / "config.yaml").read_text())
    assert saved["config"]["action_time_scale"] == 10.0 and saved["learned_from"] == "reward"
    _, policy = load_agent(run_dir)
    assert isinstance(policy, TimeScaledPolicy)
    obs = observations([20.0, 40.0])
    action = policy.predict(obs)[0]
    raw = np.clip(policy.policy.predict(obs, deterministic=True)[0], -1, 1)
    np.testing.assert_allclose(action, raw * np.asarray([[0.5], [0.25]]), rtol=1e-6)


def test_every_trainer_steps_its_env_time_scaled_and_around_the_residual() -> None:
    from train.learning.residual import ResidualVecEnv
    from train.learning.training_env import make_training_env

    config = TrainConfig(action_time_scale=10.0, residual=True, num_envs=2)
    venv = make_training_env(config)
    assert isinstance(venv, TimeScaledVecEnv) and isinstance(venv.venv, ResidualVecEnv)
    assert not isinstance(make_training_env(TrainConfig(num_envs=2)), TimeScaledVecEnv)
    pytest.importorskip("jax")
    pytest.importorskip("flax")
    from train.learning.jitted.residual import ResidualGymnaxEnv
    from train.learning.jitted.setup import make_jax_env
    from train.learning.time_scale import TimeScaledGymnaxEnv

    env, _ = make_jax_env(TrainConfig(backend="jax", action_time_scale=10.0, residual=True))
    assert isinstance(env, TimeScaledGymnaxEnv) and isinstance(env.env, ResidualGymnaxEnv)
    assert not isinstance(make_jax_env(TrainConfig(backend="jax"))[0], TimeScaledGymnaxEnv)

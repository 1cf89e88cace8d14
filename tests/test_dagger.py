"""Behaviour cloning from minimum-energy plans (train/imitation.py)."""

from __future__ import annotations

import warnings

import gymnasium as gym
import numpy as np
import pytest

pytest.importorskip("casadi")

from dwr_gym import V1_DEFAULTS
from dwr_gym.params import EnvParams
from train.agents import load_agent
from train.dagger import DaggerConfig, _solve, labelled_samples, run


def test_demonstration_samples_are_what_the_env_observes_when_the_plan_is_replayed() -> None:
    """The training pairs (observation, command) must be exactly the env's observations along the plan."""
    params = EnvParams.from_kwargs(**V1_DEFAULTS)
    start, T_con = (-1.2, 0.7, 2.5), 12.0
    plan = _solve((start, 0.85 * T_con, params.dt, params.u_max, params.omega_max, 5))
    assert plan is not None
    env = gym.make("DWRPointStabilization-v1")
    obs, _ = env.reset(seed=0, options={"start": start, "T_con": T_con})
    d0, e0 = float(obs[8]), float(obs[9])
    observations, actions = labelled_samples(plan, 0, T_con, d0, e0, params)  # type: ignore[misc]
    replayed, terminated = [obs], False
    for action in actions:
        obs, _, terminated, truncated, info = env.step(action)
        if terminated or truncated:
            break
        replayed.append(obs)
    assert terminated and info["is_success"] and info["time"] <= 0.85 * T_con + 1e-9
    np.testing.assert_allclose(np.array(replayed), observations[: len(replayed)], atol=1e-5)
    assert np.all(np.abs(actions) <= 1.0)


def test_a_tiny_cloning_run_saves_an_agent_that_loads_and_acts(tmp_path) -> None:  # type: ignore[no-untyped-def]
    env_kwargs = {**V1_DEFAULTS, "T_con_range": (10.0, 10.0), "start_distance": (0.3, 0.5)}  # few solver builds
    config = DaggerConfig(episodes=4, dagger_rounds=1, dagger_episodes=2, replans_per_episode=1, epochs=1,
                             workers=1, eval_episodes=2, eval_T_con=(10.0,), env_kwargs=env_kwargs)  # fmt: skip
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        run_dir = run(config, tmp_path / "bc", ["test"])
    assert (run_dir / "evaluations.csv").read_text().count("\n") == 3  # header and one row per fit
    label, policy = load_agent(run_dir)
    action, _ = policy.predict(np.zeros((5, 10), np.float32), deterministic=True)
    assert label == "bc" and action.shape == (5, 2) and np.all(np.isfinite(action))
    with pytest.raises(SystemExit, match="already holds a trained model"):
        run(config, run_dir, ["test"])

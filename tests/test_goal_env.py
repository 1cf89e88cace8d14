"""DWRPointStabilizationGoal-v0: env checkers, compute_reward against the rewards paid, SAC + HER."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import dwr_gym
from dwr_gym.goal_env import DWRPointStabilizationGoalEnv, goal_reward


def test_registered_and_passes_gymnasium_checker() -> None:
    env = gym.make(dwr_gym.GOAL_ENV_ID)
    check_env(env.unwrapped, skip_render_check=True)
    assert isinstance(env.observation_space, gym.spaces.Dict)
    assert set(env.observation_space.spaces) == {"observation", "achieved_goal", "desired_goal"}


def test_passes_sb3_checker() -> None:
    pytest.importorskip("stable_baselines3")
    from stable_baselines3.common.env_checker import check_env as sb3_check_env

    sb3_check_env(DWRPointStabilizationGoalEnv(), warn=True)


def reward_by_hand(pose: np.ndarray, goal: np.ndarray, reward_type: str) -> float:
    """The documented reward of the env made in the test below (goal_tolerance 0.05, the other weights default:
    time 0.5 [1/(m s)], dt 0.05 s, arrival 10, heading 5, arena 10 beyond 5 m) from the robot's true pose."""
    d = math.hypot(pose[0] - goal[0], pose[1] - goal[1])
    arrived = d <= 0.05
    if reward_type == "sparse":
        return 0.0 if arrived else -1.0
    heading_error = pose[2] - math.atan2(goal[3], goal[2])
    return (
        -0.5 * 0.05 * d
        + (10.0 + 5.0 * (math.cos(heading_error) - 1.0) if arrived else 0.0)
        - (10.0 if d > 5.0 else 0.0)
    )


@pytest.mark.parametrize("reward_type", ["dense", "sparse"])
def test_compute_reward_equals_rewards_paid(reward_type: str) -> None:
    """The rewards paid are the documented ones computed by hand; batched compute_reward on a rollout's goals (and on
    relabelled goals) equals them."""
    env = DWRPointStabilizationGoalEnv(reward_type=reward_type, goal_tolerance=0.05, T_con=5.0)
    achieved, desired, rewards, infos = [], [], [], []
    rng = np.random.default_rng(0)
    for episode in range(3):
        straight = {"start": (0.0, 0.0, 0.0), "goal": (0.3, 0.0, 0.0)}
        obs, _ = env.reset(seed=episode, options=straight if episode == 0 else None)
        done = False
        while not done:
            # episode 0 drives straight onto the goal, so that arrival (bonus and heading terms) is covered
            action = np.array([1.0, 0.0], np.float32) if episode == 0 else rng.uniform(-1, 1, 2).astype(np.float32)
            obs, reward, terminated, truncated, info = env.step(action)
            achieved.append(obs["achieved_goal"])
            desired.append(obs["desired_goal"])
            rewards.append(reward)
            infos.append(info)
            done = terminated or truncated
        if episode == 0:
            assert terminated and info["is_success"]
    achieved_arr, desired_arr = np.array(achieved), np.array(desired)
    paid = np.array(rewards)
    np.testing.assert_allclose(paid, [reward_by_hand(i["pose"], g, reward_type) for i, g in zip(infos, desired, strict=True)],
                               rtol=0, atol=1e-5)  # fmt: skip
    np.testing.assert_array_equal(env.compute_reward(achieved_arr, desired_arr, np.array(infos)), paid)
    assert len(set(paid.tolist())) > (1 if reward_type == "sparse" else 2)  # varied rewards, arrival included
    # HER's relabelling: the achieved goal as the desired one is an arrival with the heading matched
    relabelled = env.compute_reward(achieved_arr, achieved_arr, infos)
    expected = 0.0 if reward_type == "sparse" else env.params.arrival_bonus
    np.testing.assert_allclose(relabelled, expected, atol=1e-5)
    # batches with extra leading axes, as HER samples them
    assert env.compute_reward(achieved_arr[None], desired_arr[None], None).shape == (1, len(paid))


def test_goal_reward_terms() -> None:
    params = dwr_gym.EnvParams(goal_tolerance=0.1)
    goal = np.array([1.0, 2.0, 1.0, 0.0], np.float32)
    away = np.array([1.0, 2.5, 1.0, 0.0], np.float32)
    assert goal_reward(away, goal, params) == pytest.approx(-params.time_weight * params.dt * 0.5)
    reversed_heading = np.array([1.0, 2.0, -1.0, 0.0], np.float32)  # arrived, heading off by pi
    assert goal_reward(reversed_heading, goal, params) == pytest.approx(
        params.arrival_bonus - 2 * params.heading_weight
    )
    far = np.array([1.0 + params.arena_radius + 1, 2.0, 1.0, 0.0], np.float32)
    assert goal_reward(far, goal, params) < -params.arena_penalty
    assert goal_reward(away, goal, params, "sparse") == -1.0


def test_reset_options_place_start_and_goal() -> None:
    env = DWRPointStabilizationGoalEnv()
    obs, info = env.reset(seed=1, options={"start": (1.0, -1.0, 0.5), "goal": (0.5, 0.5, math.pi / 2)})
    np.testing.assert_allclose(obs["achieved_goal"], [1.0, -1.0, math.cos(0.5), math.sin(0.5)], atol=1e-6)
    np.testing.assert_allclose(obs["desired_goal"], [0.5, 0.5, 0.0, 1.0], atol=1e-6)
    assert info["distance"] == pytest.approx(math.hypot(0.5, 1.5))


def test_random_goals_vary_and_are_seeded() -> None:
    env = DWRPointStabilizationGoalEnv()
    goals = [env.reset(seed=s)[0]["desired_goal"] for s in (0, 1, 0)]
    assert not np.allclose(goals[0], goals[1])
    np.testing.assert_array_equal(goals[0], goals[2])


@pytest.mark.parametrize(("kwargs", "match"), [({"reward_type": "shaped"}, "reward_type='shaped'"),
                                               ({"T_con": -1.0}, "T_con=-1.0")])  # fmt: skip
def test_bad_arguments_name_the_parameter(kwargs: dict, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        gym.make(dwr_gym.GOAL_ENV_ID, **kwargs)


def test_sac_her_trains() -> None:
    """A tiny SAC + HerReplayBuffer run as a user writes it: learns, then acts on a dict observation."""
    pytest.importorskip("stable_baselines3")
    from stable_baselines3 import SAC, HerReplayBuffer

    env = gym.make(dwr_gym.GOAL_ENV_ID, T_con=2.0, goal_tolerance=0.1)
    model = SAC("MultiInputPolicy", env, replay_buffer_class=HerReplayBuffer,
                replay_buffer_kwargs={"n_sampled_goal": 4, "goal_selection_strategy": "future"},
                learning_starts=100, batch_size=32, policy_kwargs={"net_arch": [16, 16]}, seed=0, device="cpu")  # fmt: skip
    model.learn(200)
    assert model.replay_buffer.size() > 0
    obs, _ = env.reset(seed=0)
    action, _ = model.predict(obs, deterministic=True)
    assert action.shape == (2,) and np.all(np.abs(action) <= 1)

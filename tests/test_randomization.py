"""Disturbances drawn per episode (dwr_gym/randomization.py): validated, seeded, the vector env as the single envs,
each kind at its documented place."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import dwr_gym  # noqa: F401  (registers the envs)
from dwr_gym.randomization import DisturbanceDistribution

ENV = "DWRPointStabilization-v1"


def test_bad_settings_name_what_is_wrong() -> None:
    with pytest.raises(ValueError, match="probability"):
        DisturbanceDistribution(probability=1.5)
    with pytest.raises(ValueError, match="sinusoid_period"):
        DisturbanceDistribution(sinusoid_period=(0.0, 4.0))
    with pytest.raises(ValueError, match="fault_start"):
        DisturbanceDistribution(fault_start=(0.8, 0.2))
    with pytest.raises(ValueError, match="delay"):
        DisturbanceDistribution(delay=2.5)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="disturbance_distribution"):
        gym.make(ENV, disturbance_distribution={"probability": 0.5})
    from dwr_gym.disturbances import InputDelay

    with pytest.raises(ValueError, match="exclusive"):
        gym.make(ENV, disturbance_distribution=DisturbanceDistribution(), disturbances=[InputDelay(2)])


def test_sub_env_i_draws_what_a_single_env_reset_with_seed_plus_i_draws() -> None:
    distribution = DisturbanceDistribution(probability=0.8)
    envs = gym.make_vec(ENV, num_envs=3, disturbance_distribution=distribution)
    singles = [gym.make(ENV, disturbance_distribution=distribution, disable_env_checker=True)
               for _ in range(3)]  # fmt: skip
    obs, _ = envs.reset(seed=7)
    for i, env in enumerate(singles):
        single_obs, _ = env.reset(seed=7 + i)
        np.testing.assert_allclose(
            obs[i], single_obs, rtol=0, atol=1e-6
        )  # float32 trigonometry: numpy's, or math's for one robot
    drawn = envs.unwrapped.perturbation.episode()
    for i, env in enumerate(singles):
        mine = env.unwrapped.perturbation.episode()
        for key in drawn:
            np.testing.assert_array_equal(drawn[key][i], mine[key][0], err_msg=key)
    rng = np.random.default_rng(0)
    for _ in range(120):  # through episode ends: the vector env autoresets, the single envs are reset by hand
        actions = rng.uniform(-1, 1, (3, 2)).astype(np.float32)
        obs, rewards, terminated, truncated, _ = envs.step(actions)
        for i, env in enumerate(singles):
            if getattr(env, "_done", False):
                single_obs, _ = env.reset()
                env._done = False
                np.testing.assert_allclose(
                    obs[i], single_obs, rtol=0, atol=1e-6
                )  # float32: numpy's or math's trigonometry
                continue
            single_obs, reward, term, trunc, _ = env.step(actions[i])
            np.testing.assert_allclose(obs[i], single_obs, rtol=0, atol=1e-6)  # float32: numpy's or math's trigonometry
            assert rewards[i] == pytest.approx(reward, abs=1e-9) and terminated[i] == term and truncated[i] == trunc
            env._done = term or trunc


def test_draws_stay_within_their_bounds_and_each_kind_is_present_as_often_as_asked() -> None:
    distribution = DisturbanceDistribution(probability=0.5, seed=3)
    envs = gym.make_vec(ENV, num_envs=400, disturbance_distribution=distribution)
    envs.reset(seed=0)
    drawn = envs.unwrapped.perturbation.episode()
    assert np.all(np.abs(drawn["bias"]) <= np.array(distribution.bias))
    assert np.all((drawn["sinusoid_amplitude"] >= 0) & (drawn["sinusoid_amplitude"] <= np.array(distribution.sinusoid)))
    assert np.all((drawn["sinusoid_period"] >= 2.0) & (drawn["sinusoid_period"] <= 8.0))
    assert np.all((drawn["wheel_efficiency"] >= 1 - distribution.slip) & (drawn["wheel_efficiency"] <= 1))
    assert np.all((drawn["fault_fraction"] >= 1 - distribution.fault) & (drawn["fault_fraction"] <= 1))
    assert np.all((drawn["delay"] >= 0) & (drawn["delay"] <= distribution.delay))
    assert np.all((drawn["dropout"] >= 0) & (drawn["dropout"] < distribution.dropout))
    for present in (drawn["delay"] > 0, drawn["dropout"] > 0, drawn["fault_fraction"] < 1):
        assert 0.35 < present.mean() < 0.6  # probability 0.5 (a delay of 0 can be drawn when present)


def test_with_nothing_present_the_robot_is_the_nominal_one() -> None:
    nominal = gym.make(ENV, disable_env_checker=True)
    drawn = gym.make(ENV, disturbance_distribution=DisturbanceDistribution(probability=0.0), disable_env_checker=True)
    obs_a, _ = nominal.reset(seed=4)
    obs_b, _ = drawn.reset(seed=4)
    rng = np.random.default_rng(1)
    for _ in range(200):
        action = rng.uniform(-1, 1, 2).astype(np.float32)
        (obs_a, r_a, t_a, *_), (obs_b, r_b, t_b, *_) = nominal.step(action), drawn.step(action)
        np.testing.assert_allclose(obs_b, obs_a, atol=1e-6)  # the wheels' round trip rounds in the last bits
        assert r_b == pytest.approx(r_a, abs=1e-9)
        assert t_b == t_a
        if t_a:
            break


def drawn_robots(seed: int, reset_seed: int = 0, steps: int = 40) -> tuple[dict, np.ndarray]:
    """What 16 robots of a distribution with ``seed`` drew at reset(seed=reset_seed), and their observations after
    ``steps`` steps of one fixed action (the per-step draws: random walk, dropout)."""
    distribution = DisturbanceDistribution(probability=1.0, seed=seed)
    envs = gym.make_vec(ENV, num_envs=16, disturbance_distribution=distribution)
    obs, _ = envs.reset(seed=reset_seed)
    drawn = envs.unwrapped.perturbation.episode()
    for _ in range(steps):
        obs, *_ = envs.step(np.tile(np.float32([0.5, 0.3]), (16, 1)))
    return drawn, obs


def test_the_distributions_seed_picks_the_robots_the_same_seed_repeats_them() -> None:
    """Two runs of one seed meet the same robots, step for step; another seed (same reset seed) meets others."""
    drawn, obs = drawn_robots(seed=1)
    again, obs_again = drawn_robots(seed=1)
    other, obs_other = drawn_robots(seed=2)
    for key in drawn:
        np.testing.assert_array_equal(again[key], drawn[key], err_msg=key)
    np.testing.assert_array_equal(obs_again, obs)
    for key in ("bias", "sinusoid_amplitude", "sinusoid_period", "random_walk", "wheel_efficiency", "fault_fraction",
                "fault_start", "dropout"):  # fmt: skip
        assert not np.any(np.isclose(other[key], drawn[key], rtol=0, atol=1e-12)), key  # every robot, every kind
    assert not np.allclose(obs_other, obs)
    # the reset seed picks the robots as well: the distribution's seed is one more key, not the only one
    assert not np.any(drawn_robots(seed=1, reset_seed=1, steps=0)[0]["bias"] == drawn["bias"])

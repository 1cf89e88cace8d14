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
        gym.make(ENV, disturbance_distribution=0.5)
    with pytest.raises(ValueError, match=r"disturbance_distribution field.*probabilty"):  # its dict form, misspelt
        gym.make(ENV, disturbance_distribution={"probabilty": 0.5})
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


def seeded(distribution: DisturbanceDistribution, n: int, T_con: float = 20.0, robot: object = None) -> tuple:
    """A RandomPerturbation of n robots, seeded and reset at an observation whose T_con feature is ``T_con``."""
    from dwr_gym.params import EnvParams

    perturbation = distribution.perturbation(robot, EnvParams(T_con=T_con), n)  # type: ignore[arg-type]
    perturbation.seed(list(range(n)), [(i,) for i in range(n)])
    obs = np.random.default_rng(9).uniform(-1, 1, (n, 10)).astype(np.float32)
    obs[:, 7] = T_con
    perturbation.reset(slice(None), obs)
    return perturbation, obs


def test_each_drawn_disturbance_acts_on_the_command_as_the_module_documents_by_hand() -> None:
    """Wheels (slip, then the fault from its start on) on the commanded wheel speeds, then the bias and the sinusoid
    added to the body velocities: arithmetic written out here, robot by robot, against command()."""
    from dwr_gym.randomization import DEFAULT_GEOMETRY

    distribution = DisturbanceDistribution(probability=0.7, random_walk=(0.0, 0.0), delay=0, dropout=0.0, seed=5)
    n = 64
    perturbation, _ = seeded(distribution, n)
    drawn = perturbation.episode()
    b = DEFAULT_GEOMETRY.track_width
    rng = np.random.default_rng(0)
    for step in (0, 37, 150, 399):
        u, w = rng.uniform(-0.5, 0.5, n), rng.uniform(-2.0, 2.0, n)
        got_u, got_w = perturbation.command(u, w, np.full(n, step))
        t = 0.05 * step
        fault = np.where(t >= drawn["fault_start"], drawn["fault_fraction"], 1.0)
        left = (u - 0.5 * b * w) * drawn["wheel_efficiency"][:, 0] * np.where(drawn["fault_wheel"] == "left", fault, 1)
        right = (
            (u + 0.5 * b * w) * drawn["wheel_efficiency"][:, 1] * np.where(drawn["fault_wheel"] == "right", fault, 1)
        )
        wave = np.sin(2.0 * np.pi * t / drawn["sinusoid_period"] + perturbation.phase)
        np.testing.assert_allclose(got_u, 0.5 * (left + right) + drawn["bias"][:, 0]
                                   + drawn["sinusoid_amplitude"][:, 0] * wave, rtol=0, atol=1e-12)  # fmt: skip
        np.testing.assert_allclose(got_w, (right - left) / b + drawn["bias"][:, 1]
                                   + drawn["sinusoid_amplitude"][:, 1] * wave, rtol=0, atol=1e-12)  # fmt: skip
        info = perturbation.info()
        np.testing.assert_array_equal(info["commanded_linear_velocity"], u)
        np.testing.assert_array_equal(info["commanded_angular_velocity"], w)
        np.testing.assert_array_equal(info["fault_active"], (t >= drawn["fault_start"]) & (drawn["fault_fraction"] < 1))
    assert 0 < np.mean(drawn["fault_start"] > 0.05 * 37) < 1  # some faults started within the steps above, some not


def test_a_drawn_delay_executes_the_command_of_that_many_periods_before() -> None:
    nothing = {"bias": (0.0, 0.0), "sinusoid": (0.0, 0.0), "random_walk": (0.0, 0.0), "slip": 0.0, "fault": 0.0,
               "dropout": 0.0}  # fmt: skip
    n = 32
    perturbation, _ = seeded(DisturbanceDistribution(probability=1.0, delay=5, seed=2, **nothing), n)
    delay = perturbation.episode()["delay"]
    assert set(delay.tolist()) == set(range(6))  # 0 to 5 periods, each drawn
    sent = np.random.default_rng(1).uniform(-0.5, 0.5, (20, 2, n))
    for k in range(20):
        u, w = perturbation.command(sent[k, 0], sent[k, 1], np.full(n, k))
        late = k - delay
        expected = np.where(late >= 0, sent[np.maximum(late, 0), :, np.arange(n)].T, 0.0)  # nothing before the start
        np.testing.assert_allclose(np.stack([u, w]), expected, rtol=0, atol=1e-12)


def test_a_dropped_measurement_holds_the_last_delivered_pose_from_the_reset_on() -> None:
    nothing = {"bias": (0.0, 0.0), "sinusoid": (0.0, 0.0), "random_walk": (0.0, 0.0), "slip": 0.0, "fault": 0.0,
               "delay": 0}  # fmt: skip
    n = 200
    perturbation, reset_obs = seeded(DisturbanceDistribution(probability=1.0, dropout=0.9, seed=4, **nothing), n)
    dropout = perturbation.episode()["dropout"]
    last = reset_obs[:, :6].copy()
    held_count = np.zeros(n)
    rng = np.random.default_rng(3)
    for _ in range(60):
        fresh = rng.uniform(-1, 1, (n, 10)).astype(np.float32)
        out = perturbation.measure(fresh.copy())
        held = perturbation.info()["measurement_held"]
        np.testing.assert_array_equal(out[held, :6], last[held])  # at k = 0: the reset observation's pose
        np.testing.assert_array_equal(out[~held, :6], fresh[~held, :6])
        np.testing.assert_array_equal(out[:, 6:], fresh[:, 6:])  # the clock features are never held
        last, held_count = out[:, :6].copy(), held_count + held
    # each robot drops measurements at its drawn rate (60 draws: a binomial spread of about 0.06)
    assert np.corrcoef(held_count / 60, dropout)[0, 1] > 0.9


def test_a_drawn_random_walk_has_independent_increments_of_its_drawn_intensity() -> None:
    nothing = {"bias": (0.0, 0.0), "sinusoid": (0.0, 0.0), "slip": 0.0, "fault": 0.0, "delay": 0, "dropout": 0.0}
    n = 16
    perturbation, _ = seeded(DisturbanceDistribution(probability=1.0, random_walk=(0.05, 0.2), seed=6, **nothing), n)
    intensity = perturbation.episode()["random_walk"]
    walks = np.array([perturbation.command(np.zeros(n), np.zeros(n), np.full(n, k)) for k in range(300)])  # (300, 2, n)
    increments = np.diff(np.concatenate([np.zeros((1, 2, n)), walks]), axis=0) / (np.sqrt(0.05) * intensity.T)
    assert 0.9 < np.std(increments) < 1.1 and abs(np.mean(increments)) < 0.05  # standard normal, (m/s) / sqrt(s)
    assert abs(np.corrcoef(increments[:, 0].ravel(), increments[:, 1].ravel())[0, 1]) < 0.1


def test_draws_are_independent_where_the_docs_say_so() -> None:
    """The period and phase of the sinusoid, the slip of the two wheels, each kind's presence: separate draws."""
    perturbation, _ = seeded(DisturbanceDistribution(probability=1.0, seed=8), 400)
    drawn = perturbation.episode()
    assert abs(np.corrcoef(drawn["sinusoid_period"], perturbation.phase)[0, 1]) < 0.15
    assert abs(np.corrcoef(*drawn["wheel_efficiency"].T)[0, 1]) < 0.15
    assert 0.4 < np.mean(drawn["fault_wheel"] == "left") < 0.6
    assert np.all(perturbation.phase >= 0) and np.all(perturbation.phase < 2 * np.pi)
    starts = drawn["fault_start"] / 20.0  # fractions of T_con in fault_start = (0, 0.5)
    assert starts.max() <= 0.5 and 0.2 < np.mean(starts > 0.25) < 0.8


def test_with_nothing_present_a_robot_with_wheel_limits_is_that_robot() -> None:
    """The wheels' saturation of the chosen robot applies under the distribution as without it."""
    robot = {"robot": "turtlebot3_burger"}
    nominal = gym.make(ENV, disable_env_checker=True, **robot)
    drawn = gym.make(ENV, disturbance_distribution=DisturbanceDistribution(probability=0.0), disable_env_checker=True,
                     **robot)  # fmt: skip
    nominal.reset(seed=2)
    drawn.reset(seed=2)
    saturated = 0
    for _ in range(50):
        action = np.float32([1.0, 1.0])  # full speed and full turn: beyond what the wheels can do
        (obs_a, *_), (obs_b, _, _, _, info) = nominal.step(action), drawn.step(action)
        np.testing.assert_allclose(obs_b, obs_a, atol=1e-6)
        saturated += info["disturbance"]["wheel_saturated"]
    assert saturated == 50


def test_settings_are_normalised_and_each_bound_is_enforced() -> None:
    from dwr_gym.params import EnvParams

    assert DisturbanceDistribution(bias=[0.1, 1], fault_start=[0, 0.5]) == DisturbanceDistribution(  # type: ignore[arg-type]
        bias=(0.1, 1.0), fault_start=(0.0, 0.5)
    )
    with pytest.raises(ValueError, match=r"bias\[1\]"):
        DisturbanceDistribution(bias=(0.1, 10.5))
    with pytest.raises(ValueError, match="fault"):
        DisturbanceDistribution(fault=1.2)
    with pytest.raises(ValueError, match="seed"):
        DisturbanceDistribution(seed=-1)
    params = EnvParams(T_con=1.0, dt=0.1)
    steps = params.max_episode_steps
    DisturbanceDistribution(delay=steps - 1).perturbation(None, params, 2)
    with pytest.raises(ValueError, match="delay"):
        DisturbanceDistribution(delay=steps).perturbation(None, params, 2)  # as long as the episode: refused


def test_the_disturbance_info_has_the_same_keys_at_reset_and_at_each_step_as_the_fixed_disturbances() -> None:
    from dwr_gym.disturbances import VelocityBias

    fixed = gym.make(ENV, disturbances=[VelocityBias(0.1, 0.0)], disable_env_checker=True)
    drawn = gym.make(ENV, disturbance_distribution=DisturbanceDistribution(), disable_env_checker=True)
    keys = set(fixed.reset(seed=0)[1]["disturbance"])
    _, info = drawn.reset(seed=0)
    assert set(info["disturbance"]) == keys and not any(info["disturbance"].values())  # nothing happened yet
    *_, info = drawn.step(np.float32([0.5, -0.25]))
    assert set(info["disturbance"]) == keys
    assert info["disturbance"]["commanded_angular_velocity"] == pytest.approx(-0.5)  # -0.25 x omega_max 2 rad/s

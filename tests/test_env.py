"""DWRPointStabilization-v0 as a Gymnasium and stable-baselines3 user meets it."""

from __future__ import annotations

import math
import subprocess
import sys
import warnings
from typing import Any

import gymnasium as gym
import numpy as np
import pytest

import dwr_gym
from dwr_gym import model
from dwr_gym.env import DWRPointStabilizationEnv

ENV_ID = "DWRPointStabilization-v0"
#: This module pins the behaviour of DWRPointStabilization-v0 (fixed T_con, the paper's reward), which Gymnasium
#: rightly calls out of date now that v1 exists; that warning is not what these tests test.
pytestmark = pytest.mark.filterwarnings("ignore:.*DWRPointStabilization-v0 is out of date:DeprecationWarning")
ENV_ID_V1 = "DWRPointStabilization-v1"


def make(**kwargs: Any) -> gym.Env[Any, Any]:
    return gym.make(ENV_ID, **kwargs)


def rollout(env: gym.Env[Any, Any], seed: int, steps: int) -> tuple[np.ndarray, np.ndarray]:
    obs, _ = env.reset(seed=seed)
    env.action_space.seed(seed)
    observations, rewards = [obs], []
    for _ in range(steps):
        obs, reward, terminated, truncated, _ = env.step(env.action_space.sample())
        observations.append(obs)
        rewards.append(reward)
        if terminated or truncated:
            obs, _ = env.reset()
    return np.array(observations), np.array(rewards)


def test_gymnasium_check_env_passes_without_warnings() -> None:
    from gymnasium.utils.env_checker import check_env

    envs = [make(render_mode="rgb_array"), make(), gym.make(ENV_ID_V1)]  # made outside: v0 is out of date, it warns
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for env in envs:
            check_env(env.unwrapped)


def test_sb3_check_env_passes_without_warnings() -> None:
    from stable_baselines3.common.env_checker import check_env

    envs = [make(), gym.make(ENV_ID_V1)]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for env in envs:
            check_env(env.unwrapped, warn=True)


def test_make_works_in_a_fresh_interpreter_without_import() -> None:
    code = (
        "import gymnasium as gym; env = gym.make('dwr_gym:DWRPointStabilization-v0'); "
        "obs, info = env.reset(seed=0); print(obs.shape, type(env.unwrapped).__name__)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert "(10,) DWRPointStabilizationEnv" in out


def test_registration_is_idempotent() -> None:
    dwr_gym.register_envs()
    dwr_gym.register_envs()
    assert gym.spec(ENV_ID).entry_point == "dwr_gym.env:DWRPointStabilizationEnv"


def test_seeded_resets_and_rollouts_are_reproducible() -> None:
    obs_a, rew_a = rollout(make(), seed=7, steps=300)
    obs_b, rew_b = rollout(make(), seed=7, steps=300)
    obs_c, _ = rollout(make(), seed=8, steps=10)
    np.testing.assert_array_equal(obs_a, obs_b)
    np.testing.assert_array_equal(rew_a, rew_b)
    assert not np.array_equal(obs_a[0], obs_c[0])


def test_random_starts_lie_in_the_configured_ranges() -> None:
    env = make(start_distance=(0.5, 0.7), start_heading=(-0.1, 0.1))
    for seed in range(50):
        _, info = env.reset(seed=seed)
        assert 0.5 <= info["distance"] <= 0.7
        assert abs(info["heading_error"]) <= 0.1 + 1e-12


def test_reset_options_place_robot_and_goal_exactly() -> None:
    env = make()
    obs, info = env.reset(options={"start": (0.0, 0.0, math.pi), "goal": (0.8, 0.0, 0.0)})
    assert info["distance"] == pytest.approx(0.8)
    assert info["heading_error"] == pytest.approx(-math.pi)  # wrapped to [-pi, pi)
    np.testing.assert_allclose(info["pose"], [0.0, 0.0, -math.pi], atol=1e-12)
    assert obs[0] == pytest.approx(0.8)
    assert obs[1] == pytest.approx(1.0) and obs[2] == pytest.approx(0.0, abs=1e-7)  # goal straight ahead in x


@pytest.mark.parametrize("goal", [(0.0, 1.0, 0.0), (1.0, 0.0, 0.0), (0.0, 0.0, 0.5), (0.0, 0.0, 0.0)])
def test_info_pose_is_the_world_pose_for_goals_off_the_origin_on_each_axis(goal: tuple[float, float, float]) -> None:
    """The single env skips the frame change only when the goal is (0, 0, 0); any one coordinate off needs it."""
    env = make()
    _, info = env.reset(options={"start": (0.3, -0.2, 0.1), "goal": goal})
    np.testing.assert_allclose(info["pose"], [0.3, -0.2, 0.1], atol=1e-12)
    _, _, _, _, info = env.step(np.array([1.0, 0.0], dtype=np.float32))  # 0.025 m along the heading 0.1
    np.testing.assert_allclose(info["pose"], [0.3 + 0.025 * math.cos(0.1), -0.2 + 0.025 * math.sin(0.1), 0.1],
                               atol=1e-12)  # fmt: skip


def test_any_goal_pose_is_the_paper_case_in_the_goal_frame() -> None:
    env = make()
    paper, _ = env.reset(options={"start": (0.0, 0.0, 0.3), "goal": (0.8, 0.0, 0.0)})
    goal = (2.0, -1.0, math.pi / 3)  # the same relative pose, rotated and shifted
    c, s = math.cos(goal[2]), math.sin(goal[2])
    start = (goal[0] + c * -0.8, goal[1] + s * -0.8, 0.3 + goal[2])
    general, _ = env.reset(options={"start": start, "goal": goal})
    np.testing.assert_allclose(paper, general, atol=1e-6)


def test_reset_rejects_bad_options() -> None:
    env = make()
    with pytest.raises(ValueError, match="start"):
        env.reset(options={"start": (0.0, float("nan"), 0.0)})
    with pytest.raises(ValueError, match="goal"):
        env.reset(options={"goal": (1.0, 2.0)})
    with pytest.raises(ValueError, match="unknown reset option"):
        env.reset(options={"strat": (0.0, 0.0, 0.0)})
    with pytest.raises(ValueError, match="arena_radius"):
        env.reset(options={"start": (100.0, 0.0, 0.0)})


def test_actions_are_clipped_and_non_finite_actions_rejected() -> None:
    env_a, env_b = make(), make()
    env_a.reset(seed=1)
    env_b.reset(seed=1)
    obs_a, *_, info_a = env_a.step(np.array([5.0, -7.0], dtype=np.float32))
    obs_b, *_, _info_b = env_b.step(np.array([1.0, -1.0], dtype=np.float32))
    np.testing.assert_array_equal(obs_a, obs_b)
    assert info_a["linear_velocity"] == pytest.approx(0.5) and info_a["angular_velocity"] == pytest.approx(-2.0)
    with pytest.raises(ValueError, match="action"):
        env_a.step(np.array([np.nan, 0.0], dtype=np.float32))
    with pytest.raises(ValueError, match="action"):
        env_a.step(np.array([np.inf, 0.0], dtype=np.float32))


def test_info_and_reward_terms() -> None:
    env = make()
    env.reset(seed=3)
    _, reward, _, _, info = env.step(np.array([0.4, 0.2], dtype=np.float32))
    for key in ("distance", "orientation_error", "heading_error", "time", "is_success", "energy", "reward_terms"):
        assert key in info
    assert set(info["reward_terms"]) == {"progress", "time", "effort", "energy", "arrival", "heading", "late", "arena"}
    assert reward == pytest.approx(sum(info["reward_terms"].values()))
    u, omega = 0.4 * 0.5, 0.2 * 2.0
    assert info["energy"] == pytest.approx((u**2 + omega**2) * 0.05)
    assert info["time"] == pytest.approx(0.05)


def test_potential_based_progress_term_telescopes() -> None:
    env = make(shaping_discount=1.0)
    _, info0 = env.reset(seed=5)
    start_potential = 0.5 * (info0["distance"] ** 2 + info0["orientation_error"] ** 2)
    total = 0.0
    for _ in range(40):
        *_, info = env.step(np.array([0.3, 0.5], dtype=np.float32))
        total += info["reward_terms"]["progress"]
    end_potential = 0.5 * (info["distance"] ** 2 + info["orientation_error"] ** 2)
    assert total == pytest.approx(start_potential - end_potential)


def test_prescribed_time_term_costs_more_as_T_con_nears() -> None:
    env = make(T_con=10.0, dt=0.1, late_penalty=0.0)
    env.reset(options={"start": (-1.0, 0.0, math.pi / 2), "goal": (0.0, 0.0, 0.0)})
    costs = []
    for _ in range(99):
        *_, info = env.step(np.zeros(2, dtype=np.float32))  # stands still: d stays 1
        costs.append(-info["reward_terms"]["time"])
    growing = costs[:94]  # until T_con - t = T_con / time_gain_cap = 0.5 s
    assert np.all(np.diff(growing) > 0)
    assert growing[-1] / growing[0] > 9.0  # mu_1 grows from ~1 to T_con / (T_con - t)
    assert costs[-1] == pytest.approx(0.5 * 0.1 * 1.0 * 20.0)  # then capped at time_gain_cap


def test_arrival_terminates_with_bonus_before_T_con_and_late_penalty_after() -> None:
    env = make(goal_tolerance=0.05)
    env.reset(options={"start": (-0.06, 0.0, 0.0), "goal": (0.0, 0.0, 0.0)})
    _, _, terminated, truncated, info = env.step(np.array([1.0, 0.0], dtype=np.float32))
    assert terminated and not truncated and info["is_success"]
    assert info["reward_terms"]["arrival"] == pytest.approx(10.0)

    env = make(T_con=1.0, dt=0.1, horizon_factor=2.0)
    env.reset(options={"start": (-1.0, 0.0, 0.0), "goal": (0.0, 0.0, 0.0)})
    lates = []
    for step in range(1, 21):
        _, _, terminated, truncated, info = env.step(np.zeros(2, dtype=np.float32))
        lates.append(info["reward_terms"]["late"])
        assert terminated is False
        assert truncated == (step == 20)  # horizon = 2 T_con = 20 steps
    assert all(v == 0.0 for v in lates[:10]) and all(v == pytest.approx(-0.1) for v in lates[10:])


def test_heading_term_is_paid_on_arrival_only() -> None:
    env = make(goal_tolerance=0.05, heading_weight=2.0)
    env.reset(options={"start": (-0.2, 0.0, math.pi / 2), "goal": (0.0, 0.0, 0.0)})
    *_, info = env.step(np.zeros(2, dtype=np.float32))
    assert info["reward_terms"]["heading"] == 0.0
    env.reset(options={"start": (-0.03, 0.0, math.pi / 2), "goal": (0.0, 0.0, 0.0)})
    _, _, terminated, _, info = env.step(np.array([0.0, 0.0], dtype=np.float32))
    assert terminated and info["reward_terms"]["heading"] == pytest.approx(2.0 * (math.cos(math.pi / 2) - 1.0))


def test_heading_tolerance_is_part_of_success_when_set() -> None:
    env = make(goal_tolerance=0.05, heading_tolerance=0.1)
    env.reset(options={"start": (-0.06, 0.0, 1.0), "goal": (0.0, 0.0, 0.0)})
    _, _, terminated, _, info = env.step(np.array([0.0, 0.0], dtype=np.float32))
    assert info["distance"] < 0.07 and not terminated and not info["is_success"]


def test_leaving_the_arena_terminates_with_penalty() -> None:
    env = make(arena_radius=0.5, start_distance=(0.45, 0.45))
    env.reset(options={"start": (-0.49, 0.0, math.pi), "goal": (0.0, 0.0, 0.0)})
    _, _, terminated, _, info = env.step(np.array([1.0, 0.0], dtype=np.float32))
    assert terminated and not info["is_success"]
    assert info["reward_terms"]["arena"] == pytest.approx(-10.0)


def test_observation_noise_changes_observations_but_not_the_true_state() -> None:
    clean, noisy = make(), make(observation_noise=0.05)
    obs_c, info_c = clean.reset(seed=2)
    obs_n, info_n = noisy.reset(seed=2)
    assert info_c["distance"] == info_n["distance"]
    assert not np.allclose(obs_c, obs_n)
    again, _ = make(observation_noise=0.05).reset(seed=2)
    np.testing.assert_array_equal(obs_n, again)


BAD_KWARGS = [
    ("T_con", -1.0),
    ("T_con", float("nan")),
    ("dt", 0.0),
    ("u_max", -0.5),
    ("omega_max", float("inf")),
    ("goal_tolerance", 0.0),
    ("heading_tolerance", 4.0),
    ("horizon_factor", 0.5),
    ("arena_radius", 0.0),
    ("start_distance", (1.0, 0.5)),
    ("start_distance", (0.1, 99.0)),
    ("start_heading", (-4.0, 0.0)),
    ("integrator", "leapfrog"),
    ("substeps", 0),
    ("substeps", 1.5),
    ("k", 0.5),
    ("time_weight", -1.0),
    ("shaping_discount", 1.5),
    ("observation_noise", -0.1),
    ("actuation_noise", "loud"),
]


@pytest.mark.parametrize("name, value", BAD_KWARGS)
def test_every_invalid_keyword_names_parameter_and_value(name: str, value: Any) -> None:
    with pytest.raises(ValueError, match=name) as error:
        make(**{name: value})
    assert "invalid" in str(error.value) or "min must not exceed" in str(error.value)


def test_unknown_keywords_and_render_modes_are_rejected() -> None:
    with pytest.raises(ValueError, match=r"unknown parameter.*T_conn"):
        make(T_conn=20.0)
    with pytest.raises(ValueError, match="render_mode"):
        DWRPointStabilizationEnv(render_mode="ascii")


def test_rgb_array_frame() -> None:
    env = make(render_mode="rgb_array")
    env.reset(seed=0)
    for _ in range(5):
        env.step(np.array([1.0, 0.5], dtype=np.float32))
    frame = env.render()
    assert isinstance(frame, np.ndarray) and frame.dtype == np.uint8 and frame.shape == (480, 480, 3)
    assert len(np.unique(frame.reshape(-1, 3), axis=0)) > 5  # robot, wheels, goal, trail and text are drawn
    env.close()


def test_human_render_without_pygame_tells_how_to_install(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, "pygame", None)
    env = DWRPointStabilizationEnv(render_mode="human")
    with pytest.raises(gym.error.DependencyNotInstalled, match="pip install"):
        env.reset(seed=0)


def test_async_vector_env_with_spawn() -> None:
    envs = gym.vector.AsyncVectorEnv(
        [lambda: gym.make("dwr_gym:DWRPointStabilization-v0") for _ in range(2)], context="spawn"
    )
    try:
        obs, _ = envs.reset(seed=0)
        assert obs.shape == (2, 10)
        obs, rewards, *_ = envs.step(np.zeros((2, 2), dtype=np.float32))
        assert np.all(np.isfinite(obs)) and np.all(np.isfinite(rewards))
        single, _ = gym.make(ENV_ID).reset(seed=1)
        first, _ = envs.reset(seed=0)
        np.testing.assert_array_equal(first[1], single)
    finally:
        envs.close()


def test_edge_states_give_finite_observations_and_rewards() -> None:
    env = make(arena_radius=1e6, start_distance=(0.0, 1.0))
    for start in [(0.0, 0.0, 0.0), (-0.5, 0.0, math.pi), (-0.5, 0.0, -math.pi), (9e5, -4e5, 1.0)]:
        obs, _info = env.reset(options={"start": start, "goal": (0.0, 0.0, 0.0)})
        assert np.all(np.isfinite(obs))
        obs, reward, *_ = env.step(np.array([1.0, 1.0], dtype=np.float32))
        assert np.all(np.isfinite(obs)) and math.isfinite(reward)
    huge = make()
    obs, _ = huge.reset(options={"start": (1e9 - 1.0, 1e9, 0.0), "goal": (1e9, 1e9, 0.0)})
    assert obs[0] == pytest.approx(1.0) and np.all(np.isfinite(obs))


def test_model_and_env_agree_on_the_paper_quantities() -> None:
    env = make()
    obs, info = env.reset(options={"start": (0.1, 0.2, 0.7), "goal": (0.8, 0.0, 0.0)})
    x, y, psi = model.to_goal_frame(0.1, 0.2, 0.7, 0.8, 0.0, 0.0)
    d, alpha = model.distance(x, y), model.azimuth(x, y)
    assert info["distance"] == pytest.approx(d)
    assert info["orientation_error"] == pytest.approx(model.orientation_error(alpha, psi, d, 1 / (2 * math.pi)))
    assert math.atan2(obs[2], obs[1]) == pytest.approx(alpha, abs=1e-6)


def test_arrival_is_d_at_most_goal_tolerance_and_integer_actions_are_actions() -> None:
    env = make(goal_tolerance=0.5)
    env.reset(options={"start": (-0.5, 0.0, 0.0), "goal": (0.0, 0.0, 0.0)})  # d = 0.5 exactly
    _, _, terminated, _, info = env.step(np.array([0, 0]))  # integers: no motion
    assert info["distance"] == 0.5 and info["is_success"] and terminated
    env.reset(options={"start": (-0.5, 0.0, 0.0), "goal": (1.0, 0.0, 0.0)})
    as_int = env.step(np.array([1, -1]))[4]
    env.reset(options={"start": (-0.5, 0.0, 0.0), "goal": (1.0, 0.0, 0.0)})
    as_bool = env.step(np.array([True, False]))[4]
    assert (as_int["linear_velocity"], as_int["angular_velocity"]) == (0.5, -2.0)
    assert (as_bool["linear_velocity"], as_bool["angular_velocity"]) == (0.5, 0.0)


def test_observation_space_bounds_are_the_documented_ones() -> None:
    space = make(arena_radius=4.0, horizon_factor=2.0).observation_space
    e_max = 7.0 * math.pi / 6.0
    np.testing.assert_allclose(space.low, [0, -1, -1, -1, -1, -e_max, 0, 0, 0, -e_max], rtol=1e-7)
    np.testing.assert_allclose(space.high, [8.0, 1, 1, 1, 1, e_max, 2.0, 20.0, 4.0, e_max], rtol=1e-7)


def test_a_start_on_the_arena_border_is_allowed_and_beyond_it_is_refused() -> None:
    env = make(arena_radius=2.0)
    _, info = env.reset(options={"start": (-2.0, 0.0, 0.0), "goal": (0.0, 0.0, 0.0)})
    assert info["distance"] == 2.0
    with pytest.raises(ValueError, match=r"start pose is 2.001 m from the goal, outside the arena"):
        env.reset(options={"start": (-2.001, 0.0, 0.0), "goal": (0.0, 0.0, 0.0)})
    # on the border the robot has not left (the arena is d <= arena_radius): standing still, its episode goes on
    _, _, terminated, _, info = env.step(np.zeros(2, np.float32))
    assert info["distance"] == 2.0 and not terminated and info["reward_terms"]["arena"] == 0.0

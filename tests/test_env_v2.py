"""DWRPointStabilization-v2, the task held to T_con: its episode end, its return, and what it does not pay for."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from hypothesis import given, settings
from hypothesis import strategies as st

import dwr_gym
from dwr_gym import core

V2 = dwr_gym.ENV_ID_V2


def run(env: gym.Env, actions: object, options: dict | None = None, seed: int = 0) -> tuple[float, list[dict], bool]:
    """Step ``env`` with ``actions(obs, t)`` to the end; (return, infos, terminated at the end)."""
    obs, info = env.reset(seed=seed, options=options)
    infos, total, t = [info], 0.0, 0
    while True:
        obs, reward, terminated, truncated, info = env.step(actions(obs, t))  # type: ignore[operator]
        total, t = total + float(reward), t + 1
        infos.append(info)
        assert not truncated  # held to T_con: the episode ends there, as the task's end
        if terminated:
            return total, infos, terminated


def test_v2_passes_gymnasiums_checker_and_reports_its_length() -> None:
    env = gym.make(V2)
    check_env(env.unwrapped, skip_render_check=True)
    assert env.spec is not None and env.spec.max_episode_steps == 1200  # the steps of T_con = 60 s


def test_arriving_early_does_not_end_the_episode_it_ends_at_T_con() -> None:
    env = gym.make(V2)
    start = {"start": (0.0, 0.0, 0.0), "goal": (0.005, 0.0, 0.0), "T_con": 12.34}  # within tolerance from the start
    _, infos, _ = run(env, lambda obs, t: np.zeros(2, np.float32), start)
    assert len(infos) - 1 == int(12.34 / 0.05)  # floor(T_con / dt) steps, arrival at step 0 notwithstanding
    assert all(info["is_success"] for info in infos)
    assert infos[-1]["reward_terms"]["arrival"] == 10.0
    assert all(info["reward_terms"]["arrival"] == 0.0 for info in infos[:-1])  # paid once, at T_con


def test_v0_and_v1_still_end_on_arrival() -> None:
    for env_id in (dwr_gym.ENV_ID, dwr_gym.ENV_ID_V1):
        env = gym.make(env_id)
        env.reset(seed=0, options={"start": (0.0, 0.0, 0.0), "goal": (0.005, 0.0, 0.0)})
        assert env.step(np.zeros(2, np.float32))[2]


@settings(max_examples=15, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), T_con=st.floats(10.0, 14.0), gain=st.floats(0.0, 3.0))
def test_the_return_is_the_documented_sum_whatever_the_path(seed: int, T_con: float, gain: float) -> None:
    """G = d_0 - 2 E + 10 [at goal] + 5 (cos psi_T - 1) - 10 d_T (the env's docstring, gamma 1)."""
    env = gym.make(V2)
    rng = np.random.default_rng(seed)
    total, infos, _ = run(env, lambda obs, t: np.clip(gain * rng.normal(size=2), -1, 1).astype(np.float32),
                          {"T_con": T_con}, seed)  # fmt: skip
    first, last = infos[0], infos[-1]
    left = last["distance"] > env.unwrapped.params.arena_radius
    rest = (int(last["T_con"] / 0.05 + 1e-9) - round(last["time"] / 0.05)) * 0.05 * (0.5**2 + 2.0**2)  # [s] x power
    expected = (first["distance"] - 2.0 * last["energy"] + 10.0 * last["is_success"] + 5.0 * (np.cos(last["heading_error"]) - 1)
                - 10.0 * last["distance"] - (10.0 + 2.0 * rest) * left)  # fmt: skip
    assert total == pytest.approx(expected, abs=1e-9)


def test_the_same_path_at_any_pace_earns_the_same_but_for_its_energy() -> None:
    """Two robots drive the same straight line to the goal, one at 4x the other's speed, then stand: v2 pays the slow
    one more (less energy, same final pose); v1 pays it the same bonus, and would pay the fast one for the time it
    saves only through the discount."""
    env = gym.make(V2)
    options = {"start": (0.0, 0.0, 0.0), "goal": (1.0, 0.0, 0.0), "T_con": 20.0}

    def drive(steps: int) -> object:
        speed = 1.0 / (steps * 0.05) / 0.5  # normalised: 1 m in ``steps`` control periods
        return lambda obs, t: np.array([speed if t < steps else 0.0, 0.0], np.float32)

    fast, fast_infos, _ = run(env, drive(100), options)
    slow, slow_infos, _ = run(env, drive(400), options)
    for infos in (fast_infos, slow_infos):
        assert infos[-1]["is_success"] and infos[-1]["distance"] < 1e-6  # float32 actions
    energy_gap = fast_infos[-1]["energy"] - slow_infos[-1]["energy"]
    assert energy_gap > 0
    assert slow - fast == pytest.approx(2.0 * energy_gap, abs=1e-5)  # the miss of 1e-7 m or less aside


def test_action_noise_costs_the_same_before_and_after_arrival() -> None:
    """The energy of a step is paid whether the robot has arrived or not: no pay for arriving early to stop paying."""
    params = gym.make(V2).unwrapped.params
    state = core.new_state((0.0, 0.0, 0.0), (0.0, 0.0, 0.0), params, 20.0)
    result = core.transition(state, np.array([0.3, -0.2]), params, core.observation_space(params))
    assert not result.terminated  # at the goal, moving: the episode goes on to T_con
    assert result.reward_terms["energy"] == pytest.approx(-2.0 * 0.05 * ((0.3 * 0.5) ** 2 + (0.2 * 2.0) ** 2))


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [({"terminal_distance_weight": 1.0}, "terminal_distance_weight=1.0 is invalid: expected 0 unless hold_to_T_con"),
     ({"hold_to_T_con": "yes"}, "hold_to_T_con"), ({"hold_to_T_con": True, "terminal_distance_weight": -1.0},
                                                   "terminal_distance_weight")],
)  # fmt: skip
def test_bad_v2_keywords_are_refused_naming_them(kwargs: dict, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        gym.make(dwr_gym.ENV_ID_V1, **kwargs)


def test_v2_with_disturbances_and_a_robot_runs_to_T_con() -> None:
    from dwr_gym.disturbances import VelocityBias

    env = gym.make(V2, robot="turtlebot3_burger", disturbances=[VelocityBias(0.02, 0.05)])
    _, infos, _ = run(env, lambda obs, t: np.array([0.5, 0.1], np.float32), {"T_con": 10.0})
    assert len(infos) - 1 == 200
    assert all(np.isfinite(info["energy"]) for info in infos)


def test_the_vector_env_is_the_single_env_on_v2() -> None:
    vec = gym.make_vec(V2, num_envs=3, T_con_range=(1.0, 2.0))
    obs, _ = vec.reset(seed=5)
    singles = [gym.make(V2, T_con_range=(1.0, 2.0)) for _ in range(3)]
    for i, env in enumerate(singles):
        single_obs, _ = env.reset(seed=5 + i)
        np.testing.assert_allclose(single_obs, obs[i], atol=1e-6)
    rng = np.random.default_rng(0)
    ended = np.zeros(3, bool)
    for _ in range(40):  # to every robot's end (T_con <= 2 s: 40 steps at most)
        actions = rng.uniform(-1, 1, (3, 2)).astype(np.float32)
        _, rewards, terminated, truncated, _ = vec.step(actions)
        for i, env in enumerate(singles):
            if ended[i]:
                continue
            _, reward, single_terminated, single_truncated, _ = env.step(actions[i])
            ended[i] = single_terminated or single_truncated
            assert reward == pytest.approx(rewards[i], abs=1e-12)
            assert (single_terminated, single_truncated) == (terminated[i], truncated[i])
    assert ended.all()


def test_leaving_the_arena_never_saves_the_energy_of_the_rest_of_the_episode() -> None:
    """An exit at time t is charged the most the remaining T_con - t could cost, so standing still at the edge, or
    flailing at full commands until T_con, pays at least as much as leaving."""

    def exit_then(after: str) -> float:
        env = gym.make(V2)
        start = {"start": (4.99, 0.0, 0.0), "goal": (0.0, 0.0, 0.0), "T_con": 10.0}
        if after == "leave":
            return run(env, lambda obs, t: np.array([1.0, 0.0], np.float32), start)[0]
        return run(env, lambda obs, t: np.array([0.0, 1.0], np.float32), start)[0]  # spins at full speed to T_con

    assert exit_then("flail") > exit_then("leave")


@pytest.mark.parametrize("autoreset_mode", ["same_step", "next_step"])
def test_the_vector_envs_infos_of_an_ended_step_are_its_own_not_the_next_episodes(autoreset_mode: str) -> None:
    """On v2 the shaping potential is the distance itself: the state keeps it and a reset writes into it, so an
    ended robot's reported distance must still be that of its last pose (found by the JAX equivalence test: the
    distance of the next episode's start leaked into final_info)."""
    n = 6
    env = gym.make_vec(dwr_gym.ENV_ID_V2, num_envs=n, vectorization_mode="vector_entry_point",
                       autoreset_mode=autoreset_mode)  # fmt: skip
    env.reset(seed=3, options={"T_con": np.linspace(0.3, 0.8, n)})
    ended_seen = 0
    for _ in range(20):
        _, _, terminated, truncated, infos = env.step(np.tile([[1.0, 0.2]], (n, 1)).astype(np.float32))
        ended = terminated | truncated
        if autoreset_mode == "same_step" and ended.any():
            final = infos["final_info"]
            np.testing.assert_allclose(final["distance"][ended], np.hypot(*final["pose"][ended, :2].T), atol=1e-9)
            np.testing.assert_allclose(infos["final_obs"][ended, 0], final["distance"][ended], rtol=1e-6)
            ended_seen += int(ended.sum())
        # the infos of the step (a new episode's first, after an autoreset in the same step) describe its pose
        np.testing.assert_allclose(infos["distance"], np.hypot(*infos["pose"][:, :2].T), atol=1e-9)
        if autoreset_mode == "next_step":
            ended_seen += int(ended.sum())
    env.close()
    assert ended_seen >= n

"""The stable-baselines3 adapter (dwr_gym/sb3.py) against the native vector env it translates, step by step.

SB3 bootstraps the value of an episode cut by the time limit from ``infos[i]["TimeLimit.truncated"]``; a wrong
flag biases every PPO and SAC run on the native batch without a visible error, so it is checked against the
vector env's own ``terminated`` and ``truncated``.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from gymnasium.vector import AutoresetMode

from dwr_gym.vector_env import DWRPointStabilizationVectorEnv

pytest.importorskip("stable_baselines3")

from dwr_gym.sb3 import SB3VecEnv, make_sb3_vec_env

#: Short episodes that often end both ways: arrival (terminated) and the time limit (truncated).
KWARGS: dict[str, Any] = {"T_con": 2.0, "dt": 0.1, "goal_tolerance": 0.15, "start_distance": (0.2, 0.5)}
N = 6


def test_each_done_carries_the_vector_envs_ending_episode_statistics_and_truncated_only_without_termination() -> None:
    adapter = make_sb3_vec_env(num_envs=N, seed=3, **KWARGS)
    native = DWRPointStabilizationVectorEnv(N, autoreset_mode=AutoresetMode.SAME_STEP, **KWARGS)
    obs = adapter.reset()
    native_obs, _ = native.reset(seed=3)
    np.testing.assert_array_equal(obs, native_obs)  # sub-env i seeded with 3 + i
    rng = np.random.default_rng(0)
    returns, lengths = np.zeros(N), np.zeros(N, dtype=int)
    ends = {"truncated": 0, "terminated": 0}
    for _ in range(120):
        actions = rng.uniform(-1, 1, (N, 2)).astype(np.float32)
        obs, rewards, dones, infos = adapter.step(actions)
        native_obs, native_rewards, terminated, truncated, native_info = native.step(actions)
        np.testing.assert_array_equal(obs, native_obs)
        np.testing.assert_allclose(rewards, native_rewards, rtol=1e-6)
        np.testing.assert_array_equal(dones, terminated | truncated)
        returns += native_rewards
        lengths += 1
        for i in range(N):
            if not dones[i]:
                assert infos[i] == {}
                continue
            info = infos[i]
            assert info["TimeLimit.truncated"] is bool(truncated[i] and not terminated[i])
            ends["truncated" if info["TimeLimit.truncated"] else "terminated"] += 1
            np.testing.assert_array_equal(info["terminal_observation"], native_info["final_obs"][i])
            assert info["is_success"] is bool(native_info["final_info"]["is_success"][i])
            assert info["episode"]["l"] == lengths[i]
            assert info["episode"]["r"] == pytest.approx(returns[i], abs=1e-5)
            assert info["episode"]["t"] >= 0.0
            returns[i], lengths[i] = 0.0, 0
    assert ends["truncated"] > 0 and ends["terminated"] > 0, ends  # both endings were met and told apart


def test_robots_that_stand_still_are_cut_at_the_horizon_with_time_limit_truncated_true() -> None:
    """Not one step earlier, and not as arrivals (the test above checks the arrivals' False)."""
    adapter = make_sb3_vec_env(num_envs=2, seed=0, **KWARGS)
    adapter.reset()
    horizon = adapter.venv.params.max_episode_steps
    for step in range(1, horizon + 1):
        _, _, dones, infos = adapter.step(np.zeros((2, 2), np.float32))
        if step < horizon:
            assert not dones.any(), step
    assert dones.all()
    assert [info["TimeLimit.truncated"] for info in infos] == [True, True]
    assert [info["is_success"] for info in infos] == [False, False]
    assert [info["episode"]["l"] for info in infos] == [horizon, horizon]


def test_reset_seeds_and_options_reach_the_vector_env_and_are_used_once() -> None:
    adapter = make_sb3_vec_env(num_envs=3, **KWARGS)
    adapter.seed(11)
    first = adapter.reset()
    native = DWRPointStabilizationVectorEnv(3, autoreset_mode=AutoresetMode.SAME_STEP, **KWARGS)
    np.testing.assert_array_equal(first, native.reset(seed=11)[0])
    assert adapter.reset_infos == [{"is_success": False}] * 3
    again = adapter.reset()  # the seed is spent: a new draw
    assert not np.array_equal(first, again)
    start = (1.0, -0.5, 0.3)
    adapter.set_options({"start": start})
    obs = adapter.reset()
    np.testing.assert_allclose(obs[:, 0], np.hypot(1.0, -0.5), rtol=1e-6)  # every robot starts at `start`
    # the vector env takes one options dict for all robots: the first sub-env's
    adapter.set_options([{"start": start}, {"start": (2.0, 0.0, 0.0)}, {"start": (2.0, 0.0, 0.0)}])
    np.testing.assert_allclose(adapter.reset()[:, 0], np.hypot(1.0, -0.5), rtol=1e-6)


def test_the_episode_time_is_the_wall_time_since_the_adapter_was_made_as_a_monitor_reports_it(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    import dwr_gym.sb3

    class Clock:
        now = 1000.0

        @classmethod
        def time(cls) -> float:
            return cls.now

    monkeypatch.setattr(dwr_gym.sb3, "time", Clock)
    adapter = make_sb3_vec_env(num_envs=2, seed=0, **KWARGS)
    adapter.reset()
    Clock.now = 1012.34567891
    for _ in range(adapter.venv.params.max_episode_steps):
        _, _, dones, infos = adapter.step(np.zeros((2, 2), np.float32))
    assert dones.all() and [info["episode"]["t"] for info in infos] == [12.345679, 12.345679]  # 6 decimals


def test_attributes_methods_and_wrappers_answer_once_per_requested_sub_env() -> None:
    from stable_baselines3.common.monitor import Monitor

    adapter = make_sb3_vec_env(num_envs=4, seed=0, **KWARGS)
    assert isinstance(adapter, SB3VecEnv) and adapter.num_envs == 4
    assert [p.T_con for p in adapter.get_attr("params")] == [2.0] * 4
    assert len(adapter.get_attr("params", indices=2)) == 1 and len(adapter.get_attr("params", [0, 3])) == 2
    adapter.set_attr("marker", 7)
    assert adapter.venv.marker == 7  # type: ignore[attr-defined]
    assert adapter.env_method("__repr__", indices=[1, 2]) == [repr(adapter.venv)] * 2
    assert adapter.env_method("__getattribute__", "num_envs") == [4] * 4  # positional arguments reach the method
    obs, _ = adapter.env_method("reset", indices=0, seed=21)[0]  # and keyword arguments
    np.testing.assert_array_equal(obs, make_sb3_vec_env(num_envs=4, seed=21, **KWARGS).reset())
    assert adapter.metadata["render_fps"] == adapter.venv.metadata["render_fps"]  # VecVideoRecorder's frame rate
    assert adapter.env_is_wrapped(Monitor) == [True] * 4
    assert adapter.env_is_wrapped(Monitor, indices=1) == [True]
    import gymnasium as gym

    assert adapter.env_is_wrapped(gym.wrappers.TimeLimit) == [False] * 4
    assert adapter.get_images() == [None] * 4  # no render mode: no frames
    with pytest.raises(ValueError, match="autoreset_mode"):
        make_sb3_vec_env(num_envs=2, autoreset_mode=AutoresetMode.NEXT_STEP)
    with pytest.raises(ValueError, match="SAME_STEP"):
        SB3VecEnv(DWRPointStabilizationVectorEnv(2, **KWARGS))

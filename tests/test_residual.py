"""Residual agents (train/learning/residual.py): what the wrappers and the policy pass on to the expert and the model."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
import pytest

from baselines import ExpertPolicy, PTCController
from train.learning.residual import ResidualActionWrapper, ResidualPolicy, check_scale


class Recorder:
    """A model (or expert) that answers ``action`` and keeps its arguments."""

    def __init__(self, action: tuple[float, float]) -> None:
        self.action = np.float32(action)
        self.calls: list[dict[str, Any]] = []

    def predict(self, observation: Any, state: Any = None, episode_start: Any = None, deterministic: bool = True):  # type: ignore[no-untyped-def]
        self.calls.append({"obs": np.array(observation), "state": state, "episode_start": episode_start,
                           "deterministic": deterministic})  # fmt: skip
        return np.tile(self.action, (len(observation), 1)), "next-state"


def test_the_residual_policy_passes_state_episode_starts_and_determinism_on_and_adds_the_scaled_residual() -> None:
    model, expert = Recorder((3.0, -0.4)), Recorder((0.5, 0.5))
    policy = ResidualPolicy(model, expert, 0.25)  # type: ignore[arg-type]
    obs = np.zeros((2, 10), np.float32)
    starts = np.array([True, False])
    action, state = policy.predict(obs, state="state", episode_start=starts, deterministic=False)
    assert state == "next-state"
    assert model.calls[0]["state"] == "state" and model.calls[0]["deterministic"] is False
    np.testing.assert_array_equal(model.calls[0]["episode_start"], starts)
    np.testing.assert_array_equal(expert.calls[0]["episode_start"], starts)
    np.testing.assert_allclose(action, [[0.75, 0.4]] * 2, atol=1e-7)  # 0.5 + 0.25 x clip(3, -1, 1); 0.5 - 0.25 x 0.4


def test_the_residual_wrapper_resets_with_the_seed_and_options_it_is_given() -> None:
    base = gym.make("DWRPointStabilization-v1")
    env = ResidualActionWrapper(base, ExpertPolicy.from_env(base, PTCController()), scale=0.5)
    start = (1.0, -0.5, 0.3)
    obs, _ = env.reset(seed=5, options={"start": start})
    reference, _ = gym.make("DWRPointStabilization-v1").reset(seed=5, options={"start": start})
    np.testing.assert_array_equal(obs, reference)
    assert obs[0] == pytest.approx(np.hypot(1.0, -0.5), rel=1e-6)


def test_the_residual_scale_is_in_0_to_2() -> None:
    assert check_scale(2.0) == 2.0 and check_scale(1e-9) == 1e-9
    for bad in (0.0, 2.0000001, -1.0):
        with pytest.raises(ValueError, match=r"^residual_scale=.* is invalid: expected a finite number in \(0, 2\]$"):
            check_scale(bad)


def test_the_residual_vec_env_reports_the_expert_and_residual_parts_and_wants_a_reset_first() -> None:
    """Each step's infos carry the expert's action and the residual (scale x the clipped action), the parts a user
    reads to see what the network adds; a step before reset() says so."""
    from dwr_gym.sb3 import make_sb3_vec_env
    from train.learning.residual import ResidualVecEnv

    venv = ResidualVecEnv(make_sb3_vec_env(2, seed=0), Recorder((0.5, -0.25)), scale=0.5)  # type: ignore[arg-type]
    with pytest.raises(AssertionError, match=r"^call reset\(\) before step\(\)$"):
        venv.step_async(np.zeros((2, 2), np.float32))
    venv.reset()
    _, _, _, infos = venv.step(np.float32([[3.0, 0.2], [-0.4, -2.0]]))
    assert [info["expert_action"].tolist() for info in infos] == [[0.5, -0.25]] * 2
    np.testing.assert_allclose([info["residual_action"] for info in infos], [[0.5, 0.1], [-0.2, -0.5]], atol=1e-7)

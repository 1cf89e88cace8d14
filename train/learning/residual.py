"""Residual agents: action = clip(expert(obs) + scale * residual, -1, 1).

The arithmetic lives in :func:`residual_action`; :class:`ResidualActionWrapper` applies it to a single
Gymnasium env, :class:`ResidualVecEnv` to a stable-baselines3 ``VecEnv`` (the native batch), and
:class:`ResidualPolicy` to a trained model at evaluation time. Both wrappers log the expert's and the
residual's parts in ``info["expert_action"]`` and ``info["residual_action"]``.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
from numpy.typing import NDArray
from stable_baselines3.common.vec_env import VecEnvWrapper

from baselines.expert import ExpertPolicy
from dwr_gym.params import check_range


def residual_action(expert: NDArray[np.floating], residual: NDArray[np.floating], scale: float) -> NDArray[np.float32]:
    """clip(expert + scale * residual, -1, 1), as float32; works on one action or a batch."""
    return np.clip(np.asarray(expert) + scale * np.asarray(residual), -1.0, 1.0).astype(np.float32)


def check_scale(scale: float) -> float:
    """Validate the residual scale."""
    return check_range("residual_scale", scale, 0.0, 2.0, low_inclusive=False)


class ResidualActionWrapper(
    gym.Wrapper[NDArray[np.float32], NDArray[np.float32], NDArray[np.float32], NDArray[np.float32]]
):
    """A single env whose action is the residual added to the expert's action."""

    def __init__(
        self, env: gym.Env[NDArray[np.float32], NDArray[np.float32]], expert: ExpertPolicy, scale: float = 0.5
    ) -> None:
        super().__init__(env)
        self.expert = expert
        self.scale = check_scale(scale)
        self._obs: NDArray[np.float32] | None = None

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[NDArray[np.float32], dict[str, Any]]:
        self._obs, info = self.env.reset(seed=seed, options=options)
        return self._obs, info

    def step(self, action: NDArray[np.float32]) -> tuple[NDArray[np.float32], Any, bool, bool, dict[str, Any]]:
        assert self._obs is not None, "call reset() before step()"
        expert, _ = self.expert.predict(self._obs)
        residual = np.clip(np.asarray(action, dtype=np.float32), -1.0, 1.0)
        self._obs, reward, terminated, truncated, info = self.env.step(residual_action(expert, residual, self.scale))
        info["expert_action"], info["residual_action"] = expert, self.scale * residual
        return self._obs, reward, terminated, truncated, info


class ResidualVecEnv(VecEnvWrapper):
    """A stable-baselines3 ``VecEnv`` whose actions are residuals on the expert's batch of actions."""

    def __init__(self, venv: Any, expert: ExpertPolicy, scale: float = 0.5) -> None:
        super().__init__(venv)
        self.expert = expert
        self.scale = check_scale(scale)
        self._obs: NDArray[np.float32] | None = None
        self._expert: NDArray[np.float32] | None = None
        self._residual: NDArray[np.float32] | None = None

    def reset(self) -> NDArray[np.float32]:
        self._obs = self.venv.reset()
        return self._obs

    def step_async(self, actions: NDArray[np.float32]) -> None:
        assert self._obs is not None, "call reset() before step()"
        self._expert, _ = self.expert.predict(self._obs)
        self._residual = self.scale * np.clip(np.asarray(actions, dtype=np.float32), -1.0, 1.0)
        self.venv.step_async(residual_action(self._expert, self._residual, 1.0))

    def step_wait(self) -> Any:
        obs, rewards, dones, infos = self.venv.step_wait()
        for i, info in enumerate(infos):
            info["expert_action"], info["residual_action"] = self._expert[i], self._residual[i]  # type: ignore[index]
        self._obs = obs
        return obs, rewards, dones, infos


class ResidualPolicy:
    """A trained residual model and its expert as one policy with SB3's ``predict`` signature."""

    def __init__(self, model: Any, expert: ExpertPolicy, scale: float) -> None:
        self.model = model
        self.expert = expert
        self.scale = check_scale(scale)

    def predict(
        self,
        observation: NDArray[np.floating],
        state: Any = None,
        episode_start: Any = None,
        deterministic: bool = True,
    ) -> tuple[NDArray[np.float32], Any]:
        residual, state = self.model.predict(observation, state, episode_start, deterministic)
        expert, _ = self.expert.predict(observation, episode_start=episode_start)
        return residual_action(expert, np.clip(residual, -1.0, 1.0), self.scale), state


def zero_init_last_layer(model: Any, gain: float = 1e-3) -> None:
    """Scale the last layer of the policy's action head to ``gain`` of its initial weights, bias 0.

    The residual then starts near zero, so training starts from the expert's behaviour. Works for
    stable-baselines3's PPO/A2C (``action_net``), SAC (``actor.mu``) and TD3 (``actor.mu``).
    """
    import torch

    policy = model.policy
    if hasattr(policy, "action_net"):
        layer = policy.action_net
    else:
        mu = policy.actor.mu
        layer = mu if isinstance(mu, torch.nn.Linear) else [m for m in mu if isinstance(m, torch.nn.Linear)][-1]
    with torch.no_grad():
        layer.weight.mul_(gain)
        layer.bias.zero_()
    if getattr(model, "actor_target", None) is not None:  # TD3 keeps a target copy of the actor
        model.actor_target.load_state_dict(model.actor.state_dict())

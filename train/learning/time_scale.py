"""Time-scaled actions (``dwr-gym train --action-time-scale T_REF``): the agent's action, or a residual agent's
residual, times min(1, T_REF / T_con).

Why: the task's minimum-energy problem is time-scale invariant where the limits do not bind. If (u(t), omega(t)) is
the least-energy way to the goal pose by T, then (u(t / k) / k, omega(t / k) / k) is the least-energy way by k T,
along the same path, with 1 / k of the energy (the integral of u^2 + omega^2 over [0, k T]). A network whose output
is multiplied by T_REF / T_con commands at every T_con what the same output commands at T_REF, slowed to the longer
time: one behaviour in the time fraction, which the observation carries, serves every T_con, and its exploration
noise costs energy in proportion to the optimum's instead of growing with T_con against it. The commands stay within
the limits (the factor is at most 1: below T_REF the action is the network's). 0 turns it off (the default; every
agent trained before it).

One copy of the arithmetic (:func:`time_scaled_action`, array API: numpy and jax.numpy) serves the three places an
action enters the env: :class:`TimeScaledVecEnv` (SB3's VecEnv: the SB3 and sbx trainers), :class:`TimeScaledGymnaxEnv`
(the jitted PPO's and ES's functional env) and :class:`TimeScaledPolicy` (a saved agent at run time,
:func:`train.learning.training_env.as_policy`).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray
from stable_baselines3.common.vec_env import VecEnvWrapper

from baselines.base import array_namespace
from dwr_gym.observation import OBSERVATION_NAMES

#: Where the observation carries T_con.
T_CON_INDEX = OBSERVATION_NAMES.index("T_con")


def time_scale(T_con: Any, reference: float) -> Any:
    """min(1, reference / T_con), elementwise (T_con > 0: the env's range starts at 1 s)."""
    xp = array_namespace(T_con)
    return xp.minimum(1.0, reference / T_con)


def time_scaled_action(action: Any, observation: Any, reference: float) -> Any:
    """clip(action, -1, 1) * min(1, reference / T_con), T_con read from ``observation`` (..., 10); actions (..., 2)
    in the action's array library and dtype."""
    xp = array_namespace(action)
    factor = time_scale(observation[..., T_CON_INDEX : T_CON_INDEX + 1], reference)
    return (xp.clip(action, -1.0, 1.0) * factor).astype(action.dtype)


class TimeScaledVecEnv(VecEnvWrapper):
    """An SB3 ``VecEnv`` whose actions are time-scaled before the env (or a residual wrapper under it) takes them."""

    def __init__(self, venv: Any, reference: float) -> None:
        super().__init__(venv)
        self.reference = float(reference)
        self._obs: NDArray[np.float32] | None = None

    def reset(self) -> NDArray[np.float32]:
        self._obs = self.venv.reset()
        return self._obs

    def step_async(self, actions: NDArray[np.float32]) -> None:
        assert self._obs is not None, "call reset() before step()"
        actions = np.asarray(actions, dtype=np.float32)
        self.venv.step_async(time_scaled_action(actions, self._obs, self.reference))

    def step_wait(self) -> Any:
        obs, rewards, dones, infos = self.venv.step_wait()
        self._obs = obs  # (after an auto-reset, the next episode's first observation: its T_con)
        return obs, rewards, dones, infos


class TimeScaledPolicy:
    """A policy (SB3's ``predict`` signature) whose actions are time-scaled: a saved agent as it trained."""

    def __init__(self, policy: Any, reference: float) -> None:
        self.policy, self.reference = policy, float(reference)

    def predict(
        self,
        observation: NDArray[np.floating],
        state: Any = None,
        episode_start: Any = None,
        deterministic: bool = True,
    ) -> tuple[NDArray[np.float32], Any]:
        action, state = self.policy.predict(observation, state, episode_start, deterministic)
        return time_scaled_action(np.asarray(action, dtype=np.float32), np.asarray(observation), self.reference), state

    def __getattr__(self, name: str) -> Any:  # what the wrapped policy offers beside predict
        return getattr(self.policy, name)


class TimeScaledGymnaxEnv:
    """A gymnax-style env whose actions are time-scaled (jax arrays, under ``jit`` and ``vmap``)."""

    def __init__(self, env: Any, reference: float) -> None:
        self.env, self.reference = env, float(reference)

    def step_env(self, key: Any, state: Any, action: Any, params: Any) -> tuple[Any, ...]:
        """One step without auto-reset, with ``action`` scaled by the T_con of the observation the agent saw."""
        scaled = time_scaled_action(action, state.observation, self.reference)
        return self.env.step_env(key, state, scaled, params)  # type: ignore[no-any-return]

    def __getattr__(self, name: str) -> Any:  # reset_env, the spaces, default_params, is_truncated, ...
        return getattr(self.env, name)


__all__ = ["T_CON_INDEX", "TimeScaledGymnaxEnv", "TimeScaledPolicy", "TimeScaledVecEnv", "time_scale",
           "time_scaled_action"]  # fmt: skip

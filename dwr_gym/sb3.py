"""An adapter that lets stable-baselines3 train on the native vector env (needs the ``train`` extra).

stable-baselines3 has its own ``VecEnv`` API (a 4-tuple ``step``, automatic reset, the last
observation in ``infos[i]["terminal_observation"]`` and ``infos[i]["TimeLimit.truncated"]``), and does
not accept a Gymnasium ``VectorEnv``. :class:`SB3VecEnv` translates, keeping the batch one numpy call.
It keeps the episode statistics a ``Monitor`` would (``infos[i]["episode"]`` at the end of each
episode), so SB3 logs ``rollout/ep_rew_mean`` and ``ep_len_mean`` and ``evaluate_policy`` reports true
returns without a ``VecMonitor``; ``get_images()`` gives one frame per robot, for ``VecVideoRecorder``.

>>> from dwr_gym.sb3 import make_sb3_vec_env
>>> venv = make_sb3_vec_env(num_envs=8, seed=0, T_con=20.0)
>>> venv.reset().shape
(8, 10)
"""

from __future__ import annotations

import time
from collections.abc import Iterable, Sequence
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium.vector import AutoresetMode
from numpy.typing import NDArray

try:
    from stable_baselines3.common.monitor import Monitor
    from stable_baselines3.common.vec_env.base_vec_env import VecEnv, VecEnvIndices, VecEnvStepReturn
except ImportError as error:  # the train extra is optional; say how to get it, as every other extra does
    raise ImportError(
        f'dwr_gym.sb3 needs stable-baselines3 ({error.name} is missing): pip install "dwr-gym[train]"'
    ) from error

from dwr_gym.vector_env import DWRPointStabilizationVectorEnv


class SB3VecEnv(VecEnv):
    """A :class:`DWRPointStabilizationVectorEnv` (in ``AutoresetMode.SAME_STEP``, SB3's convention) behind
    stable-baselines3's ``VecEnv`` API, with the episode statistics of a ``Monitor``."""

    def __init__(self, venv: DWRPointStabilizationVectorEnv) -> None:
        if venv.autoreset_mode is not AutoresetMode.SAME_STEP:
            raise ValueError(
                f"autoreset_mode={venv.autoreset_mode} is invalid for SB3VecEnv: expected AutoresetMode.SAME_STEP "
                "(stable-baselines3 resets in the step that ends an episode)"
            )
        self.venv = venv
        self.params = venv.params
        super().__init__(venv.num_envs, venv.single_observation_space, venv.single_action_space)
        self.render_mode = venv.render_mode
        self.metadata["render_fps"] = venv.metadata["render_fps"]
        self._actions: NDArray[np.float32] | None = None
        self._episode_returns = np.zeros(self.num_envs)
        self._episode_lengths = np.zeros(self.num_envs, dtype=np.int64)
        self._start_time = time.time()

    def reset(self) -> NDArray[np.float32]:
        seeds = self._seeds
        seed: Any = None if all(s is None for s in seeds) else [s for s in seeds]
        options = self._options[0] if self._options and self._options[0] else None
        obs, infos = self.venv.reset(seed=seed, options=options)
        self._episode_returns[:] = 0.0
        self._episode_lengths[:] = 0
        self.reset_infos = [{"is_success": bool(infos["is_success"][i])} for i in range(self.num_envs)]
        self._reset_seeds()
        self._reset_options()
        return obs

    def step_async(self, actions: NDArray[np.float32]) -> None:
        self._actions = np.asarray(actions)

    def step_wait(self) -> VecEnvStepReturn:
        assert self._actions is not None, "step_async() must be called before step_wait()"
        obs, rewards, terminated, truncated, infos = self.venv.step(self._actions.reshape(self.num_envs, 2))
        dones = terminated | truncated
        self._episode_returns += rewards
        self._episode_lengths += 1
        out: list[dict[str, Any]] = [{} for _ in range(self.num_envs)]
        if dones.any():
            final_obs, final_success = infos["final_obs"], infos["final_info"]["is_success"]
            elapsed = round(time.time() - self._start_time, 6)
            for i in np.flatnonzero(dones):
                out[i] = {
                    "terminal_observation": final_obs[i],
                    "TimeLimit.truncated": bool(truncated[i] and not terminated[i]),
                    "is_success": bool(final_success[i]),
                    # what stable_baselines3's Monitor reports at the end of an episode
                    "episode": {"r": round(float(self._episode_returns[i]), 6), "l": int(self._episode_lengths[i]),
                                "t": elapsed},
                }  # fmt: skip
            self._episode_returns[dones] = 0.0
            self._episode_lengths[dones] = 0
        return obs, rewards.astype(np.float32), dones, out

    def close(self) -> None:
        self.venv.close()

    def _indices(self, indices: VecEnvIndices) -> list[int]:
        return list(self._get_indices(indices))

    def get_attr(self, attr_name: str, indices: VecEnvIndices = None) -> list[Any]:
        """The attribute of the (shared) vector env, once per requested sub-env."""
        return [getattr(self.venv, attr_name)] * len(self._indices(indices))

    def set_attr(self, attr_name: str, value: Any, indices: VecEnvIndices = None) -> None:
        setattr(self.venv, attr_name, value)

    def env_method(
        self, method_name: str, *method_args: Any, indices: VecEnvIndices = None, **method_kwargs: Any
    ) -> list[Any]:
        result = getattr(self.venv, method_name)(*method_args, **method_kwargs)
        return [result] * len(self._indices(indices))

    def env_is_wrapped(
        self, wrapper_class: type[gym.Wrapper[Any, Any, Any, Any]], indices: VecEnvIndices = None
    ) -> list[bool]:
        """True for ``Monitor`` (and its bases): the adapter reports episode statistics as a Monitor does."""
        return [issubclass(Monitor, wrapper_class)] * len(self._indices(indices))

    def get_images(self) -> Sequence[NDArray[np.uint8] | None]:
        """One frame per robot in "rgb_array" mode (``render()`` tiles them), None per robot otherwise."""
        frames = self.venv.render() if self.render_mode == "rgb_array" else None
        return list(frames) if frames is not None else [None] * self.num_envs

    def _get_indices(self, indices: VecEnvIndices) -> Iterable[int]:
        if indices is None:
            return range(self.num_envs)
        if isinstance(indices, int):
            return [indices]
        return indices


def make_sb3_vec_env(
    num_envs: int, seed: int | None = None, render_mode: str | None = None, **env_kwargs: Any
) -> SB3VecEnv:
    """An SB3 ``VecEnv`` of ``num_envs`` robots on the native vector env, seeded with ``seed`` (sub-env i: seed + i)."""
    if "autoreset_mode" in env_kwargs:
        raise ValueError("autoreset_mode is not a keyword of make_sb3_vec_env: the SB3 adapter always uses SAME_STEP")
    venv = SB3VecEnv(
        DWRPointStabilizationVectorEnv(
            num_envs, render_mode=render_mode, autoreset_mode=AutoresetMode.SAME_STEP, **env_kwargs
        )
    )
    if seed is not None:
        venv.seed(seed)
    return venv

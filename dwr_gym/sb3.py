"""An adapter that lets stable-baselines3 train on the native vector env (needs the ``train`` extra).

stable-baselines3 has its own ``VecEnv`` API (a 4-tuple ``step``, automatic reset, the last
observation in ``infos[i]["terminal_observation"]`` and ``infos[i]["TimeLimit.truncated"]``), and does
not accept a Gymnasium ``VectorEnv``. :class:`SB3VecEnv` translates, keeping the batch one numpy call.

>>> from dwr_gym.sb3 import make_sb3_vec_env
>>> venv = make_sb3_vec_env(num_envs=8, seed=0, T_con=20.0)
>>> venv.reset().shape
(8, 10)
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from typing import Any

import gymnasium as gym
import numpy as np
from numpy.typing import NDArray
from stable_baselines3.common.vec_env.base_vec_env import VecEnv, VecEnvIndices, VecEnvStepReturn

from dwr_gym.vector_env import DWRPointStabilizationVectorEnv


class SB3VecEnv(VecEnv):
    """A :class:`DWRPointStabilizationVectorEnv` behind stable-baselines3's ``VecEnv`` API."""

    def __init__(self, venv: DWRPointStabilizationVectorEnv) -> None:
        self.venv = venv
        self.params = venv.params
        super().__init__(venv.num_envs, venv.single_observation_space, venv.single_action_space)
        self.render_mode = venv.render_mode
        self._actions: NDArray[np.float32] | None = None

    def reset(self) -> NDArray[np.float32]:
        seeds = self._seeds
        seed: Any = None if all(s is None for s in seeds) else [s for s in seeds]
        options = self._options[0] if self._options and self._options[0] else None
        obs, infos = self.venv.reset(seed=seed, options=options)
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
        out: list[dict[str, Any]] = [{} for _ in range(self.num_envs)]
        if dones.any():
            final_obs, final_success = infos["final_obs"], infos["final_info"]["is_success"]
            for i in np.flatnonzero(dones):
                out[i] = {
                    "terminal_observation": final_obs[i],
                    "TimeLimit.truncated": bool(truncated[i] and not terminated[i]),
                    "is_success": bool(final_success[i]),
                }
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
        return [False] * len(self._indices(indices))

    def get_images(self) -> Sequence[NDArray[np.uint8] | None]:
        """A frame of sub-env 0 (the native env renders one robot)."""
        return [self.venv.render()] + [None] * (self.num_envs - 1)

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
    venv = SB3VecEnv(DWRPointStabilizationVectorEnv(num_envs, render_mode=render_mode, **env_kwargs))
    if seed is not None:
        venv.seed(seed)
    return venv

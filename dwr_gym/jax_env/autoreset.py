"""N robots of the gymnax adapter in one batched step, with optimistic resets (Craftax's technique).

gymnax's auto-reset (:meth:`DWRGymnaxEnv.step` under ``jax.vmap``) computes a whole new episode for every robot at
every step and keeps it where the episode ended: on a CPU that costs more than the step itself. With
``reset_ratio`` r > 1, :class:`OptimisticResetVecEnv` draws only ``num_envs // r`` new episodes per step and hands
them to the robots that ended, in turn (as craftax_baselines' ``OptimisticResetVecEnvWrapper``): two robots start
the same episode only when more than ``num_envs // r`` episodes end in one step. Its step is one call of
:meth:`DWRFuncEnv.transition` on the whole batch (one key draws the batch's noise, no N-way key split) and
``num_envs // r`` calls of :meth:`DWRFuncEnv.initial`, the same functions as every other env. ``reset_ratio`` 1
is exactly ``jax.vmap(env.step)`` with the batch key split in ``num_envs``.
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp

from dwr_gym.jax_env.func_env import DWRState
from dwr_gym.jax_env.gymnax import DWRGymnaxEnv
from dwr_gym.jax_env.params import FunctionalParams
from dwr_gym.validation import as_int


class OptimisticResetVecEnv:
    """``num_envs`` robots of ``env``: ``reset(key, params) -> (obs (N, 10), state)`` and ``step(key, state, action
    (N, 2), params) -> (obs, state, reward, done, info)`` with gymnax's auto-reset semantics (the step that ends an
    episode returns the new episode's observation and state and the ended step's reward, ``done`` and info, with
    ``info["final_observation"]`` the ended step's observation). Pure functions: jit them, or call them in a scan.

    ``reset_ratio`` (an integer in [1, num_envs]): 1 computes a new episode for every robot at every step, exactly
    as ``jax.vmap(env.step)`` over ``jax.random.split(key, num_envs)``; r > 1 draws ``num_envs // r`` per step (the
    batch's noise and new episodes then come from other draws of the same key than at r = 1).
    """

    def __init__(self, env: DWRGymnaxEnv, num_envs: int, reset_ratio: int = 1) -> None:
        self.env = env
        self.num_envs = as_int("num_envs", num_envs, 1, 1 << 24)
        self.reset_ratio = as_int("reset_ratio", reset_ratio, 1, self.num_envs)
        self.num_resets = self.num_envs // self.reset_ratio
        self._step = jax.vmap(env.step, in_axes=(0, 0, 0, None))
        self._initial = jax.vmap(env.func_env.initial, in_axes=(0, None))

    @property
    def default_params(self) -> FunctionalParams:
        return self.env.default_params

    def reset(self, key: jax.Array, params: FunctionalParams | None = None) -> tuple[jax.Array, DWRState]:
        """``num_envs`` new episodes: (observations (N, 10), state)."""
        params = self.default_params if params is None else params
        state = self._initial(jax.random.split(key, self.num_envs), params)
        return state.observation, state

    def step(
        self, key: jax.Array, state: DWRState, action: jax.Array, params: FunctionalParams | None = None
    ) -> tuple[jax.Array, DWRState, jax.Array, jax.Array, dict[str, Any]]:
        """One step of every robot with auto-reset (see the class)."""
        params = self.default_params if params is None else params
        if self.reset_ratio == 1:
            return self._step(jax.random.split(key, self.num_envs), state, action, params)  # type: ignore[no-any-return]
        step_key, reset_key = jax.random.split(key)
        obs, stepped, reward, done, info = self.env.step_env(step_key, state, action, params)  # the batch, unvmapped
        info["final_observation"] = obs
        fresh = self._initial(jax.random.split(reset_key, self.num_resets), params)
        # the k-th robot (in index order) whose episode ended starts new episode k mod num_resets
        slot = (jnp.cumsum(done, dtype=jnp.int32) - 1) % self.num_resets

        def pick(new: jax.Array, old: jax.Array) -> jax.Array:
            return jnp.where(jnp.reshape(done, done.shape + (1,) * (old.ndim - 1)), new[slot], old)

        next_state = jax.tree.map(pick, fresh, stepped)
        return next_state.observation, next_state, reward, done, info


__all__ = ["OptimisticResetVecEnv"]

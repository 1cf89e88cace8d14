"""DWRGymnaxEnv: the functional env behind gymnax's interface, for gymnax-based trainers (PureJaxRL, Stoix).

``reset(key, params) -> (obs, state)`` and ``step(key, state, action, params) -> (obs, state, reward, done,
info)`` for one robot (``jax.vmap`` them for a batch), with gymnax's auto-reset: the step that ends an episode
returns the new episode's observation and state, and the reward, ``done`` and info of the step that ended it
(``info["terminated"]`` and ``info["truncated"]`` tell the two apart: bootstrap on truncation from
``info["final_observation"]``, the ended step's observation). gymnax itself is
not needed: the spaces are small classes of the same interface.
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from dwr_gym.jax_env.func_env import DWRFuncEnv, DWRState
from dwr_gym.jax_env.params import FunctionalParams


class Box:
    """gymnax's ``spaces.Box``: bounds, shape, dtype, ``sample(key)`` and ``contains(x)``."""

    def __init__(self, low: Any, high: Any, shape: tuple[int, ...], dtype: Any) -> None:
        self.low, self.high, self.shape, self.dtype = np.asarray(low, dtype), np.asarray(high, dtype), shape, dtype

    def sample(self, key: jax.Array) -> jax.Array:
        """A uniform draw within the bounds."""
        return jax.random.uniform(key, self.shape, self.dtype, self.low, self.high)

    def contains(self, x: jax.Array) -> jax.Array:
        """Whether ``x`` lies within the bounds."""
        return jnp.all((x >= self.low) & (x <= self.high))


class DWRGymnaxEnv:
    """gymnax's ``Environment`` interface over :class:`DWRFuncEnv` (one robot; vmap for N)."""

    def __init__(self, func_env: DWRFuncEnv) -> None:
        self.func_env = func_env

    @property
    def default_params(self) -> FunctionalParams:
        return self.func_env.default_params  # type: ignore[no-any-return]

    @property
    def name(self) -> str:
        return "DWRPointStabilization"

    @property
    def num_actions(self) -> int:
        return 2

    def reset(self, key: jax.Array, params: FunctionalParams | None = None) -> tuple[jax.Array, DWRState]:
        """A new episode: (observation, state)."""
        return self.reset_env(key, self.default_params if params is None else params)

    def reset_env(self, key: jax.Array, params: FunctionalParams) -> tuple[jax.Array, DWRState]:
        state = self.func_env.initial(key, params)
        return state.observation, state

    def step_env(
        self, key: jax.Array, state: DWRState, action: jax.Array, params: FunctionalParams
    ) -> tuple[jax.Array, DWRState, jax.Array, jax.Array, dict[str, Any]]:
        """One step without auto-reset."""
        next_state = self.func_env.transition(state, action, key, params)
        info = self.func_env.transition_info(state, action, next_state, params)
        info["discount"] = self.discount(next_state, params)
        return next_state.observation, next_state, next_state.reward, next_state.terminated | next_state.truncated, info

    def step(
        self, key: jax.Array, state: DWRState, action: jax.Array, params: FunctionalParams | None = None
    ) -> tuple[jax.Array, DWRState, jax.Array, jax.Array, dict[str, Any]]:
        """One step with gymnax's auto-reset: where ``done``, the returned observation and state are a new
        episode's; reward, done and info are the ended step's."""
        params = self.default_params if params is None else params
        noisy = params.observation_noise > 0 or params.actuation_noise > 0  # (static) else the step draws nothing:
        step_key, reset_key = jax.random.split(key) if noisy else (key, key)  # its key is free for the reset
        obs, next_state, reward, done, info = self.step_env(step_key, state, action, params)
        info["final_observation"] = obs  # the ended step's (to bootstrap a truncated episode's value from)
        reset_obs, reset_state = self.reset_env(reset_key, params)
        next_state = jax.tree.map(lambda new, old: jnp.where(done, new, old), reset_state, next_state)
        return jnp.where(done, reset_obs, obs), next_state, reward, done, info

    def discount(self, state: DWRState, params: FunctionalParams | None = None) -> jax.Array:
        """0 where the episode terminated (no value beyond it), 1 elsewhere (also at truncation)."""
        return 1.0 - state.terminated.astype(state.reward.dtype)

    def is_terminal(self, state: DWRState, params: FunctionalParams | None = None) -> jax.Array:
        return state.terminated | state.truncated

    def observation_space(self, params: FunctionalParams | None = None) -> Box:
        space = self.func_env.observation_space
        return Box(space.low, space.high, space.shape, space.dtype)

    def action_space(self, params: FunctionalParams | None = None) -> Box:
        return Box(-1.0, 1.0, (2,), jnp.float32)


def make_gymnax_env(
    env_id: str = "DWRPointStabilization-v1", dtype: str = "float32", **env_kwargs: Any
) -> tuple[DWRGymnaxEnv, FunctionalParams]:
    """``gymnax.make``'s pair (env, default params) for ``env_id`` with the numpy env's keywords ``env_kwargs``."""
    env = DWRGymnaxEnv(DWRFuncEnv(env_id, dtype, **env_kwargs))
    return env, env.default_params

"""DWRPointStabilizationJax-v0 / -v1: :class:`DWRFuncEnv` through Gymnasium's functional JAX wrappers.

``gymnasium.make("DWRPointStabilizationJax-v1")`` and ``gymnasium.make_vec(..., num_envs=N)`` return these. They
are Gymnasium's ``FunctionalJaxEnv`` and ``FunctionalJaxVectorEnv`` with two changes: the episode is truncated
by the env at its own horizon (horizon_factor * T_con, which depends on the episode's T_con), and the vector
env's autoreset is one compiled step with the numpy vector env's NEXT_STEP semantics (the step after an
episode's end ignores its action and returns the new episode's first observation, reward 0, both flags False).
Observations, rewards and flags are jax arrays (wrap in ``gymnasium.wrappers.JaxToNumpy`` for numpy).
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp
from gymnasium.envs.functional_jax_env import FunctionalJaxEnv, FunctionalJaxVectorEnv
from gymnasium.envs.registration import EnvSpec
from gymnasium.utils import EzPickle
from gymnasium.vector import AutoresetMode

from dwr_gym.env import HorizonSpec
from dwr_gym.jax_env.func_env import DWRFuncEnv, DWRState
from dwr_gym.jax_env.params import functional_params
from dwr_gym.params import EnvParams
from dwr_gym.validation import as_int

#: The id whose keywords are none: the registered JAX ids pass all of theirs (v1's defaults) explicitly.
_BASE_ID = "DWRPointStabilization-v0"


def _func_env(render_mode: str | None, dtype: str, env_kwargs: dict[str, Any]) -> DWRFuncEnv:
    if render_mode is not None:
        raise ValueError(
            f"render_mode={render_mode!r} is invalid for the JAX env: expected None (render the numpy env)"
        )
    return DWRFuncEnv(params=functional_params(_BASE_ID, dtype, **env_kwargs))


def _check_no_options(options: dict[str, Any] | None) -> None:
    if options:
        raise ValueError(
            f"reset options {sorted(options)} are invalid for the JAX env: expected none (it draws starts and T_con; "
            "dwr_gym.jax_env.func_env.initial_state places given ones)"
        )


class DWRJaxEnv(HorizonSpec, FunctionalJaxEnv, EzPickle):
    """One robot on JAX: Gymnasium's FunctionalJaxEnv over :class:`DWRFuncEnv` (jitted), truncating itself."""

    metadata = {"render_modes": [], "jax": True}

    def __init__(self, render_mode: str | None = None, dtype: str = "float32", **env_kwargs: Any) -> None:
        EzPickle.__init__(self, render_mode=render_mode, dtype=dtype, **env_kwargs)
        func_env = _func_env(render_mode, dtype, env_kwargs)
        self.params: EnvParams = func_env.default_params.env_params
        func_env.transform(jax.jit)
        self._spec: EnvSpec | None = None
        FunctionalJaxEnv.__init__(self, func_env, metadata=self.metadata, render_mode=render_mode)

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None) -> tuple[jax.Array, dict]:
        _check_no_options(options)
        return super().reset(seed=seed)  # type: ignore[no-any-return]

    def step(self, action: Any) -> tuple[jax.Array, float, bool, bool, dict[str, Any]]:
        rng, self.rng = jax.random.split(self.rng)
        next_state = self.func_env.transition(self.state, jnp.asarray(action), rng)
        info = self.func_env.transition_info(self.state, action, next_state)
        self.state = next_state
        return (next_state.observation, float(next_state.reward), bool(next_state.terminated),
                bool(next_state.truncated), info)  # fmt: skip


class DWRJaxVectorEnv(HorizonSpec, FunctionalJaxVectorEnv, EzPickle):
    """N robots on JAX: Gymnasium's FunctionalJaxVectorEnv over :class:`DWRFuncEnv`, one jitted step with autoreset."""

    metadata = {"render_modes": [], "jax": True, "autoreset_mode": AutoresetMode.NEXT_STEP}

    def __init__(
        self, num_envs: int = 1, render_mode: str | None = None, dtype: str = "float32", **env_kwargs: Any
    ) -> None:
        num_envs = as_int("num_envs", num_envs, 1, 1 << 24)
        func_env = _func_env(render_mode, dtype, env_kwargs)
        self.params = func_env.default_params.env_params
        self._spec = None
        FunctionalJaxVectorEnv.__init__(self, func_env, num_envs, metadata=self.metadata, render_mode=render_mode)
        # after the base class, whose __init__ reaches EzPickle's without arguments (a pickle would then have 1 robot)
        EzPickle.__init__(self, num_envs=num_envs, render_mode=render_mode, dtype=dtype, **env_kwargs)
        self._step = jax.jit(self._next_step)  # after the base class vmapped the FuncEnv's functions

    def _next_step(
        self, state: DWRState, ended: jax.Array, action: jax.Array, key: jax.Array
    ) -> tuple[DWRState, dict[str, Any]]:
        step_key, reset_key = jax.random.split(key)
        stepped = self.func_env.transition(state, action, jax.random.split(step_key, self.num_envs))
        fresh = self.func_env.initial(jax.random.split(reset_key, self.num_envs))

        def pick(new: jax.Array, old: jax.Array) -> jax.Array:
            return jnp.where(jnp.reshape(ended, ended.shape + (1,) * (new.ndim - 1)), new, old)

        state = jax.tree.map(pick, fresh, stepped)
        return state, self.func_env.state_info(state)

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None) -> tuple[jax.Array, dict]:
        _check_no_options(options)
        obs, info = super().reset(seed=seed)
        self.prev_done = jnp.zeros(self.num_envs, dtype=bool)
        return obs, info  # type: ignore[no-any-return]

    def step(self, action: Any) -> tuple[jax.Array, jax.Array, jax.Array, jax.Array, dict[str, Any]]:
        key, self.rng = jax.random.split(self.rng)
        self.state, info = self._step(self.state, self.prev_done, jnp.asarray(action), key)
        state = self.state
        self.prev_done = state.terminated | state.truncated
        return state.observation, state.reward, state.terminated, state.truncated, info

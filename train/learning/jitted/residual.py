"""Residual agents on the jitted trainers (``dwr-gym train --backend jax --residual --expert ptc``, with ``--algo ppo``
or ``es``): the functional env whose action is a residual on an analytic law, so that the law runs inside the
compiled training loop.

:class:`ResidualGymnaxEnv` is to the gymnax env what :class:`train.learning.residual.ResidualVecEnv` is to the SB3
VecEnv: the env steps with clip(expert(obs) + scale * clip(residual, -1, 1), -1, 1) (:func:`residual_action`),
the expert's action computed by :func:`baselines.expert.normalized_action` from the observation the agent saw, by
the same copy of the law that the numpy expert runs (its array-API form). The PPO and the ES train on it unchanged
(both start from a residual near zero, :func:`near_zero_head`: at the expert); the run
exports the residual network as the SB3 path does, and its config.yaml (``residual: true``, ``expert``,
``residual_scale``) makes :func:`train.learning.agents.load_agent` act as expert + residual.
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp

from baselines.base import Controller
from baselines.expert import normalized_action
from train.learning.config import ConfigError, TrainConfig

#: SB3's residual agents start near the expert: :func:`train.learning.residual.zero_init_last_layer`'s gain.
LAST_LAYER_GAIN = 1e-3


@jax.custom_vjp
def finite_cotangent(x: jax.Array) -> jax.Array:
    """``x`` unchanged on the way forward; on the way back its cotangent with each non-finite entry set to 0."""
    return x


def _finite_forward(x: jax.Array) -> tuple[jax.Array, None]:
    return x, None


def _finite_backward(_: None, cotangent: jax.Array) -> tuple[jax.Array]:
    return (jnp.where(jnp.isfinite(cotangent), cotangent, 0.0),)


finite_cotangent.defvjp(_finite_forward, _finite_backward)


def residual_action(expert: Any, residual: Any, scale: float) -> Any:
    """clip(expert + scale * clip(residual, -1, 1), -1, 1), in the residual's dtype (jax arrays)."""
    return jnp.clip(expert + scale * jnp.clip(residual, -1.0, 1.0), -1.0, 1.0).astype(residual.dtype)


class ResidualGymnaxEnv:
    """A gymnax-style env (``reset_env``, ``step_env``, the spaces) whose action is a residual on ``controller``,
    a law with ``traceable`` True (it runs on jax arrays under ``jit`` and ``vmap``)."""

    def __init__(self, env: Any, controller: Controller, u_max: float, omega_max: float, scale: float) -> None:
        self.env, self.controller, self.scale = env, controller, float(scale)
        self.u_max, self.omega_max = float(u_max), float(omega_max)

    def expert_action(self, obs: Any) -> Any:
        """The law's normalised action for observations (..., 10), computed in their dtype."""
        return normalized_action(self.controller, obs, self.u_max, self.omega_max).astype(obs.dtype)

    def reset_env(self, key: jax.Array, params: Any) -> tuple[jax.Array, Any]:
        return self.env.reset_env(key, params)  # type: ignore[no-any-return]

    def reset(self, key: jax.Array, params: Any = None) -> tuple[jax.Array, Any]:
        return self.env.reset(key, params)  # type: ignore[no-any-return]

    def step_env(self, key: jax.Array, state: Any, action: jax.Array, params: Any) -> tuple[Any, ...]:
        """One step without auto-reset, with the expert's action plus the residual ``action``."""
        # the law's derivative is undefined where its gain is (at T_con, eq. (17)): a gradient through it is kept
        # wherever it is finite and is 0 at those steps, so one such step does not void a whole batch's update
        expert = self.expert_action(finite_cotangent(state.observation))
        executed = residual_action(expert, action, self.scale)
        return self.env.step_env(key, state, executed, params)  # type: ignore[no-any-return]

    def __getattr__(self, name: str) -> Any:  # the spaces, default_params, is_truncated, ...
        return getattr(self.env, name)


def check_residual_expert(config: TrainConfig) -> Controller:
    """The expert of a residual run of ``--backend jax``, or a ConfigError naming the laws that can be one."""
    from baselines.registry import CONTROLLERS, make_controller

    traceable = [name for name, cls in CONTROLLERS.items() if cls.traceable]
    if config.expert not in traceable:
        raise ConfigError(f"--expert {config.expert!r} is invalid with --backend jax --residual: the expert must run "
                          f"inside the compiled loop; expected one of {', '.join(traceable)}")  # fmt: skip
    return make_controller(config.expert)


def residual_env(config: TrainConfig, env: Any) -> ResidualGymnaxEnv:
    """``env`` (the run's gymnax env) with actions that are residuals on ``config.expert``, scaled as configured."""
    params = config.env_params()
    return ResidualGymnaxEnv(env, check_residual_expert(config), params.u_max, params.omega_max,
                             config.residual_scale)  # fmt: skip


def near_zero_head(params: Any) -> Any:
    """The network ``params`` with the mean head's weights scaled by :data:`LAST_LAYER_GAIN` and its bias zero, as
    SB3's residual agents start: the residual is near zero, the agent near its expert."""
    inner = dict(params["params"])
    head = inner["action"]
    inner["action"] = {**head, "kernel": head["kernel"] * LAST_LAYER_GAIN, "bias": jnp.zeros_like(head["bias"])}
    return {**params, "params": inner}


def start_near_expert(runner: Any) -> Any:
    """``runner`` (the jitted PPO's state) with its network's residual near zero (:func:`near_zero_head`)."""
    return runner.replace(params=near_zero_head(runner.params))


__all__ = [
    "ResidualGymnaxEnv",
    "check_residual_expert",
    "finite_cotangent",
    "near_zero_head",
    "residual_action",
    "residual_env",
    "start_near_expert",
]

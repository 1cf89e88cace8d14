"""Any controller as a policy that acts from the env's observations alone."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
from numpy.typing import NDArray

from baselines.base import Controller, ControllerInput, array_namespace
from dwr_gym.params import EnvParams, check_range


def controller_input_from_observation(obs: NDArray[np.floating]) -> ControllerInput:
    """Decode observations (..., 10) of DWRPointStabilization-v0 (a batch (N, 10)) into controller inputs.

    The prescribed time T_con is read from the observation too, so one expert serves envs of any T_con. numpy
    observations are read in float64; jax arrays (maybe traced) stay jax arrays of their own dtype.
    """
    xp = array_namespace(obs)
    if xp is np:
        obs = np.asarray(obs, dtype=np.float64)
    return ControllerInput(
        distance=obs[..., 0],
        azimuth=xp.arctan2(obs[..., 2], obs[..., 1]),
        heading=xp.arctan2(obs[..., 4], obs[..., 3]),
        time=obs[..., 6] * obs[..., 7],
        initial_distance=obs[..., 8],
        initial_orientation_error=obs[..., 9],
        prescribed_time=obs[..., 7],
    )


def normalized_action(controller: Controller, obs: Any, u_max: float, omega_max: float) -> Any:
    """The controller's (u / u_max, omega / omega_max) from observations (..., 10), clipped to [-1, 1], shape
    (..., 2), in the observations' array library: what :class:`ExpertPolicy` acts with (numpy, float64) and what
    the residual agents of ``dwr-gym train --backend jax`` add their residual to, inside the compiled loop (jax;
    ``controller.traceable`` laws only)."""
    xp = array_namespace(obs)
    u, omega = controller(controller_input_from_observation(obs))
    return xp.clip(xp.stack([u / u_max, omega / omega_max], axis=-1), -1.0, 1.0)


def env_params_of(env: Any) -> EnvParams:
    """The :class:`EnvParams` of a single env, a Gymnasium vector env or an SB3 VecEnv of ours."""
    if isinstance(env, EnvParams):
        return env
    for candidate in (env, getattr(env, "unwrapped", None)):
        params = getattr(candidate, "params", None)
        if isinstance(params, EnvParams):
            return params
    if hasattr(env, "get_attr"):  # a stable-baselines3 VecEnv over our env
        return env_params_of(env.get_attr("params", [0])[0])
    raise ValueError(f"env={env!r} is not a DWRPointStabilization env: no EnvParams found")


class ExpertPolicy:
    """Wraps a controller into a policy with stable-baselines3's ``predict`` signature.

    Actions are the controller's (u, omega) divided by (u_max, omega_max) and clipped to [-1, 1],
    as float32, for one observation (10,) or a batch (N, 10). The prescribed-time laws take T_con
    from the observation, so their own ``T_con`` parameter is not used here.

    >>> import gymnasium as gym, dwr_gym
    >>> from baselines import ExpertPolicy, PTCController
    >>> env = gym.make("DWRPointStabilization-v1")
    >>> expert = ExpertPolicy.from_env(env, PTCController())
    >>> obs, _ = env.reset(seed=1)
    >>> action, _ = expert.predict(obs)
    >>> action.shape, action.dtype
    ((2,), dtype('float32'))
    """

    def __init__(self, controller: Controller, u_max: float, omega_max: float) -> None:
        self.controller = controller
        self.u_max = check_range("u_max", u_max, 0.0, 1e9, low_inclusive=False)
        self.omega_max = check_range("omega_max", omega_max, 0.0, 1e9, low_inclusive=False)

    @classmethod
    def from_env(cls, env: gym.Env[Any, Any] | Any, controller: Controller) -> ExpertPolicy:
        """An expert scaled to the action limits of ``env``."""
        params = env_params_of(env)
        return cls(controller, params.u_max, params.omega_max)

    def commands(self, obs: NDArray[np.floating]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The controller's raw (u, omega) for a batch of observations."""
        return self.controller(controller_input_from_observation(obs))

    def predict(
        self,
        observation: NDArray[np.floating],
        state: tuple[NDArray[Any], ...] | None = None,
        episode_start: NDArray[np.bool_] | None = None,
        deterministic: bool = True,
    ) -> tuple[NDArray[np.float32], tuple[NDArray[Any], ...] | None]:
        """Normalised actions for one observation or a batch; ``state`` is passed through."""
        obs = np.asarray(observation, dtype=np.float64)
        single = obs.ndim == 1
        batch = obs[None, :] if single else obs
        if batch.ndim != 2 or batch.shape[1] != 10:
            raise ValueError(f"observation of shape {obs.shape} is invalid: expected (10,) or (N, 10)")
        if episode_start is not None:
            self.controller.reset(np.asarray(episode_start, dtype=bool).reshape(-1))
        actions = normalized_action(self.controller, batch, self.u_max, self.omega_max).astype(np.float32)
        return (actions[0] if single else actions), state

    def __call__(self, observation: NDArray[np.floating]) -> NDArray[np.float32]:
        return self.predict(observation)[0]

"""DWRFuncEnv: the task as Gymnasium's FuncEnv, pure functions of (state, action, key, params) on jax arrays.

Nothing here computes the task: :func:`initial_state` builds a state with :mod:`dwr_gym.state`'s functions and
:func:`transition_state` advances it with :func:`dwr_gym.core.transition`, the very functions the numpy envs call,
which run on ``jax.numpy`` because :func:`dwr_gym.model.namespace` hands jax arrays their own namespace.
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp
from flax import struct
from gymnasium import spaces
from gymnasium.experimental.functional import FuncEnv

from dwr_gym import core, model, observation
from dwr_gym.jax_env.params import FunctionalParams, functional_params
from dwr_gym.state import TaskState, new_state_and_coordinates, start_from_uniforms, uniform_in

TASK_FIELDS: tuple[str, ...] = tuple(TaskState.__dataclass_fields__)


@struct.dataclass
class DWRState:
    """:class:`dwr_gym.state.TaskState`'s fields (the pose in the goal's frame, the goal, the episode's clock and
    T_con), then what the step that led here returned (the reset's zeros and flags False for a new episode)."""

    x: jax.Array
    y: jax.Array
    psi: jax.Array
    goal_x: jax.Array
    goal_y: jax.Array
    goal_psi: jax.Array
    step_count: jax.Array
    energy: jax.Array
    initial_distance: jax.Array
    initial_orientation_error: jax.Array
    lyapunov: jax.Array
    goal_cos: jax.Array
    goal_sin: jax.Array
    T_con: jax.Array
    prescribed_steps: jax.Array
    max_steps: jax.Array
    observation: jax.Array
    reward: jax.Array
    terminated: jax.Array
    truncated: jax.Array
    is_success: jax.Array
    distance: jax.Array
    orientation_error: jax.Array
    heading_error: jax.Array
    linear_velocity: jax.Array
    angular_velocity: jax.Array
    reward_terms: dict[str, jax.Array]

    def task_state(self) -> TaskState:
        """A fresh TaskState of these arrays (core.transition rebinds its fields, never writes into the arrays)."""
        return TaskState(*(getattr(self, name) for name in TASK_FIELDS))


def observation_space(params: FunctionalParams) -> spaces.Box:
    """The numpy env's observation space, in ``params.dtype``."""
    space = observation.observation_space(params.env_params)
    if params.dtype == "float32":
        return space
    return spaces.Box(space.low.astype(params.dtype), space.high.astype(params.dtype), dtype=params.dtype)


def _pack(task: TaskState, coords: Any, obs: Any, **step: Any) -> DWRState:
    return DWRState(**{name: getattr(task, name) for name in TASK_FIELDS}, observation=obs, distance=coords.distance,
                    orientation_error=coords.orientation_error, heading_error=coords.psi, **step)  # fmt: skip


def initial_state(
    start: tuple[Any, Any, Any], T_con: Any, key: jax.Array, params: FunctionalParams, space: spaces.Box
) -> DWRState:
    """A new episode from ``start`` (x, y, psi) in the goal's frame (goal at the origin, as the numpy envs' default)
    with prescribed time ``T_con``; arrays of any one shape (a batch needs no vmap). ``key`` draws the pose noise."""
    dtype = jnp.dtype(params.dtype)
    start = tuple(jnp.asarray(value, dtype) for value in start)  # type: ignore[assignment]
    zero = jnp.zeros(jnp.shape(start[0]), dtype)
    goal = (zero, zero, zero)
    world = model.from_goal_frame(*start, *goal)  # as the vector env places its random starts
    task, coords = new_state_and_coordinates(world, goal, params, jnp.asarray(T_con, dtype))  # type: ignore[arg-type]
    obs = observation.observe(task, coords, params, space, _noise(key, zero.shape, 3, params.observation_noise, dtype))  # type: ignore[arg-type]
    false = jnp.zeros(zero.shape, bool)
    return _pack(task, coords, obs, reward=zero, terminated=false, truncated=false, is_success=coords.distance <= params.goal_tolerance,
                 linear_velocity=zero, angular_velocity=zero, reward_terms=dict.fromkeys(core.REWARD_TERMS, zero))  # fmt: skip


def _noise(key: jax.Array, shape: tuple[int, ...], size: int, sigma: float, dtype: Any) -> jax.Array | None:
    """Standard-normal samples (shape, size), or None when ``sigma`` is 0 (a static choice: nothing drawn)."""
    return jax.random.normal(key, (*shape, size), dtype) if sigma > 0 else None


def transition_state(
    state: DWRState, action: jax.Array, key: jax.Array, params: FunctionalParams, space: spaces.Box
) -> DWRState:
    """One control period of :func:`dwr_gym.core.transition` from ``state`` with ``action`` (..., 2)."""
    task = state.task_state()
    dtype = jnp.dtype(params.dtype)
    action_key, pose_key = jax.random.split(key)
    shape = jnp.shape(state.x)
    result = core.transition(task, action, params, space, _noise(action_key, shape, 2, params.actuation_noise, dtype),  # type: ignore[arg-type]
                             _noise(pose_key, shape, 3, params.observation_noise, dtype))  # fmt: skip
    return _pack(task, result.coords, result.observation, reward=result.reward, terminated=result.terminated,
                 truncated=result.truncated, is_success=result.is_success, linear_velocity=result.linear_velocity,
                 angular_velocity=result.angular_velocity, reward_terms=result.reward_terms)  # fmt: skip


def state_info(state: DWRState, params: FunctionalParams) -> dict[str, Any]:
    """The numpy env's info keys of ``state`` (its last step's), and "terminated" and "truncated"."""
    dx, dy = model.rotate(state.x, state.y, state.goal_cos, state.goal_sin)
    pose = jnp.stack([state.goal_x + dx, state.goal_y + dy, model.wrap_angle(state.psi + state.goal_psi)], axis=-1)
    # (the functional params write "no heading tolerance" as inf; the cost's convention for it is 0)
    heading_tolerance = jnp.where(jnp.isinf(params.heading_tolerance), 0.0, params.heading_tolerance)
    cost, distance_violation, heading_violation = core.deadline_cost(
        state.terminated | state.truncated,
        state.is_success,
        state.step_count,
        state.prescribed_steps,
        state.distance,
        state.heading_error,
        params.goal_tolerance,
        heading_tolerance,
        jnp,
    )
    return {"distance": state.distance, "orientation_error": state.orientation_error, "heading_error": state.heading_error,
            "time": state.step_count * params.dt, "T_con": state.T_con, "is_success": state.is_success,
            "energy": state.energy, "linear_velocity": state.linear_velocity, "angular_velocity": state.angular_velocity,
            "pose": pose, "terminated": state.terminated, "truncated": state.truncated,
            "cost": cost.astype(state.distance.dtype), "distance_violation": distance_violation,
            "heading_violation": heading_violation, "reward_terms": state.reward_terms}  # fmt: skip


class DWRFuncEnv(FuncEnv):
    """DWRPointStabilization (v0 or v1) as ``gymnasium.experimental.functional.FuncEnv``: ``initial``, ``transition``,
    ``observation``, ``reward``, ``terminal`` (and ``truncated``) are pure functions of one robot's state (vmap them
    for a batch; shapes (N,) work unvmapped too), an action (2,), a key and :class:`FunctionalParams` (None: the
    env's). The state carries what its last step returned, so ``observation``, ``reward`` and ``terminal`` read it.

    ``DWRFuncEnv(env_id="DWRPointStabilization-v1", dtype="float32", **env_kwargs)`` takes the numpy env's keywords;
    ``DWRFuncEnv(params=functional_params(...))`` takes ready parameters.
    """

    def __init__(
        self, env_id: str = "DWRPointStabilization-v1", dtype: str = "float32", params: FunctionalParams | None = None,
        **env_kwargs: Any,
    ) -> None:  # fmt: skip
        if params is None:
            params = functional_params(env_id, dtype, **env_kwargs)
        elif env_kwargs:
            raise ValueError(f"env_kwargs={sorted(env_kwargs)} are invalid with params: expected one of the two")
        self._params = params
        super().__init__()
        self.observation_space = observation_space(params)
        self.action_space = core.action_space()

    def get_default_params(self, **kwargs: Any) -> FunctionalParams:
        return self._params

    def _params_or_default(self, params: FunctionalParams | None) -> FunctionalParams:
        return self._params if params is None else params

    def initial(self, rng: jax.Array, params: FunctionalParams | None = None) -> DWRState:
        """A new episode: the start (distance, bearing, heading) and T_con drawn as the numpy envs draw them."""
        params = self._params_or_default(params)
        dtype = jnp.dtype(params.dtype)
        # one call for the four draws: on a CPU, jax.random's hashing costs more than the episode's arithmetic
        draws = jax.random.uniform(rng, (4,), dtype)
        start = start_from_uniforms(draws[0], draws[1], draws[2], params, jnp)
        T_con = uniform_in(params.T_con_range, draws[3])
        noise_key = jax.random.fold_in(rng, 1) if params.observation_noise > 0 else rng  # (unused without noise)
        return initial_state(start, T_con, noise_key, params, observation_space(params))

    def transition(
        self, state: DWRState, action: jax.Array, rng: jax.Array, params: FunctionalParams | None = None
    ) -> DWRState:
        params = self._params_or_default(params)
        return transition_state(state, action, rng, params, observation_space(params))

    def observation(self, state: DWRState, rng: Any = None, params: FunctionalParams | None = None) -> jax.Array:
        return state.observation

    def reward(
        self, state: DWRState, action: jax.Array, next_state: DWRState, rng: Any = None,
        params: FunctionalParams | None = None,
    ) -> jax.Array:  # fmt: skip
        return next_state.reward

    def terminal(self, state: DWRState, rng: Any = None, params: FunctionalParams | None = None) -> jax.Array:
        return state.terminated

    def truncated(self, state: DWRState, params: FunctionalParams | None = None) -> jax.Array:
        """Whether the episode was cut at its horizon horizon_factor * T_con (without arriving or leaving)."""
        return state.truncated

    def state_info(self, state: DWRState, params: FunctionalParams | None = None) -> dict[str, Any]:
        return state_info(state, self._params_or_default(params))

    def transition_info(
        self, state: DWRState, action: jax.Array, next_state: DWRState, params: FunctionalParams | None = None
    ) -> dict[str, Any]:
        return state_info(next_state, self._params_or_default(params))

    def transform(self, func: Any) -> None:
        super().transform(func)
        self.truncated = func(self.truncated)


__all__ = ["DWRFuncEnv", "DWRState", "initial_state", "observation_space", "state_info", "transition_state"]

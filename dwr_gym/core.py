"""The task on a batch of N robots: observation, reward, episode end.

Both :class:`dwr_gym.env.DWRPointStabilizationEnv` (N = 1) and
:class:`dwr_gym.vector_env.DWRPointStabilizationVectorEnv` (any N) keep a :class:`TaskState` and
advance it with :func:`transition`; they differ only in bookkeeping (seeding, autoreset, rendering).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from gymnasium import spaces
from numpy.typing import NDArray

from dwr_gym import model
from dwr_gym.model import FloatArray
from dwr_gym.params import EnvParams

#: Names of the observation features, in order.
OBSERVATION_NAMES: tuple[str, ...] = (
    "distance",
    "cos_azimuth",
    "sin_azimuth",
    "cos_heading",
    "sin_heading",
    "orientation_error",
    "time_fraction",
    "T_con",
    "initial_distance",
    "initial_orientation_error",
)
REWARD_TERMS: tuple[str, ...] = ("progress", "time", "effort", "arrival", "late", "arena")


class ErrorCoordinates(NamedTuple):
    """The robot's pose in the goal frame and the paper's error coordinates (2), (3), (6)."""

    x: FloatArray
    y: FloatArray
    psi: FloatArray
    distance: FloatArray
    azimuth: FloatArray
    orientation_error: FloatArray


def error_coordinates(
    x: FloatArray,
    y: FloatArray,
    psi: FloatArray,
    goal_x: FloatArray,
    goal_y: FloatArray,
    goal_psi: FloatArray,
    k: float,
) -> ErrorCoordinates:
    """Goal-frame pose, distance (2), azimuth (3) and orientation error (6) of a batch of poses."""
    x_g, y_g, psi_g = model.to_goal_frame(x, y, psi, goal_x, goal_y, goal_psi)
    dist = model.distance(x_g, y_g)
    alpha = model.azimuth(x_g, y_g)
    return ErrorCoordinates(x_g, y_g, psi_g, dist, alpha, model.orientation_error(alpha, psi_g, dist, k))


@dataclass
class TaskState:
    """Batched state of N robots; every array has shape (N,)."""

    x: FloatArray
    y: FloatArray
    psi: FloatArray
    goal_x: FloatArray
    goal_y: FloatArray
    goal_psi: FloatArray
    step_count: NDArray[np.int64]
    energy: FloatArray
    initial_distance: FloatArray
    initial_orientation_error: FloatArray
    lyapunov: FloatArray  # eq. (21) at the current pose, kept for the next progress term

    @classmethod
    def zeros(cls, n: int) -> TaskState:
        """A state of n robots at the goal."""
        z = np.zeros(n)
        return cls(z.copy(), z.copy(), z.copy(), z.copy(), z.copy(), z.copy(), np.zeros(n, np.int64),
                   z.copy(), z.copy(), z.copy(), z.copy())  # fmt: skip


def observation_space(params: EnvParams) -> spaces.Box:
    """The observation space; see the env's docstring for the table."""
    e_max = model.MAX_ORIENTATION_ERROR
    d_max = 2.0 * params.arena_radius
    low = np.array([0, -1, -1, -1, -1, -e_max, 0, 0, 0, -e_max], dtype=np.float32)
    high = np.array(
        [d_max, 1, 1, 1, 1, e_max, params.horizon_factor, params.T_con, params.arena_radius, e_max], dtype=np.float32
    )
    return spaces.Box(low, high, dtype=np.float32)


def action_space() -> spaces.Box:
    """Normalised (linear, angular) velocity commands."""
    return spaces.Box(-1.0, 1.0, shape=(2,), dtype=np.float32)


def observe(
    coords: ErrorCoordinates,
    step_count: NDArray[np.int64],
    initial_distance: FloatArray,
    initial_orientation_error: FloatArray,
    params: EnvParams,
    space: spaces.Box,
) -> NDArray[np.float32]:
    """Observation features (N, 10) from error coordinates; clipped to the space's bounds."""
    obs = np.empty((coords.distance.shape[0], len(OBSERVATION_NAMES)), dtype=np.float32)
    obs[:, 0] = coords.distance
    obs[:, 1] = np.cos(coords.azimuth)
    obs[:, 2] = np.sin(coords.azimuth)
    obs[:, 3] = np.cos(coords.psi)
    obs[:, 4] = np.sin(coords.psi)
    obs[:, 5] = coords.orientation_error
    obs[:, 6] = step_count * (params.dt / params.T_con)
    obs[:, 7] = params.T_con
    obs[:, 8] = initial_distance
    obs[:, 9] = initial_orientation_error
    return np.clip(obs, space.low, space.high, out=obs)


def observe_state(
    state: TaskState,
    coords: ErrorCoordinates,
    params: EnvParams,
    space: spaces.Box,
    pose_noise: FloatArray | None = None,
) -> NDArray[np.float32]:
    """Observation of ``state`` (whose true error coordinates are ``coords``), measured with pose noise."""
    if pose_noise is not None:
        sigma = params.observation_noise
        coords = error_coordinates(
            state.x + sigma * pose_noise[:, 0], state.y + sigma * pose_noise[:, 1], state.psi + sigma * pose_noise[:, 2],
            state.goal_x, state.goal_y, state.goal_psi, params.k,
        )  # fmt: skip
    return observe(coords, state.step_count, state.initial_distance, state.initial_orientation_error, params, space)


def sample_start(rng: np.random.Generator, params: EnvParams) -> tuple[float, float, float]:
    """A random start pose in the goal frame: distance and heading in their ranges, bearing uniform."""
    dist = rng.uniform(*params.start_distance)
    bearing = rng.uniform(-math.pi, math.pi)
    heading = rng.uniform(*params.start_heading)
    return dist * math.cos(bearing), dist * math.sin(bearing), heading


def parse_pose(name: str, value: object) -> tuple[float, float, float]:
    """Validate a pose option (x, y, psi) of reset()."""
    try:
        pose = tuple(float(v) for v in value)  # type: ignore[attr-defined]
    except (TypeError, ValueError):
        pose = ()
    if len(pose) != 3 or not all(math.isfinite(v) for v in pose):
        raise ValueError(
            f"options[{name!r}]={value!r} is invalid: expected three finite numbers (x [m], y [m], psi [rad])"
        )
    return pose  # type: ignore[return-value]


def reset_robots(
    state: TaskState,
    index: NDArray[np.intp] | slice,
    start: tuple[FloatArray, FloatArray, FloatArray],
    goal: tuple[FloatArray, FloatArray, FloatArray],
    params: EnvParams,
) -> ErrorCoordinates:
    """Place the robots at ``index`` at world poses ``start`` with goals ``goal``; returns their coordinates."""
    state.x[index], state.y[index], state.psi[index] = start[0], start[1], model.wrap_angle(start[2])
    state.goal_x[index], state.goal_y[index], state.goal_psi[index] = goal
    state.step_count[index] = 0
    state.energy[index] = 0.0
    coords = error_coordinates(
        state.x[index], state.y[index], state.psi[index], state.goal_x[index], state.goal_y[index],
        state.goal_psi[index], params.k,
    )  # fmt: skip
    too_far = coords.distance > params.arena_radius
    if np.any(too_far):
        raise ValueError(
            f"start pose is {float(np.max(coords.distance)):.3f} m from the goal, outside the arena: "
            f"expected a distance <= arena_radius={params.arena_radius}"
        )
    state.initial_distance[index] = coords.distance
    state.initial_orientation_error[index] = coords.orientation_error
    state.lyapunov[index] = model.lyapunov(coords.distance, coords.orientation_error)
    return coords


def commands_from_action(action: NDArray[np.floating], params: EnvParams) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Clip normalised actions (N, 2) to [-1, 1] and scale them to (u [m/s], omega [rad/s])."""
    if not np.all(np.isfinite(action)):
        raise ValueError(f"action={np.asarray(action).tolist()!r} is invalid: expected finite numbers in [-1, 1]")
    clipped = np.clip(action, -1.0, 1.0).astype(np.float64)
    return clipped, clipped[:, 0] * params.u_max, clipped[:, 1] * params.omega_max


class StepResult(NamedTuple):
    """What :func:`transition` returns for a batch (arrays of shape (N,), obs (N, 10))."""

    observation: NDArray[np.float32]
    reward: FloatArray
    terminated: NDArray[np.bool_]
    truncated: NDArray[np.bool_]
    coords: ErrorCoordinates
    is_success: NDArray[np.bool_]
    linear_velocity: FloatArray
    angular_velocity: FloatArray
    reward_terms: dict[str, FloatArray]


def transition(
    state: TaskState,
    action: NDArray[np.floating],
    params: EnvParams,
    space: spaces.Box,
    action_noise: FloatArray | None = None,
    pose_noise: FloatArray | None = None,
) -> StepResult:
    """Advance every robot by one control period and compute observation, reward and episode end.

    ``state`` is updated in place. ``action_noise`` (N, 2) and ``pose_noise`` (N, 3) are pre-drawn
    standard-normal samples (or None) so that this function stays free of random state.
    """
    if action_noise is not None:
        action = np.asarray(action, dtype=np.float64) + params.actuation_noise * action_noise
    applied, u, omega = commands_from_action(action, params)
    state.x, state.y, state.psi = model.integrate_unicycle(
        state.x,
        state.y,
        state.psi,
        u,
        omega,
        params.dt,
        params.integrator,
        params.substeps,  # type: ignore[arg-type]
    )
    state.step_count += 1
    state.energy += (u * u + omega * omega) * params.dt
    coords = error_coordinates(state.x, state.y, state.psi, state.goal_x, state.goal_y, state.goal_psi, params.k)
    time = state.step_count * params.dt

    heading_ok = True if params.heading_tolerance is None else np.abs(coords.psi) <= params.heading_tolerance
    is_success = (coords.distance <= params.goal_tolerance) & heading_ok
    out_of_arena = coords.distance > params.arena_radius
    in_time = time <= params.T_con + 1e-9 * params.dt
    lyapunov = model.lyapunov(coords.distance, coords.orientation_error)
    terms = {
        "progress": params.progress_weight * (state.lyapunov - params.shaping_discount * lyapunov),
        "time": -params.time_weight * params.dt * coords.distance
        * model.conventional_scaling(time, params.T_con, max_gain=params.time_gain_cap),
        "effort": -params.effort_weight * params.dt * np.einsum("ij,ij->i", applied, applied),
        "arrival": np.where(is_success & in_time, params.arrival_bonus, 0.0),
        "late": np.where(~is_success & ~in_time, -params.late_penalty * params.dt, 0.0),
        "arena": np.where(out_of_arena, -params.arena_penalty, 0.0),
    }  # fmt: skip
    state.lyapunov = lyapunov
    terminated = is_success | out_of_arena
    truncated = (state.step_count >= params.max_episode_steps) & ~terminated

    obs = observe_state(state, coords, params, space, pose_noise)
    reward = sum(terms.values())
    return StepResult(obs, reward, terminated, truncated, coords, is_success, u, omega, terms)  # type: ignore[arg-type]

"""The task on a batch of N robots: observation, reward, episode end.

Both :class:`dwr_gym.env.DWRPointStabilizationEnv` and
:class:`dwr_gym.vector_env.DWRPointStabilizationVectorEnv` keep a :class:`TaskState` and advance it
with :func:`transition`; they differ only in bookkeeping (seeding, autoreset, rendering). The vector
env's state holds (N,) arrays; the single env's holds Python floats, for which the same functions run
on the ``math`` module (see :func:`dwr_gym.model.namespace`).
"""

from __future__ import annotations

import contextlib
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np
from gymnasium import spaces
from numpy.typing import NDArray

from dwr_gym import model
from dwr_gym.model import FloatArray
from dwr_gym.params import EnvParams
from dwr_gym.validation import as_pose

if TYPE_CHECKING:
    from dwr_gym.disturbances import Perturbation

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
REWARD_TERMS: tuple[str, ...] = ("progress", "time", "effort", "energy", "arrival", "heading", "late", "arena")
#: Keys of the info dict besides "reward_terms".
INFO_KEYS: tuple[str, ...] = ("distance", "orientation_error", "heading_error", "time", "T_con", "is_success", "energy",
                              "linear_velocity", "angular_velocity", "pose")  # fmt: skip


class ErrorCoordinates(NamedTuple):
    """The robot's pose in the goal frame and the paper's error coordinates (2), (3), (6)."""

    x: FloatArray
    y: FloatArray
    psi: FloatArray
    distance: FloatArray
    azimuth: FloatArray
    orientation_error: FloatArray


def error_coordinates(x: FloatArray, y: FloatArray, psi: FloatArray, k: float) -> ErrorCoordinates:
    """Distance (2), azimuth (3) and orientation error (6) of a batch of goal-frame poses."""
    dist = model.distance(x, y)
    alpha = model.azimuth(x, y)
    return ErrorCoordinates(x, y, psi, dist, alpha, model.orientation_error(alpha, psi, dist, k))


@dataclass
class TaskState:
    """State of N robots: every field an array of shape (N,), or a Python number for one robot.

    The pose (x, y, psi) is kept in the goal's frame, where the task is defined; eq. (1) is
    invariant under the change of frame, so it is integrated there too. The goal's world pose maps it back.
    """

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
    goal_cos: FloatArray  # cos(goal_psi), set with the goal by new_state so world_pose needs no trigonometry
    goal_sin: FloatArray
    T_con: FloatArray  # the episode's prescribed time [s]
    prescribed_steps: NDArray[np.int64]  # control periods within T_con: arriving at or before this one is in time
    max_steps: NDArray[np.int64]  # control periods until truncation

    @classmethod
    def zeros(cls, n: int, dtype: type[np.floating] = np.float64) -> TaskState:
        """A state of n robots at the goal, computed in ``dtype`` (float64, or float32 for speed)."""
        state = cls(
            *(np.zeros(n, dtype) for _ in range(6)), np.zeros(n, np.int64), *(np.zeros(n, dtype) for _ in range(7)),
            np.zeros(n, np.int64), np.zeros(n, np.int64),
        )  # fmt: skip
        state.goal_cos[:] = 1.0
        return state

    def subset(self, index: NDArray[np.intp]) -> TaskState:
        """A copy of the robots at ``index``."""
        return TaskState(**{name: getattr(self, name)[index] for name in self.__dataclass_fields__})

    def assign(self, index: NDArray[np.intp] | slice, other: TaskState) -> None:
        """Overwrite the robots at ``index`` with those of ``other``."""
        for name in self.__dataclass_fields__:
            getattr(self, name)[index] = getattr(other, name)

    def coordinates(self, k: float) -> ErrorCoordinates:
        """Error coordinates of the current poses."""
        return error_coordinates(self.x, self.y, self.psi, k)

    def world_pose(self, copy: bool = True) -> tuple[FloatArray, FloatArray, FloatArray]:
        """The robots' poses in the world frame (with ``copy=False``, maybe the state's own arrays)."""
        if type(self.x) is float:
            if self.goal_x == 0.0 and self.goal_y == 0.0 and self.goal_psi == 0.0:  # the frames coincide
                return self.x, self.y, self.psi
        elif not (np.count_nonzero(self.goal_x) or np.count_nonzero(self.goal_y) or np.count_nonzero(self.goal_psi)):
            # every goal at the origin (count_nonzero: 1.5x any()'s speed on floats)
            return (self.x.copy(), self.y.copy(), self.psi.copy()) if copy else (self.x, self.y, self.psi)
        dx, dy = model.rotate(self.x, self.y, self.goal_cos, self.goal_sin)
        return self.goal_x + dx, self.goal_y + dy, model.wrap_angle(self.psi + self.goal_psi)


def observation_space(params: EnvParams) -> spaces.Box:
    """The observation space; see the env's docstring for the table."""
    e_max = model.MAX_ORIENTATION_ERROR
    d_max = 2.0 * params.arena_radius
    low = np.array([0, -1, -1, -1, -1, -e_max, 0, 0, 0, -e_max], dtype=np.float32)
    high = np.array(
        [d_max, 1, 1, 1, 1, e_max, params.horizon_factor, params.T_con_max, params.arena_radius, e_max],
        dtype=np.float32,
    )
    return spaces.Box(low, high, dtype=np.float32)


def action_space() -> spaces.Box:
    """Normalised (linear, angular) velocity commands."""
    return spaces.Box(-1.0, 1.0, shape=(2,), dtype=np.float32)


def observe(
    state: TaskState,
    coords: ErrorCoordinates,
    params: EnvParams,
    space: spaces.Box,
    pose_noise: FloatArray | None = None,
) -> NDArray[np.float32]:
    """Observation features (N, 10) of ``state``, whose true error coordinates are ``coords``; (10,) for one robot.

    With ``pose_noise`` (N, 3) (or (3,)) of standard-normal samples, the features are those of the
    pose measured with noise of standard deviation ``params.observation_noise``. Values are clipped
    to the space's bounds.
    """
    if pose_noise is not None:
        sigma = params.observation_noise
        coords = error_coordinates(
            state.x + sigma * pose_noise[..., 0], state.y + sigma * pose_noise[..., 1],
            model.wrap_angle(state.psi + sigma * pose_noise[..., 2]), params.k,
        )  # fmt: skip
    dist = coords.distance
    if not isinstance(dist, np.ndarray):  # one robot (as model.namespace decides, without its call)
        # one robot: cos(alpha) and sin(alpha) of eq. (3) as -x/d and -y/d, (1, 0) at the goal
        cos_alpha, sin_alpha = (-coords.x / dist, -coords.y / dist) if dist > 0.0 else (1.0, 0.0)
        features = np.array(
            [dist, cos_alpha, sin_alpha, math.cos(coords.psi), math.sin(coords.psi), coords.orientation_error,
             state.step_count * (params.dt / state.T_con), state.T_con, state.initial_distance,
             state.initial_orientation_error], dtype=np.float32,
        )  # fmt: skip
        return np.minimum(np.maximum(features, space.low, out=features), space.high, out=features)  # 2x np.clip's speed
    features = np.empty((len(OBSERVATION_NAMES), dist.shape[0]), dtype=np.float32)  # filled row by row: contiguous
    features[0] = dist
    # -cos(alpha) and -sin(alpha) of eq. (3) without trigonometry; 0 / 0 at the goal, where they are set to (1, 0)
    at_goal = dist.size and dist.min() == 0.0  # distances are >= 0: a reduction is cheaper than a search
    with np.errstate(divide="ignore", invalid="ignore") if at_goal else contextlib.nullcontext():
        np.divide(coords.x, dist, out=features[1], casting="same_kind")
        np.divide(coords.y, dist, out=features[2], casting="same_kind")
    np.negative(features[1:3], out=features[1:3])  # -(x / d) is (-x) / d exactly, and cheaper in float32
    if at_goal:
        index = np.flatnonzero(dist == 0.0)
        features[1, index], features[2, index] = 1.0, 0.0
    heading = coords.psi.astype(np.float32)  # float32 trigonometry: ~10x faster, and the features are float32
    np.cos(heading, out=features[3])
    np.sin(heading, out=features[4])
    features[5] = coords.orientation_error
    features[6] = state.step_count * (params.dt / state.T_con)
    features[7] = state.T_con
    features[8] = state.initial_distance
    features[9] = state.initial_orientation_error
    np.minimum(np.maximum(features, space.low[:, None], out=features), space.high[:, None], out=features)
    return features.T


def sample_start(rng: np.random.Generator, params: EnvParams) -> tuple[float, float, float]:
    """A random start pose in the goal frame: distance and heading in their ranges, bearing uniform."""
    # Three uniform draws as Generator.uniform(low, high) makes them, low + (high - low) * random(), in one call.
    (d_low, d_high), (h_low, h_high) = params.start_distance, params.start_heading
    u_dist, u_bearing, u_heading = rng.random(3).tolist()
    dist = d_low + (d_high - d_low) * u_dist
    bearing = -math.pi + (math.pi - -math.pi) * u_bearing
    heading = h_low + (h_high - h_low) * u_heading
    return dist * math.cos(bearing), dist * math.sin(bearing), heading


def parse_pose(name: str, value: object) -> tuple[float, float, float]:
    """Validate a pose option (x, y, psi) of reset()."""
    return as_pose(f"options[{name!r}]", value)


def new_state(
    start: tuple[Any, Any, Any], goal: tuple[Any, Any, Any], params: EnvParams, T_con: Any = None
) -> TaskState:
    """Robots at world poses ``start`` heading for world poses ``goal``: (N,) arrays, or floats for one robot.

    ``T_con`` is each episode's prescribed time (a float, or (N,)); None is ``params.T_con``.
    """
    return _new_state(start, goal, params, T_con)[0]


def _new_state(
    start: tuple[Any, Any, Any], goal: tuple[Any, Any, Any], params: EnvParams, T_con: Any
) -> tuple[TaskState, ErrorCoordinates]:
    """:func:`new_state`, and the error coordinates of its poses."""
    xp = model.namespace(*start, *goal)
    x, y, psi = model.to_goal_frame(*start, *goal)
    coords = error_coordinates(x, y, psi, params.k)
    farthest = coords.distance if xp is model.SCALAR_MATH else float(np.max(coords.distance))
    if farthest > params.arena_radius:
        raise ValueError(
            f"start pose is {farthest:.3f} m from the goal, outside the arena: "
            f"expected a distance <= arena_radius={params.arena_radius}"
        )
    zero = 0.0 * coords.distance
    steps = 0 if xp is model.SCALAR_MATH else np.zeros(coords.distance.shape, np.int64)
    state = TaskState(x, y, psi, goal[0] + zero, goal[1] + zero, goal[2] + zero, steps, zero, coords.distance,
                      coords.orientation_error, model.lyapunov(coords.distance, coords.orientation_error),
                      xp.cos(goal[2]) + zero, xp.sin(goal[2]) + zero, *episode_length(T_con, zero, params, xp))  # fmt: skip
    return state, coords


def reset_robots(
    state: TaskState,
    index: NDArray[np.intp] | slice,
    start: tuple[FloatArray, FloatArray, FloatArray],
    goal: tuple[FloatArray, FloatArray, FloatArray],
    params: EnvParams,
    T_con: FloatArray | None = None,
) -> tuple[TaskState, ErrorCoordinates]:
    """Place the robots at ``index`` of a batched state at world poses ``start`` with goals ``goal``
    and prescribed times ``T_con`` (None: ``params.T_con``). Returns a copy of these robots' new state
    (as ``state.subset(index)``) and its error coordinates."""
    fresh, coords = _new_state(start, goal, params, T_con)
    state.assign(index, fresh)
    if fresh.x.dtype != state.x.dtype:  # a float32 state: its robots as it holds them, not as computed in float64
        fresh = state.subset(index)
        coords = fresh.coordinates(params.k)
    return fresh, coords


def episode_length(T_con: Any, zero: Any, params: EnvParams, xp: Any) -> tuple[Any, Any, Any]:
    """(T_con, prescribed steps, steps until truncation) of episodes with prescribed times ``T_con`` (None:
    ``params.T_con``), broadcast like ``zero`` (floats and ints for one robot, else (N,) arrays)."""
    if T_con is None:
        T_con = params.T_con
    if xp is model.SCALAR_MATH:
        T_con = float(T_con)
        return T_con, params.prescribed_steps_of(T_con), params.max_episode_steps_of(T_con)
    T_con = np.asarray(T_con, dtype=np.float64) + np.zeros(np.shape(zero))
    prescribed = np.floor(T_con / params.dt + 1e-9).astype(np.int64)  # as EnvParams.prescribed_steps_of
    steps = np.ceil(params.horizon_factor * T_con / params.dt - 1e-9).astype(np.int64)  # as max_episode_steps_of
    return T_con.astype(np.asarray(zero).dtype), prescribed, steps


def sample_T_con(rng: np.random.Generator, params: EnvParams) -> float:
    """An episode's prescribed time: drawn uniformly from ``T_con_range``, else ``T_con`` (no draw)."""
    return params.T_con if params.T_con_range is None else float(rng.uniform(*params.T_con_range))


def commands_from_action(
    action: NDArray[np.floating], params: EnvParams, dtype: type[np.floating] = np.float64
) -> tuple[Any, Any, Any, Any]:
    """Clip normalised actions to [-1, 1]: (a_u, a_omega, u [m/s], omega [rad/s]); (N, 2) in ``dtype``, or one action (2,)."""
    if action.ndim == 1:
        a_u, a_omega = action.tolist()
        if type(a_u) is not float or type(a_omega) is not float:  # integer or boolean actions
            a_u, a_omega = float(a_u), float(a_omega)
        if not (math.isfinite(a_u) and math.isfinite(a_omega)):
            raise ValueError(f"action={action.tolist()!r} is invalid: expected finite numbers in [-1, 1]")
        # clipped to [-1, 1] with comparisons (no calls: the single env's step is bound by the interpreter)
        a_u = -1.0 if a_u < -1.0 else 1.0 if a_u > 1.0 else a_u
        a_omega = -1.0 if a_omega < -1.0 else 1.0 if a_omega > 1.0 else a_omega
        return a_u, a_omega, a_u * params.u_max, a_omega * params.omega_max
    if not np.isfinite(action).all():
        raise ValueError(f"action={np.asarray(action).tolist()!r} is invalid: expected finite numbers in [-1, 1]")
    clipped = np.empty((2, action.shape[0]), dtype)  # (2, N): each command a contiguous row
    np.copyto(clipped, action.T, casting="unsafe")
    np.minimum(np.maximum(clipped, -1.0, out=clipped), 1.0, out=clipped)  # 2x np.clip's speed
    a_u, a_omega = clipped
    return a_u, a_omega, a_u * params.u_max, a_omega * params.omega_max


class StepResult(NamedTuple):
    """What :func:`transition` returns: arrays (N,) and obs (N, 10) for a batch; floats and obs (10,) for one robot."""

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
    perturbation: Perturbation | None = None,
) -> StepResult:
    """Advance every robot by one control period and compute observation, reward and episode end.

    ``state`` is updated in place; ``action`` is (N, 2) for a batched state and (2,) for a state of
    floats (one robot). ``action_noise`` and ``pose_noise`` are pre-drawn standard-normal samples
    ((N, 2) and (N, 3), or (2,) and (3,)) or None, so that this function stays free of random state.
    A ``perturbation`` (robot wheels, disturbances; None is the nominal robot) acts at the two marked places.
    """
    if action_noise is not None:
        action = np.asarray(action, dtype=np.float64) + params.actuation_noise * action_noise
    a_u, a_omega, u, omega = commands_from_action(
        action, params, np.float64 if type(state.x) is float else state.x.dtype
    )
    if perturbation is not None:  # the command side: the velocities the robot really has
        u, omega = perturbation.command(u, omega, state.step_count)
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
    power = u * u + omega * omega
    state.energy += power * params.dt
    coords = error_coordinates(state.x, state.y, state.psi, params.k)
    scalar = not isinstance(coords.distance, np.ndarray)  # one robot (as model.namespace decides)
    xp = model.SCALAR_MATH if scalar else model.ARRAY_MATH

    is_success = coords.distance <= params.goal_tolerance
    if params.heading_tolerance is not None:
        is_success = is_success & (xp.abs(coords.psi) <= params.heading_tolerance)
    out_of_arena = coords.distance > params.arena_radius
    in_time = state.step_count <= state.prescribed_steps  # integer comparison: exact in any dtype
    lyapunov = model.lyapunov(coords.distance, coords.orientation_error)
    terminated = is_success | out_of_arena
    # Exact shaping in an episodic task gives terminal states the potential 0 (v1); v0 keeps Phi(s') there.
    next_potential = xp.where(terminated, 0.0, lyapunov) if params.zero_terminal_potential else lyapunov

    d, dt = coords.distance, params.dt
    # A term whose weight is 0 is 0: it is not computed (its own zeros instead; np.zeros: zeros_like fills, 3x
    # slower), nor summed. The sum runs in REWARD_TERMS' order.
    progress = params.progress_weight * (state.lyapunov - params.shaping_discount * next_potential)
    reward = progress  # a new array once late is added: the writes below do not touch progress
    if params.time_weight != 0.0:
        time = state.step_count * dt if scalar else (state.step_count * dt).astype(state.x.dtype, copy=False)
        time_term = (
            -params.time_weight * dt * d * model.conventional_scaling(time, state.T_con, max_gain=params.time_gain_cap)
        )
        reward = reward + time_term
    else:
        time_term = 0.0 if scalar else np.zeros(d.shape, d.dtype)
    if params.effort_weight != 0.0:
        effort_term = -params.effort_weight * dt * (a_u * a_u + a_omega * a_omega)
        reward = reward + effort_term
    else:
        effort_term = 0.0 if scalar else np.zeros(d.shape, d.dtype)
    if params.energy_weight != 0.0:
        energy_term = -params.energy_weight * dt * power
        reward = reward + energy_term
    else:
        energy_term = 0.0 if scalar else np.zeros(d.shape, d.dtype)
    late = xp.where(is_success | in_time, 0.0, -params.late_penalty * dt)
    reward = reward + late
    # arrival, heading and arena are 0 but where an episode ends; they are added last, in REWARD_TERMS' order
    # (late, the term between them there, is 0 where arrival and heading are not).
    ended = terminated if scalar else np.flatnonzero(terminated)
    arrival, heading, arena = terminal_terms(is_success, in_time, out_of_arena, ended, coords.psi, params)
    if scalar:
        reward = reward + arrival + heading + arena
    elif ended.size:
        reward[ended] = reward[ended] + arrival[ended] + heading[ended] + arena[ended]
    terms = {"progress": progress, "time": time_term, "effort": effort_term, "energy": energy_term,
             "arrival": arrival, "heading": heading, "late": late, "arena": arena}  # fmt: skip
    state.lyapunov = lyapunov
    truncated = state.step_count >= state.max_steps
    if scalar:
        truncated = truncated and not terminated
    elif truncated.any():  # rare: the & is skipped in most steps
        truncated &= ~terminated

    obs = observe(state, coords, params, space, pose_noise)
    if perturbation is not None:  # the measurement side
        obs = perturbation.measure(obs)
    return StepResult(obs, reward, terminated, truncated, coords, is_success, u, omega, terms)  # type: ignore[arg-type]


def terminal_terms(
    is_success: Any, in_time: Any, out_of_arena: Any, ended: Any, psi: Any, params: EnvParams
) -> tuple[Any, Any, Any]:
    """The reward terms paid when an episode ends: (arrival (in time), heading (weight (cos(psi) - 1) on
    arrival), arena (on leaving it)). Floats for one robot (``ended`` is whether its episode ended); for a
    batch, arrays that are 0 but at the indices ``ended`` of the robots whose episodes ended."""
    if not isinstance(psi, np.ndarray):  # one robot
        return (
            params.arrival_bonus if is_success and in_time else 0.0,
            params.heading_weight * (math.cos(psi) - 1.0) if is_success else 0.0,
            -params.arena_penalty if out_of_arena else 0.0,
        )
    arrival, heading, arena = np.zeros((3, psi.shape[0]), psi.dtype)  # one allocation: 3x faster than three
    if ended.size:
        success = is_success[ended]
        arrival[ended] = np.where(success & in_time[ended], params.arrival_bonus, 0.0)
        heading[ended] = np.where(success, params.heading_weight * (np.cos(psi[ended]) - 1.0), 0.0)
        arena[ended] = np.where(out_of_arena[ended], -params.arena_penalty, 0.0)
    return arrival, heading, arena


def infos(
    state: TaskState, coords: ErrorCoordinates, params: EnvParams, result: StepResult | None = None
) -> dict[str, Any]:
    """Infos after a reset (``result`` None) or a step: arrays (N,) and "pose" (N, 3) for a batch, or
    Python scalars and "pose" (3,) for one robot. "pose" is the world pose."""
    scalar = not isinstance(coords.distance, np.ndarray)  # one robot
    zeros = 0.0 * coords.distance if result is None else None  # the reset's velocities and reward terms
    x, y, psi = state.world_pose(copy=False)  # stacked below: copied there
    is_success = (coords.distance <= params.goal_tolerance) if result is None else result.is_success
    # copies of the state's own arrays, which later steps and resets overwrite (floats need none)
    heading, T_con, energy = (coords.psi, state.T_con, state.energy) if scalar else (
        coords.psi.copy(), state.T_con.copy(), state.energy.copy())  # fmt: skip
    return {
        "distance": coords.distance,
        "orientation_error": coords.orientation_error,
        "heading_error": heading,
        "time": state.step_count * params.dt,
        "T_con": T_con,
        "is_success": bool(is_success) if scalar else is_success,
        "energy": energy,
        "linear_velocity": zeros if result is None else result.linear_velocity,
        "angular_velocity": zeros if result is None else result.angular_velocity,
        "pose": np.array([x, y, psi]) if scalar else np.array([x, y, psi]).T,  # (N, 3): 3x np.stack's speed
        "reward_terms": {name: zeros for name in REWARD_TERMS} if result is None else result.reward_terms,
    }

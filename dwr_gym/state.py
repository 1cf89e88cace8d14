"""The state of N robots: error coordinates, the task's state, and new episodes.

A :class:`TaskState` holds (N,) arrays for the vector env and Python floats for the single env, for which
the same functions run on the ``math`` module (see :func:`dwr_gym.model.namespace`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

from dwr_gym import model
from dwr_gym.model import FloatArray
from dwr_gym.params import EnvParams
from dwr_gym.validation import as_pose


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
    # tuple.__new__ makes the named tuple at twice the speed of ErrorCoordinates(...), whose __new__ is Python code
    return tuple.__new__(ErrorCoordinates, (x, y, psi, dist, alpha, model.orientation_error(alpha, psi, dist, k)))


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
    lyapunov: (
        FloatArray  # the progress term's potential at the current pose (:func:`shaping_potential`), kept for the next
    )
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


def shaping_potential(coords: ErrorCoordinates, params: EnvParams) -> FloatArray:
    """P of the progress term's potential Phi = -P: L of eq. (21), or the distance d (``params.shaping_potential``)."""
    if params.shaping_potential == "distance":
        # a new array: the state keeps the potential, and a partial reset writes into it in place, which would
        # change the distance that the step's infos (final_info of an autoreset) hold if both were one array
        return coords.distance * 1.0
    return model.lyapunov(coords.distance, coords.orientation_error)


def sample_start(rng: np.random.Generator, params: EnvParams) -> tuple[float, float, float]:
    """A random start pose in the goal frame: distance and heading in their ranges, bearing uniform."""
    return start_from_uniforms(*rng.random(3).tolist(), params, model.SCALAR_MATH)  # three draws in one call


def start_from_uniforms(u_dist: Any, u_bearing: Any, u_heading: Any, params: Any, xp: Any) -> tuple[Any, Any, Any]:
    """The start pose (x, y, psi) in the goal frame that :func:`sample_start` makes of three uniform draws in [0, 1)
    (floats, or arrays of the namespace ``xp``), each mapped as Generator.uniform(low, high) maps its draw."""
    dist = uniform_in(params.start_distance, u_dist)
    bearing = uniform_in((-math.pi, math.pi), u_bearing)
    return dist * xp.cos(bearing), dist * xp.sin(bearing), uniform_in(params.start_heading, u_heading)


def uniform_in(interval: tuple[Any, Any], draw: Any) -> Any:
    """low + (high - low) * draw: a draw in [0, 1) mapped to [low, high), as numpy's Generator.uniform maps it."""
    low, high = interval
    return low + (high - low) * draw


def parse_pose(name: str, value: object) -> tuple[float, float, float]:
    """Validate a pose option (x, y, psi) of reset()."""
    return as_pose(f"options[{name!r}]", value)


def new_state(
    start: tuple[Any, Any, Any], goal: tuple[Any, Any, Any], params: EnvParams, T_con: Any = None
) -> TaskState:
    """Robots at world poses ``start`` heading for world poses ``goal``: (N,) arrays, or floats for one robot.

    ``T_con`` is each episode's prescribed time (a float, or (N,)); None is ``params.T_con``.
    """
    return new_state_and_coordinates(start, goal, params, T_con)[0]


def new_state_and_coordinates(
    start: tuple[Any, Any, Any], goal: tuple[Any, Any, Any], params: EnvParams, T_con: Any
) -> tuple[TaskState, ErrorCoordinates]:
    """:func:`new_state`, and the error coordinates of its poses."""
    xp = model.namespace(*start, *goal)
    x, y, psi = model.to_goal_frame(*start, *goal)
    coords = error_coordinates(x, y, psi, params.k)
    traced = model.is_traceable(xp)  # jax's arrays: the caller drew the starts within the arena (nothing can raise)
    farthest = coords.distance if xp is model.SCALAR_MATH else 0.0 if traced else float(np.max(coords.distance))
    if not traced and farthest > params.arena_radius:
        raise ValueError(
            f"start pose is {farthest:.3f} m from the goal, outside the arena: "
            f"expected a distance <= arena_radius={params.arena_radius}"
        )
    zero = 0.0 * coords.distance
    steps = 0 if xp is model.SCALAR_MATH else (xp.zeros if traced else np.zeros)(coords.distance.shape, int)
    state = TaskState(x, y, psi, goal[0] + zero, goal[1] + zero, goal[2] + zero, steps, zero, coords.distance,
                      coords.orientation_error, shaping_potential(coords, params),
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
    fresh, coords = new_state_and_coordinates(start, goal, params, T_con)
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
    # numpy: the counts of the float64 T_con, which a float32 state then holds rounded; jax's arrays: all in their
    # own dtype (float32 unless jax_enable_x64), so a T_con / dt within float32 rounding of an integer may count
    # one step fewer than float64 would
    traced = model.is_traceable(xp)
    work = zero.dtype if traced else np.float64
    T_con = xp.asarray(T_con, dtype=work) + xp.zeros(np.shape(zero), work)
    prescribed = xp.floor(T_con / params.dt + 1e-9).astype(int)  # as EnvParams.prescribed_steps_of
    steps = prescribed if params.hold_to_T_con else (  # as max_episode_steps_of
        xp.ceil(params.horizon_factor * T_con / params.dt - 1e-9).astype(int))  # fmt: skip
    return T_con if traced else T_con.astype(np.asarray(zero).dtype), prescribed, steps


def sample_T_con(rng: np.random.Generator, params: EnvParams) -> float:
    """An episode's prescribed time: drawn uniformly from ``T_con_range``, else ``T_con`` (no draw)."""
    return params.T_con if params.T_con_range is None else float(rng.uniform(*params.T_con_range))

"""The task on a batch of N robots: one control period's transition (reward, episode end) and the infos.

Both :class:`dwr_gym.env.DWRPointStabilizationEnv` and
:class:`dwr_gym.vector_env.DWRPointStabilizationVectorEnv` keep a :class:`~dwr_gym.state.TaskState` and
advance it with :func:`transition`; they differ only in bookkeeping (seeding, autoreset, rendering). The
vector env's state holds (N,) arrays; the single env's holds Python floats, for which the same functions
run on the ``math`` module (see :func:`dwr_gym.model.namespace`). The state and new episodes are in
:mod:`dwr_gym.state`, the observation in :mod:`dwr_gym.observation`; their names are importable from here
too, as they were before the split.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np
from gymnasium import spaces
from numpy.typing import NDArray

from dwr_gym import model
from dwr_gym.model import FloatArray
from dwr_gym.observation import OBSERVATION_NAMES, clip, observation_space, observe
from dwr_gym.params import EnvParams
from dwr_gym.state import (
    ErrorCoordinates,
    TaskState,
    episode_length,
    error_coordinates,
    new_state,
    parse_pose,
    reset_robots,
    sample_start,
    sample_T_con,
    shaping_potential,
)

if TYPE_CHECKING:
    from dwr_gym.disturbances import Perturbation

REWARD_TERMS: tuple[str, ...] = ("progress", "time", "effort", "energy", "arrival", "heading", "late", "arena")
#: Keys of the info dict besides "reward_terms".
INFO_KEYS: tuple[str, ...] = ("distance", "orientation_error", "heading_error", "time", "T_con", "is_success", "energy",
                              "linear_velocity", "angular_velocity", "pose", "cost", "distance_violation",
                              "heading_violation")  # fmt: skip
#: The constraint's keys of the info dict (Safety-Gymnasium's ``cost``, and the smooth violations beside it).
COST_KEYS: tuple[str, ...] = ("cost", "distance_violation", "heading_violation")


def action_space() -> spaces.Box:
    """Normalised (linear, angular) velocity commands."""
    return spaces.Box(-1.0, 1.0, shape=(2,), dtype=np.float32)


def commands_from_action(
    action: NDArray[np.floating], params: EnvParams, dtype: type[np.floating] = np.float64
) -> tuple[Any, Any, Any, Any]:
    """Clip normalised actions to [-1, 1]: (a_u, a_omega, u [m/s], omega [rad/s]); (N, 2) in ``dtype``, or one action (2,).

    Arrays of another library than numpy (jax's, maybe traced: nothing can be raised) are cast to ``dtype`` and
    clipped, with NaN read as 0 (the finite action nearest to none) and infinities clipped like any number.
    """
    if type(action) is not np.ndarray:  # an array of another library (jax's): (..., 2)
        xp = model.namespace(action)
        clipped = xp.clip(xp.nan_to_num(xp.asarray(action, dtype=dtype), nan=0.0), -1.0, 1.0)
        a_u, a_omega = clipped[..., 0], clipped[..., 1]
        return a_u, a_omega, a_u * params.u_max, a_omega * params.omega_max
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
    clip(clipped, -1.0, 1.0, out=clipped)  # the ufunc: 5x maximum then minimum with scalar bounds
    a_u, a_omega = clipped
    return a_u, a_omega, a_u * params.u_max, a_omega * params.omega_max


#: tuple.__new__(NamedTupleClass, values) makes a named tuple at twice the speed of its own Python ``__new__``.
_new_tuple = tuple.__new__


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
        action = (np.asarray(action, dtype=np.float64) if type(action) is np.ndarray else action) + (
            params.actuation_noise * action_noise)  # fmt: skip
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
    # one robot: Python floats, tested first (model.namespace's call costs a single env's step 1 %)
    xp = model.SCALAR_MATH if type(coords.distance) is float else model.namespace(coords.distance)
    scalar = xp is model.SCALAR_MATH
    # jax's (maybe traced) arrays: every term computed (a weight may be traced too), no branch on values
    traced = not scalar and xp is not model.ARRAY_MATH

    is_success = coords.distance <= params.goal_tolerance
    if params.heading_tolerance is not None:
        is_success = is_success & (xp.abs(coords.psi) <= params.heading_tolerance)
    out_of_arena = coords.distance > params.arena_radius
    in_time = state.step_count <= state.prescribed_steps  # integer comparison: exact in any dtype
    lyapunov = shaping_potential(coords, params)  # eq. (21)'s L (v0, v1) or the distance (v2)
    hold = params.hold_to_T_con  # v2: the episode runs to T_con whatever the robot does before
    terminated = ((state.step_count >= state.prescribed_steps) if hold else is_success) | out_of_arena
    # Exact shaping in an episodic task gives terminal states the potential 0 (v1); v0 keeps Phi(s') there.
    next_potential = xp.where(terminated, 0.0, lyapunov) if params.zero_terminal_potential else lyapunov

    d, dt = coords.distance, params.dt
    # A term whose weight is 0 is 0: it is not computed (its own zeros instead; np.zeros: zeros_like fills, 3x
    # slower), nor summed. The sum runs in REWARD_TERMS' order.
    progress = params.progress_weight * (state.lyapunov - params.shaping_discount * next_potential)
    reward = progress  # a new array once late is added: the writes below do not touch progress
    if traced or params.time_weight != 0.0:
        time = state.step_count * dt if scalar else (state.step_count * dt).astype(state.x.dtype, copy=False)
        time_term = (
            -params.time_weight * dt * d * model.conventional_scaling(time, state.T_con, max_gain=params.time_gain_cap)
        )
        reward = reward + time_term
    else:
        time_term = 0.0 if scalar else np.zeros(d.shape, d.dtype)
    if traced or params.effort_weight != 0.0:
        effort_term = -params.effort_weight * dt * (a_u * a_u + a_omega * a_omega)
        reward = reward + effort_term
    else:
        effort_term = 0.0 if scalar else np.zeros(d.shape, d.dtype)
    if traced or params.energy_weight != 0.0:
        energy_term = -params.energy_weight * dt * power
        reward = reward + energy_term
    else:
        energy_term = 0.0 if scalar else np.zeros(d.shape, d.dtype)
    # v2's late term is the miss, paid where its episode ends (it is never late: it ends at T_con)
    late = xp.where(terminated, -params.terminal_distance_weight * d, 0.0) if hold else xp.where(
        is_success | in_time, 0.0, -params.late_penalty * dt)  # fmt: skip
    reward = reward + late
    # arrival, heading and arena are 0 but where an episode ends; they are added last, in REWARD_TERMS' order
    # (late, the term between them there, is 0 where arrival and heading are not).
    ended = terminated if scalar or traced else np.flatnonzero(terminated)
    arrival, heading, arena = terminal_terms(is_success, in_time, out_of_arena, ended, coords.psi, params)
    if hold:  # leaving the arena would save the energy of the episode's rest (noise included): charged at its most
        rest = (state.prescribed_steps - state.step_count) * (dt * params.energy_weight * params.u_max * params.u_max
                                                              + dt * params.energy_weight * params.omega_max * params.omega_max)  # fmt: skip
        arena = arena - xp.where(out_of_arena, rest, 0.0)
    if scalar or traced:
        reward = reward + arrival + heading + arena
    elif ended.size:
        reward[ended] = reward[ended] + arrival[ended] + heading[ended] + arena[ended]
    terms = {"progress": progress, "time": time_term, "effort": effort_term, "energy": energy_term,
             "arrival": arrival, "heading": heading, "late": late, "arena": arena}  # fmt: skip
    state.lyapunov = lyapunov
    truncated = state.step_count >= state.max_steps
    if scalar:
        truncated = truncated and not terminated
    elif traced or truncated.any():  # rare in numpy: the & is skipped in most steps
        truncated = truncated & ~terminated

    obs = observe(state, coords, params, space, pose_noise)
    if perturbation is not None:  # the measurement side
        obs = perturbation.measure(obs)
    return _new_tuple(StepResult, (obs, reward, terminated, truncated, coords, is_success, u, omega, terms))


def terminal_terms(
    is_success: Any, in_time: Any, out_of_arena: Any, ended: Any, psi: Any, params: EnvParams
) -> tuple[Any, Any, Any]:
    """The reward terms paid when an episode ends: (arrival (in time), heading (weight (cos(psi) - 1) on
    arrival), arena (on leaving it)). Floats for one robot (``ended`` is whether its episode ended); for a
    numpy batch, arrays that are 0 but at the indices ``ended`` of the robots whose episodes ended; for
    arrays of another library (jax's), ``ended`` is the boolean mask and the terms are computed everywhere
    (0 where it is False, as arrival and leaving the arena end the episode)."""
    if type(psi) is float:  # one robot
        return _paid_at_the_end(is_success, in_time, out_of_arena, psi, params, model.SCALAR_MATH) if ended else (
            0.0, 0.0, 0.0)  # fmt: skip
    if type(psi) is not np.ndarray:  # jax's arrays
        return _paid_at_the_end(is_success, in_time, out_of_arena, psi, params, model.namespace(psi), ended)
    arrival, heading, arena = np.zeros((3, psi.shape[0]), psi.dtype)  # one allocation: 3x faster than three
    if ended.size:
        arrival[ended], heading[ended], arena[ended] = _paid_at_the_end(
            is_success[ended], in_time[ended], out_of_arena[ended], psi[ended], params, np
        )
    return arrival, heading, arena


def _paid_at_the_end(
    is_success: Any, in_time: Any, out_of_arena: Any, psi: Any, params: EnvParams, xp: Any, ended: Any = True
) -> tuple[Any, Any, Any]:
    """(arrival, heading, arena) of :func:`terminal_terms` where episodes end (``ended``: a mask where the terms are
    computed everywhere). Held to T_con (v2), arriving does not end an episode, so the mask is applied, and the
    heading is paid at every end, at the goal or not."""
    if params.hold_to_T_con:
        return (
            xp.where(ended & is_success & in_time, params.arrival_bonus, 0.0),
            xp.where(ended, params.heading_weight * (xp.cos(psi) - 1.0), 0.0),
            xp.where(out_of_arena, -params.arena_penalty, 0.0),
        )
    return (
        xp.where(is_success & in_time, params.arrival_bonus, 0.0),
        xp.where(is_success, params.heading_weight * (xp.cos(psi) - 1.0), 0.0),
        xp.where(out_of_arena, -params.arena_penalty, 0.0),
    )


def deadline_cost(
    ended: Any,
    is_success: Any,
    step_count: Any,
    prescribed_steps: Any,
    distance: Any,
    heading: Any,
    goal_tolerance: Any,
    heading_tolerance: Any,
    xp: Any = np,
) -> tuple[Any, Any, Any]:
    """The deadline as a constraint (a constrained MDP's cost, Safety-Gymnasium's ``info["cost"]``): (cost, distance
    violation [m], heading violation [rad]) of robots whose episodes ``ended`` at this step, 0 elsewhere.

    ``cost`` is 1 where an episode ends (T_con on v2, arrival or the horizon on v0/v1, leaving the arena) and the
    robot is not in time by the env's own test (``is_success`` at a step within T_con), else 0: an episode's summed
    cost is its deadline violation. The violations are the smooth measures a gradient learner follows: how far
    beyond the goal tolerance the robot ends (max(0, d - goal_tolerance)) and how far beyond the heading tolerance
    (max(0, |psi| - heading_tolerance); ``heading_tolerance`` 0 where the env sets none (v0, v1, v2): |psi|, the final
    heading error itself). Python floats and ``model.SCALAR_MATH`` for one robot, arrays and their namespace else.
    """
    in_time = is_success & (step_count <= prescribed_steps)
    cost = xp.where(ended & xp.logical_not(in_time), 1.0, 0.0)
    distance_violation = xp.where(ended, xp.maximum(distance - goal_tolerance, 0.0), 0.0)
    heading_violation = xp.where(ended, xp.maximum(xp.abs(heading) - heading_tolerance, 0.0), 0.0)
    return cost, distance_violation, heading_violation


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
    if result is None:  # a reset: no episode has ended
        cost = distance_violation = heading_violation = zeros
    elif scalar:
        ended = bool(result.terminated or result.truncated)
        cost, distance_violation, heading_violation = (
            (float(v) for v in deadline_cost(ended, bool(is_success), state.step_count, state.prescribed_steps,
                                             coords.distance, heading, params.goal_tolerance,
                                             params.heading_tolerance or 0.0, model.SCALAR_MATH))
            if ended else (0.0, 0.0, 0.0))  # fmt: skip
    elif not (result.terminated.any() or result.truncated.any()):  # most steps of a batch: no episode ends
        cost, distance_violation, heading_violation = np.zeros((3, coords.distance.shape[0]), coords.distance.dtype)
    else:
        cost, distance_violation, heading_violation = deadline_cost(
            result.terminated | result.truncated,
            is_success,
            state.step_count,
            state.prescribed_steps,
            coords.distance,
            heading,
            params.goal_tolerance,
            params.heading_tolerance or 0.0,
        )
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
        "pose": np.array((x, y, psi)) if scalar else np.array((x, y, psi)).T,  # (N, 3): 3x np.stack's speed
        "cost": cost,
        "distance_violation": distance_violation,
        "heading_violation": heading_violation,
        "reward_terms": {name: zeros for name in REWARD_TERMS} if result is None else result.reward_terms,
    }


__all__ = [
    "COST_KEYS",
    "INFO_KEYS",
    "OBSERVATION_NAMES",
    "REWARD_TERMS",
    "ErrorCoordinates",
    "StepResult",
    "TaskState",
    "action_space",
    "commands_from_action",
    "deadline_cost",
    "episode_length",
    "error_coordinates",
    "infos",
    "new_state",
    "observation_space",
    "observe",
    "parse_pose",
    "reset_robots",
    "sample_T_con",
    "sample_start",
    "terminal_terms",
    "transition",
]

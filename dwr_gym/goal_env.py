"""DWRPointStabilizationGoal-v0: the task as a goal-conditioned env for hindsight experience replay (HER).

The robot advances with the same :func:`dwr_gym.core.transition` as DWRPointStabilization-v0; only the
observation (a Dict of ``observation``, ``achieved_goal``, ``desired_goal``) and the reward differ. The
reward is a function of the achieved and desired goals alone (:func:`goal_reward`), so that HER can
relabel transitions with other goals and :meth:`DWRPointStabilizationGoalEnv.compute_reward` returns
exactly what the env paid, in the spirit of HighwayEnv's parking-v0.
"""

from __future__ import annotations

import math
from typing import Any, SupportsFloat

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from numpy.typing import NDArray

from dwr_gym import core, model, observation, state
from dwr_gym.env import OneRobotRendering, check_render_mode, parse_reset_options
from dwr_gym.params import EnvParams

GOAL_ENV_ID = "DWRPointStabilizationGoal-v0"
REWARD_TYPES = ("dense", "sparse")
#: A goal is a world pose as (x [m], y [m], cos psi, sin psi): continuous in the heading, as HER needs.
GOAL_NAMES: tuple[str, ...] = ("x", "y", "cos_psi", "sin_psi")
#: The goal-free observation: the robot's world pose and the elapsed fraction of the prescribed time.
GOAL_OBSERVATION_NAMES: tuple[str, ...] = (*GOAL_NAMES, "time_fraction")


def pose_to_goal(x: Any, y: Any, psi: Any) -> NDArray[np.float32]:
    """World poses (N,) (or floats) as goal vectors (N, 4) (or (4,)) in float32, the dtype of the spaces."""
    return np.stack([np.asarray(v, dtype=np.float64) for v in (x, y, np.cos(psi), np.sin(psi))], axis=-1).astype(
        np.float32
    )


def goal_errors(achieved: NDArray[np.floating], desired: NDArray[np.floating]) -> tuple[NDArray, NDArray]:
    """Distance d of eq. (2) and cos(psi - psi_d) between batches of goals (..., 4), in float64."""
    shape = np.shape(achieved)[:-1]
    # as (N, 4) batches, so that one goal and a batch take the same (array) code path and agree to the bit
    a = np.asarray(achieved, dtype=np.float64).reshape(-1, 4)
    g = np.asarray(desired, dtype=np.float64).reshape(-1, 4)
    dist = model.distance(a[:, 0] - g[:, 0], a[:, 1] - g[:, 1]).reshape(shape)
    # cos of the heading difference from the (cos, sin) pairs; the norms are 1 up to float32 rounding
    cos_heading = (a[:, 2] * g[:, 2] + a[:, 3] * g[:, 3]).reshape(shape)
    return dist, cos_heading


def goal_success(achieved: NDArray[np.floating], desired: NDArray[np.floating], params: EnvParams) -> NDArray:
    """Arrival: d <= goal_tolerance, and |psi - psi_d| <= heading_tolerance when that is set (as in v0)."""
    dist, cos_heading = goal_errors(achieved, desired)
    success = dist <= params.goal_tolerance
    if params.heading_tolerance is not None:
        success &= cos_heading >= math.cos(params.heading_tolerance)
    return success


def goal_reward(
    achieved: NDArray[np.floating], desired: NDArray[np.floating], params: EnvParams, reward_type: str = "dense"
) -> NDArray[np.float64]:
    """The reward of reaching ``achieved`` when ``desired`` is the goal, for batches (..., 4) of goals.

    dense: -time_weight * dt * d, plus arrival_bonus + heading_weight * (cos(psi - psi_d) - 1) on
    arrival, minus arena_penalty beyond arena_radius: the terms of v0 that depend on the poses alone.
    sparse: -1 for every step without arrival, 0 on arrival (the convention of the Fetch tasks).
    """
    dist, cos_heading = goal_errors(achieved, desired)
    success = goal_success(achieved, desired, params)
    if reward_type == "sparse":
        return np.where(success, 0.0, -1.0)
    return (
        -params.time_weight * params.dt * dist
        + np.where(success, params.arrival_bonus + params.heading_weight * (cos_heading - 1.0), 0.0)
        - np.where(dist > params.arena_radius, params.arena_penalty, 0.0)
    )


class DWRPointStabilizationGoalEnv(OneRobotRendering, gym.Env[dict[str, NDArray[np.float32]], NDArray[np.float32]]):
    r"""Drive a differential wheeled robot to a goal pose given in the observation: the goal-conditioned task.

    ## Description
    The robot and its dynamics are those of DWRPointStabilization-v0 (kinematic model (1), exact
    zero-order-hold integration, the same :class:`dwr_gym.params.EnvParams`); the goal changes every
    episode and is part of the observation, so that one policy reaches any goal and SB3's
    ``HerReplayBuffer`` can relabel goals in hindsight.

    ## Action Space
    ``Box(-1, 1, (2,), float32)``: normalised (u, omega), as in v0.

    ## Observation Space
    ``Dict``: ``observation`` Box(5,) = (x, y, cos psi, sin psi, t / T_con) of the robot in the world;
    ``achieved_goal`` Box(4,) = (x, y, cos psi, sin psi) of the robot; ``desired_goal`` Box(4,) = the
    same of the goal pose. The observation holds nothing relative to the goal, so a relabelled goal
    stays consistent with it.

    ## Rewards
    ``reward_type="dense"`` (default): -time_weight * dt * d each step, plus arrival_bonus +
    heading_weight * (cos(psi - psi_d) - 1) on arrival, minus arena_penalty on leaving the arena.
    ``reward_type="sparse"``: -1 for each step without arrival, 0 on arrival. Either way the reward is
    a function of (achieved_goal, desired_goal) only, and ``compute_reward(achieved, desired, info)``
    returns exactly the rewards the env paid (batched over leading axes). The time-varying terms of
    v0 (mu_1-scaled time cost, late penalty, arrival in time) and the effort term are left out: they
    depend on the time or the action, which HER does not relabel.

    ## Starting State
    The goal's position is uniform in the disc of radius ``start_distance[1]`` around the origin and
    its heading uniform in [-pi, pi); the start is drawn around the goal as in v0. ``reset(options=
    {"start": (x, y, psi), "goal": (x_d, y_d, psi_d)})`` places either or both.

    ## Episode End
    Terminated on arrival (d <= ``goal_tolerance``, and the heading within ``heading_tolerance`` when
    set) or beyond ``arena_radius`` from the goal; truncated at ``horizon_factor * T_con``.

    ## Arguments
    Every field of :class:`dwr_gym.params.EnvParams`, plus ``reward_type`` ("dense" or "sparse") and
    ``render_mode`` (None, "human", "rgb_array").

    >>> import gymnasium as gym
    >>> import dwr_gym
    >>> env = gym.make("DWRPointStabilizationGoal-v0")
    >>> obs, info = env.reset(seed=0)
    >>> sorted(obs), obs["observation"].shape, obs["desired_goal"].shape
    (['achieved_goal', 'desired_goal', 'observation'], (5,), (4,))
    >>> obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
    >>> float(env.unwrapped.compute_reward(obs["achieved_goal"], obs["desired_goal"], info)) == reward
    True

    ## Version History
    * v0: initial version.
    """

    metadata = {"render_modes": ["human", "rgb_array"], "render_fps": 20}

    def __init__(self, render_mode: str | None = None, reward_type: str = "dense", **kwargs: Any) -> None:
        if reward_type not in REWARD_TYPES:
            raise ValueError(f"reward_type={reward_type!r} is invalid: expected 'dense' or 'sparse'")
        self.params = EnvParams.from_kwargs(**kwargs)
        check_render_mode(render_mode)
        self.render_mode = render_mode
        self.reward_type = reward_type
        self._core_space = observation.observation_space(self.params)  # the v0 features core.transition computes
        reach = self.params.start_distance[1] + self.params.arena_radius  # goal disc plus the arena around it
        goal_low = np.array([-reach, -reach, -1, -1], dtype=np.float32)
        goal_high = np.array([reach, reach, 1, 1], dtype=np.float32)
        goal_space = spaces.Box(goal_low, goal_high, dtype=np.float32)
        self._observation_box = spaces.Box(np.append(goal_low, np.float32(0.0)),
                                           np.append(goal_high, np.float32(self.params.horizon_factor)),
                                           dtype=np.float32)  # fmt: skip
        self.observation_space = spaces.Dict({  # type: ignore[assignment]
            "observation": self._observation_box,
            "achieved_goal": goal_space,
            "desired_goal": goal_space,
        })  # fmt: skip
        self.action_space = core.action_space()
        self._state: state.TaskState | None = None
        self._renderer: Any = None
        self._trail: list[tuple[float, float]] = []

    def compute_reward(
        self, achieved_goal: NDArray[np.floating], desired_goal: NDArray[np.floating], info: Any
    ) -> NDArray[np.float64]:
        """The rewards for batches of (achieved, desired) goals; ``info`` is unused (accepted for HER)."""
        return goal_reward(achieved_goal, desired_goal, self.params, self.reward_type)

    def _observe(self) -> dict[str, NDArray[np.float32]]:
        assert self._state is not None
        achieved = pose_to_goal(*self._state.world_pose())
        space = self._observation_box
        time_fraction = self._state.step_count * (self.params.dt / self.params.T_con)
        obs = np.clip(np.append(achieved, np.float32(time_fraction)), space.low, space.high)
        desired = pose_to_goal(self._state.goal_x, self._state.goal_y, self._state.goal_psi)
        return {"observation": obs.astype(np.float32), "achieved_goal": achieved, "desired_goal": desired}

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[dict[str, NDArray[np.float32]], dict[str, Any]]:
        super().reset(seed=seed)
        poses = parse_reset_options(options)
        if "goal" in poses:
            goal = poses["goal"]
        else:
            radius = self.params.start_distance[1] * math.sqrt(self.np_random.uniform())  # uniform in the disc
            bearing = self.np_random.uniform(-math.pi, math.pi)
            goal = (radius * math.cos(bearing), radius * math.sin(bearing), self.np_random.uniform(-math.pi, math.pi))
        start = (
            poses["start"]
            if "start" in poses
            else model.from_goal_frame(*state.sample_start(self.np_random, self.params), *goal)
        )
        self._state = state.new_state(tuple(map(float, start)), tuple(map(float, goal)), self.params)  # type: ignore[arg-type]
        obs = self._observe()
        info = core.infos(self._state, self._state.coordinates(self.params.k), self.params)
        info["is_success"] = bool(goal_success(obs["achieved_goal"], obs["desired_goal"], self.params))
        self._trail = [(float(info["pose"][0]), float(info["pose"][1]))]
        if self.render_mode == "human":
            self.render()
        return obs, info

    def step(
        self, action: NDArray[np.float32]
    ) -> tuple[dict[str, NDArray[np.float32]], SupportsFloat, bool, bool, dict[str, Any]]:
        if self._state is None:
            raise gym.error.ResetNeeded("call reset() before step()")
        action = np.asarray(action)
        if action.shape != (2,):
            raise ValueError(f"action of shape {action.shape} is invalid: expected shape (2,)")
        result = core.transition(self._state, action, self.params, self._core_space)
        obs = self._observe()
        achieved, desired = obs["achieved_goal"], obs["desired_goal"]
        # reward, arrival and leaving the arena from the float32 goals the agent sees, so that
        # compute_reward on them reproduces the reward exactly
        reward = float(goal_reward(achieved, desired, self.params, self.reward_type))
        success = bool(goal_success(achieved, desired, self.params))
        terminated = success or bool(goal_errors(achieved, desired)[0] > self.params.arena_radius)
        truncated = not terminated and self._state.step_count >= self.params.max_episode_steps
        info = core.infos(self._state, result.coords, self.params, result)
        info["is_success"] = success
        del info["reward_terms"]  # v0's terms; this env's reward is goal_reward
        if self.render_mode is not None:
            self._trail.append((float(info["pose"][0]), float(info["pose"][1])))
            if self.render_mode == "human":
                self.render()
        return obs, reward, terminated, bool(truncated), info


__all__ = ["GOAL_ENV_ID", "DWRPointStabilizationGoalEnv", "goal_reward", "goal_success"]

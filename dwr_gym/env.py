"""DWRPointStabilization-v0: a thin gymnasium.Env over :mod:`dwr_gym.core` and :mod:`dwr_gym.model`."""

from __future__ import annotations

import dataclasses
from typing import Any, SupportsFloat

import gymnasium as gym
import numpy as np
from gymnasium.envs.registration import EnvSpec
from numpy.typing import NDArray

from dwr_gym import core, model, observation, state
from dwr_gym.disturbances import make_perturbation, split_env_kwargs
from dwr_gym.params import EnvParams
from dwr_gym.serialization import env_kwargs_from_json

RENDER_MODES = ("human", "rgb_array")
RESET_OPTIONS = ("start", "goal", "T_con")
TRAIL_LIMIT = 4096
"""Most points the render trail keeps; past it every other point is dropped, so memory stays bounded."""


def append_trail(trail: list[tuple[float, float]], point: tuple[float, float]) -> None:
    """Add a point to the render trail, halving its resolution (the start kept) when it reaches TRAIL_LIMIT."""
    trail.append(point)
    if len(trail) > TRAIL_LIMIT:
        trail[1:] = trail[-1:0:-2][::-1]  # every other point, counted back from the newest


def check_render_mode(render_mode: str | None) -> None:
    """Raise a ValueError for a render mode the env does not support."""
    if render_mode is not None and render_mode not in RENDER_MODES:
        raise ValueError(f"render_mode={render_mode!r} is invalid: expected None, 'human' or 'rgb_array'")


def parse_reset_options(options: dict[str, Any] | None) -> dict[str, tuple[float, float, float]]:
    """Validate the pose options {'start': (x, y, psi), 'goal': (x_d, y_d, psi_d)} of reset(); rejects
    unknown names ('T_con' is checked by :func:`parse_T_con_option`)."""
    options = dict(options or {})
    unknown = sorted(set(options) - set(RESET_OPTIONS))
    if unknown:
        raise ValueError(f"unknown reset option(s) {unknown}; allowed: 'start', 'goal', 'T_con'")
    return {name: state.parse_pose(name, value) for name, value in options.items() if name != "T_con"}


def parse_T_con_option(value: Any, params: EnvParams) -> NDArray[np.float64]:
    """The reset option 'T_con' [s] as an array: within [dt, the largest T_con the observation space covers]."""
    array = np.asarray(value, dtype=np.float64) if not isinstance(value, (str, bytes)) else np.array(np.nan)
    high = params.T_con_max
    if array.size == 0 or not np.all(np.isfinite(array)) or np.any(array < params.dt) or np.any(array > high):
        raise ValueError(
            f"options['T_con']={value!r} is invalid: expected prescribed times in [dt={params.dt:g}, {high:g}] s "
            "(the observation space covers T_con up to T_con, or up to T_con_range[1] when that is set)"
        )
    return array


def spec_with_horizon(spec: EnvSpec | None, params: EnvParams) -> EnvSpec | None:
    """``spec`` with ``max_episode_steps`` the number of steps after which an env of ``params`` truncates.

    Registration cannot know it (it depends on the keywords T_con, dt and horizon_factor), so the env
    fills it in when ``gymnasium.make`` sets its spec; wrappers that read the horizon from the spec
    (``TimeAwareObservation``) then see it, and ``gymnasium.make(env.spec)`` adds a ``TimeLimit`` that
    truncates at the very step the env does. A smaller limit set by the user is kept.
    """
    if spec is None:
        return None
    steps = params.max_episode_steps
    return dataclasses.replace(spec, max_episode_steps=min(spec.max_episode_steps or steps, steps))


class HorizonSpec:
    """``spec`` with the horizon in ``max_episode_steps`` (see :func:`spec_with_horizon`); needs ``self.params``."""

    params: EnvParams
    _spec: EnvSpec | None = None

    @property
    def spec(self) -> EnvSpec | None:
        """The registration, with ``max_episode_steps`` the number of steps after which an episode truncates."""
        return self._spec

    @spec.setter
    def spec(self, spec: EnvSpec | None) -> None:
        self._spec = spec_with_horizon(spec, self.params)


class OneRobotRendering:
    """``render()`` and ``close()`` of an env of one robot (``_state``, ``_trail``, ``params``, ``render_mode``)."""

    render_mode: str | None
    metadata: dict[str, Any]
    params: EnvParams
    _state: state.TaskState | None
    _trail: list[tuple[float, float]]
    _renderer: Any = None

    def render(self) -> NDArray[np.uint8] | None:
        if self.render_mode is None:
            gym.logger.warn(
                'render() called without a render_mode; pass render_mode="rgb_array" or "human" to gym.make'
            )
            return None
        if self._state is None:
            raise gym.error.ResetNeeded("call reset() before render()")
        if self._renderer is None:
            from dwr_gym.rendering import Renderer

            self._renderer = Renderer(self.render_mode, self.metadata["render_fps"])
        return self._renderer.draw_robot(self._state, 0, self._trail, self.params)

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None


class DWRPointStabilizationEnv(HorizonSpec, OneRobotRendering, gym.Env[NDArray[np.float32], NDArray[np.float32]]):
    r"""Drive a differential wheeled robot to a goal within a prescribed time T_con.

    ## Description
    The robot follows the kinematic model (1) of Zhang, Chen and Chen (2023):
    x' = u cos(psi), y' = u sin(psi), psi' = omega. Everything is computed in the goal's frame, so any
    goal pose (x_d, y_d, psi_d) is allowed; the paper's case is psi_d = 0. The task is the paper's:
    bring the distance d of eq. (2) below ``goal_tolerance`` before ``T_con`` seconds have passed.
    The commands are held constant over each control period ``dt`` and integrated exactly
    (zero-order hold, ``integrator="exact"``) or by Euler / RK4 sub-steps.

    ## Action Space
    ``Box(-1, 1, (2,), float32)``: action[0] * ``u_max`` is the linear velocity u [m/s], action[1] *
    ``omega_max`` the angular velocity omega [rad/s]. Out-of-range actions are clipped; a non-finite
    action raises ValueError.

    ## Observation Space
    ``Box((10,), float32)``, all relative to the goal, with enough to compute the paper's law (16)-(19):

    | Num | Observation                                          | Min         | Max            |
    |-----|------------------------------------------------------|-------------|----------------|
    | 0   | distance d, eq. (2) [m]                              | 0           | 2 arena_radius |
    | 1   | cos(alpha), alpha the azimuth of eq. (3)             | -1          | 1              |
    | 2   | sin(alpha)                                           | -1          | 1              |
    | 3   | cos(psi - psi_d), the heading relative to the goal's | -1          | 1              |
    | 4   | sin(psi - psi_d)                                     | -1          | 1              |
    | 5   | orientation error e_psi, eq. (6) [rad]               | -7 pi / 6   | 7 pi / 6       |
    | 6   | elapsed fraction of the prescribed time t / T_con    | 0           | horizon_factor |
    | 7   | T_con [s] (constant within an episode)               | 0           | top of range   |
    | 8   | initial distance d_0 [m]                             | 0           | arena_radius   |
    | 9   | initial orientation error e_psi0 [rad]               | -7 pi / 6   | 7 pi / 6       |

    ## Rewards
    With the Lyapunov function L = (d^2 + e_psi^2) / 2 of eq. (21), its potential Phi = -L, the
    conventional scaling mu_1(t) = T_con / (T_con - t) of eq. (12) capped at ``time_gain_cap``, and
    the normalised actions a, the reward of a step from s to s' (time t' after it) is the sum of

    - progress = progress_weight * (gamma Phi(s') - Phi(s)) with gamma = ``shaping_discount``: a
      potential-based term, which leaves the optimal policy unchanged (Ng, Harada, Russell 1999)
      when gamma is the agent's discount;
    - time = -time_weight * dt * mu_1(t') * d(s'): the cost of still being away grows as T_con nears;
    - effort = -effort_weight * dt * (a_u^2 + a_omega^2);
    - energy = -energy_weight * dt * (u^2 + omega^2), the env's ``energy`` in SI units (0 in v0);
    - arrival = +arrival_bonus on arrival at or before T_con (nothing for a late arrival);
    - heading = heading_weight * (cos(psi - psi_d) - 1) on arrival: the paper aims at a final yaw of
      zero too (Theorem 8, Remark 1), though its success criterion is the position alone; set
      ``heading_weight=0`` for a reward on the position only;
    - late = -late_penalty * dt for each step after T_con without arrival;
    - arena = -arena_penalty when the robot leaves the arena.

    Each term is in ``info["reward_terms"]``. In v1 (``time_weight=0``, ``effort_weight=0``,
    ``energy_weight=2``, ``shaping_discount=1``, ``zero_terminal_potential=True``: Phi = 0 at a terminal
    state) the return of an episode that arrives in time is L(s_0) - 2 energy + arrival_bonus + heading
    term, whatever the path: the progress term telescopes, nothing is
    paid for arriving earlier than needed, and of two arrivals in time with the same final pose the
    cheaper earns more. The task's optimum is defined on this undiscounted return; an agent that
    discounts (gamma < 1) values an early bonus more, so train with gamma close to 1 (0.999 or more).

    **Held to T_con (v2,** ``hold_to_T_con=True``, ``shaping_potential="distance"``,
    ``terminal_distance_weight=10``**).** Arriving does not end the episode: the robot acts, and pays
    the energy of every executed command, until T_con, where the task is scored: arrival = +arrival_bonus
    if d(T_con) <= goal_tolerance, heading = heading_weight * (cos(psi(T_con) - psi_d) - 1) at the goal or
    not, late = -terminal_distance_weight * d(T_con) (the miss). The potential is Phi = -d (the distance:
    eq. (21)'s L holds the orientation error, whose azimuth is undefined at the goal and jumps there, where v2
    keeps robots), 0 at the end, so with gamma = 1 the return of every episode that stays in the arena is

        G = d_0 - energy_weight * E(0, T_con) + arrival_bonus [d_T <= tol]
            + heading_weight (cos psi_T - 1) - terminal_distance_weight * d_T.

    d_0 is fixed by the start; no term depends on *when* the robot reached the goal, and action noise
    costs the same energy whether the robot has arrived or not. Why the optimum is the optimum: every
    term but the energy is at its maximum (the bonus, cos = 1, no miss) exactly when the robot ends at the
    goal pose at T_con, so among such policies G is highest for the least energy E*, the optimal-control
    problem's own (minimum energy to the goal pose by T_con); a policy that ends elsewhere gives up the
    bonus or a term of the miss and the heading, which outweighs the energy it can save, up to the goal
    tolerance: a policy may stop anywhere within ``goal_tolerance`` of the goal, and save the energy of at
    most that last centimetre. Leaving the arena ends the episode with its penalty and the most energy the
    rest of the episode could cost (every command at its limit until T_con): an exit never saves energy, noise
    included, where an exploring agent would otherwise leave to stop paying for its noise. With gamma < 1 set ``shaping_discount`` to gamma: the progress still sums to d_0, and
    the terminal terms are discounted by gamma^T, the same for every policy of the episode (T is fixed);
    only the energy is then weighed by when it is spent, which favours spending it late, never rushing.
    Train v2 with gamma = 1 (the shipped hyperparameters do).

    ## Starting State
    Without options the goal is (0, 0, 0) and the start is drawn from ``self.np_random``: distance
    uniform in ``start_distance`` (0.3-3 m in v1, 0.3-1.5 m in v0), bearing uniform in [-pi, pi), heading relative to the goal uniform
    in ``start_heading``. ``reset(options={"start": (x, y, psi), "goal": (x_d, y_d, psi_d)})`` places
    either or both exactly (a random start is then drawn around the given goal). The prescribed time
    is ``T_con``, or with ``T_con_range`` drawn uniformly per episode (after the start);
    ``options={"T_con": 35.0}`` sets it for one episode, within [dt, the observation space's bound].

    ## Episode End
    v2: terminated at T_con (the step floor(T_con / dt); the time is in the observation, so this is the
    task's end, not a time limit) or on leaving the arena; never truncated, and
    ``env.spec.max_episode_steps`` is the steps of the largest T_con (1,200). v0, v1: terminated on arrival (d <= ``goal_tolerance``, and |psi - psi_d| <= ``heading_tolerance`` when
    that is set) or on leaving the arena (d > ``arena_radius``). Truncated at the horizon
    ``horizon_factor * T_con`` (30 s in v0; in v1 1.5 times the episode's T_con), past T_con so that late
    arrivals are observable.
    The env truncates itself, because the horizon depends on the keywords ``T_con``, ``dt`` and
    ``horizon_factor``, and reports the number of steps in ``env.spec.max_episode_steps`` (600 in v0;
    1,800 in v1, the horizon of the largest T_con), where ``TimeLimit``-aware wrappers such as
    ``TimeAwareObservation`` look for it.

    ## Cost
    The deadline as a constraint, by Safety-Gymnasium's convention (a constrained MDP: maximise the return
    subject to the expected summed cost within a budget): ``info["cost"]`` is 1 at the step that ends an
    episode where the robot is not in time by the env's own test (v2: ``is_success`` at T_con; v0, v1:
    arrived by T_con), else 0, so an episode's summed cost is its deadline violation (0 or 1). Beside it,
    the smooth violations a gradient learner follows, nonzero only at that last step:
    ``info["distance_violation"]`` = max(0, d - ``goal_tolerance``) [m] and ``info["heading_violation"]``
    = max(0, |psi - psi_d| - ``heading_tolerance``) [rad] (with no heading tolerance, as in every
    registered id: the final heading error |psi - psi_d| itself). Neither enters the reward.

    ## Arguments
    Every field of :class:`dwr_gym.params.EnvParams` is a keyword (``T_con``, ``dt``, ``u_max``,
    ``omega_max``, ``goal_tolerance``, ``heading_tolerance``, ``horizon_factor``, ``arena_radius``,
    ``start_distance``, ``start_heading``, ``integrator``, ``substeps``, ``k``, the reward weights,
    ``observation_noise``, ``actuation_noise``), plus ``render_mode`` (None, "human", "rgb_array"),
    and, off by default, ``robot`` (a preset of :data:`dwr_gym.robots.ROBOTS` or a
    :class:`dwr_gym.robots.DifferentialDrive`: wheel speed limits, and u_max / omega_max from them),
    ``wheel_saturation`` ('scale' or 'clip') and ``disturbances`` (a list of the objects of
    :mod:`dwr_gym.disturbances`; their effect is in ``info["disturbance"]``, and ``linear_velocity`` /
    ``angular_velocity`` are then the velocities the robot really had). Invalid values and unknown
    keywords raise ValueError.

    >>> import gymnasium as gym
    >>> import dwr_gym
    >>> env = gym.make("DWRPointStabilization-v1")
    >>> obs, info = env.reset(seed=0, options={"start": (0.0, 0.0, 0.0), "goal": (0.8, 0.0, 0.0)})
    >>> round(info["distance"], 3), obs.shape
    (0.8, (10,))
    >>> obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
    >>> sorted(info["reward_terms"])
    ['arena', 'arrival', 'effort', 'energy', 'heading', 'late', 'progress', 'time']

    ## Version History
    * Every id, returns and dynamics unchanged: ``info["cost"]``, ``info["distance_violation"]`` and
      ``info["heading_violation"]`` (see Cost).
    * v2: the defaults of ``dwr_gym.V2_DEFAULTS``: v1's robot, T_con range and starts, held to T_con
      (``hold_to_T_con``: energy paid until T_con, arrival, heading and the miss paid there; the progress
      term's potential the distance), so that its return pays nothing for arriving early (see Rewards). ``info["is_success"]``
      is whether the robot is at the goal now; in time means at the goal at T_con. The keywords
      ``hold_to_T_con``, ``terminal_distance_weight`` and ``shaping_potential`` exist in every id (v0's and
      v1's values keep their behaviour).
    * v1: the defaults of ``dwr_gym.V1_DEFAULTS``: T_con drawn per episode from ``T_con_range`` = (10, 60) s
      (observed, in info["T_con"]), starts 0.3 to 3 m away, and the reward above (energy instead of
      effort and the prescribed-time term, exact shaping with Phi = 0 at terminal states). A new ``energy``
      term (0 in v0) and the ``T_con_range`` keyword and ``options={"T_con": ...}`` of reset() exist in both ids.
    * v0: initial version. Later, with unchanged returns: ``spec.max_episode_steps`` reports the horizon
      the env truncates at; the native vector env takes ``autoreset_mode`` and defaults to NEXT_STEP, as
      Gymnasium's own vector envs (it used SAME_STEP before: pass ``autoreset_mode="same_step"`` for that).
      Later additions, all off by default and leaving v0's dynamics and returns as they were: ``robot``,
      ``wheel_saturation`` and ``disturbances``.
    """

    metadata = {"render_modes": list(RENDER_MODES), "render_fps": 20}

    def __init__(self, render_mode: str | None = None, **kwargs: Any) -> None:
        if "autoreset_mode" in kwargs:  # reaches the single env through gym.make_vec(..., vectorization_mode="sync")
            raise ValueError(
                f"autoreset_mode={kwargs['autoreset_mode']!r} is a keyword of vector envs, not of the single env: "
                "with vectorization_mode 'sync' or 'async' pass vector_kwargs={'autoreset_mode': ...}"
            )
        kwargs, drive, disturbances = split_env_kwargs(env_kwargs_from_json(kwargs))  # dicts: a stored spec's
        self.params = EnvParams.from_kwargs(**kwargs)
        self.perturbation = make_perturbation(drive, disturbances, self.params, 1)
        check_render_mode(render_mode)
        self.render_mode = render_mode
        self.observation_space = observation.observation_space(self.params)
        self.action_space = core.action_space()
        self._state: state.TaskState | None = None  # a state of Python floats: one robot
        self._trail: list[tuple[float, float]] = []
        self._renderer: Any = None
        self._spec: EnvSpec | None = None

    def _noise(self, size: int, sigma: float) -> NDArray[np.float64] | None:
        return self.np_random.standard_normal(size) if sigma > 0 else None

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[NDArray[np.float32], dict[str, Any]]:
        super().reset(seed=seed)
        poses = parse_reset_options(options)
        goal = poses.get("goal", (0.0, 0.0, 0.0))
        start = (
            poses["start"]
            if "start" in poses
            else model.from_goal_frame(*state.sample_start(self.np_random, self.params), *goal)
        )
        if options and "T_con" in options:
            T_con = parse_T_con_option(options["T_con"], self.params)
            if T_con.shape != ():
                raise ValueError(f"options['T_con'] of shape {T_con.shape} is invalid: expected one number")
            T_con = float(T_con)
        else:
            T_con = state.sample_T_con(self.np_random, self.params)
        self._state = state.new_state(tuple(map(float, start)), tuple(map(float, goal)), self.params, T_con)  # type: ignore[arg-type]
        coords = self._state.coordinates(self.params.k)
        obs = observation.observe(
            self._state, coords, self.params, self.observation_space, self._noise(3, self.params.observation_noise)
        )
        info = core.infos(self._state, coords, self.params)
        if self.perturbation is not None:
            if seed is not None:
                self.perturbation.seed([0], [(seed,)])
            self.perturbation.reset(slice(None), obs)
            info["disturbance"] = self.perturbation.info(scalar=True)
        self._trail = [(float(info["pose"][0]), float(info["pose"][1]))]
        if self.render_mode == "human":
            self.render()
        return obs, info

    def step(
        self, action: NDArray[np.float32]
    ) -> tuple[NDArray[np.float32], SupportsFloat, bool, bool, dict[str, Any]]:
        if self._state is None:
            raise gym.error.ResetNeeded("call reset() before step()")
        action = np.asarray(action)
        if action.shape != (2,):
            raise ValueError(f"action of shape {action.shape} is invalid: expected shape (2,)")
        params = self.params
        result = core.transition(  # the noise drawn only if there is any: the step is bound by the interpreter's calls
            self._state, action, params, self.observation_space,
            self._noise(2, params.actuation_noise) if params.actuation_noise > 0 else None,
            self._noise(3, params.observation_noise) if params.observation_noise > 0 else None, self.perturbation,
        )  # fmt: skip
        info = core.infos(self._state, result.coords, params, result)
        if self.perturbation is not None:
            info["disturbance"] = self.perturbation.info(scalar=True)
        if self.render_mode is not None:
            append_trail(self._trail, (float(info["pose"][0]), float(info["pose"][1])))
            if self.render_mode == "human":
                self.render()
        return result.observation, result.reward, bool(result.terminated), bool(result.truncated), info


__all__ = ["DWRPointStabilizationEnv", "spec_with_horizon"]

"""DWRPointStabilizationVectorEnv: N robots stepped as one numpy computation over :mod:`dwr_gym.core`."""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium.envs.registration import EnvSpec
from gymnasium.error import ResetNeeded
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space
from numpy.typing import NDArray

from dwr_gym import core, model, observation, state
from dwr_gym.disturbances import make_perturbation, split_env_kwargs
from dwr_gym.env import HorizonSpec, append_trail, check_render_mode, parse_reset_options, parse_T_con_option
from dwr_gym.params import EnvParams
from dwr_gym.serialization import env_kwargs_from_json
from dwr_gym.validation import POSE_LIMIT, as_choice, as_int

MAX_NUM_ENVS = 1_000_000
"""More robots than this would take gigabytes for the state alone; larger values are refused."""
#: The keys of the masks that Gymnasium's vector infos carry beside each entry.
_INFO_MASKS = tuple(f"_{key}" for key in (*core.INFO_KEYS, "reward_terms"))
_TERM_MASKS = tuple(f"_{name}" for name in core.REWARD_TERMS)

Trail = list[tuple[float, float]]


def parse_autoreset_mode(value: Any) -> AutoresetMode:
    """An ``AutoresetMode`` from itself, its value ("NextStep") or its name in any case ("next_step")."""
    if isinstance(value, AutoresetMode):
        return value
    if isinstance(value, str):
        for mode in AutoresetMode:
            if value in (mode.value, mode.name) or value.upper() == mode.name:
                return mode
    raise ValueError(
        f"autoreset_mode={value!r} is invalid: expected an AutoresetMode or one of 'next_step', 'same_step', 'disabled'"
    )


def _pose_batch(name: str, value: Any, n: int) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """A pose option as three (n,) arrays: one pose (3,) for every env, or one per env (n, 3)."""
    array = np.asarray(value, dtype=np.float64)
    if array.shape == (3,):
        array = np.broadcast_to(array, (n, 3))
    if array.shape != (n, 3) or not np.all(np.abs(array) <= POSE_LIMIT):
        raise ValueError(
            f"options[{name!r}] of shape {array.shape} is invalid: expected (3,) or ({n}, 3) finite numbers "
            f"within [-{POSE_LIMIT:g}, {POSE_LIMIT:g}]"
        )
    return array[:, 0].copy(), array[:, 1].copy(), array[:, 2].copy()


class DWRPointStabilizationVectorEnv(HorizonSpec, VectorEnv):
    """The native vector version of DWRPointStabilization-v0 (same keywords, same math, N robots at once).

    ``gymnasium.make_vec("DWRPointStabilization-v0", num_envs=N)`` returns it. ``autoreset_mode``
    (a keyword of ``make_vec``) has Gymnasium's semantics, exactly as ``SyncVectorEnv`` of single envs:

    - ``AutoresetMode.NEXT_STEP`` (the default, as Gymnasium's own vector envs): the step that ends
      robot i's episode returns its last observation; the next step ignores action i and returns the
      new episode's first observation, reward 0, both flags False and the reset info.
    - ``AutoresetMode.SAME_STEP``: the step that ends the episode already returns the new episode's
      observation and info; the last ones are in ``infos["final_obs"][i]`` and ``infos["final_info"]``
      (masks ``_final_obs``, ``_final_info``). The stable-baselines3 adapter uses this mode.
    - ``AutoresetMode.DISABLED``: no reset; reset finished robots with
      ``reset(options={"reset_mask": mask})`` before the next step, which otherwise raises ResetNeeded.

    ``metadata["autoreset_mode"]`` is the mode in use. Truncation at the horizon is done here, as in
    the single env (``spec.max_episode_steps`` reports it). ``reset(seed=s)`` seeds sub-env i with
    s + i, as ``SyncVectorEnv`` does, so sub-env i draws the same starts as
    ``gym.make(...).reset(seed=s + i)``. Reset options take one pose (3,) or one pose per env (N, 3)
    for "start" and "goal", and an optional boolean "reset_mask" (N,). Observation and actuation
    noise (off by default) are drawn from the vector env's own generator, so noisy rollouts do not
    match single envs draw for draw. ``render()`` returns a tuple of one frame per sub-env in
    "rgb_array" mode (as ``SyncVectorEnv``), and shows sub-env 0 in "human" mode.

    ``dtype="float32"`` computes the whole batch in single precision, faster than float64 (docs/throughput.md
    measures by how much), at a position resolution of about 5e-7 m at 5 m; the default float64 matches the
    single env to 1e-9.
    """

    metadata = {"render_modes": ["human", "rgb_array"], "render_fps": 20, "autoreset_mode": AutoresetMode.NEXT_STEP}

    def __init__(
        self,
        num_envs: int = 1,
        render_mode: str | None = None,
        dtype: str = "float64",
        autoreset_mode: AutoresetMode | str = AutoresetMode.NEXT_STEP,
        **kwargs: Any,
    ) -> None:
        num_envs = as_int("num_envs", num_envs, 1, MAX_NUM_ENVS)
        self.dtype = as_choice("dtype", dtype, ("float64", "float32"))
        self.autoreset_mode = parse_autoreset_mode(autoreset_mode)
        self.metadata = {**type(self).metadata, "autoreset_mode": self.autoreset_mode}
        kwargs, drive, disturbances = split_env_kwargs(env_kwargs_from_json(kwargs))  # dicts: a stored spec's
        self.params = EnvParams.from_kwargs(**kwargs)
        self.perturbation = make_perturbation(drive, disturbances, self.params, int(num_envs))
        check_render_mode(render_mode)
        self.render_mode = render_mode
        self.num_envs = int(num_envs)
        self.single_observation_space = observation.observation_space(self.params)
        self.single_action_space = core.action_space()
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self._state = state.TaskState.zeros(self.num_envs, np.dtype(dtype).type)
        self._started = False  # step() before the first reset() is an error
        self._rngs: list[np.random.Generator] = []
        self._all = np.ones(self.num_envs, dtype=bool)
        self._needs_reset = np.zeros(self.num_envs, dtype=bool)  # episodes that ended in the last step
        self._trails: list[Trail] = [[] for _ in range(self.num_envs)] if render_mode is not None else []
        self._renderer: Any = None
        self._spec: EnvSpec | None = None

    def _seed_sub_envs(self, seed: int | list[int | None] | None) -> None:
        if seed is None:
            if not self._rngs:
                entropy = np.random.SeedSequence().spawn(self.num_envs)
                self._rngs = [np.random.Generator(np.random.PCG64(s)) for s in entropy]
            return
        seeds = [seed + i for i in range(self.num_envs)] if isinstance(seed, (int, np.integer)) else list(seed)
        if len(seeds) != self.num_envs:
            raise ValueError(f"seed list of length {len(seeds)} is invalid: expected {self.num_envs} seeds")
        # Same stream as gymnasium.utils.seeding.np_random(seed) in each single env.
        self._rngs = [np.random.Generator(np.random.PCG64(np.random.SeedSequence(s))) for s in seeds]

    def _reset_envs(
        self,
        index: NDArray[np.intp],
        start: tuple[NDArray[np.float64], ...] | None = None,
        goal: tuple[NDArray[np.float64], ...] | None = None,
        T_con: NDArray[np.float64] | None = None,
    ) -> tuple[state.TaskState, state.ErrorCoordinates]:
        """Reset the sub-envs in ``index``: given poses and T_con, else the default goal, and starts and
        prescribed times drawn per env (in the order a single env draws them). Returns the new state of
        these sub-envs and its error coordinates."""
        n = index.size
        goal = goal if goal is not None else (np.zeros(n), np.zeros(n), np.zeros(n))
        if start is None:
            local = np.array([state.sample_start(self._rngs[i], self.params) for i in index.tolist()]).reshape(n, 3)
            start = model.from_goal_frame(local[:, 0], local[:, 1], local[:, 2], *goal)
        if T_con is None and self.params.T_con_range is not None:  # (else T_con is params.T_con: nothing is drawn)
            T_con = np.array([state.sample_T_con(self._rngs[i], self.params) for i in index.tolist()], dtype=np.float64)
        return state.reset_robots(self._state, index, start, goal, self.params, T_con)  # type: ignore[arg-type]

    def _noise(self, size: int, sigma: float) -> NDArray[np.float64] | None:
        return self.np_random.standard_normal((self.num_envs, size)) if sigma > 0 else None

    def reset(
        self, *, seed: int | list[int | None] | None = None, options: dict[str, Any] | None = None
    ) -> tuple[NDArray[np.float32], dict[str, Any]]:
        super().reset(seed=seed if isinstance(seed, (int, np.integer)) or seed is None else None)
        self._seed_sub_envs(seed)
        options = dict(options or {})
        mask = np.asarray(options.pop("reset_mask", self._all))
        if mask.shape != (self.num_envs,) or not (mask.dtype == np.bool_ or np.isin(mask, (0, 1)).all()):
            raise ValueError(
                f"options['reset_mask'] of shape {mask.shape} is invalid: expected ({self.num_envs},) booleans"
            )
        mask = mask.astype(bool)
        if not self._started and not mask.all():
            raise ResetNeeded("the first reset() must reset every sub-env: drop options['reset_mask']")
        parse_reset_options({k: (0.0, 0.0, 0.0) for k in options})  # rejects unknown option names
        index = np.flatnonzero(mask)
        start = _pose_batch("start", options["start"], self.num_envs) if "start" in options else None
        goal = _pose_batch("goal", options["goal"], self.num_envs) if "goal" in options else None
        T_con = None
        if "T_con" in options:
            T_con = parse_T_con_option(options["T_con"], self.params)
            if T_con.shape not in ((), (self.num_envs,)):
                raise ValueError(
                    f"options['T_con'] of shape {T_con.shape} is invalid: expected one number or ({self.num_envs},)"
                )
            T_con = np.broadcast_to(T_con, (self.num_envs,))[index]
        if index.size:
            self._reset_envs(
                index,
                None if start is None else tuple(a[index] for a in start),
                None if goal is None else tuple(a[index] for a in goal),
                T_con,
            )
        self._started = True
        coords = self._state.coordinates(self.params.k)
        obs = observation.observe(self._state, coords, self.params, self.single_observation_space,
                           self._noise(3, self.params.observation_noise))  # fmt: skip
        infos = self._with_masks(core.infos(self._state, coords, self.params), mask)
        if self.perturbation is not None:
            if seed is not None:  # sub-env i's disturbances draw as a single env's reset with seed s + i
                subs = [seed + i for i in range(self.num_envs)] if isinstance(seed, (int, np.integer)) else seed
                known = [i for i in index if subs[i] is not None]
                self.perturbation.seed(known, [(int(subs[i]),) for i in known])  # type: ignore[arg-type]
            self.perturbation.reset(index, obs[index])
            infos["disturbance"], infos["_disturbance"] = self.perturbation.info(), self._all
        self._needs_reset[index] = False
        self._start_trails(index, infos["pose"])
        if self.render_mode == "human":
            self.render()
        return obs, infos

    def _with_masks(self, infos: dict[str, Any], mask: NDArray[np.bool_] | None = None) -> dict[str, Any]:
        """Add the masks ``_key`` that Gymnasium's vector infos carry: all True, or ``mask`` after a partial reset."""
        mask = self._all if mask is None else mask
        infos["reward_terms"].update(dict.fromkeys(_TERM_MASKS, mask))
        infos.update(dict.fromkeys(_INFO_MASKS, mask))
        return infos

    def _start_trails(self, index: NDArray[np.intp], pose: NDArray[np.floating]) -> None:
        """Begin the drawn trails of the robots at ``index`` at their current positions."""
        if self._trails:
            for i in index:
                self._trails[i] = [(float(pose[i, 0]), float(pose[i, 1]))]

    def _restart(self, index: NDArray[np.intp], obs: NDArray[np.float32], infos: dict[str, Any]) -> None:
        """Autoreset the robots at ``index``: new episodes, whose first observation and info replace the step's."""
        fresh, coords = self._reset_envs(index)
        obs[index] = observation.observe(fresh, coords, self.params, self.single_observation_space)
        if self.perturbation is not None:  # in SAME_STEP mode final_info keeps the step's disturbance info
            self.perturbation.reset(index, obs[index])
            infos["disturbance"] = self.perturbation.info()
        reset_infos = core.infos(fresh, coords, self.params)
        keep = self.autoreset_mode is AutoresetMode.SAME_STEP  # final_info keeps the step's arrays: write on copies
        for key in core.INFO_KEYS:
            if keep:
                infos[key] = infos[key].copy()
            infos[key][index] = reset_infos[key]
        if keep:
            infos["reward_terms"] = {k: v.copy() for k, v in infos["reward_terms"].items()}
        for term in core.REWARD_TERMS:
            infos["reward_terms"][term][index] = 0.0

    def step(
        self, actions: NDArray[np.float32]
    ) -> tuple[NDArray[np.float32], NDArray[np.float64], NDArray[np.bool_], NDArray[np.bool_], dict[str, Any]]:
        if not self._started:
            raise ResetNeeded("call reset() before step()")
        actions = np.asarray(actions)
        if actions.shape != (self.num_envs, 2):
            raise ValueError(f"actions of shape {actions.shape} are invalid: expected ({self.num_envs}, 2)")
        restart = np.flatnonzero(self._needs_reset) if self._needs_reset.any() else None
        if restart is not None and self.autoreset_mode is AutoresetMode.DISABLED:
            raise ResetNeeded(
                f"sub-env(s) {restart.tolist()} ended and autoreset_mode is DISABLED: "
                "reset them with reset(options={'reset_mask': mask}) before the next step"
            )
        result = core.transition(
            self._state, actions, self.params, self.single_observation_space,
            self._noise(2, self.params.actuation_noise), self._noise(3, self.params.observation_noise),
            self.perturbation,
        )  # fmt: skip
        infos = self._with_masks(core.infos(self._state, result.coords, self.params, result))
        if self.perturbation is not None:
            infos["disturbance"], infos["_disturbance"] = self.perturbation.info(), self._all
        obs, rewards, terminated, truncated = result.observation, result.reward, result.terminated, result.truncated
        if self.autoreset_mode is AutoresetMode.SAME_STEP:
            done = terminated | truncated
            if done.any():
                infos["final_obs"], infos["_final_obs"] = obs.copy(), done
                infos["final_info"] = {**infos, **dict.fromkeys(_INFO_MASKS, done)}
                infos["_final_info"] = done
                restart = np.flatnonzero(done)
                self._restart(restart, obs, infos)
        else:
            if restart is not None:  # NEXT_STEP: the robots that ended last step start anew, with nothing earned
                self._restart(restart, obs, infos)
                rewards[restart], terminated[restart], truncated[restart] = 0.0, False, False
            self._needs_reset = terminated | truncated
        if self._trails:
            pose = infos["pose"]
            for i, trail in enumerate(self._trails):
                append_trail(trail, (float(pose[i, 0]), float(pose[i, 1])))
            if restart is not None:
                self._start_trails(restart, pose)
        if self.render_mode == "human":
            self.render()
        return obs, rewards, terminated, truncated, infos

    def render(self) -> tuple[NDArray[np.uint8], ...] | None:
        """One frame per sub-env in "rgb_array" mode; sub-env 0 in a window in "human" mode."""
        if self.render_mode is None:
            return None
        if self._renderer is None:
            from dwr_gym.rendering import Renderer

            self._renderer = Renderer(self.render_mode, self.metadata["render_fps"])
        if self.render_mode == "human":
            self._renderer.draw_robot(self._state, 0, self._trails[0], self.params)
            return None
        return tuple(
            self._renderer.draw_robot(self._state, i, self._trails[i], self.params) for i in range(self.num_envs)
        )

    def close_extras(self, **kwargs: Any) -> None:
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None

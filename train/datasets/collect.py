"""Episodes of any policy, collected from the native vector env in batches and cut per robot.

N robots step as one :class:`~dwr_gym.vector_env.DWRPointStabilizationVectorEnv` in ``SAME_STEP`` autoreset
mode: the step that ends robot i's episode returns its last observation in ``infos["final_obs"]`` and already
the next episode's first one. Robot i's j-th episode is episode ``j * N + i`` of the dataset, kept when that is
below the number asked for, so which episodes are kept does not depend on their lengths (stopping at the first
E episodes to end would favour short ones). The steps are kept in chunks of (steps, N) arrays and cut into
episodes per robot at the chunk's end, so memory grows with the episodes in flight, not with the dataset.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from gymnasium.vector import AutoresetMode
from numpy.typing import NDArray

from dwr_gym.params import EnvParams
from dwr_gym.vector_env import DWRPointStabilizationVectorEnv
from train.evaluation.rollout import Policy

#: Steps kept as one block before they are cut into episodes.
CHUNK_STEPS = 256
#: The keys of each episode's metadata (besides the policy's name and what the optimum adds).
EPISODE_KEYS = ("T_con", "start", "goal", "steps", "return", "energy", "in_time", "arrived", "arrival_time",
                "final_distance", "heading_error", "disturbance")  # fmt: skip


class RandomPolicy:
    """Uniform random actions in [-1, 1]^2 from a seeded generator: the reference of ``ref_min_score``."""

    def __init__(self, seed: int = 0) -> None:
        self.rng = np.random.default_rng(seed)

    def predict(self, observation: Any, state: Any = None, episode_start: Any = None,
                deterministic: bool = True) -> tuple[NDArray[np.float32], Any]:  # fmt: skip
        obs = np.asarray(observation)
        shape = (2,) if obs.ndim == 1 else (obs.shape[0], 2)
        return self.rng.uniform(-1.0, 1.0, size=shape).astype(np.float32), state


@dataclass
class Episodes:
    """Collected episodes: per episode, observations (T + 1, 10), actions (T, 2), rewards, flags and metadata."""

    observations: list[NDArray[np.float32]] = field(default_factory=list)
    actions: list[NDArray[np.float32]] = field(default_factory=list)
    rewards: list[NDArray[np.float64]] = field(default_factory=list)
    terminations: list[NDArray[np.bool_]] = field(default_factory=list)
    truncations: list[NDArray[np.bool_]] = field(default_factory=list)
    metadata: list[dict[str, Any]] = field(default_factory=list)
    seconds: float = 0.0

    @property
    def steps(self) -> int:
        return int(sum(len(r) for r in self.rewards))

    def returns(self) -> NDArray[np.float64]:
        return np.array([float(np.sum(r)) for r in self.rewards])


def collect(
    policy: Policy,
    env_kwargs: dict[str, Any],
    episodes: int,
    *,
    seed: int = 0,
    num_envs: int = 1024,
    progress: bool = False,
    description: str = "episodes",
) -> Episodes:
    """``episodes`` episodes of ``policy`` on the env of ``env_kwargs``, from min(num_envs, episodes) robots at once.

    Robot i is reset with seed ``seed + i`` (as Gymnasium's vector envs do), so a dataset is reproducible from
    its seed. A planning controller (``freeze``) stops planning for robots whose episodes are no longer kept.
    """
    n = min(num_envs, episodes)
    env = DWRPointStabilizationVectorEnv(num_envs=n, autoreset_mode=AutoresetMode.SAME_STEP, **env_kwargs)
    params: EnvParams = env.params
    obs, infos = env.reset(seed=seed)
    rounds = np.zeros(n, dtype=np.int64)  # which of its episodes each robot is in
    kept = np.arange(n) < episodes  # whether the robot's current episode is kept
    begun = [_episode_start(env, infos, i) for i in range(n)]
    pending: list[list[tuple[NDArray[Any], ...]]] = [[] for _ in range(n)]  # pieces of the episodes in flight
    slots: dict[int, int] = {}  # dataset index -> position in the output lists
    out = Episodes()
    freeze = getattr(getattr(policy, "controller", None), "freeze", None)
    bar: Any = None
    if progress:
        from train.progress import Progress

        bar = Progress(total=episodes, desc=description, unit="episode", leave=False)
    began = time.perf_counter()
    episode_start = np.ones(n, dtype=bool)
    while kept.any():
        block_obs = np.empty((CHUNK_STEPS, n, obs.shape[1]), np.float32)
        block_act = np.empty((CHUNK_STEPS, n, 2), np.float32)
        block_rew, block_term, block_trunc = np.empty((CHUNK_STEPS, n)), *np.empty((2, CHUNK_STEPS, n), bool)
        ends: list[tuple[int, int, int, NDArray[np.float32], dict[str, Any], dict[str, Any]]] = []
        steps = 0
        while steps < CHUNK_STEPS and kept.any():
            action, _ = policy.predict(obs, episode_start=episode_start & kept, deterministic=True)
            action = np.clip(np.asarray(action, dtype=np.float32).reshape(n, 2), -1.0, 1.0)
            block_obs[steps], block_act[steps] = obs, action
            obs, reward, terminated, truncated, infos = env.step(action)
            block_rew[steps], block_term[steps], block_trunc[steps] = reward, terminated, truncated
            episode_start = terminated | truncated
            for i in np.flatnonzero(episode_start).tolist():
                if kept[i]:  # (step, robot, dataset index, last observation, last info, how it began)
                    ends.append((steps, i, int(rounds[i] * n + i), infos["final_obs"][i].copy(),
                                 _final(infos["final_info"], i), begun[i]))  # fmt: skip
                rounds[i] += 1
                kept[i] = kept[i] and rounds[i] * n + i < episodes
                if kept[i]:
                    begun[i] = _episode_start(env, infos, i)
            if freeze is not None and episode_start.any():
                freeze(~kept)
            steps += 1
        # cut the block per robot: (N, steps, ...), so that each robot's steps are contiguous
        per_robot = [np.ascontiguousarray(a[:steps].swapaxes(0, 1))
                     for a in (block_obs, block_act, block_rew, block_term, block_trunc)]  # fmt: skip
        cut = np.zeros(n, dtype=np.int64)
        for step, i, index, last_obs, last_info, start in ends:
            pieces = [*pending[i], tuple(a[i, cut[i] : step + 1] for a in per_robot)]
            pending[i], cut[i] = [], step + 1
            slots[index] = len(out.rewards)
            _append(out, pieces, last_obs, {**start, **last_info}, params)
            if bar is not None:
                bar.update()
        for i in np.flatnonzero(kept).tolist():
            pending[i].append(tuple(a[i, cut[i] : steps] for a in per_robot))
    if bar is not None:
        bar.close()
    env.close()
    order = [slots[k] for k in sorted(slots)]
    for name in ("observations", "actions", "rewards", "terminations", "truncations", "metadata"):
        values = getattr(out, name)
        setattr(out, name, [values[k] for k in order])
    out.seconds = time.perf_counter() - began
    return out


def _episode_start(env: DWRPointStabilizationVectorEnv, infos: dict[str, Any], i: int) -> dict[str, Any]:
    """What robot i's new episode begins with: its start (world frame), goal, T_con and drawn disturbance."""
    # the goal is the env's default, the origin: collect passes no goal option
    start: dict[str, Any] = {"T_con": float(infos["T_con"][i]), "start": [float(v) for v in infos["pose"][i]],
                             "goal": [0.0, 0.0, 0.0]}  # fmt: skip
    episode = getattr(env.perturbation, "episode", None)
    start["disturbance"] = None if episode is None else {k: np.asarray(v[i]).tolist() for k, v in episode().items()}
    return start


def _final(final_info: dict[str, Any], i: int) -> dict[str, Any]:
    """Robot i's outcome from the info of the step that ended its episode."""
    return {"energy": float(final_info["energy"][i]), "arrived": bool(final_info["is_success"][i]),
            "final_distance": float(final_info["distance"][i]),
            "heading_error": abs(float(final_info["heading_error"][i])), "time": float(final_info["time"][i])}  # fmt: skip


def _append(out: Episodes, pieces: list[tuple[NDArray[Any], ...]], last_obs: NDArray[np.float32],
            info: dict[str, Any], params: EnvParams) -> None:  # fmt: skip
    """One finished episode from its pieces (observations, actions, rewards, terminations, truncations)."""
    obs, act, rew, term, trunc = (np.concatenate(parts) for parts in zip(*pieces, strict=True))
    out.observations.append(np.concatenate([obs, last_obs[None]]))
    out.actions.append(act)
    out.rewards.append(rew)
    out.terminations.append(term)
    out.truncations.append(trunc)
    steps = len(rew)
    in_time = info["arrived"] and steps <= math.floor(info["T_con"] / params.dt + 1e-9)  # as the env counts it
    out.metadata.append({
        "T_con": info["T_con"], "start": info["start"], "goal": info["goal"], "steps": steps,
        "return": float(np.sum(rew)), "energy": info["energy"], "in_time": bool(in_time), "arrived": info["arrived"],
        "arrival_time": info["time"] if info["arrived"] else None, "final_distance": info["final_distance"],
        "heading_error": info["heading_error"], "disturbance": info["disturbance"],
    })  # fmt: skip

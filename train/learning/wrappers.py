"""Options of ``dwr-gym train`` that change what the agent sees or how often it acts, never the task.

- **Action repeat** (``--action-repeat K``): the agent decides every K control periods and its action is held
  in between, so an episode of up to 1,800 env steps (T_con 60 s, horizon 1.5 T_con, dt 0.05 s) is at most
  ceil(1,800 / K) decisions. The env, its dynamics, its reward and its arrival test at every period are those
  of the env id; the agent's transition is K env steps and its reward their sum (the discount ``gamma`` then
  applies per decision, i.e. gamma^(1/K) per env step). :class:`ActionRepeatVecEnv` does it in training,
  :class:`ActionRepeatPolicy` at evaluation (it acts when the observation's elapsed periods are a multiple of
  K). A robot whose episode ends inside a held action starts its next episode standing still (zero command,
  zero energy) for the rest of that held action: at most K - 1 periods of its new episode, in training only.
- **Observation normalisation** (``--normalize-obs``): stable-baselines3's ``VecNormalize`` running mean and
  variance of the observations. The statistics are saved beside every model file (``model.zip`` ->
  ``model_obs_norm.npz``, ``checkpoints/ppo_N_steps.zip`` -> ``checkpoints/ppo_N_steps_obs_norm.npz``) and
  :func:`train.learning.agents.load_agent` applies them (:class:`NormalizedPolicy`).
- **Reward normalisation** (``--normalize-reward``): ``VecNormalize``'s scaling of the rewards by the running
  deviation of the discounted return, in training only (evaluations report v1's own return).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray
from stable_baselines3.common.vec_env import VecEnvWrapper

#: Indices of the observation features the action repeat reads (dwr_gym.observation.OBSERVATION_NAMES).
TIME_FRACTION, T_CON = 6, 7
NORM_SUFFIX = "_obs_norm.npz"


class ActionRepeatVecEnv(VecEnvWrapper):
    """Each action held for ``repeat`` env steps; the rewards summed; an episode's end ends the held action."""

    def __init__(self, venv: Any, repeat: int) -> None:
        super().__init__(venv)
        if isinstance(repeat, bool) or not isinstance(repeat, int) or repeat < 1:
            raise ValueError(f"action_repeat={repeat!r} is invalid: expected an integer >= 1")
        self.repeat = repeat
        self._actions: NDArray[np.float32] | None = None

    def reset(self) -> NDArray[np.float32]:
        return self.venv.reset()

    def step_async(self, actions: NDArray[np.float32]) -> None:
        self._actions = np.asarray(actions, dtype=np.float32).reshape(self.num_envs, -1)

    def step_wait(self) -> Any:
        assert self._actions is not None, "step_async() must be called before step_wait()"
        total = np.zeros(self.num_envs, dtype=np.float32)
        ended = np.zeros(self.num_envs, dtype=bool)
        infos: list[dict[str, Any]] = [{} for _ in range(self.num_envs)]
        obs: Any = None
        for _ in range(self.repeat):
            actions = np.where(ended[:, None], 0.0, self._actions).astype(np.float32)
            self.venv.step_async(actions)
            obs, rewards, dones, step_infos = self.venv.step_wait()
            live = ~ended
            total += np.where(live, rewards, 0.0).astype(np.float32)
            for i in np.flatnonzero(live):
                infos[i] = step_infos[i]
            ended |= dones
            if ended.all():
                break
        return obs, total, ended.copy(), infos


def decision_mask(observation: NDArray[np.floating], dt: float, repeat: int) -> NDArray[np.bool_]:
    """Which robots decide now: those whose elapsed control periods (time fraction * T_con / dt) are a multiple
    of ``repeat``."""
    obs = np.asarray(observation, dtype=np.float64).reshape(-1, observation.shape[-1])
    steps = np.rint(obs[:, TIME_FRACTION] * obs[:, T_CON] / dt).astype(np.int64)
    return steps % repeat == 0


class ActionRepeatPolicy:
    """A policy that acts every ``repeat`` control periods of each episode and holds its action in between."""

    def __init__(self, policy: Any, dt: float, repeat: int) -> None:
        self.policy, self.dt, self.repeat = policy, float(dt), int(repeat)
        self._last: NDArray[np.float32] | None = None

    def predict(
        self, observation: Any, state: Any = None, episode_start: Any = None, deterministic: bool = True
    ) -> tuple[NDArray[np.float32], Any]:
        obs = np.asarray(observation)
        actions, state = self.policy.predict(obs, state, episode_start, deterministic)
        actions = np.asarray(actions, dtype=np.float32)
        flat = actions.reshape(-1, actions.shape[-1])
        if self._last is not None and self._last.shape == flat.shape and self.repeat > 1:
            hold = ~decision_mask(obs, self.dt, self.repeat)
            flat = np.where(hold[:, None], self._last, flat)
        self._last = flat.copy()
        return flat.reshape(actions.shape), state


class NormalizedPolicy:
    """A model trained on normalised observations, acting on raw ones: (obs - mean) / sqrt(var + eps), clipped."""

    def __init__(self, model: Any, mean: NDArray[np.floating], var: NDArray[np.floating], clip: float, eps: float):
        self.model = model
        self.mean, self.std = np.asarray(mean), np.sqrt(np.asarray(var) + eps)
        self.clip = float(clip)

    def normalize(self, observation: Any) -> NDArray[np.float32]:
        return np.clip((np.asarray(observation) - self.mean) / self.std, -self.clip, self.clip).astype(np.float32)

    def predict(
        self, observation: Any, state: Any = None, episode_start: Any = None, deterministic: bool = True
    ) -> tuple[Any, Any]:
        return self.model.predict(self.normalize(observation), state, episode_start, deterministic)


def norm_path(model_path: str | Path) -> Path:
    """The observation statistics saved beside a model file: ``<stem>_obs_norm.npz``."""
    path = Path(model_path)
    return path.with_name(path.stem + NORM_SUFFIX)


def find_vec_normalize(env: Any) -> Any:
    """The ``VecNormalize`` layer of a VecEnv stack, or None."""
    from stable_baselines3.common.vec_env import VecNormalize

    layer = env
    while layer is not None:
        if isinstance(layer, VecNormalize):
            return layer
        layer = getattr(layer, "venv", None)
    return None


def save_obs_norm(env: Any, model_path: str | Path) -> None:
    """Save the observation statistics of the env's VecNormalize (if it normalises them) beside ``model_path``."""
    layer = find_vec_normalize(env)
    if layer is None or not layer.norm_obs:
        return
    rms = layer.obs_rms
    np.savez(norm_path(model_path), mean=rms.mean, var=rms.var, clip=layer.clip_obs, eps=layer.epsilon)


def load_obs_norm(model: Any, model_path: str | Path) -> NormalizedPolicy:
    """The model acting on raw observations, with the statistics saved beside ``model_path``."""
    path = norm_path(model_path)
    if not path.is_file():
        raise FileNotFoundError(f"{path} is missing: the agent was trained with --normalize-obs")
    with np.load(path) as data:
        return NormalizedPolicy(model, data["mean"], data["var"], float(data["clip"]), float(data["eps"]))


__all__ = ["ActionRepeatPolicy", "ActionRepeatVecEnv", "NormalizedPolicy", "decision_mask", "load_obs_norm",
           "norm_path", "save_obs_norm"]  # fmt: skip


class LiveNormalizedPolicy:
    """A model acting on raw observations through a normaliser with ``normalize_obs`` or ``normalize`` (a
    ``VecNormalize`` during training, a :class:`NormalizedPolicy`'s statistics after)."""

    def __init__(self, model: Any, normalizer: Any) -> None:
        self.model = model
        self.normalize = getattr(normalizer, "normalize_obs", None) or normalizer.normalize

    def predict(
        self, observation: Any, state: Any = None, episode_start: Any = None, deterministic: bool = True
    ) -> tuple[Any, Any]:
        return self.model.predict(self.normalize(np.asarray(observation)), state, episode_start, deterministic)

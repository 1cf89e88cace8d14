"""rl-zoo3 finds dwr-gym's tuned hyperparameters by itself, and trains on the native vector env.

rl-zoo3 reads hyperparameters from its own ``hyperparams/<algo>.yml`` unless ``--conf-file`` is given,
and those files do not know our env ids. ``python -m rl_zoo3.train --env DWRPointStabilization-v0
--gym-packages dwr_gym`` imports dwr_gym after rl-zoo3 is loaded; :func:`use_our_hyperparameters` then
points rl-zoo3's default configuration file at ``train/hyperparams/<algo>.yml`` for our env ids only, so
that command works as it is. An explicit ``--conf-file`` is left alone.

rl-zoo3 builds ``n_envs`` copies of the single env in a ``DummyVecEnv``, stepped one after the other in
Python; for our env ids it gets the ``n_envs`` robots of one native vector env instead (:mod:`dwr_gym.sb3`, which
reports the episode statistics a ``Monitor`` would, but writes no monitor files), unless ``--vec-env subproc``
or an ``env_wrapper`` asks for copies of the single env.
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

HYPERPARAMS_DIR = Path(__file__).resolve().parent.parent / "train" / "hyperparams"


OUR_IDS = ("DWRPointStabilization-v0", "DWRPointStabilization-v1")


def use_our_hyperparameters() -> None:
    """Patch rl-zoo3's ExperimentManager (once, and only if rl-zoo3 is already imported)."""
    module = sys.modules.get("rl_zoo3.exp_manager")
    manager = getattr(module, "ExperimentManager", None)
    if manager is None or getattr(manager, "_dwr_gym_defaults", False):
        return
    original_read, original_create = manager.read_hyperparameters, manager.create_envs

    def read_hyperparameters(self: Any) -> Any:
        ours = HYPERPARAMS_DIR / f"{self.algo}.yml"
        own_default = Path(str(self.config)).parent.name == "hyperparams" and "rl_zoo3" in str(self.config)
        if own_default and str(self.env_name.gym_id) in OUR_IDS and ours.is_file():
            self.config = str(ours)
        return original_read(self)

    def create_envs(self: Any, n_envs: int, eval_env: bool = False, no_log: bool = False) -> Any:
        from stable_baselines3.common.vec_env import DummyVecEnv, VecFrameStack

        gym_id = str(self.env_name.gym_id)
        if gym_id not in OUR_IDS or self.vec_env_class is not DummyVecEnv or self.env_wrapper is not None:
            return original_create(self, n_envs, eval_env, no_log)
        import gymnasium

        from dwr_gym.sb3 import make_sb3_vec_env

        kwargs = {**gymnasium.spec(gym_id).kwargs, **(self.eval_env_kwargs if eval_env else self.env_kwargs)}
        env: Any = make_sb3_vec_env(n_envs, seed=self.seed, **kwargs)
        if self.vec_env_wrapper is not None:
            env = self.vec_env_wrapper(env)
        env = self._maybe_normalize(env, eval_env)
        return VecFrameStack(env, self.frame_stack) if self.frame_stack is not None else env

    manager.read_hyperparameters = read_hyperparameters
    manager.create_envs = create_envs
    manager._dwr_gym_defaults = True

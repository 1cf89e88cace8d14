"""The env a run trains on and the policy its model acts as: the native vector env behind SB3's VecEnv API
(residual, action repeat and normalisation as configured), and the model wrapped the same way at run time.
Shared by both trainers (:mod:`train.learning.training`, :mod:`train.learning.jitted.trainer`) and the agent loader.
"""

from __future__ import annotations

from typing import Any

from train.learning.config import TrainConfig


def make_expert(config: TrainConfig) -> Any:
    """The expert policy under a residual agent, scaled to the env's action limits."""
    from baselines.expert import ExpertPolicy
    from baselines.registry import make_controller

    params = config.env_params()
    kwargs = {}
    if config.expert == "optimal":  # the planner must know the env's grid and limits
        kwargs = {"T_con": params.T_con, "dt": params.dt, "u_max": params.u_max, "omega_max": params.omega_max}
    return ExpertPolicy(make_controller(config.expert, **kwargs), params.u_max, params.omega_max)


def make_training_env(config: TrainConfig) -> Any:
    """The native vector env behind SB3's VecEnv API (residual-wrapped if asked); the adapter reports the
    episode statistics (``ep_rew_mean``, ``ep_len_mean``, ``success_rate``) itself, as a Monitor would."""
    from dwr_gym.sb3 import make_sb3_vec_env
    from train.learning.residual import ResidualVecEnv

    venv: Any = make_sb3_vec_env(config.num_envs, seed=config.seed, **config.env_keywords())
    if config.residual:
        venv = ResidualVecEnv(venv, make_expert(config), config.residual_scale)
    if config.action_time_scale:  # outside the residual: the residual is what is scaled
        from train.learning.time_scale import TimeScaledVecEnv

        venv = TimeScaledVecEnv(venv, config.action_time_scale)
    if config.action_repeat > 1:
        from train.learning.wrappers import ActionRepeatVecEnv

        venv = ActionRepeatVecEnv(venv, config.action_repeat)
    if config.normalize_obs or config.normalize_reward:
        from stable_baselines3.common.vec_env import VecNormalize

        gamma = float(config.algo_kwargs.get("gamma", 0.99))
        venv = VecNormalize(venv, norm_obs=config.normalize_obs, norm_reward=config.normalize_reward, gamma=gamma)
    return venv


def as_policy(model: Any, config: TrainConfig, normalizer: Any = None) -> Any:
    """The policy that acts in the env: the model (on observations normalised by ``normalizer``, a
    :class:`~train.learning.wrappers.NormalizedPolicy` or ``VecNormalize``, when trained so), its action held for
    ``action_repeat`` periods, alone or as the residual on the expert (see :func:`make_training_env`)."""
    from train.learning.deterministic_actor import deterministic_actor

    policy: Any = deterministic_actor(model)  # predict's deterministic actions to the last bit, faster
    if config.normalize_obs:
        from train.learning.wrappers import LiveNormalizedPolicy

        if normalizer is None:
            raise ValueError("an agent trained with normalize_obs needs its observation statistics")
        policy = LiveNormalizedPolicy(policy, normalizer)
    if config.action_repeat > 1:
        from train.learning.wrappers import ActionRepeatPolicy

        policy = ActionRepeatPolicy(policy, config.env_params().dt, config.action_repeat)
    if config.action_time_scale:
        from train.learning.time_scale import TimeScaledPolicy

        policy = TimeScaledPolicy(policy, config.action_time_scale)
    if not config.residual:
        return policy
    from train.learning.residual import ResidualPolicy

    return ResidualPolicy(policy, make_expert(config), config.residual_scale)


def runtime_of(config: TrainConfig) -> list[str]:
    """What acts beside the network at run time (config.yaml's ``runtime``): the expert under a residual."""
    return [f"expert: {config.expert}"] if config.residual else []

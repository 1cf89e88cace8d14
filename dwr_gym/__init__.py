"""dwr-gym: prescribed-time point stabilization of a differential wheeled robot as a Gymnasium benchmark.

Importing this package registers ``DWRPointStabilization-v0``, ``-v1`` and ``-v2``
(idempotently), so both ``gymnasium.make("DWRPointStabilization-v1")`` after ``import dwr_gym`` and
``gymnasium.make("dwr_gym:DWRPointStabilization-v1")`` in a fresh interpreter work. v1 is the same env
with the defaults of :data:`V1_DEFAULTS`: T_con drawn per episode and a reward whose optimum is the task
(arrive by T_con with the least energy); see the env's docstring, "Version History".
"""

from __future__ import annotations

import sys
from importlib.metadata import PackageNotFoundError, version

import gymnasium

from dwr_gym.env import DWRPointStabilizationEnv
from dwr_gym.params import EnvParams

try:
    __version__ = version("dwr-gym")
except PackageNotFoundError:  # running from a source tree that is not installed
    __version__ = "0.0.0+unknown"

ENV_ID = "DWRPointStabilization-v0"
ENV_ID_V1 = "DWRPointStabilization-v1"
ENV_ID_V2 = "DWRPointStabilization-v2"
GOAL_ENV_ID = "DWRPointStabilizationGoal-v0"
#: The same tasks on JAX (dwr_gym.jax_env, the ``jax`` extra; docs/jax.md): jax is imported when one is made.
JAX_ENV_ID = "DWRPointStabilizationJax-v0"
JAX_ENV_ID_V1 = "DWRPointStabilizationJax-v1"
JAX_ENV_ID_V2 = "DWRPointStabilizationJax-v2"
#: The keywords that make v1 of the same env class: any T_con in [10, 60] s, starts 0.3-3 m away, and a
#: reward that pays for arriving by T_con with the heading, charges the energy, and pays nothing for
#: arriving earlier than needed (no prescribed-time term, shaping that telescopes exactly).
V1_DEFAULTS: dict[str, object] = {
    "T_con_range": (10.0, 60.0),
    "start_distance": (0.3, 3.0),
    "time_weight": 0.0,
    "effort_weight": 0.0,
    "energy_weight": 2.0,
    "shaping_discount": 1.0,
    "zero_terminal_potential": True,
}
#: v2, the task held to T_con: v1's robot, starts and T_con range, but the episode runs until T_con whatever the
#: robot does before (terminated there: the time is observed), every executed command is charged until then, and
#: what the task pays for is paid at T_con: the arrival bonus if the robot is at the goal, the heading, and
#: 10 per metre of the miss; the progress shaping's potential is the distance (continuous at the goal, where v2 keeps
#: robots; eq. (21)'s orientation error jumps there). Nothing depends on *when* the robot arrived, so neither exploration noise nor the
#: discount pays for rushing; train it with gamma = 1 (the env's docstring derives why the optimum is the optimum).
V2_DEFAULTS: dict[str, object] = {
    **V1_DEFAULTS,
    "shaping_potential": "distance",
    "hold_to_T_con": True,
    "terminal_distance_weight": 10.0,
}


def register_envs() -> None:
    """Register DWRPointStabilization-v0, -v1 and -v2 (numpy and JAX) with Gymnasium unless they are registered already."""
    for env_id, defaults in ((ENV_ID, {}), (ENV_ID_V1, V1_DEFAULTS), (ENV_ID_V2, V2_DEFAULTS)):
        if env_id not in gymnasium.registry:
            gymnasium.register(
                id=env_id,
                entry_point="dwr_gym.env:DWRPointStabilizationEnv",
                vector_entry_point="dwr_gym.vector_env:DWRPointStabilizationVectorEnv",
                # The env truncates itself at horizon_factor * T_con, which depends on its keywords, and reports
                # that number of steps as env.spec.max_episode_steps (see dwr_gym.env.spec_with_horizon).
                max_episode_steps=None,
                kwargs=dict(defaults),
            )
    for env_id, defaults in ((JAX_ENV_ID, {}), (JAX_ENV_ID_V1, V1_DEFAULTS), (JAX_ENV_ID_V2, V2_DEFAULTS)):
        if env_id not in gymnasium.registry:
            gymnasium.register(
                id=env_id,
                entry_point="dwr_gym.jax_env.wrappers:DWRJaxEnv",
                vector_entry_point="dwr_gym.jax_env.wrappers:DWRJaxVectorEnv",
                max_episode_steps=None,  # the env truncates itself, as the numpy one
                disable_env_checker=True,  # the passive checker reads numpy arrays: check through JaxToNumpy
                kwargs=dict(defaults),
            )
    if GOAL_ENV_ID not in gymnasium.registry:  # the goal-conditioned task for HER (dwr_gym/goal_env.py)
        gymnasium.register(id=GOAL_ENV_ID, entry_point="dwr_gym.goal_env:DWRPointStabilizationGoalEnv")


register_envs()

if "rl_zoo3.exp_manager" in sys.modules:  # imported by `python -m rl_zoo3.train --gym-packages dwr_gym`
    from dwr_gym.zoo import use_our_hyperparameters

    use_our_hyperparameters()

__all__ = [
    "ENV_ID",
    "ENV_ID_V1",
    "ENV_ID_V2",
    "GOAL_ENV_ID",
    "JAX_ENV_ID",
    "JAX_ENV_ID_V1",
    "JAX_ENV_ID_V2",
    "V1_DEFAULTS",
    "V2_DEFAULTS",
    "DWRPointStabilizationEnv",
    "EnvParams",
    "__version__",
    "register_envs",
]

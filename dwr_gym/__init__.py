"""dwr-gym: prescribed-time point stabilization of a differential wheeled robot as a Gymnasium benchmark.

Importing this package registers ``DWRPointStabilization-v0`` (idempotently), so both
``gymnasium.make("DWRPointStabilization-v0")`` after ``import dwr_gym`` and
``gymnasium.make("dwr_gym:DWRPointStabilization-v0")`` in a fresh interpreter work.
"""

from __future__ import annotations

from importlib.metadata import PackageNotFoundError, version

import gymnasium

from dwr_gym.env import DWRPointStabilizationEnv
from dwr_gym.params import EnvParams

try:
    __version__ = version("dwr-gym")
except PackageNotFoundError:  # running from a source tree that is not installed
    __version__ = "0.0.0+unknown"

ENV_ID = "DWRPointStabilization-v0"
GOAL_ENV_ID = "DWRPointStabilizationGoal-v0"


def register_envs() -> None:
    """Register DWRPointStabilization-v0 with Gymnasium unless it is registered already."""
    if ENV_ID not in gymnasium.registry:
        gymnasium.register(
            id=ENV_ID,
            entry_point="dwr_gym.env:DWRPointStabilizationEnv",
            vector_entry_point="dwr_gym.vector_env:DWRPointStabilizationVectorEnv",
            # The env truncates itself at horizon_factor * T_con, which depends on its keywords.
            max_episode_steps=None,
        )
    if GOAL_ENV_ID not in gymnasium.registry:  # the goal-conditioned task for HER (dwr_gym/goal_env.py)
        gymnasium.register(id=GOAL_ENV_ID, entry_point="dwr_gym.goal_env:DWRPointStabilizationGoalEnv")


register_envs()

__all__ = ["ENV_ID", "GOAL_ENV_ID", "DWRPointStabilizationEnv", "EnvParams", "__version__", "register_envs"]

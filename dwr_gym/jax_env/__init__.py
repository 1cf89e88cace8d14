"""The task on JAX: :class:`DWRFuncEnv` (Gymnasium's FuncEnv), :class:`DWRGymnaxEnv` (gymnax's interface),
:class:`OptimisticResetVecEnv` (a batch of it with fewer new episodes per step) and :class:`FunctionalParams`, over
the same functions as the numpy envs (docs/jax.md). Needs the ``jax`` extra."""

from __future__ import annotations

try:
    import flax  # noqa: F401
    import jax  # noqa: F401
except ImportError as error:  # one line, naming the extra
    raise ImportError(
        f'dwr_gym.jax_env needs jax and flax ({error.name} is missing): pip install "dwr-gym[jax]"'
    ) from None

from dwr_gym.jax_env.autoreset import OptimisticResetVecEnv
from dwr_gym.jax_env.func_env import DWRFuncEnv, DWRState
from dwr_gym.jax_env.gymnax import DWRGymnaxEnv, make_gymnax_env
from dwr_gym.jax_env.params import FunctionalParams, functional_params

__all__ = ["DWRFuncEnv", "DWRGymnaxEnv", "DWRState", "FunctionalParams", "OptimisticResetVecEnv", "functional_params",
           "make_gymnax_env"]  # fmt: skip

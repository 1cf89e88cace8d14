"""What every jitted trainer (the PPO of :mod:`train.learning.jitted.trainer`, the ES of
:mod:`train.learning.evolution.trainer`) sets up before it runs: XLA's threads, its compilation cache, the functional
env, what it refuses."""

from __future__ import annotations

import os
import sys
from typing import Any

from train.learning.config import ConfigError, TrainConfig

JAX_EXTRA = 'pip install "dwr-gym[jax]"'


def check_jitted_options(config: TrainConfig) -> None:
    """Raise ConfigError (one line) for what a jitted trainer does not train: the options of the SB3 path's env
    wrappers (train.learning.wrappers), and a residual on an expert that cannot run inside the compiled loop."""
    if config.normalize_obs:
        raise ConfigError(f"--normalize-obs is invalid with --backend {config.backend}: give --hyperparams "
                          "'policy_kwargs=dict(net_arch=[64, 64], normalize_observations=True)' (folded into the "
                          "exported weights)")  # fmt: skip
    for name, inactive in (("normalize_reward", False), ("action_repeat", 1)):
        if getattr(config, name) != inactive:
            flag = "--" + name.replace("_", "-")
            raise ConfigError(f"{flag} is invalid with --backend {config.backend}: it is an option of --backend sb3 "
                              "and sbx only")  # fmt: skip
    if config.residual:
        from train.learning.jitted.residual import check_residual_expert

        check_residual_expert(config)


def configure_threads(threads: int | None) -> None:
    """``--threads 1``: XLA's CPU backend on one thread (no Eigen thread pool), if jax is not yet imported; other
    counts leave XLA its default pool (one thread per core), which XLA offers no flag to size."""
    if threads != 1 or "jax" in sys.modules:
        return
    flags = os.environ.get("XLA_FLAGS", "")
    os.environ["XLA_FLAGS"] = f"{flags} --xla_cpu_multi_thread_eigen=false intra_op_parallelism_threads=1".strip()


def use_compilation_cache() -> None:
    """Keep XLA's compiled programs in ``<dwr-gym cache>/xla`` (``$DWR_GYM_CACHE``, else ~/.cache/dwr-gym), so a
    second run of the same configuration starts in seconds instead of compiling again."""
    import jax

    from train.evaluation.optimum import cache_dir

    if jax.config.jax_compilation_cache_dir is None:
        jax.config.update("jax_compilation_cache_dir", str(cache_dir() / "xla"))


def make_jax_env(config: TrainConfig) -> tuple[Any, Any]:
    """The functional env of ``config.env_id`` and its params, gymnax-style (``dwr_gym.jax_env``); a ConfigError
    naming the extra when jax, flax or optax is missing."""
    try:
        import flax  # noqa: F401
        import jax  # noqa: F401
        import optax  # noqa: F401

        from dwr_gym.jax_env import make_gymnax_env
    except ImportError as error:
        missing = getattr(error, "name", None) or "jax"
        raise ConfigError(f"--backend jax needs jax, flax and optax ({missing} is missing): {JAX_EXTRA}") from None
    try:
        env, env_params = make_gymnax_env(config.env_id, **config.env_keywords())
    except (TypeError, ValueError, NotImplementedError) as error:
        raise ConfigError(f"--backend jax cannot run this env: {error}") from None
    if config.residual:  # the env's action is the residual on the expert (train.learning.jitted.residual)
        from train.learning.jitted.residual import residual_env

        env = residual_env(config, env)
    if config.action_time_scale:  # outside the residual, as train.learning.training_env wraps the VecEnv
        from train.learning.time_scale import TimeScaledGymnaxEnv

        env = TimeScaledGymnaxEnv(env, config.action_time_scale)
    return env, env_params


__all__ = ["JAX_EXTRA", "check_jitted_options", "configure_threads", "make_jax_env", "use_compilation_cache"]

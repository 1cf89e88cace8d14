"""``dwr-gym train --algo es --backend jax``: the evolution strategies of :mod:`train.learning.evolution.strategies`
as a :class:`train.learning.jitted.run.JitTrainer`, in the same run directory, with the same evaluations, checkpoints,
resume and Ctrl-C as the jitted PPO.

The env steps a run counts are every step of every candidate's episodes (an ended episode's held steps are not
counted: they are computed but simulate nothing). A chunk is a whole number of generations; each is one jitted
call, so the run checks its budget, its time limit and Ctrl-C between two generations. The generation's
candidates are split over one XLA CPU device per core (``--threads N``: N devices, default the machine's cores),
which must be asked for before jax is imported: a process that imported jax before keeps the devices it has.
"""

from __future__ import annotations

import os
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

from train.learning.config import ConfigError, TrainConfig
from train.learning.evolution.settings import ESSettings
from train.learning.jitted.policy import sb3_network_kwargs


def force_host_devices(count: int) -> bool:
    """Ask XLA for ``count`` CPU devices (``--xla_force_host_platform_device_count``), so that a generation runs on
    ``count`` cores; possible only before jax is imported (returns whether the flag is set)."""
    flags = os.environ.get("XLA_FLAGS", "")
    if "xla_force_host_platform_device_count" in flags:
        return True
    if "jax" in sys.modules or count <= 1:
        return False
    os.environ["XLA_FLAGS"] = f"{flags} --xla_force_host_platform_device_count={count}".strip()
    return True


def host_devices(threads: int | None) -> int:
    """The CPU devices a generation is split over: ``--threads``, else one per core."""
    return int(threads) if threads is not None else max(1, os.cpu_count() or 1)


def es_policy_kwargs(settings: ESSettings) -> dict[str, Any]:
    """The SB3 PPO ``policy_kwargs`` of the ES's network (the architecture the exporter builds)."""
    return sb3_network_kwargs(settings.net_arch, settings.activation, settings.ortho_init)


class ESTrainer:
    """ES as a :class:`train.learning.jitted.run.JitTrainer`: settings checked, env, strategy and exporter built,
    before any run directory is made."""

    def __init__(self, config: TrainConfig) -> None:
        from train.learning.jitted.setup import configure_threads, make_jax_env, use_compilation_cache

        devices = host_devices(config.threads)
        force_host_devices(devices)
        configure_threads(config.threads)
        self.settings = ESSettings.from_algo_kwargs(config.algo_kwargs)
        initial_actor = None
        if config.init_from is not None:  # the saved actor's architecture, raw observations (init_from's docstring)
            from train.learning.evolution.init_from import adopt, saved_actor

            if config.residual:
                raise ConfigError("--init-from is invalid with --algo es --residual: a residual starts at its expert")
            initial_actor, net_arch, activation = saved_actor(config.init_from)
            self.settings = adopt(self.settings, net_arch, activation)
            config.algo_kwargs["policy_kwargs"] = {**es_policy_kwargs(self.settings), "normalize_observations": False}
        config.num_envs = 1  # (the exporter's native env; the ES's robots are population_size x episodes)
        env, env_params = make_jax_env(config)
        use_compilation_cache()
        from train.learning.evolution.strategies import JaxES
        from train.learning.jitted.export import SB3Exporter
        from train.learning.training_env import make_training_env

        self.es = JaxES(
            self.settings,
            env,
            env_params,
            devices,
            residual=bool(config.residual),
            initial_actor=initial_actor,
            initial_source=str(config.init_from),
        )
        venv = make_training_env(config)
        self.exporter = SB3Exporter(venv, {"policy_kwargs": es_policy_kwargs(self.settings)}, config.seed)
        venv.close()

    def init(self, seed: int) -> Any:
        return self.es.init(seed)

    def advance(self, state: Any, steps: int, target: int, stop: Callable[[], bool]) -> tuple[Any, int]:
        """Generations until ``target`` env steps (or ``stop()``); at least one."""
        import jax

        state = jax.device_put(state, self.es.replicated)  # (a state read from a file is on one device)
        while True:
            state, metrics = self.es.generation(state)
            steps += int(metrics["steps"])
            if steps >= target or stop():
                return state, steps

    def export(self, state: Any, steps: int) -> Any:
        import jax

        params, stats = jax.device_get((self.es.mean_params(state), state.obs_stats))
        scaling = (stats.mean, stats.var) if self.settings.normalize_observations else (None, None)
        return self.exporter.load(params, *scaling, timesteps=steps)

    def steps_to_run(self, config: TrainConfig, done: int) -> int:
        return max(0, int(config.total_timesteps) - done)

    def start_note(self, config: TrainConfig) -> str | None:
        start = ""
        if config.init_from is not None:
            start = f" from {config.init_from} ({list(self.settings.net_arch)}, {self.settings.activation})"
        return (f"ES: {self.settings.strategy}, {self.settings.population_size} candidates x "
                f"{self.settings.episodes} episodes per generation on {self.es.devices} device(s){start}")  # fmt: skip


def train(
    config: TrainConfig,
    command: list[str] | None = None,
    on_evaluation: Callable[[dict[str, Any]], None] | None = None,
) -> Path:
    """Train as configured with ES; returns the run directory (the learner of ``--algo es --backend jax``, called by
    :func:`train.learning.training.train`, whose contract it keeps through
    :func:`train.learning.jitted.run.train_jitted`)."""
    from train.learning.jitted.run import train_jitted
    from train.learning.jitted.setup import check_jitted_options
    from train.threads import torch_threads

    check_jitted_options(config)
    if config.num_envs not in (None, 1):
        raise ConfigError(f"--num-envs {config.num_envs} is invalid with --algo es: its robots are population_size x "
                          "episodes, hyperparameters (--hyperparams population_size=64 episodes=8)")  # fmt: skip
    with torch_threads(config.threads):
        return train_jitted(config, ESTrainer(config), command, on_evaluation)

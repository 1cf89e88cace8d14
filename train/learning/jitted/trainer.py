"""``dwr-gym train --backend jax``: the jitted PPO of :mod:`train.learning.jitted.ppo` on the functional env, in the
run directory of :mod:`train.learning.runs`, the same as the stable-baselines3 path writes.

:class:`PPOTrainer` runs the updates up to the next evaluation or checkpoint in one jitted function and exports the
weights into an SB3 PPO model (:mod:`train.learning.jitted.export`); :func:`train.learning.jitted.run.train_jitted`
evaluates, checkpoints and resumes it as every jitted trainer (a resumed run continues bit for bit: the same
updates, so the same weights, as the uninterrupted run; tests/test_jax_training.py checks it).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from pathlib import Path
from typing import Any

from train.learning.config import TrainConfig
from train.learning.jitted.constraint_log import CONSTRAINT_FILE, ConstraintLog
from train.learning.jitted.setup import check_jitted_options, configure_threads, make_jax_env, use_compilation_cache

#: PPO-Lagrangian's updates per row of the constraint's log (and per jitted call: the log reads the sums of each).
CONSTRAINT_LOG_UPDATES = 10


def check_jax_config(config: TrainConfig) -> None:
    """Raise ConfigError (one line) for what the jitted PPO does not train (:func:`check_jitted_options`)."""
    check_jitted_options(config)


def export_runner(exporter: Any, ppo: Any, runner: Any, timesteps: int) -> Any:
    """The SB3 model holding ``runner``'s policy (with its observation scaling folded in, if it has one)."""
    import jax

    params, stats = jax.device_get((runner.params, runner.obs_stats))
    scaling = (stats.mean, stats.var) if ppo.settings.normalize_observations else (None, None)
    return exporter.load(params, *scaling, timesteps=timesteps)


class PPOTrainer:
    """The jitted PPO as a :class:`train.learning.jitted.run.JitTrainer`: its settings checked and its env and
    exporter built before any run directory is made."""

    def __init__(self, config: TrainConfig) -> None:
        configure_threads(config.threads)
        from train.learning.hyperparams import fill_budget
        from train.learning.jitted.policy import PPOSettings

        fill_budget(config)
        self.settings = PPOSettings.from_algo_kwargs(config.algo_kwargs, int(config.num_envs or 0))
        self.settings = dataclasses.replace(self.settings, critic_warmup=config.critic_warmup)
        self.residual = bool(config.residual)
        self.config = config  # (its run_dir is set when the run starts: the constraint's log goes there)
        self.constraint_log: ConstraintLog | None = None
        env, env_params = make_jax_env(config)
        use_compilation_cache()
        from train.learning.jitted.export import SB3Exporter
        from train.learning.jitted.ppo import JaxPPO
        from train.learning.training_env import make_training_env

        if self.settings.constraint.lagrangian:
            from train.learning.jitted.ppo_lagrangian import JaxPPOLagrangian

            self.ppo: JaxPPO = JaxPPOLagrangian(self.settings, env, env_params)
        else:
            self.ppo = JaxPPO(self.settings, env, env_params)
        venv = make_training_env(config)
        self.exporter = SB3Exporter(venv, config.algo_kwargs, config.seed)
        venv.close()
        self.total_timesteps = float(config.total_timesteps)

    def init(self, seed: int) -> Any:
        runner = self.ppo.init(seed)
        if self.residual:  # the residual starts near zero, as the SB3 path's (zero_init_last_layer)
            from train.learning.jitted.residual import start_near_expert

            runner = start_near_expert(runner)
        return runner

    def advance(self, runner: Any, steps: int, target: int, stop: Callable[[], bool]) -> tuple[Any, int]:
        per_update = self.settings.steps_per_update
        n_updates = max(1, -(-(target - steps) // per_update))
        if not self.settings.constraint.lagrangian:
            runner, _ = self.ppo.run(runner, n_updates, self.total_timesteps)
            return runner, int(runner.updates) * per_update
        from train.learning.jitted.ppo_lagrangian import constraint_rows

        if self.constraint_log is None:
            self.constraint_log = ConstraintLog(Path(str(self.config.run_dir)) / CONSTRAINT_FILE,
                                                self.ppo.env_params.T_con_range, steps, every=1)  # fmt: skip
        while n_updates > 0:  # in chunks of CONSTRAINT_LOG_UPDATES, each a row of the log; Ctrl-C between two
            chunk = min(n_updates, CONSTRAINT_LOG_UPDATES)
            runner, metrics = self.ppo.run(runner, chunk, self.total_timesteps)
            n_updates -= chunk
            self.constraint_log.add(constraint_rows(metrics, runner.multipliers), int(runner.updates) * per_update)
            if stop():
                break
        return runner, int(runner.updates) * per_update

    def export(self, runner: Any, steps: int) -> Any:
        return export_runner(self.exporter, self.ppo, runner, steps)

    def steps_to_run(self, config: TrainConfig, done: int) -> int:
        from train.learning.hyperparams import steps_to_run

        return steps_to_run(config, done)

    def start_note(self, config: TrainConfig) -> str | None:
        from train.learning.hyperparams import rollout_rounding

        note = rollout_rounding(config)
        c = self.settings.constraint
        if c.lagrangian:
            lagrange = (f"PPO-Lagrangian: the deadline a constraint (at most {c.cost_budget:g} of episodes late) and the "
                        f"heading one (a mean of at most {c.heading_budget:g} rad), a cost critic, their multipliers "
                        f"in {c.multiplier_bins} T_con bins from {c.multiplier_init:g}, PID gains "
                        f"{c.pid_kp:g}/{c.pid_ki:g}/{c.pid_kd:g}; per bin in {CONSTRAINT_FILE}")  # fmt: skip
            note = f"{note}\n{lagrange}" if note else lagrange
        return note


def train(
    config: TrainConfig,
    command: list[str] | None = None,
    on_evaluation: Callable[[dict[str, Any]], None] | None = None,
) -> Path:
    """Train as configured with the jitted PPO; returns the run directory (the learner of ``--algo ppo --backend
    jax``, called by :func:`train.learning.training.train`, whose contract it keeps through
    :func:`train.learning.jitted.run.train_jitted`). torch (the evaluations) runs on ``config.threads`` threads
    (default 1), XLA on one thread with ``--threads 1``, else on its default pool."""
    from train.learning.jitted.run import train_jitted
    from train.threads import torch_threads

    with torch_threads(config.threads):
        check_jax_config(config)
        return train_jitted(config, PPOTrainer(config), command, on_evaluation)

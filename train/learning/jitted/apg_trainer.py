"""``dwr-gym train --algo apg --backend jax``: the analytic policy gradients of :mod:`train.learning.jitted.apg` as a
:class:`train.learning.jitted.run.JitTrainer`, in the same run directory, with the same evaluations, checkpoints,
resume and Ctrl-C as the jitted PPO and the ES.

The env steps a run counts are the steps of every episode an update plays (an ended episode's held steps are not
counted). A chunk is a whole number of updates, each one jitted call, so the run checks its budget, its time limit and
Ctrl-C between two updates. ``--residual --expert ptc`` differentiates through the law too (it runs on jax arrays).
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

from train.learning.config import ConfigError, TrainConfig
from train.learning.jitted.apg_settings import APGSettings
from train.learning.jitted.constraint_log import CONSTRAINT_FILE, ConstraintLog


def apg_policy_kwargs(settings: APGSettings) -> dict[str, Any]:
    """The SB3 PPO ``policy_kwargs`` of the APG's network (the architecture the exporter builds)."""
    from train.learning.jitted.policy import sb3_network_kwargs

    return sb3_network_kwargs(settings.net_arch, settings.activation, settings.ortho_init)


class APGTrainer:
    """APG as a :class:`train.learning.jitted.run.JitTrainer`: settings checked, env and exporter built before any
    run directory is made."""

    def __init__(self, config: TrainConfig) -> None:
        from train.learning.hyperparams import fill_budget
        from train.learning.jitted.setup import configure_threads, make_jax_env, use_compilation_cache

        configure_threads(config.threads)
        fill_budget(config)
        self.settings = APGSettings.from_algo_kwargs(config.algo_kwargs)
        self.progress = bool(config.progress)
        self.config = config  # (its run_dir is set when the run starts: the constraint's log goes there)
        self.constraint_log: ConstraintLog | None = None
        config.num_envs = 1  # (the exporter's native env; the APG's robots are its episodes per update)
        env, env_params = make_jax_env(config)
        use_compilation_cache()
        from train.learning.jitted.apg import JaxAPG
        from train.learning.jitted.export import SB3Exporter
        from train.learning.training_env import make_training_env

        self.apg = JaxAPG(self.settings, env, env_params, residual=bool(config.residual),
                          total_timesteps=float(config.total_timesteps))  # fmt: skip
        venv = make_training_env(config)
        self.exporter = SB3Exporter(venv, {"policy_kwargs": apg_policy_kwargs(self.settings)}, config.seed)
        venv.close()

    def init(self, seed: int) -> Any:
        return self.apg.init(seed)

    def advance(self, state: Any, steps: int, target: int, stop: Callable[[], bool]) -> tuple[Any, int]:
        """Updates until ``target`` env steps (or ``stop()``); at least one. With ``keep_best`` the policy is
        validated before the first update and after every ``keep_best``-th (those env steps count). With
        ``teacher_episodes``, a run's first call clones the policy from the open-loop teacher first."""
        every = self.settings.keep_best
        if self.settings.teacher_episodes and int(state.updates) == 0:  # (a resumed run has been taught already)
            from train.learning.jitted.apg_teacher import clone_from_teacher

            state, measures = clone_from_teacher(self.apg, state, progress=self.progress)
            steps += int(measures["steps"])
            print(f"open-loop teacher: {measures['teacher_in_time']:.0%} of its {self.settings.teacher_episodes} "
                  f"sequences in time, mean return {measures['teacher_return']:.2f}; cloned (least squares "
                  f"{measures['clone_loss']:.2g}) in {int(measures['steps']):,} env steps",
                  file=sys.stderr)  # fmt: skip
        while True:
            if every and int(state.updates) % every == 0:
                state, metrics = self.apg.validate(state)
                steps += int(metrics["steps"])
            state, metrics = self.apg.update(state)
            steps += int(metrics["steps"])
            if self.settings.constraint.lagrangian:
                if self.constraint_log is None:
                    self.constraint_log = ConstraintLog(Path(str(self.config.run_dir)) / CONSTRAINT_FILE,
                                                        self.apg.env_params.T_con_range, steps)  # fmt: skip
                self.constraint_log.add(metrics, steps)
            if steps >= target or stop():
                if self.constraint_log is not None:  # (a chunk ends at an evaluation or checkpoint: logged there)
                    self.constraint_log.flush(steps)
                return state, steps

    def export(self, state: Any, steps: int) -> Any:
        import jax

        params, stats = jax.device_get((self.apg.exported_params(state), state.obs_stats))
        scaling = (stats.mean, stats.var) if self.settings.normalize_observations else (None, None)
        return self.exporter.load(params, *scaling, timesteps=steps)

    def steps_to_run(self, config: TrainConfig, done: int) -> int:
        return max(0, int(config.total_timesteps) - done)

    def start_note(self, config: TrainConfig) -> str | None:
        s = self.settings
        rate = (
            f"{s.learning_rate:g} to 0 over {self.apg.decay_updates} updates"
            if s.linear_schedule
            else f"{s.learning_rate:g}"
        )
        policy = f"the weights' moving average (decay {s.weight_average:g} an update)" if s.weight_average else ""
        kept = (
            f"; the best {'of ' + policy if policy else 'policy'} on {s.validation_episodes} validation episodes "
            f"(every {s.keep_best} updates) is the one exported"
            if s.keep_best
            else f"; {policy} is the one exported"
            if policy
            else ""
        )
        taught = (
            f"; the policy first cloned from the best sequences of {s.teacher_episodes} episodes "
            f"({s.teacher_iterations} Adam steps each)"
            if s.teacher_episodes
            else ""
        )
        near, within = "", f"within {s.near_miss_distance:g} m of the goal but not at it"
        if s.near_miss_clip is not None:
            near += f" ({s.near_miss_clip:g} for the episodes that end {within})"
        weighed = ""
        if s.hold_steps and not s.constraint.lagrangian:
            weighed += (f"; the gradient follows the miss over the last {s.hold_steps} steps before T_con too "
                        f"({s.hold_weight:g} per metre"
                        + (f", and the heading's error at {s.hold_heading_weight:g} per radian"
                           if s.hold_heading_weight else "") + ")")  # fmt: skip
        clip = f"{s.state_grad_clip:g}{near}"
        c = s.constraint
        if c.lagrangian:
            window = f"the last {s.hold_steps} steps" if s.hold_steps else "T_con"
            weighed += (f"; the deadline a constraint (at most {c.cost_budget:g} of episodes late) and the heading one "
                        f"(a mean of at most {c.heading_budget:g} rad), their multipliers in {c.multiplier_bins} T_con "
                        f"bins from {c.multiplier_init:g}, PID gains {c.pid_kp:g}/{c.pid_ki:g}/{c.pid_kd:g}, weighing "
                        f"the distance and the heading error over {window}; per bin "
                        f"in {CONSTRAINT_FILE}")  # fmt: skip
        return (f"APG: {s.episodes} episodes per update, Adam {rate}, the state's gradient clipped to {clip} per step "
                f"in each episode{weighed}{kept}{taught}")  # fmt: skip


def train(
    config: TrainConfig,
    command: list[str] | None = None,
    on_evaluation: Callable[[dict[str, Any]], None] | None = None,
) -> Path:
    """Train as configured with APG; returns the run directory (the learner of ``--algo apg --backend jax``, called by
    :func:`train.learning.training.train`, whose contract it keeps through :func:`train.learning.jitted.run.train_jitted`)."""
    from train.learning.jitted.run import train_jitted
    from train.learning.jitted.setup import check_jitted_options
    from train.threads import torch_threads

    check_jitted_options(config)
    if config.num_envs not in (None, 1):
        raise ConfigError(f"--num-envs {config.num_envs} is invalid with --algo apg: its robots are the episodes of an "
                          "update, a hyperparameter (--hyperparams episodes=64)")  # fmt: skip
    with torch_threads(config.threads):
        return train_jitted(config, APGTrainer(config), command, on_evaluation)

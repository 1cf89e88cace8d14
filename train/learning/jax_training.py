"""``dwr-gym train --backend jax``: the jitted PPO of :mod:`train.learning.jax_ppo` on the functional env, in the
run directory of :mod:`train.learning.runs`, the same as the stable-baselines3 path writes.

A jitted function runs the updates up to the next evaluation or checkpoint; between two such chunks Python
exports the weights into an SB3 PPO model (:mod:`train.learning.jax_export`) and evaluates it with the same
rollout, on the same fixed seeded scenario set, as the SB3 path (so their evaluations.csv compare), keeps
best_model.zip, writes checkpoints and run_state.json. The training state (network, optimiser, the envs, the key)
is saved beside each checkpoint with ``flax.serialization``; a resumed run continues from it bit for bit (the
same updates, so the same weights, as the uninterrupted run; tests/test_jax_training.py checks it).
"""

from __future__ import annotations

import dataclasses
import os
import pickle
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from train.learning.config import ConfigError, TrainConfig
from train.learning.runs import (
    EVAL_FILE,
    MODEL_FILE,
    RESUME_FILE,
    prepare_run_dir,
    read_state,
    resume_command,
    save_config,
    truncate_log,
    write_state,
)

JAX_EXTRA = 'pip install "dwr-gym[jax]"'


def check_jax_config(config: TrainConfig) -> None:
    """Raise ConfigError (one line) for what --backend jax does not train."""
    if config.algo != "ppo":
        raise ConfigError(f"--algo {config.algo!r} is invalid with --backend jax: the jitted trainer is PPO only; "
                          "use --algo ppo, or --backend sb3 for the others")  # fmt: skip
    if config.residual:  # the expert must run inside the compiled loop
        from train.learning.jax_residual import check_residual_expert

        check_residual_expert(config)
    # Options of the SB3 path's env wrappers (train.learning.wrappers), where this TrainConfig has them.
    if getattr(config, "normalize_obs", False):
        raise ConfigError("--normalize-obs is invalid with --backend jax: give --hyperparams "
                          "'policy_kwargs=dict(net_arch=[64, 64], normalize_observations=True)' (folded into the "
                          "exported weights)")  # fmt: skip
    for name, inactive in (("normalize_reward", False), ("action_repeat", 1)):
        if getattr(config, name, inactive) != inactive:
            flag = "--" + name.replace("_", "-")
            raise ConfigError(f"{flag} is invalid with --backend jax: it is an option of --backend sb3 only")


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
    if config.residual:  # the env's action is the residual on the expert (train.learning.jax_residual)
        from train.learning.jax_residual import residual_env

        env = residual_env(config, env)
    return env, env_params


def export_runner(exporter: Any, ppo: Any, runner: Any, timesteps: int) -> Any:
    """The SB3 model holding ``runner``'s policy (with its observation scaling folded in, if it has one)."""
    import jax

    params, stats = jax.device_get((runner.params, runner.obs_stats))
    scaling = (stats.mean, stats.var) if ppo.settings.normalize_observations else (None, None)
    return exporter.load(params, *scaling, timesteps=timesteps)


def save_runner(path: Path, runner: Any, timesteps: int) -> None:
    """The whole training state, serialised with flax, written atomically."""
    import flax.serialization

    tmp = path.with_suffix(".tmp")
    with tmp.open("wb") as handle:
        pickle.dump({"timesteps": timesteps, "runner": flax.serialization.to_bytes(runner)}, handle)
    tmp.replace(path)


def load_runner(path: Path, template: Any) -> tuple[Any, int]:
    """The training state saved by :func:`save_runner`, in the structure of ``template`` (a fresh runner)."""
    import flax.serialization

    with path.open("rb") as handle:
        saved = pickle.load(handle)
    return flax.serialization.from_bytes(template, saved["runner"]), int(saved["timesteps"])


class JaxRun:
    """One run of the jitted PPO in its run directory: evaluations, checkpoints, the run state."""

    def __init__(self, config: TrainConfig, run_dir: Path, ppo: Any, exporter: Any, state: dict[str, Any],
                 on_evaluation: Callable[[dict[str, Any]], None] | None) -> None:  # fmt: skip
        from train.evaluation.scenarios import make_scenario

        self.config, self.run_dir, self.ppo, self.exporter = config, run_dir, ppo, exporter
        self.on_evaluation = on_evaluation
        self.params = config.env_params()
        self.scenario = make_scenario("random", n=config.eval_episodes, seed=config.eval_seed,
                                      env_kwargs=config.env_keywords())  # fmt: skip
        from train.learning.runs import saved_best

        self.best = saved_best(state, run_dir / EVAL_FILE)
        self.best_row: dict[str, float] = dict(state.get("best", {}))
        self.start = time.time() - float(state.get("wall_time", 0.0))
        self.last_eval = int(state.get("last_eval", -1))
        self.last_checkpoint = int(state.get("timesteps", 0))
        self.csv_path = run_dir / EVAL_FILE

    def wall_time(self) -> float:
        return round(time.time() - self.start, 2)

    def evaluate(self, runner: Any, steps: int) -> None:
        """Evaluate the exported policy with the SB3 path's rollout; a row of evaluations.csv, best_model.zip."""
        import csv

        from train.evaluation.rollout import rollout
        from train.learning.runs import EVAL_FIELDS, evaluation_cells, task_score
        from train.learning.training_env import as_policy

        if not self.csv_path.exists():
            with self.csv_path.open("w", newline="") as handle:
                csv.writer(handle).writerow(EVAL_FIELDS)
        model = export_runner(self.exporter, self.ppo, runner, steps)
        policy, s = as_policy(model, self.config), self.scenario  # expert + residual for a residual agent
        summary = rollout(policy, self.params, s.starts, s.goals, T_con=s.T_cons, env_kwargs=s.env_kwargs).summary()
        row = {"timesteps": steps, "wall_time": self.wall_time(), **{k: summary[k] for k in EVAL_FIELDS[2:]}}
        with self.csv_path.open("a", newline="") as handle:
            csv.writer(handle).writerow(evaluation_cells(row))
        self.last_eval = steps
        score = task_score(row)  # the SB3 path's rule: in time first, then lower energy, then return
        if score > self.best:
            self.best, self.best_row = score, {k: row[k] for k in ("timesteps", *EVAL_FIELDS[2:])}
            model.save(self.run_dir / "best_model.zip")
        if self.on_evaluation is not None:
            self.on_evaluation(row)

    def checkpoint(self, runner: Any, steps: int, finished: bool = False) -> None:
        """model.zip, a numbered checkpoint and the training state, then run_state.json (last)."""
        model = export_runner(self.exporter, self.ppo, runner, steps)
        (self.run_dir / "checkpoints").mkdir(exist_ok=True)
        model.save(self.run_dir / "checkpoints" / f"{self.config.algo}_{steps}_steps.zip")
        save_runner(self.run_dir / RESUME_FILE, runner, steps)
        model.save(self.run_dir / MODEL_FILE)
        self.last_checkpoint = steps
        write_state(self.run_dir, {"timesteps": steps, "wall_time": self.wall_time(), "best": self.best_row,
                                   "best_score": self.best[2], "last_eval": self.last_eval, "finished": finished,
                                   "backend": "jax"})  # fmt: skip


def train_jax(
    config: TrainConfig,
    command: list[str] | None = None,
    on_evaluation: Callable[[dict[str, Any]], None] | None = None,
) -> Path:
    """Train as configured with the jitted PPO; returns the run directory (see :func:`train.learning.training.train`,
    whose contract this keeps). Ctrl-C saves at the end of the running chunk (at most one evaluation period);
    a second Ctrl-C stops at once and saves the state of the last finished chunk. torch (the evaluations) runs on
    ``config.threads`` threads (default 1), XLA on one thread with ``--threads 1``, else on its default pool."""
    from train.threads import torch_threads

    config.validate()
    with torch_threads(config.threads):
        return _train_jax(config, command, on_evaluation)


def _train_jax(
    config: TrainConfig, command: list[str] | None, on_evaluation: Callable[[dict[str, Any]], None] | None
) -> Path:
    import signal
    import threading

    check_jax_config(config)
    configure_threads(config.threads)
    from train.learning.hyperparams import fill_budget, rollout_rounding, steps_to_run
    from train.learning.jax_policy import PPOSettings

    fill_budget(config)
    settings = PPOSettings.from_algo_kwargs(config.algo_kwargs, int(config.num_envs or 0))
    settings = dataclasses.replace(settings, critic_warmup=config.critic_warmup)
    env, env_params = make_jax_env(config)
    use_compilation_cache()
    from train.learning.jax_export import SB3Exporter
    from train.learning.jax_ppo import JaxPPO
    from train.learning.training_env import make_training_env, runtime_of

    run_dir, lock = prepare_run_dir(config)
    try:
        config.run_dir = str(run_dir)
        note = rollout_rounding(config)
        if note and config.resume is None:
            print(note, file=sys.stderr)
        ppo = JaxPPO(settings, env, env_params)
        venv = make_training_env(config)
        exporter = SB3Exporter(venv, config.algo_kwargs, config.seed)
        venv.close()
        state = read_state(run_dir) if config.resume is not None else {}
        runner = ppo.init(config.seed)
        if config.residual:  # the residual starts near zero, as the SB3 path's (zero_init_last_layer)
            from train.learning.jax_residual import start_near_expert

            runner = start_near_expert(runner)
        steps = 0
        if config.resume is not None:
            runner, steps = load_runner(run_dir / RESUME_FILE, runner)
            truncate_log(run_dir / EVAL_FILE, steps)
        save_config(config, run_dir, {"command": command or sys.argv, "learned_from": "reward",
                                      "runtime": runtime_of(config)})  # fmt: skip
        run = JaxRun(config, run_dir, ppo, exporter, state, on_evaluation)
        bar = None
        if config.progress:
            from train.progress import Progress

            bar = Progress(total=steps_to_run(config, steps), desc="training", unit="step")
        interrupts = [0]

        def on_sigint(signum: int, frame: Any) -> None:
            interrupts[0] += 1
            if interrupts[0] > 1:
                raise KeyboardInterrupt
            print("\ninterrupt: saving at the end of this chunk of updates (Ctrl-C again to stop now, keeping the "
                  "last finished chunk)", file=sys.stderr)  # fmt: skip

        main_thread = threading.current_thread() is threading.main_thread()
        previous = signal.signal(signal.SIGINT, on_sigint) if main_thread else None
        start, done_before = time.time(), steps
        try:
            if run.last_eval < 0:
                run.evaluate(runner, steps)
            time_limit = getattr(config, "time_limit", None)  # --time-limit, where this TrainConfig has it
            while steps < config.total_timesteps and not interrupts[0]:
                if time_limit is not None and run.wall_time() >= time_limit:
                    break
                target = min((steps // config.eval_freq + 1) * config.eval_freq,
                             run.last_checkpoint + config.checkpoint_freq, config.total_timesteps)  # fmt: skip
                n_updates = max(1, -(-(target - steps) // settings.steps_per_update))
                new_runner, _ = ppo.run(runner, n_updates, float(config.total_timesteps))
                runner, steps = new_runner, int(new_runner.updates) * settings.steps_per_update
                if bar is not None:
                    bar.update(n_updates * settings.steps_per_update)
                if steps // config.eval_freq > max(run.last_eval, 0) // config.eval_freq:
                    run.evaluate(runner, steps)
                if steps - run.last_checkpoint >= config.checkpoint_freq:
                    run.checkpoint(runner, steps)
            if interrupts[0]:
                raise KeyboardInterrupt
            if run.last_eval != steps:  # a run ending between two evaluations is evaluated at its last step
                run.evaluate(runner, steps)
        except KeyboardInterrupt:
            if bar is not None:
                bar.close()
            if steps > run.last_checkpoint or not (run_dir / MODEL_FILE).exists():
                run.checkpoint(runner, steps)
            print(f"interrupted at {steps} steps: saved {run_dir / MODEL_FILE}\n"
                  f"resume with: {resume_command(run_dir)}", file=sys.stderr)  # fmt: skip
            raise
        finally:
            if main_thread:
                signal.signal(signal.SIGINT, previous)
        if bar is not None:
            bar.close()
        run.checkpoint(runner, steps, finished=True)
    finally:
        lock.release()
    elapsed, done = time.time() - start, steps - done_before
    print(f"trained {steps} steps ({done} in {elapsed:.0f} s, {done / max(elapsed, 1e-9):.0f} steps/s, "
          f"compilation included); saved {run_dir / MODEL_FILE}")  # fmt: skip
    return run_dir

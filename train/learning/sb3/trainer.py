"""The learners of stable-baselines3's API (``--backend sb3``, and sbx-rl's ``--backend sbx``, the same path with
sbx's classes: :mod:`train.learning.sb3.sbx_backend`) on the native vector env, plain or residual on an expert.

:func:`train` runs one configuration in its run directory (:mod:`train.learning.runs`): periodic
evaluation on a fixed seeded scenario set, checkpoints that resume bit for bit, and Ctrl-C handling.
"""

from __future__ import annotations

import csv
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from train.learning.config import ConfigError, TrainConfig
from train.learning.hyperparams import (
    algorithm_class,
    build_algo_kwargs,
    fill_budget,
    rollout_rounding,
    steps_to_run,
)
from train.learning.runs import (
    EVAL_FIELDS,
    EVAL_FILE,
    MODEL_FILE,
    RESUME_FILE,
    evaluation_cells,
    learned_from,
    prepare_run_dir,
    read_state,
    resume_command,
    save_config,
    saved_best,
    task_score,
    truncate_log,
    write_state,
)
from train.learning.sb3 import finetune
from train.learning.training_env import as_policy, make_training_env, runtime_of

OPTIMAL_EXPERT_NOTE = (
    "note: --expert optimal solves a minimum-energy plan with CasADi for each robot (about 0.1 s of CPU per plan, "
    "docs/controllers.md) at every episode's start, and again every second of simulated time once the residual moves "
    "it off its plan: about {solves:g} plans per step of the {n} robots, seconds per step where --expert ptc takes "
    "milliseconds; try --num-envs 4 --total-timesteps 2000 first"
)
"""What ``train`` says at once when the residual's expert is ``optimal`` (``n``, ``solves``: robots, plans per step)."""


class InterruptRequestedError(Exception):
    """Raised by the run callback at a rollout boundary after Ctrl-C, once everything is saved."""


def make_run_callback(
    config: TrainConfig,
    run_dir: Path,
    env: Any,
    state: dict[str, Any],
    on_evaluation: Callable[[dict[str, Any]], None] | None = None,
) -> Any:
    """Evaluation on a fixed seeded scenario set (TensorBoard, evaluations.csv, best_model.zip) and checkpoints;
    each evaluation's row also goes to ``on_evaluation`` (how ``dwr-gym sweep`` reports to Ray Tune).

    Checkpoints are taken at rollout boundaries, with the env and the random generators, so that a run
    resumed from one continues exactly as the uninterrupted run would have. Ctrl-C sets a flag; the next
    boundary saves a checkpoint and raises :class:`InterruptRequestedError`. A second Ctrl-C sets
    ``stop_now``: training stops after the current env step, mid-rollout.
    """
    from stable_baselines3.common.callbacks import BaseCallback

    from train.evaluation.rollout import rollout
    from train.evaluation.scenarios import make_scenario

    params = config.env_params()
    scenario = make_scenario("random", n=config.eval_episodes, seed=config.eval_seed, env_kwargs=config.env_keywords())

    class RunCallback(BaseCallback):
        def __init__(self) -> None:
            super().__init__()
            self.csv_path = run_dir / EVAL_FILE
            self.best = saved_best(state, self.csv_path)
            self.best_row: dict[str, float] = dict(state.get("best", {}))
            self.start = time.time() - float(state.get("wall_time", 0.0))
            self.last_eval = int(state.get("last_eval", -1))
            self.last_checkpoint = int(state.get("timesteps", 0))
            self.interrupt_requested = False
            self.stop_now = False

        def _on_training_start(self) -> None:
            if not self.csv_path.exists():
                with self.csv_path.open("w", newline="") as handle:
                    csv.writer(handle).writerow(EVAL_FIELDS)
            if self.last_eval < 0:
                self.evaluate()

        def _on_step(self) -> bool:
            if self.stop_now:  # a second Ctrl-C: stop after this env step, between steps where the state is whole
                return False
            if config.time_limit is not None and self.wall_time() >= config.time_limit:
                return False  # --time-limit: stop here; train() saves the run as finished
            if self.num_timesteps // config.eval_freq > max(self.last_eval, 0) // config.eval_freq:
                self.evaluate()
            return True

        def _on_rollout_start(self) -> None:
            due = self.num_timesteps - self.last_checkpoint >= config.checkpoint_freq
            if self.num_timesteps > self.last_checkpoint and (due or self.interrupt_requested):
                self.checkpoint()
            if self.interrupt_requested:
                raise InterruptRequestedError

        def wall_time(self) -> float:
            return round(time.time() - self.start, 2)

        def checkpoint(self, finished: bool = False) -> None:
            """Save model.zip, a numbered checkpoint, the env and generators, then the run state (last)."""
            import pickle
            import random

            import torch

            steps = self.num_timesteps
            (run_dir / "checkpoints").mkdir(exist_ok=True)
            self.save(run_dir / "checkpoints" / f"{config.algo}_{steps}_steps.zip")
            if hasattr(self.model, "replay_buffer") and self.model.replay_buffer is not None:
                self.model.save_replay_buffer(run_dir / "replay_buffer.pkl")
            generators = {"torch": torch.get_rng_state(), "numpy": np.random.get_state(), "random": random.getstate()}
            if hasattr(self.model, "key"):  # sbx's JAX key, which its load() resets to the seed's
                generators["jax"] = np.asarray(self.model.key)
            with (run_dir / RESUME_FILE).open("wb") as handle:
                pickle.dump({"timesteps": steps, "env": env_snapshot(env), "generators": generators}, handle)
            self.save(run_dir / MODEL_FILE)
            self.last_checkpoint = steps
            write_state(run_dir, {"timesteps": steps, "wall_time": self.wall_time(), "best": self.best_row,
                                  "best_score": self.best[2], "last_eval": self.last_eval,
                                  "finished": finished})  # fmt: skip  # best_score: the best's return, as before

        def save(self, path: Path) -> None:
            """The model, and beside it the observation statistics when it was trained on normalised ones."""
            from train.learning.wrappers import save_obs_norm

            self.model.save(path)
            save_obs_norm(env, path)

        def evaluate(self) -> None:
            """Evaluate now; best_model.zip is replaced where :func:`task_score` ranks this model higher."""
            from train.learning.wrappers import find_vec_normalize

            policy = as_policy(self.model, config, find_vec_normalize(env))
            summary = rollout(policy, params, scenario.starts, scenario.goals,
                              T_con=scenario.T_cons, env_kwargs=scenario.env_kwargs).summary()  # fmt: skip
            row = {"timesteps": self.num_timesteps, "wall_time": self.wall_time(),
                   **{k: summary[k] for k in EVAL_FIELDS[2:]}}  # fmt: skip
            with self.csv_path.open("a", newline="") as handle:
                csv.writer(handle).writerow(evaluation_cells(row))
            for key in EVAL_FIELDS[2:]:
                self.logger.record(f"eval/{key}", row[key])
            self.last_eval = self.num_timesteps
            score = task_score(row)
            if score > self.best:
                self.best, self.best_row = score, {k: row[k] for k in ("timesteps", *EVAL_FIELDS[2:])}
                self.save(run_dir / "best_model.zip")
            if on_evaluation is not None:
                on_evaluation(row)

    return RunCallback()


def make_anneal_callback(config: TrainConfig) -> Any:
    """PPO's ``log_std_final`` (ours, as the jitted PPO's
    :attr:`~train.learning.jitted.policy.PPOSettings.log_std_final`): after each rollout's update the policy's
    log_std is capped at log_std_init + (log_std_final - log_std_init) * (env steps done / budget), annealing the
    exploration noise whose energy v1 charges."""
    import torch
    from stable_baselines3.common.callbacks import BaseCallback

    init = float((config.algo_kwargs.get("policy_kwargs") or {}).get("log_std_init", 0.0))
    final = float(config.algo_kwargs.get("log_std_final", init))
    fixed = bool(config.algo_kwargs.get("log_std_fixed", False))  # set to the schedule, not capped by it

    class AnnealCallback(BaseCallback):
        def _on_step(self) -> bool:
            return True

        def _on_rollout_start(self) -> None:  # after the previous rollout's update
            self.cap()

        def _on_training_end(self) -> None:  # after the last update
            self.cap()

        def cap(self) -> None:
            fraction = min(self.num_timesteps / config.total_timesteps, 1.0)
            with torch.no_grad():
                value = init + (final - init) * fraction
                if fixed:
                    self.model.policy.log_std.fill_(value)
                else:
                    self.model.policy.log_std.clamp_(max=value)

    return AnnealCallback()


def make_progress_callback(total: int) -> Any:
    """A progress bar over the ``total`` env steps that will run (the budget rounded up to whole collections)."""
    from stable_baselines3.common.callbacks import BaseCallback

    from train.progress import Progress

    class ProgressCallback(BaseCallback):
        def __init__(self) -> None:
            super().__init__()
            self.bar: Any = None

        def _on_training_start(self) -> None:
            self.bar = Progress(total=total, desc="training", unit="step")

        def _on_step(self) -> bool:
            self.bar.update(self.training_env.num_envs)
            return True

        def close(self) -> None:
            if self.bar is not None:
                self.bar.close()
                self.bar = None

    return ProgressCallback()


def _layers(env: Any) -> list[Any]:
    """The wrappers of a VecEnv stack, outermost first, down to the native vector env."""
    layers = [env]
    while hasattr(layers[-1], "venv"):
        layers.append(layers[-1].venv)
    return layers


def env_snapshot(env: Any) -> list[dict[str, Any]]:
    """The state of every layer of the training env (robots, generators, episode statistics), picklable."""
    import pickle

    def picklable(value: Any) -> bool:
        try:
            pickle.dumps(value)
        except Exception:  # e.g. a compiled CasADi solver in the 'optimal' expert: rebuilt from the config
            return False
        return True

    skip = ("venv", "class_attributes")
    return [{k: v for k, v in vars(layer).items() if k not in skip and picklable(v)} for layer in _layers(env)]


def restore_env(env: Any, snapshot: list[dict[str, Any]]) -> None:
    """Put a fresh training env, built from the same config, back in the state of ``snapshot``."""
    for layer, attributes in zip(_layers(env), snapshot, strict=True):
        for key, value in attributes.items():
            setattr(layer, key, value)


def train(
    config: TrainConfig,
    command: list[str] | None = None,
    on_evaluation: Callable[[dict[str, Any]], None] | None = None,
) -> Path:
    """Train as configured (:func:`train.learning.training.train`, which validated ``config``); returns the run
    directory. ``on_evaluation`` receives each periodic evaluation as a dict of EVAL_FIELDS (e.g. to report it to a
    tuner).

    torch runs on ``config.threads`` threads (default 1) while it trains; the caller's count is restored
    afterwards (:mod:`train.threads`).

    Ctrl-C saves a checkpoint at the next rollout boundary; a second Ctrl-C stops after the current env
    step and saves what there is (a third stops at once, saving nothing more). Then it prints the command
    that resumes and raises KeyboardInterrupt.
    """
    from train.threads import torch_threads

    if config.backend == "sbx":  # sbx-rl: the same path, with sbx's classes (train.learning.sb3.sbx_backend)
        from train.learning.sb3.sbx_backend import check_sbx_config

        check_sbx_config(config)
    with torch_threads(config.threads):
        return _train(config, command, on_evaluation)


def _train(
    config: TrainConfig,
    command: list[str] | None,
    on_evaluation: Callable[[dict[str, Any]], None] | None,
) -> Path:
    import pickle
    import random
    import signal
    import threading

    import torch

    fill_budget(config)
    run_dir, lock = prepare_run_dir(config)
    try:
        config.run_dir = str(run_dir)
        note = rollout_rounding(config)
        if note and config.resume is None:
            print(note, file=sys.stderr)
        if config.residual and config.expert == "optimal":
            print(OPTIMAL_EXPERT_NOTE.format(n=config.num_envs, solves=config.num_envs / 20), file=sys.stderr)
        algo = algorithm_class(config.algo, config.backend)
        state = read_state(run_dir) if config.resume is not None else {}
        if config.resume is not None:
            with (run_dir / RESUME_FILE).open("rb") as handle:
                saved = pickle.load(handle)
            env = make_training_env(config)
            restore_env(env, saved["env"])
            model = algo.load(
                config.resume, env=env, device=config.device, tensorboard_log=str(run_dir / "tb"), force_reset=False
            )  # continue the saved episodes
            if (run_dir / "replay_buffer.pkl").is_file() and hasattr(model, "load_replay_buffer"):
                model.load_replay_buffer(run_dir / "replay_buffer.pkl")
            torch.set_rng_state(saved["generators"]["torch"])
            np.random.set_state(saved["generators"]["numpy"])
            random.setstate(saved["generators"]["random"])
            if "jax" in saved["generators"]:
                import jax.numpy as jnp

                model.key = jnp.asarray(saved["generators"]["jax"])
            truncate_log(run_dir / EVAL_FILE, model.num_timesteps)
        else:
            source = None
            if config.init_from is not None:  # RL fine-tuning: the saved network's architecture, then its weights
                source = finetune.load_source(config)
                finetune.adopt_architecture(config, source)
            env = make_training_env(config)
            try:
                model = algo(env=env, seed=config.seed, device=config.device, tensorboard_log=str(run_dir / "tb"),
                             verbose=0, **build_algo_kwargs(config.algo_kwargs, config.backend))  # fmt: skip
            except (TypeError, ValueError, AssertionError) as error:
                raise ConfigError(f"hyperparameters rejected by {config.algo.upper()}: {error}") from None
            if source is not None:
                finetune.load_weights(model, source)
            elif config.residual:
                from train.learning.residual import zero_init_last_layer

                zero_init_last_layer(model)
        save_config(config, run_dir, {"command": command or sys.argv, "learned_from": learned_from(config),
                                      "runtime": runtime_of(config)})  # fmt: skip
        callback = make_run_callback(config, run_dir, env, state, on_evaluation)
        remaining = config.total_timesteps - model.num_timesteps
        bar = make_progress_callback(steps_to_run(config, model.num_timesteps)) if config.progress else None

        def on_sigint(signum: int, frame: Any) -> None:
            if callback.stop_now:
                raise KeyboardInterrupt
            if callback.interrupt_requested:
                callback.stop_now = True
                print("\ninterrupt: saving now and stopping (Ctrl-C again to stop without saving)", file=sys.stderr)
                return
            callback.interrupt_requested = True
            print("\ninterrupt: saving at the end of this rollout (Ctrl-C again to save now and stop)",
                  file=sys.stderr)  # fmt: skip

        main_thread = threading.current_thread() is threading.main_thread()
        previous = signal.signal(signal.SIGINT, on_sigint) if main_thread else None
        start = time.time()
        try:
            noise_schedule = "log_std_final" in config.algo_kwargs or config.algo_kwargs.get("log_std_fixed")
            anneal = [make_anneal_callback(config)] if noise_schedule else []
            if config.critic_warmup:
                anneal.append(finetune.make_warmup_callback(config.critic_warmup))
            model.learn(remaining, callback=[callback, *anneal] + ([bar] if bar else []), progress_bar=False,
                        reset_num_timesteps=config.resume is None, tb_log_name=config.algo)  # fmt: skip
            if callback.stop_now:  # stopped by the second Ctrl-C, mid-rollout
                raise InterruptRequestedError
        except (InterruptRequestedError, KeyboardInterrupt):
            if bar is not None:
                bar.close()  # before the last lines, so that they are the last on the terminal
            if model.num_timesteps > callback.last_checkpoint or not (run_dir / MODEL_FILE).exists():
                callback.checkpoint()
            print(f"interrupted at {model.num_timesteps} steps: saved {run_dir / MODEL_FILE}\n"
                  f"resume with: {resume_command(run_dir)}", file=sys.stderr)  # fmt: skip
            raise KeyboardInterrupt from None
        finally:
            if main_thread:
                signal.signal(signal.SIGINT, previous)
            env.close()
        if bar is not None:
            bar.close()
        if callback.last_eval != model.num_timesteps:  # a run shorter than --eval-freq, or ending between two
            callback.evaluate()
        callback.checkpoint(finished=True)
    finally:
        lock.release()
    elapsed = time.time() - start
    done = model.num_timesteps - int(state.get("timesteps", 0))
    print(f"trained {model.num_timesteps} steps ({done} in {elapsed:.0f} s, {done / max(elapsed, 1e-9):.0f} "
          f"steps/s); saved {run_dir / MODEL_FILE}")  # fmt: skip
    return run_dir

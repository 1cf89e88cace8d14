"""The run of a jitted trainer (``dwr-gym train --backend jax``: the PPO of :mod:`train.learning.jitted.trainer`, the
ES of :mod:`train.learning.evolution.trainer`) in the run directory of :mod:`train.learning.runs`, the same as the
stable-baselines3 path writes.

A trainer (:class:`JitTrainer`) advances its state, a pytree, by jitted chunks up to the next evaluation or
checkpoint and exports it as an SB3 model. Between two chunks :func:`train_jitted` evaluates that model with the
same rollout, on the same fixed seeded scenario set, as the SB3 path (so their evaluations.csv compare), keeps
best_model.zip, writes checkpoints and run_state.json. The state is saved beside each checkpoint with
``flax.serialization``; a resumed run continues from it bit for bit (tests/test_jax_training.py, tests/test_es.py).
"""

from __future__ import annotations

import pickle
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any, Protocol

from train.learning.config import TrainConfig
from train.learning.runs import (
    EVAL_FILE,
    MODEL_FILE,
    RESUME_FILE,
    learned_from,
    prepare_run_dir,
    read_state,
    resume_command,
    save_config,
    truncate_log,
    write_state,
)


class JitTrainer(Protocol):
    """What :func:`train_jitted` needs of a jitted trainer, built (and its settings checked) before the run starts."""

    def init(self, seed: int) -> Any:
        """A fresh training state."""

    def advance(self, state: Any, steps: int, target: int, stop: Callable[[], bool]) -> tuple[Any, int]:
        """The state and the env steps done after training from ``steps`` to at least ``target`` (a whole number
        of its own units: updates, generations), or less where ``stop()`` turns true between two units."""

    def export(self, state: Any, steps: int) -> Any:
        """The SB3 model (with ``save(path)``, ``predict``) of the state's policy."""

    def steps_to_run(self, config: TrainConfig, done: int) -> int:
        """The env steps a run at ``done`` steps will take to reach its budget (for the progress bar)."""

    def start_note(self, config: TrainConfig) -> str | None:
        """A line printed when a run starts (not when it resumes), or None."""


def save_runner(path: Path, runner: Any, timesteps: int) -> None:
    """The whole training state, serialised with flax, written atomically."""
    import flax.serialization

    tmp = path.with_suffix(".tmp")
    with tmp.open("wb") as handle:
        pickle.dump({"timesteps": timesteps, "runner": flax.serialization.to_bytes(runner)}, handle)
    tmp.replace(path)


def load_runner(path: Path, template: Any) -> tuple[Any, int]:
    """The training state saved by :func:`save_runner`, in the structure of ``template`` (a fresh state)."""
    import flax.serialization

    with path.open("rb") as handle:
        saved = pickle.load(handle)
    runner = flax.serialization.msgpack_restore(saved["runner"])
    if hasattr(template, "average_params") and "average_params" not in runner:  # an APG state saved before it had one
        runner["average_params"] = runner["params"]
    return flax.serialization.from_state_dict(template, runner), int(saved["timesteps"])


class JaxRun:
    """One run of a jitted trainer in its run directory: evaluations, checkpoints, the run state."""

    def __init__(self, config: TrainConfig, run_dir: Path, export: Callable[[Any, int], Any], state: dict[str, Any],
                 on_evaluation: Callable[[dict[str, Any]], None] | None) -> None:  # fmt: skip
        from train.evaluation.scenarios import make_scenario
        from train.learning.runs import saved_best

        self.config, self.run_dir, self.export = config, run_dir, export
        self.on_evaluation = on_evaluation
        self.params = config.env_params()
        self.scenario = make_scenario("random", n=config.eval_episodes, seed=config.eval_seed,
                                      env_kwargs=config.env_keywords())  # fmt: skip
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
        model = self.export(runner, steps)
        s = self.scenario
        policy = as_policy(model, self.config)  # expert + residual for a residual agent
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
        model = self.export(runner, steps)
        (self.run_dir / "checkpoints").mkdir(exist_ok=True)
        model.save(self.run_dir / "checkpoints" / f"{self.config.algo}_{steps}_steps.zip")
        save_runner(self.run_dir / RESUME_FILE, runner, steps)
        model.save(self.run_dir / MODEL_FILE)
        self.last_checkpoint = steps
        write_state(self.run_dir, {"timesteps": steps, "wall_time": self.wall_time(), "best": self.best_row,
                                   "best_score": self.best[2], "last_eval": self.last_eval, "finished": finished,
                                   "backend": self.config.backend})  # fmt: skip


def train_jitted(
    config: TrainConfig,
    trainer: JitTrainer,
    command: list[str] | None = None,
    on_evaluation: Callable[[dict[str, Any]], None] | None = None,
) -> Path:
    """Train ``config`` (validated, its hyperparameters resolved) with ``trainer``; returns the run directory (the
    contract of :func:`train.learning.training.train`). Ctrl-C saves at the end of the running chunk (at most one
    evaluation period); a second Ctrl-C stops at once and saves the state of the last finished chunk."""
    import signal
    import threading

    run_dir, lock = prepare_run_dir(config)
    try:
        config.run_dir = str(run_dir)
        note = trainer.start_note(config)
        if note and config.resume is None:
            print(note, file=sys.stderr)
        state = read_state(run_dir) if config.resume is not None else {}
        runner = trainer.init(config.seed)
        steps = 0
        if config.resume is not None:
            runner, steps = load_runner(run_dir / RESUME_FILE, runner)
            truncate_log(run_dir / EVAL_FILE, steps)
        from train.learning.training_env import runtime_of

        save_config(config, run_dir, {"command": command or sys.argv, "learned_from": learned_from(config),
                                      "runtime": runtime_of(config)})  # fmt: skip
        run = JaxRun(config, run_dir, trainer.export, state, on_evaluation)
        bar = None
        if config.progress:
            from train.progress import Progress

            bar = Progress(total=trainer.steps_to_run(config, steps), desc="training", unit="step")
        interrupts = [0]

        def on_sigint(signum: int, frame: Any) -> None:
            interrupts[0] += 1
            if interrupts[0] > 1:
                raise KeyboardInterrupt
            print("\ninterrupt: saving at the end of this chunk of updates (Ctrl-C again to stop now, keeping the "
                  "last finished chunk)", file=sys.stderr)  # fmt: skip

        main_thread = threading.current_thread() is threading.main_thread()
        previous = signal.signal(signal.SIGINT, on_sigint) if main_thread else None
        time_limit = getattr(config, "time_limit", None)  # --time-limit, where this TrainConfig has it

        def stop() -> bool:
            return bool(interrupts[0]) or (time_limit is not None and run.wall_time() >= time_limit)

        start, done_before = time.time(), steps
        try:
            if run.last_eval < 0:
                run.evaluate(runner, steps)
            while steps < config.total_timesteps and not stop():
                target = min((steps // config.eval_freq + 1) * config.eval_freq,
                             run.last_checkpoint + config.checkpoint_freq, config.total_timesteps)  # fmt: skip
                runner, new_steps = trainer.advance(runner, steps, target, stop)
                if bar is not None:
                    bar.update(new_steps - steps)
                steps = new_steps
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

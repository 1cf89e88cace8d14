"""``dwr-gym train``: stable-baselines3 on the native vector env, plain or residual on an expert."""

from __future__ import annotations

import csv
import json
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from train.config import ConfigError, TrainConfig, algorithm_class, build_algo_kwargs

CONFIG_FILE = "config.yaml"
MODEL_FILE = "model.zip"
EVAL_FILE = "evaluations.csv"
EVAL_FIELDS = ("timesteps", "wall_time", "success_rate", "arrival_time_mean", "final_heading_error_mean",
               "energy_mean", "return_mean", "final_distance_mean")  # fmt: skip


def save_config(config: TrainConfig, run_dir: Path, extra: dict[str, Any] | None = None) -> None:
    """Write the full configuration beside the model (YAML), so any run can be repeated exactly."""
    import yaml

    import dwr_gym

    data = {"config": config.to_dict(), "dwr_gym_version": dwr_gym.__version__, **(extra or {})}
    (run_dir / CONFIG_FILE).write_text(yaml.safe_dump(json.loads(json.dumps(data, default=str)), sort_keys=False))


def load_config(run_dir: Path) -> TrainConfig:
    """The TrainConfig saved in a run directory."""
    import yaml

    path = run_dir / CONFIG_FILE
    if not path.is_file():
        raise ConfigError(f"{str(path)!r} not found: a trained agent needs the config.yaml written beside it")
    data = yaml.safe_load(path.read_text())
    config = data.get("config", data) if isinstance(data, dict) else None
    if not isinstance(config, dict):
        raise ConfigError(f"{str(path)!r} is not a dwr-gym training config")
    config["env_kwargs"] = {k: tuple(v) if isinstance(v, list) else v for k, v in config.get("env_kwargs", {}).items()}
    return TrainConfig.from_dict(config)


def make_expert(config: TrainConfig) -> Any:
    """The expert policy under a residual agent, scaled to the env's action limits."""
    from baselines.controllers import make_controller
    from baselines.expert import ExpertPolicy
    from dwr_gym.params import EnvParams

    params = EnvParams.from_kwargs(**config.env_kwargs)
    kwargs = {}
    if config.expert == "optimal":  # the planner must know the env's grid and limits
        kwargs = {"T_con": params.T_con, "dt": params.dt, "u_max": params.u_max, "omega_max": params.omega_max}
    return ExpertPolicy(make_controller(config.expert, **kwargs), params.u_max, params.omega_max)


def make_training_env(config: TrainConfig) -> Any:
    """The native vector env behind SB3's VecEnv API (residual-wrapped if asked); the adapter reports the
    episode statistics (``ep_rew_mean``, ``ep_len_mean``, ``success_rate``) itself, as a Monitor would."""
    from dwr_gym.sb3 import make_sb3_vec_env
    from train.residual import ResidualVecEnv

    venv: Any = make_sb3_vec_env(config.num_envs, seed=config.seed, **config.env_kwargs)
    if config.residual:
        venv = ResidualVecEnv(venv, make_expert(config), config.residual_scale)
    return venv


def as_policy(model: Any, config: TrainConfig) -> Any:
    """The policy that acts in the env: the model itself, or the model's residual on the expert."""
    if not config.residual:
        return model
    from train.residual import ResidualPolicy

    return ResidualPolicy(model, make_expert(config), config.residual_scale)


def make_eval_callback(
    config: TrainConfig, run_dir: Path, on_evaluation: Callable[[dict[str, Any]], None] | None = None
) -> Any:
    """A callback that evaluates on a fixed seeded scenario set, logs to TensorBoard and evaluations.csv,
    and hands each evaluation's row to ``on_evaluation`` (how ``dwr-gym sweep`` reports to Ray Tune)."""
    from stable_baselines3.common.callbacks import BaseCallback

    from dwr_gym.params import EnvParams
    from train.evaluation import make_scenario, rollout

    params = EnvParams.from_kwargs(**config.env_kwargs)
    scenario = make_scenario("random", n=config.eval_episodes, seed=config.eval_seed, env_kwargs=config.env_kwargs)
    every = max(1, config.eval_freq // config.num_envs)

    class ScenarioEvalCallback(BaseCallback):
        def __init__(self) -> None:
            super().__init__()
            self.best = -np.inf
            self.start = time.time()
            self.csv_path = run_dir / EVAL_FILE

        def _on_training_start(self) -> None:
            if not self.csv_path.exists():
                with self.csv_path.open("w", newline="") as handle:
                    csv.writer(handle).writerow(EVAL_FIELDS)
            self._evaluate()

        def _on_step(self) -> bool:
            if self.n_calls % every == 0:
                self._evaluate()
            return True

        def _evaluate(self) -> None:
            summary = rollout(as_policy(self.model, config), params, scenario.starts, scenario.goals).summary()
            row = {"timesteps": self.num_timesteps, "wall_time": round(time.time() - self.start, 2),
                   **{k: summary[k] for k in EVAL_FIELDS[2:]}}  # fmt: skip
            with self.csv_path.open("a", newline="") as handle:
                csv.writer(handle).writerow([row[k] for k in EVAL_FIELDS])
            for key in EVAL_FIELDS[2:]:
                self.logger.record(f"eval/{key}", row[key])
            score = summary["return_mean"]
            if score > self.best:
                self.best = score
                self.model.save(run_dir / "best_model.zip")
            if on_evaluation is not None:
                on_evaluation(row)

    return ScenarioEvalCallback()


def prepare_run_dir(config: TrainConfig) -> Path:
    """The run directory; refuses to overwrite a finished run unless resuming into it."""
    run_dir = Path(config.run_dir or config.default_run_dir())
    if config.resume is None and (run_dir / MODEL_FILE).exists():
        raise ConfigError(f"--run-dir {str(run_dir)!r} already holds a trained model: choose another or use --resume")
    run_dir.mkdir(parents=True, exist_ok=True)
    return run_dir


def train(
    config: TrainConfig,
    command: list[str] | None = None,
    on_evaluation: Callable[[dict[str, Any]], None] | None = None,
) -> Path:
    """Train as configured; returns the run directory. Ctrl-C saves the current model and re-raises.

    ``on_evaluation`` receives each periodic evaluation as a dict of EVAL_FIELDS (e.g. to report it to a tuner).
    """
    from stable_baselines3.common.callbacks import CallbackList, CheckpointCallback

    config.validate()
    run_dir = prepare_run_dir(config)
    config.run_dir = str(run_dir)
    algo = algorithm_class(config.algo)
    env = make_training_env(config)
    if config.resume is not None:
        model = algo.load(config.resume, env=env, device=config.device, tensorboard_log=str(run_dir / "tb"))
        model.set_random_seed(config.seed)
    else:
        model = algo(env=env, seed=config.seed, device=config.device, tensorboard_log=str(run_dir / "tb"), verbose=0,
                     **build_algo_kwargs(config.algo_kwargs))  # fmt: skip
        if config.residual:
            from train.residual import zero_init_last_layer

            zero_init_last_layer(model)
    save_config(config, run_dir, {"command": command or sys.argv})
    callbacks = CallbackList([
        make_eval_callback(config, run_dir, on_evaluation),
        CheckpointCallback(max(1, config.checkpoint_freq // config.num_envs), str(run_dir / "checkpoints"),
                           name_prefix=config.algo),
    ])  # fmt: skip
    remaining = config.total_timesteps - (model.num_timesteps if config.resume else 0)
    start = time.time()
    try:
        if remaining > 0:
            model.learn(remaining, callback=callbacks, progress_bar=config.progress,
                        reset_num_timesteps=config.resume is None, tb_log_name=config.algo)  # fmt: skip
    except KeyboardInterrupt:
        model.save(run_dir / MODEL_FILE)
        print(f"\ninterrupted at {model.num_timesteps} steps: saved {run_dir / MODEL_FILE}", file=sys.stderr)
        raise
    finally:
        env.close()
    model.save(run_dir / MODEL_FILE)
    elapsed = time.time() - start
    print(f"trained {model.num_timesteps} steps in {elapsed:.0f} s ({model.num_timesteps / max(elapsed, 1e-9):.0f} "
          f"steps/s); saved {run_dir / MODEL_FILE}")  # fmt: skip
    return run_dir

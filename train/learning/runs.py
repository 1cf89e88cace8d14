"""The run directory of ``dwr-gym train``: its files, its config.yaml, its lock, its state, and resuming it.

A run directory holds one run: ``config.yaml`` (the full configuration), ``model.zip`` (the newest
checkpoint), ``best_model.zip``, ``evaluations.csv``, ``checkpoints/``, ``tb/`` and the state that a
resumed run continues from.

The format is the same whichever library trained the agent (``backend`` sb3, jax or sbx): ``model.zip`` and every
checkpoint are stable-baselines3 model files of ``config.algo`` (the jax backend writes its weights into an SB3
``MlpPolicy`` of the same architecture; sbx-rl saves its own class in SB3's zip format), ``evaluations.csv`` has the
columns of :data:`EVAL_FIELDS`, and config.yaml holds ``config`` (a :class:`TrainConfig`), ``command``,
``learned_from`` (``reward`` or ``expert``) and ``runtime`` (what acts beside the network at run time: an expert
under a residual, a hand-over law, a planner; empty for the network alone). So
``train.learning.agents.load_agent`` loads any of them, and ``dwr-gym evaluate --agents DIR`` compares it.
"""

from __future__ import annotations

import csv
import json
import math
import os
from pathlib import Path
from typing import Any

from train.learning.config import ConfigError, TrainConfig

CONFIG_FILE = "config.yaml"
MODEL_FILE = "model.zip"
EVAL_FILE = "evaluations.csv"
STATE_FILE = "run_state.json"
RESUME_FILE = "resume_state.pkl"
LOCK_FILE = ".lock"
EVAL_FIELDS = ("timesteps", "wall_time", "success_rate", "arrival_time_mean", "final_heading_error_mean",
               "energy_mean", "return_mean", "final_distance_mean")  # fmt: skip
"""The columns of evaluations.csv, one row per evaluation on the run's fixed scenario set."""
MISSING = ""
"""How evaluations.csv writes a mean over no episodes (``arrival_time_mean`` where none arrived): an empty cell,
which :func:`read_evaluations` (and pandas) read back as NaN, so no file a user opens holds ``nan``."""
RUN_OUTPUTS = (MODEL_FILE, "best_model.zip", EVAL_FILE, CONFIG_FILE, STATE_FILE, RESUME_FILE, "replay_buffer.pkl",
               "checkpoints", "tb")  # fmt: skip


class AgentLoadError(Exception):
    """The agent file is missing or unreadable."""


class RunDirError(ConfigError):
    """A run directory that cannot be used as asked (in use, or holding another run)."""


def saved_model(init_from: str) -> Path:
    """The model file of ``--init-from``: the path itself if it is a file, else its run directory's model.zip."""
    path = Path(init_from)
    return path if path.is_file() else path / MODEL_FILE


def learned_from(config: TrainConfig) -> str:
    """config.yaml's ``learned_from``: "reward", or "expert, then reward" for RL fine-tuning of a cloned network."""
    if config.init_from is None:
        return "reward"
    import yaml

    saved = saved_model(config.init_from).parent / "config.yaml"
    source = yaml.safe_load(saved.read_text()).get("learned_from") if saved.is_file() else None
    return "expert, then reward" if source in ("expert", "expert, then reward") else "reward"


def find_run_dir(path: Path) -> Path:
    """The run directory holding config.yaml for a model file, a checkpoint or a run directory."""
    for candidate in (path, *path.parents[:3]):
        if candidate.is_dir() and (candidate / "config.yaml").is_file():
            return candidate
    raise AgentLoadError(f"agent {str(path)!r} is invalid: no config.yaml found beside it or above it")


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


def read_state(run_dir: Path) -> dict[str, Any]:
    """The run's progress: timesteps and wall time of the last save, best score, whether it finished."""
    path = run_dir / STATE_FILE
    return json.loads(path.read_text()) if path.is_file() else {}


def write_state(run_dir: Path, state: dict[str, Any]) -> None:
    """Write run_state.json atomically (a kill leaves the old or the new file, never half of one)."""
    tmp = run_dir / (STATE_FILE + ".tmp")
    tmp.write_text(json.dumps(state, indent=2) + "\n")
    tmp.replace(run_dir / STATE_FILE)


def resume_command(run_dir: Path) -> str:
    return f"dwr-gym train --resume {run_dir}"


def checkpoint_steps(path: Path, state: dict[str, Any]) -> int | None:
    """The step count of a checkpoint: from its name (algo_<steps>_steps.zip), or the run state for model.zip."""
    import re

    match = re.search(r"_(\d+)_steps\.zip$", path.name)
    if match:
        return int(match.group(1))
    return int(state["timesteps"]) if path.name == MODEL_FILE and "timesteps" in state else None


def resume_config(given: dict[str, Any]) -> TrainConfig:
    """The saved config of the run to resume (``given['resume']``: its directory or its newest checkpoint)."""
    target = Path(given["resume"])
    if not target.exists():
        raise ConfigError(f"--resume {str(target)!r} is invalid: no such run directory or checkpoint")
    allowed = {"resume", "total_timesteps", "progress", "device"}
    extra = sorted(set(given) - allowed)
    if extra:
        flags = ", ".join("--" + name.replace("_", "-") for name in extra)
        raise ConfigError(f"--resume reuses the run's saved config; {flags} cannot be changed (only "
                          f"--total-timesteps, --device, --no-progress)")  # fmt: skip
    try:
        run_dir = find_run_dir(target if target.is_dir() else target.parent)
    except AgentLoadError as error:
        raise ConfigError(str(error)) from None
    state = read_state(run_dir)
    if "timesteps" not in state or not (run_dir / MODEL_FILE).is_file():
        raise ConfigError(f"--resume {str(target)!r} is invalid: {str(run_dir)!r} has no checkpoint to resume from")
    checkpoint = target if target.is_file() else run_dir / MODEL_FILE
    steps = checkpoint_steps(checkpoint, state)
    if steps != state["timesteps"]:
        raise ConfigError(
            f"--resume {str(target)!r} is invalid: the run is at {state['timesteps']} steps and this checkpoint "
            f"at {steps}; resuming from it would replace newer results. Resume with: {resume_command(run_dir)}"
        )
    config = load_config(run_dir)
    for key in ("total_timesteps", "progress", "device"):
        if key in given:
            setattr(config, key, given[key])
    config.resume, config.run_dir = str(checkpoint), str(run_dir)
    config.validate()
    if config.total_timesteps <= state["timesteps"]:
        raise ConfigError(
            f"--total-timesteps {config.total_timesteps} is invalid: the run has done {state['timesteps']} steps "
            "already; give a larger budget to continue it"
        )
    return config


class RunLock:
    """An exclusive lock on a run directory, held for the whole run and released by the OS if the process dies."""

    def __init__(self, run_dir: Path) -> None:
        self.path = run_dir / LOCK_FILE
        self.handle: Any = None

    def acquire(self) -> None:
        self.handle = self.path.open("a+")
        try:
            import fcntl

            fcntl.flock(self.handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except ImportError:  # no fcntl (Windows): no lock
            return
        except OSError:
            self.handle.seek(0)
            owner = self.handle.read().strip() or "another process"
            self.handle.close()
            raise RunDirError(
                f"--run-dir {str(self.path.parent)!r} is in use by a running training ({owner})"
            ) from None
        self.handle.seek(0)
        self.handle.truncate()
        self.handle.write(f"pid {os.getpid()}")
        self.handle.flush()

    def release(self) -> None:
        if self.handle is not None:
            self.handle.close()
            self.handle = None


def prepare_run_dir(config: TrainConfig) -> tuple[Path, RunLock]:
    """The run directory, locked; refuses one holding another run unless resuming it or --overwrite."""
    import shutil

    run_dir = Path(config.run_dir or config.default_run_dir())
    if run_dir.exists() and not run_dir.is_dir():
        raise RunDirError(f"--run-dir {str(run_dir)!r} is invalid: it is a file, expected a directory")
    try:
        run_dir.mkdir(parents=True, exist_ok=True)
        lock = RunLock(run_dir)
        lock.acquire()
    except OSError as error:
        raise RunDirError(f"--run-dir {str(run_dir)!r} is not writable: {error.strerror or error}") from None
    leftovers = sorted(name for name in RUN_OUTPUTS if (run_dir / name).exists())
    if leftovers and config.resume is None:
        if not config.overwrite:
            lock.release()
            raise RunDirError(
                f"--run-dir {str(run_dir)!r} already holds a run ({', '.join(leftovers)}): continue it with "
                f"{resume_command(run_dir)}, choose another --run-dir, or add --overwrite to delete it"
            )
        for name in leftovers:
            path = run_dir / name
            shutil.rmtree(path) if path.is_dir() else path.unlink()
    return run_dir, lock


def evaluation_cells(row: dict[str, Any]) -> list[Any]:
    """A row of evaluations.csv in :data:`EVAL_FIELDS` order, a non-finite number written as :data:`MISSING`."""
    return [MISSING if isinstance(row[k], float) and not math.isfinite(row[k]) else row[k] for k in EVAL_FIELDS]


def read_evaluations(path: Path) -> list[dict[str, float]]:
    """The rows of an evaluations.csv as numbers (an empty cell as NaN); [] if there is no such file."""
    if not path.is_file():
        return []
    with path.open(newline="") as handle:
        return [{k: math.nan if v == MISSING else float(v) for k, v in row.items()} for row in csv.DictReader(handle)]


def truncate_log(path: Path, steps: int) -> None:
    """Drop evaluation rows logged after the checkpoint a run resumes from, so the log stays monotonic."""
    if not path.is_file():
        return
    with path.open(newline="") as handle:
        rows = list(csv.reader(handle))
    kept = [rows[0], *(row for row in rows[1:] if row and int(float(row[0])) <= steps)]
    if len(kept) != len(rows):
        with path.open("w", newline="") as handle:
            csv.writer(handle).writerows(kept)


def task_score(row: dict[str, Any]) -> tuple[float, float, float]:
    """The order in which evaluations rank, highest best: the share of episodes in time (``success_rate``) first;
    among equal shares the lower mean energy, when any episode arrives in time (a policy that arrives nowhere
    would win on energy by standing still); then the higher return."""
    success, energy, ret = (float(row.get(key, math.nan)) for key in ("success_rate", "energy_mean", "return_mean"))
    finite = [v if math.isfinite(v) else -math.inf for v in (success, -energy if success > 0 else 0.0, ret)]
    return finite[0], finite[1], finite[2]


def saved_best(state: dict[str, Any], csv_path: Path) -> tuple[float, float, float]:
    """The score of the run's best_model.zip: ``best`` of run_state.json, or, in a run saved before the task score
    (``best_score``, a return), the score of the evaluation whose return that was."""
    if "best" in state:
        return task_score(state["best"])
    best_return = float(state.get("best_score", -math.inf))
    if math.isfinite(best_return) and csv_path.is_file():
        rows = read_evaluations(csv_path)
        matching = [row for row in rows if math.isclose(row["return_mean"], best_return, rel_tol=1e-9, abs_tol=1e-12)]
        if matching:
            return task_score(matching[-1])
    return -math.inf, -math.inf, best_return

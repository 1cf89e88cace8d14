"""Run directories: one run each, resumable, reproducible, never corrupted."""

from __future__ import annotations

import csv
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from train.learning.config import TrainConfig
from train.learning.hyperparams import resolve_hyperparams
from train.learning.runs import RunDirError, RunLock, read_evaluations, resume_config, task_score
from train.learning.training import train


def tiny(run_dir: Path, total: int = 512, **overrides: object) -> TrainConfig:
    config = TrainConfig(total_timesteps=total, num_envs=4, eval_freq=200, eval_episodes=8, checkpoint_freq=128,
                         run_dir=str(run_dir), progress=False, **overrides)  # type: ignore[arg-type]  # fmt: skip
    resolve_hyperparams(config, set())
    config.algo_kwargs.update(n_steps=32, batch_size=64)  # a rollout is 128 steps
    return config


def parameters(run_dir: Path) -> list[np.ndarray]:
    from stable_baselines3 import PPO

    return [p.detach().numpy().copy() for p in PPO.load(run_dir / "model.zip").policy.parameters()]


def evaluations(run_dir: Path) -> list[list[str]]:
    """The evaluation log without its wall-time column."""
    with (run_dir / "evaluations.csv").open() as handle:
        return [row[:1] + row[2:] for row in csv.reader(handle)]


def test_same_seed_same_agent_and_resume_equals_the_uninterrupted_run(tmp_path: Path) -> None:
    first, second, split = tmp_path / "first", tmp_path / "second", tmp_path / "split"
    train(tiny(first))
    train(tiny(second))
    for a, b in zip(parameters(first), parameters(second), strict=True):
        np.testing.assert_array_equal(a, b)
    assert evaluations(first) == evaluations(second)

    train(tiny(split, total=256))  # stops at a rollout boundary, as Ctrl-C does
    train(resume_config({"resume": str(split), "total_timesteps": 512, "progress": False}))
    for a, b in zip(parameters(first), parameters(split), strict=True):
        np.testing.assert_array_equal(a, b)
    # the same evaluations, and one more where the first part ended: a finished run is evaluated at its last step
    assert [row for row in evaluations(split) if row[0] != "256"] == evaluations(first)
    steps = [int(row[0]) for row in evaluations(split)[1:]]
    assert steps == [0, 200, 256, 400, 512]
    best = max(read_evaluations(split / "evaluations.csv"), key=task_score)
    assert json.loads((split / "run_state.json").read_text())["best"]["timesteps"] == int(best["timesteps"])
    wall = [float(row[1]) for row in list(csv.reader((split / "evaluations.csv").read_text().splitlines()))[1:]]
    assert wall == sorted(wall)  # wall time continues across the resume


def test_a_run_directory_holds_one_run(tmp_path: Path) -> None:
    run_dir = tmp_path / "run"
    train(tiny(run_dir, total=128))
    with pytest.raises(RunDirError, match="already holds a run"):
        train(tiny(run_dir, total=128))
    with pytest.raises(Exception, match="the run has done 128 steps already"):
        resume_config({"resume": str(run_dir), "total_timesteps": 128})
    newest = run_dir / "checkpoints" / "ppo_128_steps.zip"
    assert newest.is_file()
    train(resume_config({"resume": str(run_dir), "total_timesteps": 256, "progress": False}))
    with pytest.raises(Exception, match="would replace newer results"):
        resume_config({"resume": str(newest), "total_timesteps": 512})
    lock = RunLock(run_dir)
    lock.acquire()
    try:
        with pytest.raises(RunDirError, match="is in use by a running training"):
            train(tiny(run_dir, total=128, overwrite=True))
    finally:
        lock.release()
    train(tiny(run_dir, total=128, overwrite=True))
    assert [int(row[0]) for row in evaluations(run_dir)[1:]] == [0, 128]  # the old run's log went with --overwrite


def test_a_run_dir_that_is_a_file_is_refused_before_any_work(tmp_path: Path) -> None:
    (tmp_path / "file").write_text("")
    with pytest.raises(RunDirError, match="it is a file"):
        train(tiny(tmp_path / "file"))


def test_ctrl_c_saves_a_checkpoint_and_prints_the_resume_line(tmp_path: Path) -> None:
    env = {**os.environ, "OMP_NUM_THREADS": "1"}
    process = subprocess.Popen(
        [sys.executable, "-m", "train.cli", "train", "--total-timesteps", "1e7", "--num-envs", "4",
         "--eval-freq", "1e5", "--eval-episodes", "4", "--run-dir", "run", "--no-progress",
         "--hyperparams", "n_steps=32", "batch_size=64"],
        cwd=tmp_path, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    deadline = time.time() + 120
    while not (tmp_path / "run" / "evaluations.csv").exists() and time.time() < deadline:
        time.sleep(0.2)
    time.sleep(1.0)
    process.send_signal(signal.SIGINT)
    _, stderr = process.communicate(timeout=120)
    assert process.returncode == 130, stderr
    assert "resume with: dwr-gym train --resume run" in stderr
    config = resume_config({"resume": str(tmp_path / "run"), "total_timesteps": "1e7"})
    assert config.total_timesteps == 10**7 and config.algo_kwargs["n_steps"] == 32

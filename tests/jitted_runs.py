"""Helpers of the jitted learners' CLI tests (ES, APG): ``dwr-gym train`` in a fresh process, and the check that a run
stopped halfway and resumed ends as the uninterrupted run does, bit for bit."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent


def cli(*args: str) -> subprocess.CompletedProcess[str]:
    """``python -m train.cli ARGS`` of this checkout on one thread, its output captured."""
    env = {**os.environ, "PYTHONPATH": str(ROOT), "OMP_NUM_THREADS": "1"}
    return subprocess.run([sys.executable, "-m", "train.cli", *args], cwd=ROOT, env=env, text=True,
                          capture_output=True, timeout=600)  # fmt: skip


def assert_resume_is_bit_for_bit(train_args: tuple[str, ...], total: int, every: int, tmp_path: Path) -> Path:
    """Train ``total`` steps straight, and ``total // 2`` then resumed to ``total`` (evaluations and checkpoints every
    ``every``): the same steps, finished, the same weights to the last bit. Returns the resumed run's directory."""
    from train.learning.agents import load_agent
    from train.learning.runs import read_state

    straight, split = tmp_path / "straight", tmp_path / "split"
    common = ("--eval-freq", str(every), "--checkpoint-freq", str(every))
    done = cli(*train_args, *common, "--total-timesteps", str(total), "--run-dir", str(straight))
    assert done.returncode == 0, done.stderr
    done = cli(*train_args, *common, "--total-timesteps", str(total // 2), "--run-dir", str(split))
    assert done.returncode == 0, done.stderr
    done = cli("train", "--resume", str(split), "--total-timesteps", str(total), "--no-progress")
    assert done.returncode == 0, done.stderr
    assert read_state(split)["timesteps"] == read_state(straight)["timesteps"] and read_state(split)["finished"]
    _, resumed = load_agent(split)
    _, uninterrupted = load_agent(straight)
    for a, b in zip(resumed.policy.state_dict().values(), uninterrupted.policy.state_dict().values(), strict=True):
        assert np.array_equal(a.numpy(), b.numpy())  # the resumed run is the uninterrupted one, bit for bit
    return split

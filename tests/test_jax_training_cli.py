"""``dwr-gym train --backend jax`` from the command line, as a user runs it: a refused algorithm is one line, a run
resumes bit for bit and is evaluated, and Ctrl-C keeps the last model and says how to resume."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest

pytest.importorskip("jax")
pytest.importorskip("flax")
pytest.importorskip("optax")
pytest.importorskip("stable_baselines3")

ROOT = Path(__file__).resolve().parent.parent


def cli(*args: str, **kwargs: Any) -> subprocess.Popen[str]:
    env = {**os.environ, "PYTHONPATH": str(ROOT), "OMP_NUM_THREADS": "1"}
    return subprocess.Popen([sys.executable, "-m", "train.cli", *args], cwd=ROOT, env=env, text=True,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, **kwargs)  # fmt: skip


TINY = ("train", "--backend", "jax", "--num-envs", "8", "--eval-episodes", "4", "--no-progress", "--hyperparams",
        "n_steps=8", "batch_size=32", "n_epochs=1")  # fmt: skip


def finish(process: subprocess.Popen[str], timeout: float = 300) -> tuple[int, str, str]:
    out, err = process.communicate(timeout=timeout)
    return process.returncode, out, err


def test_backend_jax_refuses_other_algorithms(tmp_path: Path) -> None:
    code, _, err = finish(cli("train", "--backend", "jax", "--algo", "sac", "--run-dir", str(tmp_path / "r")))
    assert code == 2 and len(err.strip().splitlines()) == 1
    assert "--algo 'sac' is invalid with --backend jax" in err


@pytest.mark.slow
def test_cli_trains_resumes_bit_for_bit_and_evaluates(tmp_path: Path) -> None:
    from train.learning.agents import load_agent
    from train.learning.runs import read_state

    straight, split = tmp_path / "straight", tmp_path / "split"
    common = ("--eval-freq", "64", "--checkpoint-freq", "128")
    code, out, err = finish(cli(*TINY, *common, "--total-timesteps", "192", "--run-dir", str(straight)))
    assert code == 0, err
    code, _, err = finish(cli(*TINY, *common, "--total-timesteps", "128", "--run-dir", str(split)))
    assert code == 0, err
    code, _, err = finish(cli("train", "--resume", str(split), "--total-timesteps", "192", "--no-progress"))
    assert code == 0, err
    assert read_state(split)["timesteps"] == 192 and read_state(split)["finished"]
    rows = (split / "evaluations.csv").read_text().splitlines()
    assert [int(row.split(",")[0]) for row in rows[1:]] == [0, 64, 128, 192]
    assert (split / "checkpoints" / "ppo_128_steps.zip").is_file()
    _, resumed = load_agent(split)
    _, uninterrupted = load_agent(straight)
    for a, b in zip(resumed.policy.state_dict().values(), uninterrupted.policy.state_dict().values(), strict=True):
        assert np.array_equal(a.numpy(), b.numpy())  # the resumed run is the uninterrupted one, bit for bit
    import yaml

    saved = yaml.safe_load((split / "config.yaml").read_text())
    assert saved["learned_from"] == "reward" and saved["runtime"] == [] and saved["config"]["backend"] == "jax"
    code, out, err = finish(
        cli(
            "evaluate",
            "--agents",
            str(split),
            "--n",
            "3",
            "--scenarios",
            "random",
            "--controllers",
            "ptc",
            "--optimum",
            "none",
            "--no-progress",
            "--out",
            str(tmp_path / "evaluate"),
        )
    )
    assert code == 0, err
    assert "split" in out and "ptc" in out


@pytest.mark.slow
def test_ctrl_c_keeps_the_last_model_and_says_how_to_resume(tmp_path: Path) -> None:
    from train.learning.runs import read_state

    run_dir = tmp_path / "run"
    process = cli(*TINY, "--eval-freq", "64", "--total-timesteps", "1000000000", "--run-dir", str(run_dir))
    deadline = time.time() + 240
    while not (run_dir / "evaluations.csv").is_file() or len((run_dir / "evaluations.csv").read_text().split()) < 3:
        assert process.poll() is None and time.time() < deadline, process.communicate()
        time.sleep(0.5)
    process.send_signal(signal.SIGINT)
    code, _, err = finish(process, 120)
    assert code == 130, err
    assert "resume with: dwr-gym train --resume" in err
    steps = read_state(run_dir)["timesteps"]
    assert steps > 0 and (run_dir / "model.zip").is_file()
    assert (run_dir / "checkpoints" / f"ppo_{steps}_steps.zip").is_file()

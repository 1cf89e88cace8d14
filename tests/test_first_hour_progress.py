"""The first hour of a new user, its progress bars and Ctrl-C: each friction they met, tried as they tried
it, in a subprocess (the rest: test_first_hour.py)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest


def dwr_gym(*args: str, cwd: Path | None = None) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "SDL_VIDEODRIVER": "dummy", "MPLBACKEND": "Agg"}
    return subprocess.run([sys.executable, "-m", "train.cli", *args], capture_output=True, text=True, cwd=cwd,
                          env=env, timeout=600)  # fmt: skip


# 5. A progress bar's total is the work that will run: PPO rounds the budget up to whole rollouts.


def bar_states(stderr: str) -> list[str]:
    """Every state a tqdm bar printed (it rewrites its line with carriage returns)."""
    return [line for line in stderr.replace("\r", "\n").splitlines() if line.startswith("training:")]


def test_the_training_bar_counts_to_the_steps_that_run_also_on_resume(tmp_path: Path) -> None:
    args = ["train", "--num-envs", "4", "--hyperparams", "n_steps=128", "--eval-freq", "1e6", "--eval-episodes", "4",
            "--run-dir", "run"]  # fmt: skip
    first = dwr_gym(*args, "--total-timesteps", "1000", cwd=tmp_path)  # rollouts of 512 steps: 1024 run
    assert first.returncode == 0, first.stderr
    assert "runs 1024 steps" in first.stderr and bar_states(first.stderr)[-1].count("1024/1024") == 1
    assert not any("/1000 " in state for state in bar_states(first.stderr))
    resumed = dwr_gym("train", "--resume", "run", "--total-timesteps", "1500", cwd=tmp_path)
    assert resumed.returncode == 0, resumed.stderr
    assert "512/512" in bar_states(resumed.stderr)[-1]  # 1024 + 512 = 1536 >= 1500, in whole rollouts


# 16. Ctrl-C: the first saves at the end of the rollout, a second stops after the current step and saves what it
# can; the resume line is the last thing printed.


def test_a_second_ctrl_c_stops_mid_rollout_saves_and_ends_with_the_resume_line(tmp_path: Path) -> None:
    import re
    import signal
    import threading
    import time

    env = {**os.environ, "OMP_NUM_THREADS": "1"}
    rollout = 4 * 1_000_000  # steps per PPO rollout: it would take many minutes to end by itself
    process = subprocess.Popen(
        [sys.executable, "-m", "train.cli", "train", "--total-timesteps", "1e8", "--num-envs", "4",
         "--eval-freq", "1e7", "--eval-episodes", "4", "--run-dir", "run",
         "--hyperparams", f"n_steps={rollout // 4}", "batch_size=64"],
        cwd=tmp_path, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    assert process.stderr is not None
    printed: list[str] = []
    reader = threading.Thread(target=lambda: printed.extend(iter(lambda: process.stderr.read(1), "")))  # type: ignore[union-attr]
    reader.start()
    deadline = time.time() + 300
    while not re.search(r"\| [1-9]\d*/100000000", "".join(printed)) and time.time() < deadline:
        time.sleep(0.2)  # until the bar shows steps: the first rollout is under way
    process.send_signal(signal.SIGINT)
    time.sleep(1.0)
    assert process.poll() is None  # the first Ctrl-C waits for the end of the rollout
    process.send_signal(signal.SIGINT)
    process.wait(timeout=120)
    reader.join(timeout=10)
    stderr = "".join(printed)
    assert process.returncode == 130, stderr
    assert "(Ctrl-C again to save now and stop)" in stderr and "interrupt: saving now and stopping" in stderr
    lines = [line for line in stderr.replace("\r", "\n").splitlines() if line.strip()]
    assert lines[-1] == "resume with: dwr-gym train --resume run"
    saved = json.loads((tmp_path / "run" / "run_state.json").read_text())["timesteps"]
    assert 0 < saved < rollout and (tmp_path / "run" / "model.zip").is_file()


# 6. The time left leaves out the first item, which pays the start-up cost (all plans of `optimal`, a pool, torch).


def test_the_time_left_is_unknown_after_a_slow_first_item_then_measured_from_its_end() -> None:
    import io

    from train.progress import Progress

    clock = [0.0]
    bar = Progress(total=600, desc="random: optimal", file=io.StringIO(), mininterval=0)
    bar._time = lambda: clock[0]
    bar.start_t = bar.last_print_t = 0.0
    clock[0] = 18.0
    bar.update()  # the first step plans every robot
    assert "[00:18<?" in str(bar)  # unknown, where tqdm alone predicts 2:59:42
    for _ in range(9):
        clock[0] += 0.01
        bar.update()
    assert "[00:18<00:05" in str(bar)  # 590 steps left at 100 steps/s


def test_evaluate_and_the_optimum_show_such_bars(monkeypatch: pytest.MonkeyPatch) -> None:
    import numpy as np

    import train.progress
    from train.evaluation.optimum import optimal_energies
    from train.evaluation.rollout import rollout
    from train.evaluation.scenarios import make_scenario

    made = []

    class Recorded(train.progress.Progress):  # type: ignore[misc]
        def __init__(self, *args: object, **kwargs: object) -> None:
            made.append(kwargs["desc"])
            super().__init__(*args, **kwargs)

    monkeypatch.setattr(train.progress, "Progress", Recorded)
    from baselines import ExpertPolicy, PTCController
    from dwr_gym.params import EnvParams

    params = EnvParams()
    scenario = make_scenario("random", n=2)
    rollout(ExpertPolicy(PTCController(), params.u_max, params.omega_max), params, scenario.starts, scenario.goals,
            progress=True, description="random: ptc")  # fmt: skip
    optimal_energies(params, scenario.starts[:1], np.zeros((1, 3)), progress=True, description="random: optimum")
    assert made == ["random: ptc", "random: optimum"]

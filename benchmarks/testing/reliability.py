"""The reliability check: fuzz count, bad-input table, interrupt/resume. Everything must be green.

    OMP_NUM_THREADS=1 python -m benchmarks run reliability              # about 2 minutes on 2 cores
    python -m benchmarks run reliability --states 1e6                   # the full fuzz (the fuzz entry)

1. Fuzz: NaN/inf count over random and edge states of the env, the vector env and every controller (must be 0).
2. Bad input: every row is a bad input a user can give; each must end in one line naming it, exit code 2
   (command line) or a ValueError (Python API), never a traceback, and no output written.
3. Interrupt and resume: Ctrl-C during ``dwr-gym train`` saves and prints the resume line; resuming continues
   the step count, the wall time and the best score, keeps the log monotonic, and a run split in two
   equals the uninterrupted run at the same seed.
"""

from __future__ import annotations

import contextlib
import csv
import io
import json
import os
import signal
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks.core.commands import parser_for

GREEN, RED, RESET = ("\033[32m", "\033[31m", "\033[0m") if sys.stdout.isatty() else ("", "", "")
results: list[bool] = []


def report(ok: bool, what: str, detail: str = "") -> None:
    results.append(ok)
    mark = f"{GREEN}PASS{RESET}" if ok else f"{RED}FAIL{RESET}"
    print(f"  [{mark}] {what}" + (f"  ({detail})" if detail else ""), flush=True)


def cli(*args: str) -> tuple[int, str]:
    """Run ``dwr-gym ARGS`` in this process: (exit code, stderr)."""
    from train.cli import main

    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        try:
            code = main(list(args))
        except SystemExit as exit_:
            code = int(exit_.code or 0)
        except Exception as error:  # a traceback is a failure of this check
            code, err = -1, io.StringIO(f"Traceback: {type(error).__name__}: {error}")
    return code, err.getvalue()


def api(call: Callable[[], Any]) -> tuple[int, str]:
    try:
        call()
    except ValueError as error:
        return 2, str(error) + "\n"
    except Exception as error:
        return -1, f"Traceback: {type(error).__name__}: {error}"
    return 0, ""


def bad_inputs(tmp: Path) -> list[tuple[str, Callable[[], tuple[int, str]], str]]:
    import gymnasium as gym

    from baselines.controllers import PTCParams
    from dwr_gym.env import DWRPointStabilizationEnv

    env_id = "DWRPointStabilization-v0"
    yaml_of = {
        "cartpole.yml": "CartPole-v1:\n  n_timesteps: 1000\n",
        "abc.yml": f'{env_id}:\n  batch_size: "abc"\n',
        "lr.yml": f"{env_id}:\n  learning_rate: -1\n",
        "nan.yml": f"{env_id}:\n  learning_rate: .nan\n",
        "act.yml": f'{env_id}:\n  policy_kwargs: "dict(activation_fn=nn.Swish)"\n',
        "envs.yml": f"{env_id}:\n  n_envs: 2.7\n",
    }
    for name, text in yaml_of.items():
        (tmp / name).write_text(text)
    (tmp / "binary.yml").write_bytes(bytes(range(256)) * 4)
    (tmp / "a_file").write_text("")
    train = ("train", "--run-dir", str(tmp / "never"), "--no-progress")
    venv = gym.make_vec(env_id, num_envs=2, vectorization_mode="vector_entry_point")
    return [
        ("--device gpu", lambda: cli(*train, "--device", "gpu"), "--device 'gpu' is invalid"),
        ("--device tpu9", lambda: cli(*train, "--device", "tpu9"), "--device 'tpu9' is invalid"),
        ("--seed -1", lambda: cli(*train, "--seed", "-1"), "--seed -1 is invalid"),
        ("--total-timesteps 2.5", lambda: cli(*train, "--total-timesteps", "2.5"), "--total-timesteps 2.5"),
        ("--num-envs 100000000", lambda: cli(*train, "--num-envs", "100000000"), "--num-envs 100000000"),
        ("--algo dqn", lambda: cli(*train, "--algo", "dqn"), "--algo 'dqn' is invalid"),
        ("YAML for CartPole-v1", lambda: cli(*train, "--hyperparams", str(tmp / "cartpole.yml")), "another env"),
        ('YAML batch_size: "abc"', lambda: cli(*train, "--hyperparams", str(tmp / "abc.yml")), "batch_size='abc'"),
        ("YAML learning_rate: -1", lambda: cli(*train, "--hyperparams", str(tmp / "lr.yml")), "learning_rate=-1"),
        ("YAML learning_rate: .nan", lambda: cli(*train, "--hyperparams", str(tmp / "nan.yml")), "learning_rate=nan"),
        ("YAML unknown activation_fn", lambda: cli(*train, "--hyperparams", str(tmp / "act.yml")), "activation_fn"),
        ("YAML n_envs: 2.7", lambda: cli(*train, "--hyperparams", str(tmp / "envs.yml")), "n_envs (YAML)=2.7"),
        ("YAML binary file", lambda: cli(*train, "--hyperparams", str(tmp / "binary.yml")), "binary.yml"),
        ("--hyperparams learning_rate", lambda: cli(*train, "--hyperparams", "learning_rate"), "no such file"),
        ("--run-dir is a file", lambda: cli("train", "--run-dir", str(tmp / "a_file")), "it is a file"),
        ("evaluate --out is a file", lambda: cli("evaluate", "--out", str(tmp / "a_file")), "it is a file"),
        ("evaluate --out unwritable", lambda: cli("evaluate", "--out", "/proc/dwr"), "--out '/proc/dwr'"),
        ("evaluate --seed -1", lambda: cli("evaluate", "--seed", "-1", "--out", str(tmp / "o")), "--seed -1"),
        ("evaluate --n 1e9", lambda: cli("evaluate", "--n", "1e9", "--out", str(tmp / "o")), "--n 1000000000"),
        ("--env-kwargs goal_tolerance=6", lambda: cli("evaluate", "--env-kwargs", "goal_tolerance=6"),
         "goal_tolerance=6.0 is invalid"),
        ("T_con=dt=5e-324", lambda: api(lambda: gym.make(env_id, T_con=5e-324, dt=5e-324)), "T_con=5e-324"),
        ("T_con=1e6, dt=1e6 (blames dt)", lambda: api(lambda: gym.make(env_id, T_con=1e6, dt=1e6)), "dt=1000000.0"),
        ('start="123"', lambda: api(lambda: gym.make(env_id).unwrapped.reset(options={"start": "123"})),
         "options['start']='123'"),
        ("pose near 1.7e308", lambda: api(lambda: gym.make(env_id).unwrapped.reset(options={"start": (1.7e308, 0, 0)})),
         "options['start']"),
        ("render_mode=1", lambda: api(lambda: DWRPointStabilizationEnv(render_mode=1)), "render_mode=1"),  # type: ignore[arg-type]
        ("substeps=2.5", lambda: api(lambda: gym.make(env_id, substeps=2.5)), "substeps=2.5"),
        ("PTCParams(K1=-1)", lambda: api(lambda: PTCParams(K1=-1)), "K1=-1.0"),
        ("vector step() before reset()", lambda: _reset_needed(venv), "call reset() before step()"),
    ]  # fmt: skip


def _reset_needed(venv: Any) -> tuple[int, str]:
    import gymnasium as gym

    try:
        venv.step(np.zeros((2, 2)))
    except gym.error.ResetNeeded as error:
        return 2, str(error) + "\n"
    return 0, ""


def check_bad_inputs() -> None:
    with tempfile.TemporaryDirectory() as tmp:
        for what, run, expected in bad_inputs(Path(tmp)):
            code, err = run()
            lines = err.strip().splitlines()
            ok = code == 2 and len(lines) == 1 and expected in err and "Traceback" not in err
            report(ok, f"bad input: {what}", lines[0][:110] if lines else f"exit {code}, no message")
        report(not (Path(tmp) / "never").exists(), "bad input: nothing written to --run-dir")


def evaluations(path: Path) -> list[dict[str, str]]:
    with path.open() as handle:
        return list(csv.DictReader(handle))


def check_interrupt_and_resume() -> None:
    from train.learning.config import TrainConfig
    from train.learning.hyperparams import resolve_hyperparams
    from train.learning.runs import resume_config
    from train.learning.training import train

    with tempfile.TemporaryDirectory() as tmp_name:
        tmp = Path(tmp_name)
        env = {**os.environ, "OMP_NUM_THREADS": "1"}
        args = [sys.executable, "-m", "train.cli", "train", "--total-timesteps", "1e7", "--num-envs", "4",
                "--eval-freq", "2000", "--eval-episodes", "8", "--checkpoint-freq", "1e6", "--run-dir", "run",
                "--no-progress", "--hyperparams", "n_steps=32", "batch_size=64"]  # fmt: skip
        process = subprocess.Popen(args, cwd=tmp, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        log = tmp / "run" / "evaluations.csv"
        deadline = time.time() + 180
        while time.time() < deadline and (not log.exists() or len(log.read_text().splitlines()) < 3):
            time.sleep(0.5)
        process.send_signal(signal.SIGINT)
        _, stderr = process.communicate(timeout=180)
        report(process.returncode == 130, "Ctrl-C: exit code 130", f"exit {process.returncode}")
        report("resume with: dwr-gym train --resume run" in stderr, "Ctrl-C: prints the line that resumes")
        state = json.loads((tmp / "run" / "run_state.json").read_text())
        report((tmp / "run" / "model.zip").is_file() and state["timesteps"] > 0, "Ctrl-C: checkpoint saved",
               f"{state['timesteps']} steps")  # fmt: skip
        busy = subprocess.run([*args[:-3], "--no-progress"], cwd=tmp, env=env, capture_output=True, text=True)
        report(busy.returncode == 2 and "already holds a run" in busy.stderr, "a second train into the run is refused")
        rows_before = evaluations(log)
        target = state["timesteps"] + 2048
        resumed = subprocess.run([sys.executable, "-m", "train.cli", "train", "--resume", "run", "--total-timesteps",
                                  str(target), "--no-progress"], cwd=tmp, env=env, capture_output=True, text=True)  # fmt: skip
        after = json.loads((tmp / "run" / "run_state.json").read_text())
        rows = evaluations(log)
        steps = [int(r["timesteps"]) for r in rows]
        walls = [float(r["wall_time"]) for r in rows]
        report(resumed.returncode == 0 and after["timesteps"] >= target, "resume continues the step count",
               f"{state['timesteps']} -> {after['timesteps']}")  # fmt: skip
        report(steps == sorted(steps) and len(set(steps)) == len(steps), "evaluations.csv stays monotonic in steps")
        report(walls == sorted(walls) and after["wall_time"] >= state["wall_time"], "wall time continues")
        report(after["best_score"] >= state["best_score"] and rows[: len(rows_before)] == rows_before,
               "best score kept; earlier log rows untouched")  # fmt: skip

        def tiny(run_dir: Path, total: int) -> TrainConfig:
            config = TrainConfig(total_timesteps=total, num_envs=4, eval_freq=200, eval_episodes=8,
                                 checkpoint_freq=128, run_dir=str(run_dir), progress=False)  # fmt: skip
            resolve_hyperparams(config, set())
            config.algo_kwargs.update(n_steps=32, batch_size=64)
            return config

        with contextlib.redirect_stdout(io.StringIO()):
            train(tiny(tmp / "whole", 512))
            train(tiny(tmp / "split", 256))
            train(resume_config({"resume": str(tmp / "split"), "total_timesteps": 512, "progress": False}))
        from stable_baselines3 import PPO

        whole, split = (PPO.load(tmp / name / "model.zip").policy.state_dict() for name in ("whole", "split"))
        same = all(np.array_equal(whole[k].numpy(), split[k].numpy()) for k in whole)
        report(same, "a run resumed at 256 of 512 steps equals the uninterrupted run (same seed)")


def main(argv: list[str] | None = None) -> int:
    parser = parser_for("reliability", __doc__)
    parser.add_argument("--states", type=float, default=1e5, help="fuzzed env states (default: 1e5)")
    args = parser.parse_args(argv)
    from benchmarks.testing.fuzz import fuzz_controllers, fuzz_env, fuzz_single_env

    print("1. fuzz")
    rng = np.random.default_rng(0)
    for name, (tried, bad) in (("single env", fuzz_single_env(rng, int(args.states) // 20)),
                               ("vector env", fuzz_env(rng, int(args.states))),
                               ("controllers", fuzz_controllers(rng, int(args.states)))):  # fmt: skip
        report(bad == 0, f"fuzz {name}: {bad} NaN/inf", f"{tried} states")
    print("2. bad input")
    check_bad_inputs()
    print("3. interrupt and resume")
    check_interrupt_and_resume()
    passed = sum(results)
    colour = GREEN if passed == len(results) else RED
    print(f"{colour}{passed}/{len(results)} checks passed{RESET}")
    return 0 if passed == len(results) else 1

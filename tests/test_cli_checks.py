"""Bad input on the command line is answered in one line, before the heavy imports (torch, the learners, Ray):
each case runs ``dwr-gym`` in a Python process of its own, as a user does, and reports which heavy modules it
had loaded when it answered."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
#: What a bad argument must be answered without: each takes seconds to import on a busy machine.
HEAVY = ("torch", "stable_baselines3", "ray", "jax", "matplotlib")
#: Runs the CLI as its console script does (``-c RUNNER HEAVY,... ARGS``), then prints which of the heavy modules the
#: process had imported.
RUNNER = """
import json, sys
from train.cli import main
try:
    code = main(sys.argv[2:])
except SystemExit as exit:  # argparse's own errors
    code = exit.code
heavy = sorted(m for m in sys.argv[1].split(",") if m in sys.modules)
print(json.dumps({"code": code, "heavy": heavy}))
"""


def answer(*args: str) -> tuple[int, list[str], str]:
    """(exit code, the heavy modules imported, stderr) of ``dwr-gym ARGS``."""
    env = {**os.environ, "MPLBACKEND": "Agg"}
    result = subprocess.run([sys.executable, "-c", RUNNER, ",".join(HEAVY), *args], capture_output=True, text=True,
                            cwd=ROOT, env=env, timeout=300)  # fmt: skip
    found = json.loads(result.stdout.strip().splitlines()[-1])
    return found["code"], found["heavy"], result.stderr


@pytest.mark.parametrize(
    "args, message",
    [
        (["evaluate", "--n", "-5"], "dwr-gym evaluate: error: --n -5 is invalid: expected an integer in [1, 1e7]"),
        (["compare", "--n", "0"], "dwr-gym compare: error: --n 0 is invalid: expected an integer in [1, 1e7]"),
        (["evaluate", "--env", "DWRPointStabilization-v9"],
         "--env 'DWRPointStabilization-v9' is invalid: expected DWRPointStabilization-v2"),
        (["compare", "--scenarios", "randm"], "--scenarios 'randm' is invalid: expected any of paper-fig5"),
        (["robustness", "--disturbances", "wind"], "--disturbances 'wind' is invalid: expected any of bias"),
        (["compare", "--agents", "train/pretrained/apg_hold_heading10_time_scaled_30min"],
         "--agents 'train/pretrained/apg_hold_heading10_time_scaled_30min' is invalid: no such file or directory; "
         "the agents shipped with dwr-gym"),
        (["compare", "--agents", "train/pretrained/apg_hold_heading10_time_scaled_30min_v2"],
         "apg-hold-heading10-time-scaled-30min-v2 is shipped as apg-v2 now; the agents shipped with dwr-gym"),
        (["evaluate", "--agents", "dagger-handover"],
         "--agents 'dagger-handover' is invalid: dagger-handover is no longer shipped"),
        (["evaluate", "--agents", "runs/ppo"],  # a user's path is never read as the shipped agent of its name
         "--agents 'runs/ppo' is invalid: no such file or directory; the agents shipped with dwr-gym"),
        (["evaluate", "--threads", "0"], "--threads 0 is invalid: expected an integer in [1, 1024]"),
        (["train", "--total-timesteps", "-5"], "--total-timesteps -5 is invalid"),
        (["train", "--env", "CartPole-v1"], "--env 'CartPole-v1' is invalid"),
        (["sweep", "--seeds", "0"], "--seeds 0 is invalid: expected >= 1"),
    ],
)  # fmt: skip
def test_bad_input_is_one_line_naming_it_before_any_heavy_import(args: list[str], message: str) -> None:
    code, heavy, stderr = answer(*args)
    assert code == 2 and message in stderr and len(stderr.strip().splitlines()) == 1, stderr
    assert heavy == [], f"dwr-gym {' '.join(args)} imported {heavy} before answering"


@pytest.mark.parametrize(
    "given", ["train/pretrained/no_such_agent", "apg-teacher-v2", "train/pretrained/es_arena50_v1"]
)
def test_an_agent_not_shipped_is_one_line_naming_the_shipped_agents(given: str) -> None:
    from train.learning.agents import PRETRAINED

    code, _, stderr = answer("evaluate", "--agents", given)
    line = stderr.strip()
    assert code == 2 and len(line.splitlines()) == 1, stderr
    assert all(name in line.rsplit(":", 1)[-1] for name in PRETRAINED), stderr


def test_a_measure_not_asked_for_has_no_column_and_no_line(tmp_path: Path) -> None:
    """--optimum none: no E/opt columns (they would be nan throughout) and no word of the optimum in the time line;
    asked for, the columns are there."""
    common = ["evaluate", "--controllers", "ptc", "--scenarios", "paper-fig5", "--no-progress"]
    env = {**os.environ, "MPLBACKEND": "Agg"}
    runs = {}
    for optimum in ("none", "pose"):
        runs[optimum] = subprocess.run([sys.executable, "-m", "train.cli", *common, "--optimum", optimum, "--out",
                                        str(tmp_path / optimum)], capture_output=True, text=True, cwd=ROOT, env=env,
                                       timeout=600)  # fmt: skip
        assert runs[optimum].returncode == 0, runs[optimum].stderr
    without = runs["none"].stdout
    assert "E/opt" not in without and "nan" not in without and "optimum" not in without.splitlines()[-1]
    assert "E/opt mean" in runs["pose"].stdout and "optimum" in runs["pose"].stdout.splitlines()[-1]


def test_compare_runs_a_shipped_agent_by_name_on_its_own_env_and_without_the_optimum_no_E_opt(tmp_path: Path) -> None:
    """``--agents ppo``: the paper's reward's agent, on v0 where it was trained, beside PTC on --env (v2)."""
    env = {**os.environ, "MPLBACKEND": "Agg"}
    result = subprocess.run([sys.executable, "-m", "train.cli", "compare", "--controllers", "ptc", "--scenarios",
                             "random", "noise", "--n", "5", "--optimum", "none", "--no-progress", "--agents",
                             "ppo", "--out", str(tmp_path)], capture_output=True, text=True,
                            cwd=ROOT, env=env, timeout=600)  # fmt: skip
    assert result.returncode == 0, result.stderr
    assert "the robust headline" in result.stdout and "E/opt" not in result.stdout
    assert "optimum" not in result.stdout.splitlines()[-1] and not (tmp_path / "pareto.png").exists()
    rows = json.loads((tmp_path / "comparison.json").read_text())
    assert {(row["policy"], row["env_id"]) for row in rows} == {("ppo", "DWRPointStabilization-v0"),
                                                                 ("ptc", "DWRPointStabilization-v2")}  # fmt: skip

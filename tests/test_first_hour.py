"""The first hour of a new user (issue 25): each friction they met, tried as they tried it, in a subprocess."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from train.env_ids import PAPER_ENV_ID, TASK_ENV_ID

ROOT = Path(__file__).resolve().parents[1]


def dwr_gym(*args: str, cwd: Path | None = None) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "SDL_VIDEODRIVER": "dummy", "MPLBACKEND": "Agg"}
    return subprocess.run([sys.executable, "-m", "train.cli", *args], capture_output=True, text=True, cwd=cwd,
                          env=env, timeout=600)  # fmt: skip


# 1. One env id story: v1 is the task and every command's default; v0 is the paper's reward, kept for reproduction.


def test_train_takes_the_env_id_and_records_it_with_the_discount_of_that_env(tmp_path: Path) -> None:
    result = dwr_gym("train", "--env", TASK_ENV_ID, "--total-timesteps", "512", "--num-envs", "4", "--hyperparams",
                     "n_steps=128", "--eval-freq", "512", "--eval-episodes", "4", "--run-dir", "v1", "--no-progress",
                     cwd=tmp_path)  # fmt: skip
    assert result.returncode == 0, result.stderr
    config = yaml.safe_load((tmp_path / "v1" / "config.yaml").read_text())["config"]
    assert config["env_id"] == TASK_ENV_ID and config["algo_kwargs"]["gamma"] == 0.999


def test_the_default_env_is_the_task_and_v0_keeps_its_own_hyperparameters() -> None:
    from train.learning.config import TrainConfig
    from train.learning.hyperparams import resolve_hyperparams

    task = resolve_hyperparams(TrainConfig(), set())
    assert task.env_id == TASK_ENV_ID and task.env_params().T_con_range == (10.0, 60.0)
    paper = resolve_hyperparams(TrainConfig(env_id=PAPER_ENV_ID), set())
    assert paper.env_params().T_con_range is None and paper.algo_kwargs["gamma"] == 0.99


def test_a_run_that_recorded_no_env_id_loads_as_v0_and_the_shipped_agents_record_theirs(tmp_path: Path) -> None:
    from train.learning.agents import PRETRAINED, trained_env_id
    from train.learning.runs import load_config

    (tmp_path / "config.yaml").write_text(yaml.safe_dump({"config": {"algo": "ppo", "env_kwargs": {}}}))
    old = load_config(tmp_path)
    assert old.env_id == PAPER_ENV_ID and old.env_params().T_con_range is None
    shipped = {name: trained_env_id(path) for name, path in PRETRAINED.items()}
    assert shipped == {"residual-ppo": PAPER_ENV_ID, "ppo": PAPER_ENV_ID, "dagger": TASK_ENV_ID,
                       "dagger-handover": TASK_ENV_ID}  # fmt: skip


def test_evaluate_runs_on_the_task_the_paper_sets_keep_their_T_con_and_T_con_replaces_the_range(
    tmp_path: Path,
) -> None:
    common = ["--controllers", "ptc", "--scenarios", "paper-fig5", "random", "--n", "5", "--optimum", "none",
              "--no-progress"]  # fmt: skip
    task = dwr_gym("evaluate", *common, "--out", str(tmp_path / "task"), "--agent", str(ROOT / "train/pretrained/ppo"))
    assert task.returncode == 0, task.stderr
    rows = json.loads((tmp_path / "task" / "evaluation.json").read_text())
    assert {(r["scenario"], r["T_con"], r["env_id"]) for r in rows} == {("paper-fig5", 20.0, TASK_ENV_ID),
                                                                         ("random", None, TASK_ENV_ID)}  # fmt: skip
    assert "random, T_con drawn per episode" in task.stdout
    assert f"note: ppo trained on {PAPER_ENV_ID}, run here on {TASK_ENV_ID}" in task.stderr
    fixed = dwr_gym("evaluate", *common, "--T-con", "30", "--out", str(tmp_path / "fixed"))
    assert fixed.returncode == 0, fixed.stderr
    assert [r["T_con"] for r in json.loads((tmp_path / "fixed" / "evaluation.json").read_text())] == [30.0, 30.0]
    paper = dwr_gym("evaluate", *common, "--env", PAPER_ENV_ID, "--out", str(tmp_path / "paper"))
    assert paper.returncode == 0, paper.stderr
    assert [r["T_con"] for r in json.loads((tmp_path / "paper" / "evaluation.json").read_text())] == [20.0, 20.0]


# 2. `--env` is an option of its own, and no option is guessed from a prefix.


@pytest.mark.parametrize("command", ["train", "evaluate", "compare", "robustness", "sweep", "imitate"])
def test_every_command_that_makes_an_env_takes_env_and_refuses_an_abbreviation(command: str) -> None:
    wrong = dwr_gym(command, "--env", "CartPole-v1")
    assert wrong.returncode == 2 and "--env 'CartPole-v1' is invalid: expected DWRPointStabilization-v1" in wrong.stderr
    abbreviated = dwr_gym(command, "--env-kw", "T_con=25")
    assert abbreviated.returncode == 2 and "unrecognized arguments: --env-kw" in abbreviated.stderr


# 3. One spelling for one concept: --agents in every command, --agent (repeatable) meaning the same.


def test_evaluate_takes_agents_and_agent_alike(tmp_path: Path) -> None:
    ppo, dagger = str(ROOT / "train/pretrained/ppo"), str(ROOT / "train/pretrained/dagger")
    for i, flags in enumerate((["--agents", ppo, dagger], ["--agent", ppo, "--agent", dagger])):
        result = dwr_gym("evaluate", "--controllers", "ptc", "--scenarios", "paper-fig5", "--optimum", "none",
                         "--no-progress", "--out", str(tmp_path / str(i)), *flags)  # fmt: skip
        assert result.returncode == 0, result.stderr
        rows = json.loads((tmp_path / str(i) / "evaluation.json").read_text())
        assert [row["policy"] for row in rows] == ["ptc", "ppo", "dagger"]


@pytest.mark.parametrize("command", ["evaluate", "compare", "robustness"])
def test_every_command_with_agents_reads_both_spellings(command: str) -> None:
    from train.cli import build_parser

    parser = build_parser()
    assert parser.parse_args([command, "--agents", "a", "b"]).agents == ["a", "b"]
    assert parser.parse_args([command, "--agent", "a", "--agent", "b"]).agents == ["a", "b"]


# 4. The help says what the options take, each default once, and lists every command.


def option_entries(help_text: str) -> dict[str, str]:
    """Each option's entry in ``--help`` (flags and help text, wrapped lines joined), by its first flag."""
    entries: dict[str, str] = {}
    flag = None
    for line in help_text.split("options:", 1)[1].splitlines():
        if line.startswith("  -"):
            flag = line.split()[0].rstrip(",")
            entries[flag] = line.strip()
        elif flag is not None and line.startswith("      "):
            entries[flag] += " " + line.strip()
    return entries


def test_help_lists_every_command_and_each_option_says_its_default_once() -> None:
    from train.cli import build_parser

    top = dwr_gym("--help").stdout
    description = " ".join(top.split("positional arguments:")[0].split())
    commands = list(build_parser()._subparsers._group_actions[0].choices)  # type: ignore[union-attr]
    assert len(commands) == 8 and "``" not in top
    assert f"Commands: {', '.join(commands)};" in description
    for command in commands:
        entries = option_entries(dwr_gym(command, "--help").stdout)
        assert all(text.count("(default:") <= 1 for text in entries.values()), command
    train = option_entries(dwr_gym("train", "--help").stdout)
    assert "a run directory (or a checkpoint .zip in one)" in train["--resume"]
    assert train["--run-dir"].count("runs/<algo>[-residual]-seed<seed>") == 1

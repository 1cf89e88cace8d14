"""The leaderboard's reproducing commands train what was shipped: each shipped learner's benchmark entry (the row's
``dwr-gym benchmark`` entry, as its recipe runs it) asks for the same run as the command its config.yaml recorded."""

from __future__ import annotations

import dataclasses
import shlex
from pathlib import Path
from typing import Any

import pytest
import yaml

from tests.test_pretrained import asked
from train.learning.agents import PRETRAINED_DIR
from train.learning.benchmark import parse_entry, train_config
from train.reporting.leaderboard import ROWS

ROOT = Path(__file__).resolve().parents[1]
#: What a run trains with (beside the budget, which the entry or the recipe sets).
TRAINED_WITH = ("env_id", "algo", "backend", "residual", "expert", "action_time_scale", "hyperparam_overrides",
                "env_kwargs", "threads")  # fmt: skip
SHIPPED_LEARNERS = [row for row in ROWS if row.kind == "benchmark" and row.agent != "-"]


def recorded_config(agent: str, monkeypatch: pytest.MonkeyPatch) -> Any:
    """The TrainConfig the shipped agent's recorded ``dwr-gym train`` command parses into (training stubbed)."""
    command = [str(word) for word in yaml.safe_load((PRETRAINED_DIR / agent / "config.yaml").read_text())["command"]]
    assert Path(command[0]).name == "dwr-gym" and command[1] == "train", shlex.join(command)
    monkeypatch.chdir(ROOT)  # the commands name the repository's hyperparameter files
    return asked(command, monkeypatch)[1]


def recipe_words(recipe: str, entry: str) -> list[str]:
    """The words of the ``dwr-gym benchmark`` command of the recipe script that trains ``entry``."""
    text = (ROOT / "benchmarks" / "recipes" / recipe).read_text().replace("\\\n", " ")
    line = next(line for line in text.splitlines() if "dwr-gym benchmark" in line and entry in line)
    return shlex.split(line.split("#")[0])


def test_every_shipped_learner_has_a_benchmark_row() -> None:
    assert {row.agent for row in SHIPPED_LEARNERS} >= {"apg_v2", "apg_residual_ptc_v2", "ppo_jax_v1", "es_v1"}


@pytest.mark.parametrize("row", SHIPPED_LEARNERS, ids=lambda row: row.agent)
def test_the_rows_entry_trains_what_the_shipped_agent_was_trained_with(
    row: Any, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    shipped = recorded_config(row.agent, monkeypatch)
    recipe = row.reproduce.split()[-1].replace("-", "_") + ".sh"
    # the recipe's own agent options (``NAME:threads=1``) and budget, as `dwr-gym benchmark` passes them on
    words = recipe_words(recipe, row.entry)
    options = next((word for word in words if word.startswith(f"{row.entry}:")), row.entry)
    flags = {flag: int(words[words.index(flag) + 1]) for flag in ("--eval-episodes", "--env-steps", "--eval-freq")
             if flag in words}  # fmt: skip
    budget: dict[str, Any] = {"eval_episodes": flags.get("--eval-episodes", 1000)}
    budget.update({key: flags[flag] for key, flag in (("env_steps", "--env-steps"), ("eval_freq", "--eval-freq"))
                   if flag in flags})  # fmt: skip
    entry = parse_entry(options)
    config = train_config(entry, shipped.seed, tmp_path / "run", budget)
    for key in (*TRAINED_WITH, "total_timesteps", "eval_freq", "checkpoint_freq", "eval_episodes", "eval_seed"):
        assert getattr(config, key) == getattr(shipped, key), (
            f"{row.agent}: {key} is {getattr(config, key)!r} by the entry {row.entry!r} of {recipe}, "
            f"{getattr(shipped, key)!r} by the shipped agent's recorded command"
        )
    assert Path(config.hyperparams or "").resolve() == Path(ROOT / (shipped.hyperparams or "")).resolve()


def test_a_runs_command_names_each_budget_flag_once_and_overrides_as_the_command_line_reads_them(
    tmp_path: Path,
) -> None:
    from train.learning.benchmark import train_command

    entry = parse_entry("apg-hold-heading10-time-scaled-30min-v2:env_kwargs={T_con_range: [10, 20]}")
    config = train_config(entry, 3, tmp_path / "run", {"eval_episodes": 200})
    command = train_command(entry, config)
    for flag in ("--total-timesteps", "--eval-freq", "--checkpoint-freq", "--eval-episodes", "--eval-seed", "--env"):
        assert command.count(flag) == 1, (flag, command)  # the entry's own budget is given once, from the config
    assert command[command.index("--eval-episodes") + 1] == "200"
    hyperparams = command[command.index("--hyperparams") + 1 : command.index("--run-dir")]
    assert hyperparams[0].endswith("apg_teacher.yml") and "hold_heading_weight=10.0" in hyperparams, hyperparams
    # a string stays as typed, anything else as JSON (what KEY=VALUE reads back as YAML)
    assert command[command.index("--env-kwargs") + 1] == "T_con_range=[10, 20]", command
    typed = dataclasses.replace(
        entry, options={**entry.options, "hyperparam_overrides": {"note": "as typed", "on": True}}
    )
    assert train_command(typed, config)[-4:-2] == ["note=as typed", "on=true"]


def test_each_reference_controller_is_evaluated_on_the_env_asked_for(monkeypatch: pytest.MonkeyPatch) -> None:
    import train.evaluation.benchmark as benchmark

    calls: list[tuple[str, str, dict[str, Any]]] = []
    monkeypatch.setattr(benchmark, "evaluate_policy",
                        lambda name, env_id, **kwargs: calls.append((name, env_id, kwargs)) or {"set": name})  # fmt: skip
    got = benchmark.reference_controllers(("ptc", "pt-astolfi"), "DWRPointStabilization-v2", n=7)
    assert got == {"ptc": {"set": "ptc"}, "pt-astolfi": {"set": "pt-astolfi"}}
    assert calls == [
        ("ptc", "DWRPointStabilization-v2", {"n": 7}),
        ("pt-astolfi", "DWRPointStabilization-v2", {"n": 7}),
    ]

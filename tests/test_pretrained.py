"""The shipped agents' recipes: the command each config.yaml records runs as written in this checkout and asks for
the run that was shipped (its env id, algorithm and budget); read by the command line's own parsing and checks,
with the training itself replaced by a stub that keeps what it was asked to do."""

from __future__ import annotations

import dataclasses
import sys
from pathlib import Path
from typing import Any

import pytest
import yaml

from benchmarks.training import retrain_pretrained
from train.learning.agents import PRETRAINED, pretrained_paths


def asked(step: list[str], monkeypatch: pytest.MonkeyPatch) -> tuple[str, Any]:
    """(module, the config it would train with) of one recorded step, as its command line parses it."""
    import train.learning.imitation.dagger as dagger
    import train.learning.imitation.robust_dagger as robust_dagger
    import train.learning.training as training
    from train.cli import main

    caught: list[Any] = []
    monkeypatch.setattr(training, "train", lambda config, command=None: caught.append(config))
    monkeypatch.setattr(dagger, "run", lambda config, run_dir, command: caught.append(config))
    monkeypatch.setattr(robust_dagger, "run", lambda config, run_dir, command: caught.append(config))
    if Path(step[0]).name == "dwr-gym":
        assert main(step[1:]) == 0
    else:
        assert step[1] == "-m", step
        modules = {"train.learning.imitation.dagger": dagger, "train.learning.imitation.robust_dagger": robust_dagger}
        monkeypatch.setattr(sys, "argv", step[2:])
        modules[step[2]].main(step[3:])
    assert len(caught) == 1, step
    return step[2] if step[1] == "-m" else "train.cli", caught[0]


@pytest.mark.parametrize("name", sorted(PRETRAINED))
def test_each_shipped_agents_recorded_command_runs_as_written(
    name: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    agent = pretrained_paths()[name]
    recorded = yaml.safe_load((agent / "config.yaml").read_text())
    steps, dirs = retrain_pretrained.moved_run_dirs(retrain_pretrained.recipe(agent), tmp_path / "run")
    monkeypatch.chdir(Path(__file__).resolve().parents[1])  # the commands name the repository's hyperparameter files
    for index, (step, run_dir) in enumerate(zip(steps, dirs, strict=True)):
        step = retrain_pretrained._set(step, "--run-dir", str(run_dir))
        module, config = asked(step, monkeypatch)
        if index < len(steps) - 1:  # an earlier step's network, which the next one starts from
            run_dir.mkdir(parents=True)
            (run_dir / "model.zip").touch()
            continue
        if module == "train.cli":
            for key in ("env_id", "algo", "residual", "total_timesteps", "env_kwargs"):
                assert getattr(config, key) == recorded["config"][key], (name, key)
            for key in ("backend", "action_time_scale", "hyperparam_overrides"):  # recorded by the runs since they were
                assert getattr(config, key) == recorded["config"].get(key, getattr(config, key)), (name, key)
        else:  # robust: the robust DAgger run it records, started from the network of the step before
            wanted = {**recorded["robust_dagger"], "init_from": str(dirs[0]), "eval_T_con": None, "threads": None}
            got = {**dataclasses.asdict(config), "eval_T_con": None, "threads": None}
            assert got == wanted


def test_robust_dagger_without_its_starting_network_says_how_to_train_it(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit):
        from train.learning.imitation.robust_dagger import main

        main(["--run-dir", "runs/x", "--init-from", "runs/no_such_dagger_run"])
    line = capsys.readouterr().err.strip().splitlines()[-1]
    assert "--init-from 'runs/no_such_dagger_run' is invalid: no model.zip in it" in line
    assert "python -m train.learning.imitation.dagger --run-dir runs/no_such_dagger_run" in line

"""The first hour of a new user, training and comparing: a short run that evaluates at its end, the best
model chosen by the task, and the smaller frictions of evaluate, compare and train."""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path

import pytest

from tests.solving import energies_one_by_one
from train.learning.config import TrainConfig
from train.learning.hyperparams import resolve_hyperparams
from train.learning.runs import saved_best, task_score
from train.learning.training import train


def tiny(run_dir: Path, total: int, eval_freq: int) -> TrainConfig:
    config = TrainConfig(total_timesteps=total, num_envs=4, eval_freq=eval_freq, eval_episodes=4,
                         run_dir=str(run_dir), progress=False)  # fmt: skip
    resolve_hyperparams(config, set())
    config.algo_kwargs.update(n_steps=32, batch_size=64)  # a rollout is 128 steps
    return config


def evaluated_steps(run_dir: Path) -> list[int]:
    with (run_dir / "evaluations.csv").open() as handle:
        return [int(row["timesteps"]) for row in csv.DictReader(handle)]


# 1. A run shorter than --eval-freq (the README's example was) evaluates at its end too, so best_model.zip is trained.


def test_a_run_shorter_than_the_evaluation_period_is_evaluated_at_its_last_step(tmp_path: Path) -> None:
    run_dir = train(tiny(tmp_path / "run", 256, eval_freq=10**6), command=["test"])
    assert evaluated_steps(run_dir) == [0, 256]
    state = json.loads((run_dir / "run_state.json").read_text())
    assert state["last_eval"] == 256 and state["finished"]
    assert (run_dir / "best_model.zip").is_file()


def test_the_evaluation_log_holds_no_nan_where_no_episode_arrives(tmp_path: Path) -> None:
    from train.learning.runs import read_evaluations

    run_dir = train(tiny(tmp_path / "run", 128, eval_freq=10**6), command=["test"])
    text = (run_dir / "evaluations.csv").read_text()
    rows = read_evaluations(run_dir / "evaluations.csv")
    assert rows[0]["success_rate"] == 0.0  # the untrained policy at step 0 arrives nowhere in 4 episodes
    assert "nan" not in text.lower() and "inf" not in text.lower()
    assert math.isnan(rows[0]["arrival_time_mean"]) and math.isfinite(rows[0]["energy_mean"])


def test_a_run_ending_on_an_evaluation_is_not_evaluated_twice(tmp_path: Path) -> None:
    run_dir = train(tiny(tmp_path / "run", 256, eval_freq=128), command=["test"])
    assert evaluated_steps(run_dir) == [0, 128, 256]


# 2. best_model.zip is chosen by the task: the share in time first, then the lower energy, then the return.


def row(success: float, energy: float, ret: float) -> dict[str, float]:
    return {"success_rate": success, "energy_mean": energy, "return_mean": ret}


def test_the_best_model_is_the_one_that_arrives_in_time_most_not_the_one_with_the_highest_return() -> None:
    assert task_score(row(0.56, 3.0, -14.96)) > task_score(row(0.09, 1.0, -13.17))  # a 600 k-step run
    assert task_score(row(0.5, 2.0, -20.0)) > task_score(row(0.5, 2.5, -10.0))  # equal share: the lower energy
    assert task_score(row(0.5, 2.0, -10.0)) > task_score(row(0.5, 2.0, -20.0))  # then the return
    # arriving nowhere, standing still would be the cheapest: the return decides
    assert task_score(row(0.0, 9.0, -10.0)) > task_score(row(0.0, 0.0, -20.0))
    assert task_score(row(0.1, math.nan, -20.0)) < task_score(row(0.1, 5.0, -20.0))


def test_a_run_saved_with_a_return_as_its_best_score_resumes_with_that_evaluations_task_score(tmp_path: Path) -> None:
    evaluations = tmp_path / "evaluations.csv"
    with evaluations.open("w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=["timesteps", "success_rate", "energy_mean", "return_mean"])
        writer.writeheader()
        writer.writerows([{"timesteps": 0, **row(0.0, 0.5, -20.0)}, {"timesteps": 200, **row(0.09, 1.0, -13.17)},
                          {"timesteps": 400, **row(0.56, 3.0, -14.96)}])  # fmt: skip
    older = saved_best({"best_score": -13.17}, evaluations)  # run_state.json before --threads
    assert older == task_score(row(0.09, 1.0, -13.17))
    assert saved_best({"best_score": -13.17, "best": row(0.56, 3.0, -14.96)}, evaluations) > older
    assert saved_best({}, evaluations) < task_score(row(0.0, 0.0, -1e9))


# 3. The optimum cache keeps every optimum solved, even when interrupted, and two commands may share it.


def test_the_optimum_cache_keeps_what_an_interrupted_command_solved(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:

    import train.evaluation.optimum as optimum
    from dwr_gym.params import EnvParams
    from train.evaluation.scenarios import make_scenario

    monkeypatch.setenv("DWR_GYM_CACHE", str(tmp_path))
    params, scenario = EnvParams(), make_scenario("random", n=6, seed=3)
    solved: list[object] = []

    def interrupted_after_three(job: object) -> float:
        if len(solved) == 3:
            raise KeyboardInterrupt
        solved.append(job)
        return float(len(solved))

    monkeypatch.setattr(optimum, "_solve_energies", energies_one_by_one(interrupted_after_three))
    monkeypatch.setattr(optimum, "BATCH_PER_WORKER", 3)  # the second batch is interrupted: the first one is kept
    with pytest.raises(KeyboardInterrupt):
        optimum.optimal_energies(params, scenario.starts, scenario.goals, workers=1)
    (cache_file,) = tmp_path.glob("optimal-energy-*.json")
    assert sorted(json.loads(cache_file.read_text()).values()) == [1.0, 2.0, 3.0]

    again: list[object] = []
    monkeypatch.setattr(optimum, "_solve_energies", energies_one_by_one(lambda job: again.append(job) or 7.0))
    energies, _ = optimum.optimal_energies(params, scenario.starts, scenario.goals, workers=1)
    assert len(again) == 3 and sorted(energies) == [1.0, 2.0, 3.0, 7.0, 7.0, 7.0]


def test_two_commands_caching_at_once_keep_each_others_optima(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    import train.evaluation.optimum as optimum
    from dwr_gym.params import EnvParams
    from train.evaluation.scenarios import make_scenario

    monkeypatch.setenv("DWR_GYM_CACHE", str(tmp_path))
    params, scenario = EnvParams(), make_scenario("random", n=4, seed=5)
    path = optimum._cache_file(params, True)

    written: list[str] = []

    def solved_while_another_writes(job: object) -> float:
        written.append(f"another command's {len(written)}")
        optimum._merge_into_cache(path, {written[-1]: 0.5})
        return 2.0

    monkeypatch.setattr(optimum, "_solve_energies", energies_one_by_one(solved_while_another_writes))
    optimum.optimal_energies(params, scenario.starts, scenario.goals, workers=1)
    cache = json.loads(path.read_text())
    assert set(written) < set(cache) and len(written) == 4 and list(cache.values()).count(2.0) == 4


def test_the_cache_is_read_merged_and_replaced_under_one_exclusive_lock(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    """While one command merges its optima (reads, updates, replaces the file) or claims a batch, no other command
    can take the cache's lock, not even to read: the read-modify-write is whole. The lock is let go afterwards."""
    fcntl = pytest.importorskip("fcntl")
    import train.evaluation.optimum as optimum
    from dwr_gym.params import EnvParams

    monkeypatch.setenv("DWR_GYM_CACHE", str(tmp_path))
    path = optimum._cache_file(EnvParams(), True)

    def others_can_lock() -> bool:
        with path.with_suffix(".lock").open("a") as handle:  # another open file: as another process holds it
            try:
                fcntl.flock(handle, fcntl.LOCK_SH | fcntl.LOCK_NB)  # refused only while the lock is exclusive
            except BlockingIOError:
                return False
            fcntl.flock(handle, fcntl.LOCK_UN)
            return True

    replace, held = optimum._replace, []

    def watched(target: Path, data: dict) -> None:
        held.append((target.suffix, not others_can_lock()))
        replace(target, data)

    monkeypatch.setattr(optimum, "_replace", watched)
    optimum._merge_into_cache(path, {"a": 1.0})
    optimum._claim(path, ["a", "b", "c"], 1)
    optimum._merge_into_cache(path, {"b": 2.0}, release=True)
    assert held == [(".json", True), (".claims", True), (".claims", True), (".json", True), (".claims", True)]
    assert others_can_lock() and json.loads(path.read_text()) == {"a": 1.0, "b": 2.0}
    with optimum._locked(path):
        assert not others_can_lock()
    assert others_can_lock()


def test_two_commands_solving_the_same_episodes_share_the_work(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    import os
    import subprocess
    import sys

    import train.evaluation.optimum as optimum
    from dwr_gym.params import EnvParams
    from train.evaluation.scenarios import make_scenario

    monkeypatch.setenv("DWR_GYM_CACHE", str(tmp_path))
    params, scenario = EnvParams(), make_scenario("random", n=6, seed=7)
    keys = [optimum._start_key(s, params.T_con) for s in optimum.goal_frame_starts(scenario.starts, scenario.goals)]
    path = optimum._cache_file(params, True)
    ended = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True)
    other, dead = os.getppid(), int(ended.stdout)  # a running process, and one that has ended
    path.parent.mkdir(parents=True, exist_ok=True)
    path.with_suffix(".claims").write_text(json.dumps({keys[0]: other, keys[1]: other, keys[2]: dead}))
    solved: list[object] = []

    def solve(job: object) -> float:
        solved.append(job)
        if len(solved) == 4:  # meanwhile the other command finishes the two episodes it claimed
            optimum._merge_into_cache(path, {keys[0]: 10.0, keys[1]: 11.0})
        return 1.0

    monkeypatch.setattr(optimum, "_solve_energies", energies_one_by_one(solve))
    energies, _ = optimum.optimal_energies(params, scenario.starts, scenario.goals, workers=1)
    assert len(solved) == 4  # the dead process's claim is taken over, the running one's left to it
    assert list(energies) == [10.0, 11.0, 1.0, 1.0, 1.0, 1.0]
    assert json.loads(path.with_suffix(".claims").read_text()) == {}


# 3. Ctrl-C in evaluate and compare: one line, the finished sets' rows written, exit code 130.


@pytest.mark.parametrize("command, stem", [("evaluate", "evaluation"), ("compare", "comparison")])
def test_ctrl_c_in_evaluate_and_compare_writes_the_finished_sets_and_says_so_in_one_line(
    command: str, stem: str, monkeypatch: pytest.MonkeyPatch, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    import train.evaluation.evaluate as evaluate
    from train.cli import main

    finished = evaluate.evaluate_subset
    calls: list[str] = []

    def interrupted_on_the_second_set(policies: dict, scenario: object, *args: object) -> object:
        calls.append(scenario.name)  # type: ignore[attr-defined]
        if len(calls) == 2:
            raise KeyboardInterrupt
        return finished(policies, scenario, *args)  # type: ignore[arg-type]

    monkeypatch.setattr(evaluate, "evaluate_subset", interrupted_on_the_second_set)
    out = tmp_path / "out"
    code = main([command, "--controllers", "ptc", "pt-astolfi", "--scenarios", "paper-fig5", "random", "--n", "4",
                 "--optimum", "none", "--no-progress", "--out", str(out), "--agents", "train/pretrained/ppo"])  # fmt: skip
    assert code == 130
    err = capsys.readouterr().err.strip().splitlines()
    # evaluate runs the three policies as one set; compare runs the agent on its own env id, apart from the laws, so
    # the first set it finishes holds the two laws' rows
    finished_rows = 3 if command == "evaluate" else 2
    assert err[-1].startswith(f"interrupted: wrote the {finished_rows} rows finished so far"), err[-1]
    assert "Traceback" not in "".join(err)
    rows = json.loads((out / f"{stem}.json").read_text())
    assert {row["scenario"] for row in rows} == {"paper-fig5"} and len(rows) == finished_rows


# 4. The smaller frictions.


def test_evaluate_shows_the_range_a_per_episode_T_con_is_drawn_from_not_nan(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from train.cli import main

    assert main(["evaluate", "--controllers", "ptc", "--scenarios", "random", "--n", "3", "--optimum", "none",
                 "--no-progress", "--out", str(tmp_path)]) == 0  # fmt: skip
    printed = capsys.readouterr().out
    row = next(line for line in printed.splitlines() if line.startswith("random ") and " ptc " in line)
    assert "drawn in [10, 60]" in row and "nan" not in row.split("ptc")[0]
    assert "random, T_con drawn per episode in [10, 60] s" in printed


def test_a_mean_energy_ratio_over_few_episodes_says_how_many() -> None:
    from train.reporting.tables import EVAL_COLUMNS, format_table

    few = {"scenario": "random", "T_con": 20.0, "policy": "agent", "n": 200.0, "energy_ratio_mean": 1.34,
           "energy_ratio_episodes": 3.0}  # fmt: skip
    every = {**few, "policy": "ptc", "energy_ratio_mean": 2.56, "energy_ratio_episodes": 200.0}
    columns = [c for c in EVAL_COLUMNS if c[0] in few]
    table = format_table([few, every], columns).splitlines()
    assert table[2].split()[-2:] == ["1.34", "(3/200)"] and table[3].split()[-1] == "2.56"


def test_a_mistyped_flag_names_the_near_match_and_the_commands_help(capsys: pytest.CaptureFixture[str]) -> None:
    from train.cli import main

    with pytest.raises(SystemExit) as exit_:
        main(["train", "--total-timestep", "5"])
    error = capsys.readouterr().err.strip()
    assert exit_.value.code == 2 and len(error.splitlines()) == 1
    assert "--total-timestep 5 (did you mean --total-timesteps?) (see dwr-gym train --help)" in error


def test_an_unknown_hyperparameter_lists_the_accepted_ones(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from train.cli import main

    assert main(["train", "--hyperparams", "lr=1e-3", "--run-dir", str(tmp_path / "run")]) == 2
    error = capsys.readouterr().err
    assert "['lr'] are not accepted by PPO (did you mean learning_rate?); accepted: " in error
    assert {"learning_rate", "n_steps", "batch_size", "gamma"} <= set(error.split("accepted: ")[1].strip().split(", "))


def test_a_residual_on_the_optimal_expert_warns_at_once_that_it_plans_per_robot(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    import train.learning.sb3.trainer as training

    def stop(config: TrainConfig) -> None:
        raise RuntimeError("stopped before the first plan")

    monkeypatch.setattr(training, "make_training_env", stop)
    config = tiny(tmp_path / "run", 256, eval_freq=10**6)
    config.residual, config.expert = True, "optimal"
    with pytest.raises(RuntimeError, match="stopped before the first plan"):
        train(config, command=["test"])
    assert "note: --expert optimal solves a minimum-energy plan with CasADi for each robot" in capsys.readouterr().err


@pytest.mark.parametrize("command", ["evaluate", "compare", "robustness"])
def test_a_command_that_stops_early_leaves_no_empty_results_folder(
    command: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from train.cli import main

    monkeypatch.chdir(tmp_path)
    assert main([command, "--agents", "missing.zip"]) == 2
    assert list(tmp_path.iterdir()) == []

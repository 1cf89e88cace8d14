"""dwr-gym sweep: search spaces, the summary over seeds, the best configuration as rl-zoo3 YAML, a sweep on Ray."""

from __future__ import annotations

import csv
from pathlib import Path

import pytest

from train.learning.config import ConfigError, TrainConfig
from train.learning.hyperparams import resolve_hyperparams
from train.learning.sweep import parse_param, sample_configurations, summarize, zoo_yaml


def test_parse_param_choices_and_ranges() -> None:
    assert parse_param("n_steps=128,256") == ("n_steps", {"kind": "choice", "values": [128, 256]})
    assert parse_param("learning_rate=loguniform:1e-4:1e-3") == (
        "learning_rate", {"kind": "loguniform", "low": 1e-4, "high": 1e-3})  # fmt: skip
    for bad in ("n_steps", "gamma=uniform:1:0", "learning_rate=loguniform:0:1", "gamma=uniform:a:b"):
        with pytest.raises(ConfigError, match="--param"):
            parse_param(bad)


def test_grid_crosses_choices_and_random_is_seeded_within_ranges() -> None:
    space = dict(parse_param(p) for p in ("n_steps=128,256", "n_epochs=5,10,20"))
    assert len(sample_configurations(space, "grid", 0, 0)) == 6
    space = dict(parse_param(p) for p in ("learning_rate=loguniform:1e-4:1e-3", "n_epochs=int:3:5"))
    draws = sample_configurations(space, "random", 50, seed=1)
    assert draws == sample_configurations(space, "random", 50, seed=1)
    assert all(1e-4 <= d["learning_rate"] <= 1e-3 and d["n_epochs"] in (3, 4, 5) for d in draws)
    with pytest.raises(ConfigError, match="grid"):
        sample_configurations(space, "grid", 0, 0)


def test_summary_is_mean_and_sd_over_seeds_best_first() -> None:
    def runs(*returns: float) -> dict:
        return {seed: [{"success_rate": 1.0, "return_mean": r, "energy_mean": 1.0, "arrival_time_mean": 5.0}]
                for seed, r in enumerate(returns)}  # fmt: skip

    groups = {"c000": {"hyperparams": {}, "runs": runs(1.0, 3.0)}, "c001": {"hyperparams": {}, "runs": runs(5.0, 9.0)}}
    table = summarize(groups, "return_mean")
    assert [row["config"] for row in table] == ["c001", "c000"]
    assert table[0]["return_mean_mean"] == 7.0 and table[0]["return_mean_sd"] == pytest.approx(2**0.5 * 2)


@pytest.mark.parametrize(("algo", "residual"), [("ppo", False), ("td3", True)])
def test_best_yaml_reads_back_as_the_same_configuration(tmp_path: Path, algo: str, residual: bool) -> None:
    config = resolve_hyperparams(TrainConfig(algo=algo, residual=residual, num_envs=8), set())
    config.algo_kwargs["learning_rate"] = 5e-4
    path = tmp_path / "best.yml"
    path.write_text(zoo_yaml(config))
    again = resolve_hyperparams(TrainConfig(algo=algo, residual=residual, hyperparams=str(path)), set())
    assert again.algo_kwargs == config.algo_kwargs and again.num_envs == 8


@pytest.mark.slow
@pytest.mark.own_process
def test_two_trial_sweep_on_local_ray_then_resume(tmp_path: Path) -> None:
    """Two configurations x one seed with a tiny budget on a local Ray, as a user runs it; --resume reuses them.

    Marked slow (two local Ray start-ups and two trainings: 52-64 s on 2 shared cores); .ci/run runs it as its
    second step, `pytest -m slow`."""
    pytest.importorskip("ray")
    from train.cli import main

    out = tmp_path / "sweep"
    args = ["sweep", "--param", "learning_rate=1e-3,3e-4", "--seeds", "1", "--total-timesteps", "256",
            "--num-envs", "2", "--eval-freq", "128", "--eval-episodes", "3", "--out", str(out)]  # fmt: skip
    assert main(args) == 0
    with (out / "trials.csv").open() as handle:
        rows = list(csv.DictReader(handle))
    assert sorted(row["hyperparams"] for row in rows) == ['{"learning_rate": 0.0003}', '{"learning_rate": 0.001}']
    assert (out / "learning_curves.png").stat().st_size > 0
    best = resolve_hyperparams(TrainConfig(hyperparams=str(out / "best.yml")), set())
    assert best.algo_kwargs["learning_rate"] in (1e-3, 3e-4) and best.total_timesteps == 256
    models = sorted(out.glob("runs/*/model.zip"))
    assert len(models) == 2
    stamps = [m.stat().st_mtime_ns for m in models]
    assert main(args) == 2  # refuses to overwrite a sweep
    assert main([*args, "--resume"]) == 0
    assert [m.stat().st_mtime_ns for m in models] == stamps  # finished runs are not trained again


@pytest.mark.parametrize(
    ("extra", "message"),
    [(["--param", "gamma=uniform:1:0"], "--param 'gamma=uniform:1:0' is invalid"),
     (["--param", "not_a_hyperparameter=1,2"], "not_a_hyperparameter"),
     (["--search", "optuna"], "--search optuna needs at least one --param"),
     (["--resources-per-trial", "cpu=-1"], "--resources-per-trial 'cpu=-1' is invalid"),
     (["--seeds", "0"], "--seeds 0 is invalid")],
)  # fmt: skip
def test_bad_sweep_input_is_one_line_before_ray_starts(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], extra: list[str], message: str
) -> None:
    pytest.importorskip("ray")
    from train.cli import main

    assert main(["sweep", "--out", str(tmp_path / "s"), *extra]) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and len(err.splitlines()) == 1
    assert not (tmp_path / "s").exists()

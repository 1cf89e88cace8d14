"""DAgger under randomised disturbances (train/learning/imitation/robust_dagger.py) on a tiny budget: the loop, the data it
aggregates, the student it rolls out, the run directory it leaves."""

from __future__ import annotations

import csv
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from stable_baselines3 import PPO

pytest.importorskip("casadi")

from dwr_gym import V1_DEFAULTS
from train.learning.imitation import robust_dagger
from train.learning.imitation.robust_dagger import RobustDaggerConfig, expert_arrival, run

#: One T_con and near starts: few and small plans (the T_con of tests/test_dagger.py's tiny run: the same solvers).
ENV_KWARGS = {**V1_DEFAULTS, "T_con_range": (10.0, 10.0), "start_distance": (0.3, 0.5)}


def tiny(**kwargs: Any) -> RobustDaggerConfig:
    return RobustDaggerConfig(**{"init_from": "", "episodes": 3, "dagger_rounds": 1, "dagger_episodes": 4,
                                 "replans_per_episode": 1, "epochs": 1, "workers": 1, "eval_episodes": 1,
                                 "eval_T_con": (10.0,), "net_arch": [16], "env_kwargs": ENV_KWARGS, **kwargs})  # fmt: skip


def test_a_tiny_robust_dagger_run_aggregates_disturbed_rollouts_and_leaves_a_robust_agent(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, ticking_clock: Any
) -> None:
    from baselines.estimation import FilteredPolicy
    from baselines.robust import RobustPTController
    from train.learning.agents import load_agent

    added: list[int] = []
    rolled: list[tuple[bool, int, type]] = []

    def counted(*args: Any, **kwargs: Any) -> Any:
        data = collect(*args, **kwargs)
        added.append(len(data[0]))
        return data

    def watched(policy: Any, params: Any, config: Any, n: int, rng: Any, disturbed: bool, record: bool = False) -> Any:
        rolled.append((disturbed, n, type(policy)))
        return roll(policy, params, config, n, rng, disturbed, record)

    collect, roll = robust_dagger.dagger_samples, robust_dagger.rollouts
    monkeypatch.setattr(robust_dagger, "dagger_samples", counted)
    monkeypatch.setattr(robust_dagger, "rollouts", watched)
    monkeypatch.setattr(robust_dagger, "time", ticking_clock)  # the run's clock: 10 s per reading
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        run_dir = run(tiny(), tmp_path / "runs" / "robust", ["test"])  # its parent made too
    rows = list(csv.DictReader((run_dir / "evaluations.csv").open()))
    assert [int(r["round"]) for r in rows] == [0, 1]
    wall = [float(r["wall_time"]) for r in rows]
    assert wall == [10.0, 20.0]  # seconds since the run began, at the end of each round
    assert (run_dir / "learning_curve.png").is_file() and (run_dir / "learning_curve_disturbed.png").is_file()
    samples = [int(r["samples"]) for r in rows]
    assert samples[0] > 0 and len(added) == 1 and added[0] > 0
    assert samples == [samples[0], samples[0] + added[0]]  # the demonstrations kept, the round's data added
    # the round: 3 of 4 rollouts (disturbed_fraction 0.75) on drawn robots, 1 nominal, the student behind the filter
    assert rolled == [(True, 3, FilteredPolicy), (False, 1, FilteredPolicy)]
    for prefix in ("", "disturbed_"):
        assert all(
            0.0 <= float(r[f"{prefix}success_T10"]) <= 1.0 and float(r[f"{prefix}energy_T10"]) >= 0 for r in rows
        )
    saved = yaml.safe_load((run_dir / "config.yaml").read_text())
    assert saved["robust_agent"] == {"plan_arrival": 0.8} and saved["robust_dagger"]["dagger_rounds"] == 1
    model = yaml.safe_load((run_dir / "config.yaml").read_text())["config"]
    assert model["num_envs"] == PPO.load(run_dir / "model.zip", device="cpu").n_envs  # the record is the model's
    label, agent = load_agent(run_dir)
    assert label == "robust" and isinstance(agent.controller, RobustPTController)
    assert agent.controller.cruise is not None  # the network drives the cruise
    action, _ = agent.predict(np.tile(np.float32([1.0, 1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 8.0, 1.0, 0.0]), (2, 1)))
    assert action.shape == (2, 2) and np.all(np.abs(action) <= 1.0)
    with pytest.raises(SystemExit, match="already holds a trained model"):
        run(tiny(), run_dir, ["test"])


def test_an_interrupted_run_keeps_the_model_of_its_last_round(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    def interrupted(*args: Any, **kwargs: Any) -> Any:
        raise KeyboardInterrupt

    monkeypatch.setattr(robust_dagger, "dagger_samples", interrupted)  # Ctrl-C in the first round
    with warnings.catch_warnings(), pytest.raises(KeyboardInterrupt):
        warnings.simplefilter("ignore")
        run(tiny(), tmp_path / "robust", ["test"])
    rows = list(csv.DictReader((tmp_path / "robust" / "evaluations.csv").open()))
    assert [int(r["round"]) for r in rows] == [0] and (tmp_path / "robust" / "model.zip").is_file()


def test_the_expert_plans_to_its_arrival_or_as_early_as_the_limits_allow_once_behind() -> None:
    config = RobustDaggerConfig(plan_arrival=0.8, hold_steps=5)
    assert expert_arrival(config, 20.0, 4.0, 3.0) == pytest.approx(12.0)  # 0.8 * 20 - 4: on schedule
    assert expert_arrival(config, 20.0, 14.0, 3.0) == pytest.approx(3.3)  # behind: 1.1 x the least time
    assert expert_arrival(config, 20.0, 19.0, 0.1) == pytest.approx(1.0)  # never under 4 intervals of 5 x 0.05 s


def test_a_bad_distribution_keyword_fails_before_any_work(tmp_path: Path) -> None:
    with pytest.raises(TypeError, match="nope"):
        run(tiny(distribution={"nope": 1}), tmp_path / "bad", ["test"])
    assert not (tmp_path / "bad").exists()


def test_the_rollouts_run_each_episode_with_the_T_con_they_return() -> None:
    """v1 draws T_con per episode: each rollout episode runs to the T_con returned with it (the samples' labels and the
    learning curve read it), whether the robot is disturbed or not."""
    from dwr_gym.params import EnvParams

    class Still:
        def predict(self, observation: Any, *args: Any, **kwargs: Any) -> Any:
            return np.zeros((len(observation), 2), np.float32), None

    params = EnvParams.from_kwargs(**{**ENV_KWARGS, "T_con_range": (5.0, 15.0)})
    for disturbed in (False, True):
        result, starts, T_con = robust_dagger.rollouts(Still(), params, RobustDaggerConfig(), 3,
                                                       np.random.default_rng(1), disturbed)  # fmt: skip
        assert len(set(T_con.tolist())) == 3 and starts.shape == (3, 3)
        np.testing.assert_array_equal(result.T_con, T_con)

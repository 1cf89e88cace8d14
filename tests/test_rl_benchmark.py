"""The RL options of dwr-gym train (action repeat, normalisation, TQC/CrossQ) and the benchmark protocol."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

from train.cli import main
from train.learning.benchmark import Entry, parse_entry, run_benchmark
from train.learning.config import ConfigError
from train.learning.wrappers import ActionRepeatPolicy, ActionRepeatVecEnv
from train.reporting.rl_benchmark import aggregate, iqm_interval, table

TINY_PPO = "num_envs=4,hyperparams={n_steps: 32, batch_size: 64}"


def test_a_held_action_is_the_env_stepped_k_times_with_it_and_the_rewards_summed() -> None:
    from dwr_gym.sb3 import make_sb3_vec_env

    held, plain = ActionRepeatVecEnv(make_sb3_vec_env(3, seed=5), 4), make_sb3_vec_env(3, seed=5)
    held.reset(), plain.reset()
    action = np.array([[0.3, -0.2], [1.0, 1.0], [-0.5, 0.1]], dtype=np.float32)
    obs, reward, done, _ = held.step(action)
    total = np.zeros(3)
    for _ in range(4):
        plain_obs, r, _, _ = plain.step(action)
        total += r
    np.testing.assert_allclose(obs, plain_obs)
    np.testing.assert_allclose(reward, total, rtol=1e-5)
    assert not done.any()


def test_the_repeat_policy_decides_only_every_k_periods() -> None:
    class Counter:
        calls = 0

        def predict(self, obs, state=None, episode_start=None, deterministic=True):
            Counter.calls += 1
            return np.full((len(obs), 2), float(Counter.calls), dtype=np.float32), state

    policy = ActionRepeatPolicy(Counter(), dt=0.05, repeat=3)
    obs = np.zeros((2, 10), dtype=np.float32)
    obs[:, 7] = 20.0  # T_con
    actions = []
    for step in range(7):
        obs[:, 6] = step * 0.05 / 20.0  # time fraction
        actions.append(policy.predict(obs)[0][0, 0])
    assert actions == [1.0, 1.0, 1.0, 4.0, 4.0, 4.0, 7.0]


def test_an_agent_trained_on_normalised_observations_acts_on_raw_ones_after_loading(tmp_path: Path) -> None:
    from stable_baselines3 import PPO

    from train.learning.agents import load_agent
    from train.learning.runs import AgentLoadError

    run = tmp_path / "run"
    argv = ["train", "--total-timesteps", "128", "--num-envs", "4", "--hyperparams", "n_steps=32", "batch_size=64",
            "--normalize-obs", "--action-repeat", "2", "--eval-freq", "1000", "--eval-episodes", "2",
            "--run-dir", str(run), "--no-progress"]  # fmt: skip
    assert main(argv) == 0
    stats = np.load(run / "model_obs_norm.npz")
    assert stats["var"].shape == (10,) and not np.allclose(stats["mean"], 0.0)
    obs = np.random.default_rng(0).uniform(0.1, 1.0, (5, 10)).astype(np.float32)
    model = PPO.load(run / "model.zip", device="cpu")
    normalised = np.clip((obs - stats["mean"]) / np.sqrt(stats["var"] + stats["eps"]), -stats["clip"], stats["clip"])
    _, policy = load_agent(run)
    np.testing.assert_allclose(
        policy.predict(obs)[0], model.predict(normalised.astype(np.float32), deterministic=True)[0], rtol=1e-6
    )
    (run / "model_obs_norm.npz").unlink()
    with pytest.raises(AgentLoadError, match="normalize-obs"):
        load_agent(run)


@pytest.mark.parametrize("algo", ["tqc", "crossq"])
def test_tqc_and_crossq_train_and_load(algo: str, tmp_path: Path) -> None:
    from train.learning.agents import load_agent

    run = tmp_path / algo
    argv = ["train", "--algo", algo, "--total-timesteps", "64", "--num-envs", "4", "--hyperparams",
            "learning_starts=16", "batch_size=16", "--eval-freq", "1000", "--eval-episodes", "2",
            "--run-dir", str(run), "--no-progress"]  # fmt: skip
    assert main(argv) == 0
    assert load_agent(run)[1].predict(np.zeros((2, 10), dtype=np.float32))[0].shape == (2, 2)


def test_agent_specs_are_parsed_or_refused_in_one_line() -> None:
    entry = parse_entry("ppo-rep5:action_repeat=5,normalize_obs=true")
    assert entry.options == {"algo": "ppo", "action_repeat": 5, "normalize_obs": True}
    assert parse_entry("residual-ppo").options["expert"] == "ptc"
    for bad in ("nonsense", "ppo:no_such_option=1", "ppo:action_repeat"):
        with pytest.raises(ConfigError, match="invalid"):
            parse_entry(bad)


def test_iqm_is_the_mean_of_the_middle_half_with_an_interval_around_it() -> None:
    result = iqm_interval([0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0])
    assert result["iqm"] == pytest.approx(3.5)
    assert result["low"] < 3.5 < result["high"] and result["n"] == 8
    assert iqm_interval([None, float("nan")])["iqm"] is None


def test_the_protocol_trains_evaluates_and_aggregates_any_policy_over_seeds(tmp_path: Path) -> None:
    from baselines.expert import ExpertPolicy
    from baselines.registry import make_controller

    def make(seed: int, run_dir: Path) -> ExpertPolicy:  # a user's "algorithm": anything with predict(obs)
        return ExpertPolicy(make_controller("ptc"), 0.5, 2.0)

    entries = [Entry("my-ptc", make=make), parse_entry(f"tiny:algo=ppo,{TINY_PPO}")]
    budget = {"env_steps": 128, "eval_freq": 128, "eval_episodes": 4, "disturbed_episodes": 2}
    results = run_benchmark(entries[:1], [0, 1], tmp_path, budget) + run_benchmark(entries[1:], [0], tmp_path, budget)
    assert [(r["entry"], r["seed"]) for r in results] == [("my-ptc", 0), ("my-ptc", 1), ("tiny", 0)]
    assert set(results[0]["sets"]) == {"random", "disturbed", "fault", "delay", "noise", "T_con=10", "T_con=20",
                                       "T_con=40", "T_con=60"}  # fmt: skip
    assert results[0]["sets"]["T_con=10"]["in_time"] == 1.0  # PTC at the shortest deadline, apart from the range
    assert results[0]["sets"]["random"]["in_time"] == 1.0 and results[0]["sets"]["random"]["energy_ratio"] > 1.0
    assert [row["env_steps"] for row in results[2]["curve"]] == [0, 128] and results[2]["env_steps"] == 128
    summary = aggregate(results)
    assert summary["my-ptc"]["sets"]["random"]["in_time"]["iqm"] == 1.0
    assert "| my-ptc | 2 | - |" in table(summary) and "| 1.000 [1.000, 1.000] |" in table(summary)
    # a finished run is not run again: the results are read back
    (tmp_path / "results" / "tiny-seed0.json").write_text(json.dumps({**results[2], "seconds": -1.0}))
    assert "train" in json.dumps(
        yaml.safe_load((tmp_path / "runs" / "tiny-seed0" / "config.yaml").read_text())["command"]
    )
    assert run_benchmark(entries[1:], [0], tmp_path, budget)[0]["seconds"] == -1.0


def test_the_command_refuses_an_unknown_agent_in_one_line(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["benchmark", "--agents", "nonsense", "--out", "/nonexistent/x"]) == 2
    assert len(capsys.readouterr().err.strip().splitlines()) == 1


def test_a_sweep_searches_the_initial_exploration_noise_inside_policy_kwargs(tmp_path: Path) -> None:
    from train.learning.sweep import trial_config

    config = trial_config({"algo": "ppo", "residual": True}, {"log_std_init": -3.0, "learning_rate": 1e-4}, 0, tmp_path)
    assert config.algo_kwargs["policy_kwargs"] == {"net_arch": [64, 64], "log_std_init": -3.0}
    assert config.algo_kwargs["learning_rate"] == 1e-4


def test_every_shipped_agent_says_what_it_learned_from_and_what_acts_beside_it() -> None:
    from train.learning.agents import PRETRAINED, pretrained_paths
    from train.learning.config import LEARNED_FROM

    assert set(pretrained_paths()) == set(PRETRAINED)
    for name, path in PRETRAINED.items():
        data = yaml.safe_load((path / "config.yaml").read_text())
        assert data["learned_from"] in LEARNED_FROM, name
        assert isinstance(data["runtime"], list), name
        residual = data["config"].get("residual", False)
        assert residual == any(item.startswith("expert: ") for item in data["runtime"]), name


def test_docs_keep_the_agents_of_earlier_runs_and_take_this_runs_rows(tmp_path: Path) -> None:
    from train.commands.benchmark import merged_with_docs

    old = {"budget": {"env_steps": 1}, "versions": {"jax": "1"}, "summary": {"a": {"n": 5}, "b": {"n": 5}},
           "best_seed": {"a": 0, "b": 3}}  # fmt: skip
    (tmp_path / "benchmark.json").write_text(json.dumps(old))
    new = {"budget": {"env_steps": 2}, "versions": {"jax": "2"}, "summary": {"b": {"n": 2}, "c": {"n": 5}},
           "best_seed": {"b": 1, "c": 4}, "references": {}}  # fmt: skip
    merged = merged_with_docs(new, tmp_path)
    assert merged["summary"] == {"a": {"n": 5}, "b": {"n": 2}, "c": {"n": 5}}
    assert merged["best_seed"] == {"a": 0, "b": 1, "c": 4}
    assert merged["budgets"] == {"a": {"env_steps": 1}, "b": {"env_steps": 2}, "c": {"env_steps": 2}}
    assert merged["agent_versions"] == {"a": {"jax": "1"}, "b": {"jax": "2"}, "c": {"jax": "2"}}
    assert merged_with_docs(new, tmp_path / "none") is new


@pytest.mark.parametrize(
    "text",
    [
        "sac-utd:algo=sac,hyperparams=train/hyperparams/sac_tuned.yml,hyperparam_overrides={gradient_steps: 8}",
        "ppo-x:backend=jax,hyperparams={log_std_final: -2.5, gamma: 1.0, learning_rate: lin_3e-4},action_repeat=2",
        "res:algo=ppo,residual=true,expert=ptc,hyperparams={policy_kwargs: 'dict(net_arch=[64, 64], log_std_init=-3.0)'}",
        "ppo-ckpt:checkpoint_freq=500",  # the benchmark's evaluations set the checkpoints: 2048, not 500
    ],
)
def test_a_runs_recorded_recipe_trains_the_same_configuration(
    text: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """config.yaml's command (what the retrain-pretrained entry runs again) is a valid dwr-gym train command
    that resolves to the configuration the benchmark trained: the YAML file and the overrides together."""
    import train.learning.training as training
    from train.cli import main
    from train.learning.benchmark import train_command, train_config

    entry = parse_entry(text)
    budget = {"env_steps": 4096, "eval_freq": 2048, "eval_episodes": 4, "time_limit": 600.0}
    config = train_config(entry, 1, tmp_path / "run", budget)
    captured = []
    monkeypatch.setattr(training, "train", lambda cfg, command=None: captured.append(cfg))
    command = train_command(entry, config)
    assert command[:2] == ["dwr-gym", "train"] and main(command[1:]) == 0
    (again,) = captured
    for name in ("algo", "backend", "residual", "expert", "action_repeat", "hyperparams", "total_timesteps", "seed",
                 "eval_freq", "checkpoint_freq", "eval_episodes", "eval_seed", "time_limit", "env_id"):  # fmt: skip
        assert getattr(again, name) == getattr(config, name), name
    assert again.algo_kwargs == config.algo_kwargs


def test_the_reference_laws_run_on_the_agents_env_id_and_v2_agents_ship_under_their_version() -> None:
    """A table of v2 agents puts the laws beside them on v2 (in time there: at the goal at T_con), a mixed table
    on v1; shipped v2 entries keep their version in their directory name."""
    from benchmarks.learning.ship_rl_agents import shipped_name
    from train.commands.benchmark import references_env
    from train.learning.benchmark import parse_entry

    v2 = [parse_entry("es-residual-v2"), parse_entry("ppo-jax-fixed-noise-v2")]
    assert references_env(v2) == "DWRPointStabilization-v2"
    assert references_env([*v2, parse_entry("ppo-jax")]) == "DWRPointStabilization-v1"
    assert references_env([parse_entry("ppo")]) == "DWRPointStabilization-v1"
    assert shipped_name("es-residual-v2") == "es_residual_v2" and shipped_name("sac-tuned") == "sac_tuned_v1"


def test_shipped_configs_name_no_directory_of_the_machine_that_trained_them() -> None:
    """Shipping makes the benchmark's absolute hyperparameter paths relative to the repository, and no shipped
    config.yaml names an absolute path inside a checkout."""
    from pathlib import Path

    from benchmarks.learning.ship_rl_agents import ROOT, portable_config

    text = "hyperparams: /tmp/wt3/train/hyperparams/apg.yml\nrun_dir: /tmp/wt3/results/x\nother: /data/a.yml\n"
    assert portable_config(text, Path("/tmp/wt3")) == (
        "hyperparams: train/hyperparams/apg.yml\nrun_dir: results/x\nother: /data/a.yml\n"
    )
    # a run made in another checkout: its hyperparameter files too
    assert portable_config("- /work/copy/train/hyperparams/a.yml\n", Path("/tmp/wt3")) == "- train/hyperparams/a.yml\n"
    for config in sorted((ROOT / "train" / "pretrained").glob("*/config.yaml")):
        assert "/train/hyperparams/" not in config.read_text().replace(" train/hyperparams/", ""), config


def test_the_benchmarks_evaluation_rolls_the_nominal_set_out_once_when_e_over_opt_takes_all_its_episodes(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """With n_optimum >= n the nominal set's E/opt is over its own n episodes, measured in the one rollout of it (a
    second would cost its time again); the disturbed sets stay without E/opt. Each rollout (E/opt's set of n_optimum
    episodes and the per-T_con sets too) is silent unless asked for its progress, which then goes to stderr."""
    import oracles

    from train.evaluation import benchmark

    oracles.use_stand_in_optimum(monkeypatch)
    rolled: list[tuple[str, int, str]] = []
    evaluate_sets = benchmark.evaluate_sets

    def counted(*args: Any, **kwargs: Any) -> list[dict[str, Any]]:  # (set, episodes, stderr) of each rollout
        rows = evaluate_sets(*args, **kwargs)
        rolled.append((args[1][0], args[2], capsys.readouterr().err))
        return rows

    monkeypatch.setattr(benchmark, "evaluate_sets", counted)
    for n_optimum in (2, 5):
        rolled.clear()
        sets = benchmark.evaluate_policy("ptc", n=2, n_disturbed=1, n_optimum=n_optimum, sets=("random", "delay"),
                                         per_T_con=())  # fmt: skip
        assert rolled == [("random", 2, ""), ("delay", 1, "")], (n_optimum, rolled)
        assert sets["delay"]["energy_ratio"] is None and sets["random"]["energy_ratio"] is not None
        alone = benchmark.evaluate_policy("ptc", n=2, n_disturbed=1, n_optimum=None, sets=("random",), per_T_con=())
        assert sets["random"] == alone["random"], (n_optimum, sets["random"], alone["random"])
    rolled.clear()
    benchmark.evaluate_policy("ptc", n=2, n_disturbed=1, n_optimum=1, sets=("random",), per_T_con=(10.0,),
                              n_per_T_con=1, progress=True)  # fmt: skip
    assert [(name, n) for name, n, _ in rolled] == [("random", 2), ("random", 1), ("random", 1)]
    assert all("%" in err for _, _, err in rolled), rolled


def test_a_summary_without_a_metric_gives_none_for_it_not_a_crash() -> None:
    """A rollout summary that lacks a measure (a row of another tool's, or one written before the measure existed)
    reads None there, as an undefined one does; the measures it holds are kept."""
    from train.evaluation.benchmark import metrics_of

    got = metrics_of({"success_rate": 0.75, "energy_mean": 2.5, "final_heading_error_mean": float("nan")})
    assert got == {"in_time": 0.75, "energy_ratio": None, "final_heading": None, "energy": 2.5}, got


def test_env_steps_that_an_entry_overrides_is_said(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """``--env-steps`` does not change an entry that names its own budget (its schedules are sized to it): the command
    says so, naming the entry, its budget and how to change it, instead of training another budget than asked."""
    code = main(["benchmark", "--agents", "apg-lagrangian-averaged-v2", "--env-steps", "1000", "--report-only",
                 "--out", str(tmp_path)])  # fmt: skip
    err = capsys.readouterr().err
    assert code == 2  # (nothing to report in an empty --out)
    assert "--env-steps 1000 leaves apg-lagrangian-averaged-v2 at its own 560,000,000 env steps" in err
    assert "apg-lagrangian-averaged-v2:total_timesteps=N" in err

"""DAgger on minimum-energy plans and the hand-over agents (train/learning/imitation/dagger.py,
train/learning/imitation/handover.py)."""

from __future__ import annotations

import warnings
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import pytest

pytest.importorskip("casadi")

from dwr_gym import V1_DEFAULTS
from dwr_gym.params import EnvParams
from train.learning.agents import load_agent
from train.learning.imitation.dagger import DaggerConfig, _solve, labelled_samples, run


def test_demonstration_samples_are_what_the_env_observes_when_the_plan_is_replayed() -> None:
    """The training pairs (observation, command) must be exactly the env's observations along the plan."""
    params = EnvParams.from_kwargs(**V1_DEFAULTS)
    start, T_con = (-1.2, 0.7, 2.5), 12.0
    plan = _solve((start, 0.85 * T_con, params.dt, params.u_max, params.omega_max, 5))
    assert plan is not None
    env = gym.make("DWRPointStabilization-v1")
    obs, _ = env.reset(seed=0, options={"start": start, "T_con": T_con})
    d0, e0 = float(obs[8]), float(obs[9])
    observations, actions = labelled_samples(plan, 0, T_con, d0, e0, params)  # type: ignore[misc]
    replayed, terminated = [obs], False
    for action in actions:
        obs, _, terminated, truncated, info = env.step(action)
        if terminated or truncated:
            break
        replayed.append(obs)
    assert terminated and info["is_success"] and info["time"] <= 0.85 * T_con + 1e-9
    np.testing.assert_allclose(np.array(replayed), observations[: len(replayed)], atol=1e-5)
    assert np.all(np.abs(actions) <= 1.0)


def test_a_tiny_cloning_run_aggregates_each_rounds_data_and_saves_an_agent_that_loads_and_acts(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, ticking_clock: Any
) -> None:
    """DAgger fits each round on all the data so far: the demonstrations and every round's re-planned labels."""
    import csv

    from train.learning.imitation import dagger

    added: list[int] = []

    def counted(*args, **kwargs):  # type: ignore[no-untyped-def]
        data = collect(*args, **kwargs)
        added.append(len(data[0]))
        return data

    collect = dagger.dagger_samples
    monkeypatch.setattr(dagger, "dagger_samples", counted)
    env_kwargs = {**V1_DEFAULTS, "T_con_range": (10.0, 10.0), "start_distance": (0.3, 0.5)}  # few solver builds
    config = DaggerConfig(episodes=4, dagger_rounds=2, dagger_episodes=2, replans_per_episode=1, epochs=1,
                             workers=1, eval_episodes=2, eval_T_con=(10.0,), env_kwargs=env_kwargs)  # fmt: skip
    monkeypatch.setattr(dagger, "time", ticking_clock)  # the run's clock: 10 s per reading
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        run_dir = run(config, tmp_path / "bc", ["test"])
    rows = list(csv.DictReader((run_dir / "evaluations.csv").open()))
    assert [int(r["round"]) for r in rows] == [0, 1, 2]  # one row per fit
    wall = [float(r["wall_time"]) for r in rows]
    assert wall == [10.0, 20.0, 30.0]  # seconds since the run began, at the end of each round
    assert (run_dir / "learning_curve.png").is_file()
    samples = [int(r["samples"]) for r in rows]
    assert len(added) == 2 and min(added) > 0 and samples[0] > 0
    assert samples == [samples[0], samples[0] + added[0], samples[0] + added[0] + added[1]]
    label, policy = load_agent(run_dir)
    action, _ = policy.predict(np.zeros((5, 10), np.float32), deterministic=True)
    assert label == "bc" and action.shape == (5, 2) and np.all(np.isfinite(action))
    with pytest.raises(SystemExit, match="already holds a trained model"):
        run(config, run_dir, ["test"])


class ConstantModel:
    """A stand-in network that always answers (0.7, -0.7)."""

    def predict(self, obs, state=None, episode_start=None, deterministic=True):  # type: ignore[no-untyped-def]
        return np.tile(np.float32([0.7, -0.7]), (np.asarray(obs).shape[0], 1)), state


def test_handover_policy_is_the_network_far_and_early_and_the_law_near_or_late() -> None:
    from baselines import ExpertPolicy, make_controller
    from train.learning.imitation.handover import HandoverPolicy

    law = ExpertPolicy(make_controller("pt-astolfi"), 0.5, 2.0)
    policy = HandoverPolicy(ConstantModel(), law, distance=0.05, time_fraction=0.9)
    obs = np.zeros((3, 10), np.float32)
    obs[:, 0], obs[:, 1], obs[:, 3], obs[:, 7], obs[:, 8] = [1.0, 0.02, 1.0], 1.0, 1.0, 20.0, 1.0
    obs[:, 6] = [0.5, 0.5, 0.95]  # far and early; near; late
    action, _ = policy.predict(obs)
    np.testing.assert_array_equal(action[0], np.float32([0.7, -0.7]))
    np.testing.assert_array_equal(action[1:], law.predict(obs[1:])[0])
    single, _ = policy.predict(obs[0])
    assert single.shape == (2,)
    behind = HandoverPolicy(ConstantModel(), law, distance=0.0, time_fraction=1.0, speed_margin=2.0)
    obs[0, 6] = 0.96  # 0.8 s left for 1 m at 0.5 m/s: less than 2 x the 2 s a straight line takes
    np.testing.assert_array_equal(behind.predict(obs[:1])[0], law.predict(obs[:1])[0])
    obs[0, 6] = 0.5  # 10 s left
    np.testing.assert_array_equal(behind.predict(obs[:1])[0][0], np.float32([0.7, -0.7]))
    with pytest.raises(ValueError, match="time_fraction"):
        HandoverPolicy(ConstantModel(), law, distance=0.05, time_fraction=0.0)


def network_run(tmp_path: Path) -> Path:
    """A run directory of a network cloned from the expert on v1: the shipped ``robust``'s, without its robust-pt."""
    import shutil

    import yaml

    run_dir = tmp_path / "agent"
    shutil.copytree(Path(__file__).resolve().parents[1] / "train" / "pretrained" / "robust", run_dir)
    data = yaml.safe_load((run_dir / "config.yaml").read_text())
    del data["robust_agent"]
    (run_dir / "config.yaml").write_text(yaml.safe_dump(data))
    return run_dir


def test_a_run_with_a_handover_section_loads_as_a_handover_policy_and_a_bad_one_is_refused(tmp_path) -> None:  # type: ignore[no-untyped-def]

    import yaml

    from train.learning.agents import AgentLoadError
    from train.learning.imitation.handover import HandoverPolicy

    run_dir = network_run(tmp_path)
    data = yaml.safe_load((run_dir / "config.yaml").read_text())
    data["handover"] = {"expert": "pt-astolfi", "distance": 0.05, "time_fraction": 0.9}
    (run_dir / "config.yaml").write_text(yaml.safe_dump(data))
    _, policy = load_agent(run_dir)
    assert isinstance(policy, HandoverPolicy) and policy.distance == 0.05 and policy.time_fraction == 0.9
    data["handover"]["expert"] = "nope"
    (run_dir / "config.yaml").write_text(yaml.safe_dump(data))
    with pytest.raises(AgentLoadError, match="handover"):
        load_agent(run_dir)


def test_a_composite_agent_comes_apart_so_that_its_network_is_reported_alone(tmp_path: Path) -> None:
    import yaml

    from train.learning.agents import AgentLoadError
    from train.learning.imitation.handover import HandoverPolicy

    run_dir = network_run(tmp_path)
    data = yaml.safe_load((run_dir / "config.yaml").read_text())
    data["handover"] = {"expert": "pt-astolfi", "distance": 0.0, "time_fraction": 0.8, "speed_margin": 3.0}
    (run_dir / "config.yaml").write_text(yaml.safe_dump(data))
    label, network = load_agent(run_dir, part="network")
    assert label == "agent (network alone)"
    assert not isinstance(network, HandoverPolicy)
    _, whole = load_agent(run_dir)
    assert isinstance(whole, HandoverPolicy) and type(whole.model) is type(network)
    with pytest.raises(AgentLoadError, match="part='finish'"):
        load_agent(run_dir, part="finish")


def test_the_module_command_line_builds_the_config_from_its_flags(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """`python -m train.learning.imitation.dagger` and `... robust_dagger`: every int, float and str field is a flag."""
    from train.learning.imitation import dagger, robust_dagger

    got: dict[str, object] = {}
    monkeypatch.setattr(dagger, "run", lambda config, run_dir, command: got.update(config=config, run_dir=run_dir,
                                                                                   command=command))  # fmt: skip
    dagger.main(["--run-dir", str(tmp_path / "a"), "--episodes", "7", "--arrival-fraction", "0.9",
                 "--env", "dwr_gym:DWRPointStabilization-v0", "--handover-expert", "ptc"])  # fmt: skip
    config = got["config"]
    assert isinstance(config, DaggerConfig) and got["run_dir"] == tmp_path / "a"
    assert (config.episodes, config.arrival_fraction, config.env_id, config.handover_expert) == (
        7, 0.9, "DWRPointStabilization-v0", "ptc")  # fmt: skip
    assert config.dagger_rounds == DaggerConfig().dagger_rounds  # the others keep their defaults
    assert got["command"][:3] == ["python", "-m", "train.learning.imitation.dagger"] and "--episodes" in got["command"]
    with pytest.raises(SystemExit) as exit_info:
        dagger.main(["--run-dir", str(tmp_path / "b"), "--env", "CartPole-v1"])
    assert exit_info.value.code == 2
    assert "--env 'CartPole-v1' is invalid" in capsys.readouterr().err

    monkeypatch.setattr(robust_dagger, "run", lambda config, run_dir, command: got.update(config=config))
    robust_dagger.main(["--run-dir", str(tmp_path / "c"), "--plan-arrival", "0.7", "--init-from", "", "--seed", "3"])
    config = got["config"]
    assert (config.plan_arrival, config.init_from, config.seed) == (0.7, "", 3)
    with pytest.raises(SystemExit):
        robust_dagger.main(["--run-dir", str(tmp_path / "d"), "--env", "nope"])


def test_handover_only_chooses_the_handover_of_a_trained_run_and_writes_it(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:

    import yaml

    from train.learning.imitation import dagger

    run_dir = network_run(tmp_path)
    chosen = {"expert": "pt-astolfi", "distance": 0.0, "time_fraction": 0.85, "speed_margin": 1.5, "selected_on": "x"}
    asked = []

    def select(model, config, params):  # type: ignore[no-untyped-def]
        asked.append((config.handover_expert, config.eval_episodes, params.T_con_range))
        return chosen, [{"tried": 1}]

    monkeypatch.setattr(dagger, "select_handover", select)
    dagger.main(
        ["--run-dir", str(run_dir), "--handover-only", "--handover-expert", "pt-astolfi", "--eval-episodes", "9"]
    )
    saved = yaml.safe_load((run_dir / "config.yaml").read_text())
    assert saved["handover"] == chosen and saved["handover_tried"] == [{"tried": 1}]
    assert saved["learned_from"] == "expert" and saved["runtime"] == ["handover: pt-astolfi"]  # beside the network
    assert asked[0][:2] == ("pt-astolfi", 9) and asked[0][2] is not None  # the run's own env (v1: T_con drawn)
    with pytest.raises(SystemExit, match="--handover-expert 'nope' is invalid"):
        dagger.main(["--run-dir", str(run_dir), "--handover-only", "--handover-expert", "nope"])
    with pytest.raises(SystemExit, match=r"holds no model\.zip"):
        dagger.main(["--run-dir", str(tmp_path / "empty"), "--handover-only", "--handover-expert", "ptc"])


def test_select_handover_takes_the_least_energy_among_those_in_time_and_on_heading_else_the_most_in_time(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The rule of select_handover's docstring, on made-up evaluations of the grid (no rollout)."""
    from train.learning.imitation import dagger

    def fake(table):  # type: ignore[no-untyped-def]
        def evaluate(policy, evaluated_on, T_cons, n, seed):  # type: ignore[no-untyped-def]
            assert evaluated_on is params  # the run's own env, not a default one
            success, heading, energy = table(policy.time_fraction, policy.speed_margin)
            return [{"T_con": T, "success": success, "heading": heading, "energy": energy / T} for T in T_cons]

        return evaluate

    config = DaggerConfig(handover_expert="pt-astolfi", eval_episodes=3, eval_T_con=(10.0, 20.0))
    params = EnvParams.from_kwargs(**V1_DEFAULTS)
    # good where fraction >= 0.85 and margin >= 1.5; the energy falls with the fraction, rises with the margin
    monkeypatch.setattr(dagger, "evaluate_by_T_con", fake(lambda f, m: (1.0 if f >= 0.85 and m >= 1.5 else 0.9,
                                                                        0.05, 10.0 - 5 * f + m)))  # fmt: skip
    chosen, tried = dagger.select_handover(ConstantModel(), config, params)
    assert len(tried) == len(dagger.HANDOVER_GRID) == 16
    assert (chosen["expert"], chosen["time_fraction"], chosen["speed_margin"]) == ("pt-astolfi", 1.0, 1.5)
    assert chosen["selected_on"] == "3 random starts per T_con in [10.0, 20.0], seed 12345"
    assert tried[0]["energy"] == pytest.approx(10.0 - 4.0 + 0.0)  # energy x T_con, averaged over the T_cons
    # none good: the most often in time (then the least heading error)
    monkeypatch.setattr(dagger, "evaluate_by_T_con", fake(lambda f, m: (0.5 + 0.1 * m, 0.3 - 0.1 * f, 1.0)))
    chosen, _ = dagger.select_handover(ConstantModel(), config, params)
    assert (chosen["time_fraction"], chosen["speed_margin"]) == (1.0, 3.0)


def test_dagger_rounds_re_plan_from_visited_states_to_the_original_target_or_most_of_the_time_left(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A robot that stands still visits its start at every step t: each re-plan from there arrives at
    0.85 T_con - t while that is at least half the time left, else at 0.85 (T_con - t); none of one interval or less."""
    from train.learning.imitation import dagger

    class Still:
        def predict(self, obs, state=None, episode_start=None, deterministic=True):  # type: ignore[no-untyped-def]
            return np.zeros((len(obs), 2), np.float32), state

    jobs: list = []
    monkeypatch.setattr(dagger, "solve_plans", lambda batch, workers: jobs.extend(batch) or [None] * len(batch))
    params = EnvParams.from_kwargs(**{**V1_DEFAULTS, "T_con_range": (10.0, 10.0)})
    config = DaggerConfig(dagger_episodes=40, replans_per_episode=3, hold_steps=5)
    data = dagger.dagger_samples(Still(), config, params, np.random.default_rng(0))
    assert len(data[0]) == 0 and len(jobs) > 60  # no plan solved (all None): no samples
    late = 0
    for start, arrival, dt, u_max, omega_max, hold in jobs:
        assert (dt, u_max, omega_max, hold) == (0.05, 0.5, 2.0, 5) and np.hypot(*start[:2]) > params.goal_tolerance
        assert arrival > 0.25  # a re-plan of one interval or less is not asked for
        t_on_target, t_late = 8.5 - arrival, 10.0 - arrival / 0.85

        def a_step(t: float) -> bool:
            return 0.0 < t < 15.0 and abs(t / 0.05 - round(t / 0.05)) < 1e-6

        on_target = a_step(t_on_target) and t_on_target <= 7.0 + 1e-9  # 0.85 T - t >= 0.5 (T - t) while t <= 7 s
        behind = a_step(t_late) and t_late > 7.0
        assert on_target or behind, arrival
        late += behind
    assert 0 < late < len(jobs)  # both rules were met


def test_plans_solved_in_worker_processes_are_those_solved_in_order() -> None:
    from train.learning.imitation.dagger import solve_plans

    jobs = [((-0.4, 0.2, 0.3), 3.0, 0.05, 0.5, 2.0, 5), ((0.3, -0.3, 1.0), 2.0, 0.05, 0.5, 2.0, 5),
            ((0.2, 0.0, 0.0), 0.1, 0.05, 0.5, 2.0, 5)]  # fmt: skip  # the last one infeasible: None
    serial, parallel = solve_plans(jobs, 1), solve_plans(jobs, 2)
    assert serial[2] is None and parallel[2] is None
    for a, b in zip(serial[:2], parallel[:2], strict=True):
        np.testing.assert_allclose(a[0], b[0], atol=1e-9)
        np.testing.assert_allclose(a[1], b[1], atol=1e-9)


def test_fit_regresses_the_actors_mean_action_onto_the_demonstrated_commands() -> None:
    """Behaviour cloning's step: after fit the network's deterministic actions are much closer to the demonstrated
    commands (here an affine law of the observation) than before, and the loss it returns is a mean squared error."""
    import torch

    from train.learning.imitation.dagger import fit, make_model

    config = DaggerConfig(epochs=30, batch_size=32, net_arch=[32], learning_rate=3e-3)
    rng = np.random.default_rng(0)
    obs = rng.uniform(-1.0, 1.0, (256, 10)).astype(np.float32)
    target = (np.float32([0.3, -0.2]) + 0.4 * obs[:, 1:3]).astype(np.float32)
    torch.manual_seed(0)
    model = make_model(config)

    def error() -> float:
        return float(np.mean((model.predict(obs, deterministic=True)[0] - target) ** 2))

    before = error()
    loss = fit(model, (obs, target), config, rng)
    after = error()
    assert after < 0.1 * before
    assert 0.0 <= loss < 0.2 * before

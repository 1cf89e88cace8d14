"""Per-episode prescribed time (T_con_range, reset option), DWRPointStabilization-v1's reward, and v0 unchanged."""

from __future__ import annotations

import dataclasses
import math
import warnings

import gymnasium as gym
import numpy as np
import pytest

import dwr_gym  # noqa: F401  (registers the envs)
from train.evaluation.evaluate import evaluate
from train.evaluation.scenarios import make_scenario

V0, V1 = "DWRPointStabilization-v0", "DWRPointStabilization-v1"


def make(env_id: str, **kwargs: object) -> gym.Env:  # type: ignore[type-arg]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)  # v0 is out of date now that v1 exists
        return gym.make(env_id, **kwargs)


def random_actions_rollout(env_id: str, kwargs: dict[str, object], seed: int, steps: int = 700) -> tuple[int, float]:
    """(episodes ended, total reward) of a seeded single env under seeded random actions."""
    env = make(env_id, **kwargs)
    env.reset(seed=seed)
    rng = np.random.default_rng(seed)
    rewards, ended = [], 0
    for _ in range(steps):
        _, reward, terminated, truncated, _ = env.step(rng.uniform(-1, 1, 2).astype(np.float32))
        rewards.append(reward)
        if terminated or truncated:
            ended += 1
            env.reset()
    return ended, float(np.sum(rewards))


@pytest.mark.parametrize(
    ("kwargs", "seed", "total"),
    [
        ({}, 0, -204.6475053950984),
        ({"T_con": 5.0, "dt": 0.1}, 1, -284.4973671801804),
        ({"observation_noise": 0.01, "actuation_noise": 0.1}, 2, -74.14659687781885),
    ],
)
def test_v0_returns_are_what_they_were(kwargs: dict[str, object], seed: int, total: float) -> None:
    """Total rewards of seeded v0 episodes, pinned before v1 and T_con_range existed (bit for bit until the
    env-speed work, which keeps them to 1e-12; tests/test_golden.py pins whole trajectories)."""
    assert random_actions_rollout(V0, kwargs, seed)[1] == pytest.approx(total, rel=0, abs=1e-9)


def test_v0_returns_of_the_experts_are_unchanged() -> None:
    results = evaluate({"ptc": "ptc", "astolfi": "astolfi"}, make_scenario("random", n=20, seed=5))
    assert float(results["ptc"].episode_return.sum()) == pytest.approx(82.30626649521052, rel=0, abs=1e-9)
    assert float(results["astolfi"].episode_return.sum()) == pytest.approx(253.4081652078928, rel=0, abs=1e-9)


def test_v1_draws_T_con_per_episode_observes_it_and_reports_it() -> None:
    env = make(V1)
    assert env.observation_space.high[7] == 60.0 and env.spec is not None and env.spec.max_episode_steps == 1800
    seen = []
    for seed in range(20):
        obs, info = env.reset(seed=seed)
        assert 10.0 <= info["T_con"] <= 60.0 and obs[7] == np.float32(info["T_con"])
        seen.append(info["T_con"])
    assert np.ptp(seen) > 20.0  # spread over the range
    obs, info = env.reset(seed=0, options={"T_con": 33.0})
    assert info["T_con"] == 33.0 and obs[7] == 33.0
    _, _, _, _, info = env.step(np.zeros(2, np.float32))
    assert info["T_con"] == 33.0 and info["time"] == pytest.approx(0.05)


def test_an_episode_truncates_at_its_own_horizon() -> None:
    env = make(V1)
    env.reset(seed=0, options={"T_con": 10.0, "start": (1.0, 0.0, 0.0)})
    steps, truncated = 0, False
    while not truncated:
        _, reward, terminated, truncated, _ = env.step(np.zeros(2, np.float32))
        steps += 1
        assert not terminated
    assert steps == 300 and reward == pytest.approx(-0.05 + 0.0)  # late penalty per step after T_con


def test_vector_env_draws_per_sub_env_as_the_single_envs_do() -> None:
    envs = gym.make_vec(V1, num_envs=4)
    _, infos = envs.reset(seed=7)
    singles = [make(V1).reset(seed=7 + i)[1]["T_con"] for i in range(4)]
    np.testing.assert_array_equal(infos["T_con"], singles)
    _, infos = envs.reset(options={"T_con": [11.0, 22.0, 33.0, 44.0]})
    np.testing.assert_array_equal(infos["T_con"], [11.0, 22.0, 33.0, 44.0])


@pytest.mark.parametrize(
    ("option", "message"),
    [(70.0, r"options\['T_con'\]=70.0 is invalid: expected prescribed times in \[dt=0.05, 60\] s"),
     (float("nan"), r"options\['T_con'\]=nan is invalid"), ("20", r"options\['T_con'\]='20' is invalid")],
)  # fmt: skip
def test_bad_T_con_option_is_a_clear_error(option: object, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        make(V1).reset(options={"T_con": option})


def test_bad_T_con_range_is_a_clear_error() -> None:
    with pytest.raises(ValueError, match=r"T_con_range=\(30(\.0)?, 10(\.0)?\) is invalid: min must not exceed max"):
        make(V0, T_con_range=(30, 10))
    with pytest.raises(ValueError, match=r"dt=2.0 is invalid"):
        make(V0, T_con_range=(1.0, 10.0), dt=2.0)


def replay(commands: np.ndarray, T_con: float) -> tuple[float, dict[str, object]]:
    """The v1 return of playing (u, omega) commands from Figure 5's psi0 = pi/2 start."""
    env = make(V1)
    env.reset(seed=0, options={"start": (-0.8, 0.0, math.pi / 2), "goal": (0.0, 0.0, 0.0), "T_con": T_con})
    total = 0.0
    for u, omega in commands:
        _, reward, terminated, truncated, info = env.step(np.array([u / 0.5, omega / 2.0], np.float32))
        total += float(reward)
        if terminated or truncated:
            break
    return total, info


def test_v1_pays_the_cheaper_of_two_timely_arrivals_with_the_heading_more() -> None:
    pytest.importorskip("casadi")
    from baselines.optimal import solve_minimum_energy

    start = (-0.8, 0.0, math.pi / 2)
    slow = solve_minimum_energy(start, 20.0, dt=0.05, u_max=0.5, omega_max=2.0).commands  # arrives at 20 s
    fast = solve_minimum_energy(start, 8.0, dt=0.05, u_max=0.5, omega_max=2.0).commands  # arrives at 8 s
    slow_return, slow_info = replay(slow, 20.0)
    fast_return, fast_info = replay(fast, 20.0)
    for info in (slow_info, fast_info):  # both arrive in time, with the heading
        assert info["is_success"] and info["time"] <= 20.0 and abs(info["heading_error"]) < 0.05  # type: ignore[arg-type,operator]
    assert slow_info["energy"] < fast_info["energy"]  # type: ignore[operator]
    assert slow_return > fast_return
    # and the difference is the energy's: nothing is paid for arriving 12 s earlier
    energy_gap = 2.0 * (fast_info["energy"] - slow_info["energy"])  # type: ignore[operator]
    assert slow_return - fast_return == pytest.approx(energy_gap, abs=0.02)


def test_v1_defaults_are_registered() -> None:
    """v1 is v0 with the values its docstring's Version History and the README state, written out here."""
    stated = {"T_con_range": (10.0, 60.0), "start_distance": (0.3, 3.0), "time_weight": 0.0, "effort_weight": 0.0,
              "energy_weight": 2.0, "shaping_discount": 1.0, "zero_terminal_potential": True}  # fmt: skip
    v1 = make(V1).unwrapped.params  # type: ignore[attr-defined]
    v0 = make(V0).unwrapped.params  # type: ignore[attr-defined]
    for field in dataclasses.fields(v1):
        expected = stated.get(field.name, getattr(v0, field.name))
        assert getattr(v1, field.name) == expected, field.name
    assert v0.T_con_range is None and v0.time_weight == 0.5 and v0.energy_weight == 0.0  # v0 differs where stated


def test_imitate_clones_the_optimal_planner_into_a_loadable_agent(tmp_path: object) -> None:
    pytest.importorskip("casadi")
    import os
    import subprocess
    import sys
    from pathlib import Path

    from train.learning.agents import load_agent

    run_dir = Path(str(tmp_path)) / "bc"
    command = [sys.executable, "-m", "train.cli", "imitate", "--episodes", "4", "--T-con-range", "2", "3",
               "--start-distance", "0.2", "0.3", "--epochs", "2", "--eval-every", "1", "--eval-episodes", "4",
               "--batch-size", "256", "--net-arch", "16", "--run-dir", str(run_dir), "--no-progress"]  # fmt: skip
    env = {**os.environ, "MPLBACKEND": "Agg"}
    result = subprocess.run(command, capture_output=True, text=True, env=env, timeout=600)
    assert result.returncode == 0, result.stderr
    assert "recorded" in result.stdout and (run_dir / "model.zip").is_file()
    rows = (run_dir / "evaluations.csv").read_text().splitlines()
    assert rows[0].startswith("epoch,samples") and len(rows) == 3
    label, policy = load_agent(run_dir)
    obs, _ = make(V1).reset(seed=0)
    action, _ = policy.predict(obs, deterministic=True)
    assert label == "bc" and action.shape == (2,) and np.all(np.abs(action) <= 1.0)
    again = subprocess.run(command, capture_output=True, text=True, env=env, timeout=600)
    assert again.returncode == 2 and "already holds a model.zip" in again.stderr

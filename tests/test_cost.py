"""The deadline as a constraint: ``info["cost"]`` and the smooth violations beside it, on every env that reports them.

The cost is 1 at the step that ends an episode where the robot is not in time by the env's own test (at the goal at
T_con on v2; arrived by T_con on v0 and v1), else 0; its sum over an episode is the episode's deadline violation.
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import dwr_gym
from dwr_gym import core

V1, V2 = dwr_gym.ENV_ID_V1, dwr_gym.ENV_ID_V2


def episode(env: gym.Env, policy: object, options: dict | None = None, seed: int = 0) -> list[dict]:
    """The infos of each step of one episode (the reset's first), ``policy(obs, t)`` acting."""
    obs, info = env.reset(seed=seed, options=options)
    infos, t = [info], 0
    while True:
        obs, _, terminated, truncated, info = env.step(policy(obs, t))  # type: ignore[operator]
        infos.append(info)
        t += 1
        if terminated or truncated:
            return infos


def costs(infos: list[dict], key: str = "cost") -> np.ndarray:
    return np.array([info[key] for info in infos])


def still(obs: object, t: int) -> np.ndarray:
    return np.zeros(2, np.float32)


def test_a_robot_at_the_goal_at_T_con_costs_nothing() -> None:
    infos = episode(gym.make(V2), still, {"start": (0.0, 0.0, 0.0), "goal": (0.005, 0.0, 0.0), "T_con": 10.0})
    assert infos[-1]["is_success"] and costs(infos).sum() == 0.0
    assert costs(infos, "distance_violation").sum() == 0.0 and costs(infos, "heading_violation").sum() == 0.0


def test_reaching_the_goal_and_leaving_it_before_T_con_costs_one_at_the_end() -> None:
    """At the goal for the first 100 steps, then away: v2's rule is the pose at T_con, not an arrival before it."""
    infos = episode(gym.make(V2), lambda obs, t: np.array([0.0 if t < 100 else 0.2, 0.0], np.float32),
                    {"start": (0.0, 0.0, 0.0), "goal": (0.005, 0.0, 0.0), "T_con": 10.0})  # fmt: skip
    assert any(info["is_success"] for info in infos[:100]) and not infos[-1]["is_success"]
    assert costs(infos)[:-1].sum() == 0.0 and costs(infos)[-1] == 1.0
    miss = infos[-1]["distance"] - 0.01
    assert miss > 0 and infos[-1]["distance_violation"] == pytest.approx(miss, abs=1e-12)
    assert costs(infos, "distance_violation")[:-1].sum() == 0.0


def test_the_heading_violation_is_the_final_heading_error() -> None:
    """v2 sets no heading tolerance: its heading violation is |psi| at the episode's end (at the goal or not)."""
    infos = episode(gym.make(V2), still, {"start": (0.0, 0.0, 0.7), "goal": (0.005, 0.0, 0.0), "T_con": 10.0})
    assert costs(infos).sum() == 0.0  # in time: the heading is a measure of its own, not part of v2's test
    assert infos[-1]["heading_violation"] == pytest.approx(abs(infos[-1]["heading_error"]), abs=1e-12)
    assert infos[-1]["heading_violation"] > 0.6


def test_a_heading_tolerance_enters_the_cost_and_the_violation() -> None:
    options = {"start": (0.0, 0.0, 0.7), "goal": (0.005, 0.0, 0.0), "T_con": 10.0}
    infos = episode(gym.make(V2, heading_tolerance=0.5), still, options)
    assert costs(infos)[-1] == 1.0 and infos[-1]["heading_violation"] == pytest.approx(0.2, abs=1e-9)


def test_leaving_the_arena_costs_one_where_it_ends() -> None:
    infos = episode(gym.make(V2), lambda obs, t: np.array([1.0, 0.0], np.float32),
                    {"start": (4.99, 0.0, 0.0), "goal": (0.0, 0.0, 0.0), "T_con": 10.0})  # fmt: skip
    assert infos[-1]["time"] < 10.0 and costs(infos).tolist() == [0.0] * (len(infos) - 1) + [1.0]
    assert infos[-1]["distance_violation"] > 4.9


@pytest.mark.parametrize(("T_con", "cost"), [(2.0, 0.0), (1.2, 1.0)])
def test_v1_counts_an_arrival_after_T_con_as_a_violation(T_con: float, cost: float) -> None:
    """v1 ends on arrival: 0.3 m at 0.2 m/s arrives after some 1.5 s, in time for T_con 2 s, late for 1.2 s (before its horizon, 1.5 T_con)."""
    infos = episode(gym.make(V1), lambda obs, t: np.array([-0.4, 0.0], np.float32),
                    {"start": (0.3, 0.0, 0.0), "goal": (0.0, 0.0, 0.0), "T_con": T_con})  # fmt: skip
    assert infos[-1]["is_success"] and costs(infos).sum() == cost and costs(infos)[-1] == cost


def test_an_arrival_one_control_period_after_T_con_costs_one_and_one_at_T_con_nothing() -> None:
    """v1 at the deadline's edge: the same drive arrives at the step ending at T_con (in time, cost 0) and, with
    T_con one control period shorter, at the step after it (late, cost 1)."""
    drive = {"start": (0.3, 0.0, 0.0), "goal": (0.0, 0.0, 0.0)}

    def reverse(obs: object, t: int) -> np.ndarray:
        return np.array([-0.4, 0.0], np.float32)

    arrival = episode(gym.make(V1), reverse, {**drive, "T_con": 5.0})[-1]["time"]  # the step it arrives at [s]
    dt = gym.make(V1).unwrapped.params.dt
    at = episode(gym.make(V1), reverse, {**drive, "T_con": arrival})
    after = episode(gym.make(V1), reverse, {**drive, "T_con": arrival - dt})
    assert at[-1]["time"] == after[-1]["time"] == arrival and at[-1]["is_success"] and after[-1]["is_success"]
    assert costs(at).sum() == 0.0 and costs(after).sum() == 1.0 and costs(after)[-1] == 1.0


@settings(max_examples=12, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), env_id=st.sampled_from([dwr_gym.ENV_ID, V1, V2]), disturbed=st.booleans())
def test_the_cost_is_0_or_1_once_per_episode_at_its_end(seed: int, env_id: str, disturbed: bool) -> None:
    """Random commands on short episodes, the nominal robot or a disturbed one: the cost is 0 or 1, nothing else,
    nonzero only at an episode's last step, and 1 there exactly where the robot is not in time."""
    from dwr_gym.disturbances import VelocityBias

    kwargs = {"disturbances": [VelocityBias(0.05, 0.1)]} if disturbed else {}
    env = gym.make(env_id, **kwargs)
    rng = np.random.default_rng(seed)
    T_con = float(rng.uniform(0.5, 3.0))
    infos = episode(env, lambda obs, t: rng.uniform(-1, 1, 2).astype(np.float32), {"T_con": T_con}, seed=seed)
    values = costs(infos)
    assert set(values.tolist()) <= {0.0, 1.0} and values[:-1].sum() == 0.0
    last = infos[-1]
    in_time = last["is_success"] and last["time"] <= last["T_con"] + 1e-9
    assert values[-1] == (0.0 if in_time else 1.0)
    for key in core.COST_KEYS:
        assert np.all(np.isfinite(costs(infos, key))) and np.all(costs(infos, key) >= 0.0)


def test_the_vector_env_reports_the_single_envs_cost_each_step() -> None:
    n = 4
    vec = gym.make_vec(V2, num_envs=n, T_con_range=(1.0, 2.0), autoreset_mode="same_step")
    singles = [gym.make(V2, T_con_range=(1.0, 2.0)) for _ in range(n)]
    vec.reset(seed=7)
    for i, env in enumerate(singles):
        env.reset(seed=7 + i)
    rng, ended, total = np.random.default_rng(1), np.zeros(n, bool), np.zeros(n)
    for _ in range(40):
        actions = rng.uniform(-1, 1, (n, 2)).astype(np.float32)
        _, _, terminated, truncated, infos = vec.step(actions)
        done = terminated | truncated
        final = infos["final_info"] if done.any() else infos
        for i, env in enumerate(singles):
            if ended[i]:
                continue
            _, _, single_terminated, single_truncated, info = env.step(actions[i])
            ended[i] = single_terminated or single_truncated
            for key in core.COST_KEYS:
                assert info[key] == pytest.approx(final[key][i], abs=1e-12), (key, i)
            total[i] += info["cost"]
        if ended.all():
            break
    assert ended.all() and set(total.tolist()) <= {0.0, 1.0}

"""The planners' plans kept on disk (baselines.plan_store): a later command takes a stored plan, bit for bit the plan
a solve returns, and its rollouts equal those that solved; an interrupted command keeps what it solved."""

from __future__ import annotations

import dataclasses
from collections import OrderedDict
from pathlib import Path

import numpy as np
import pytest

from tests.solving import plans_one_by_one

pytest.importorskip("casadi")

from baselines import nmpc, plan_store
from baselines.expert import ExpertPolicy
from baselines.optimal import InfeasibleArrivalTimeError, Plan, solve_minimum_energy
from baselines.registry import make_controller
from train.evaluation.evaluate import evaluate
from train.evaluation.scenarios import Scenario

JOB = {"start": (-0.8, 0.3, 2.5), "arrival_time": 6.0, "dt": 0.05, "u_max": 0.5, "omega_max": 2.0, "hold_steps": 5}


def assert_same_plan(a: Plan, b: Plan) -> None:
    for field in dataclasses.fields(Plan):
        x, y = getattr(a, field.name), getattr(b, field.name)
        if isinstance(x, np.ndarray):
            assert x.shape == y.shape and x.tobytes() == y.tobytes(), field.name
        else:
            assert x == y, field.name


def test_a_stored_plan_is_the_solved_plan_to_the_last_bit(tmp_path: Path) -> None:
    padded = {
        **JOB,
        "arrival_time": 6.5,
        "response": (0.01, -0.05, 0.9, 0.02),
        "pad_to": 8,
        "max_iter": 150,
    }  # robust-pt's kind of job
    plans = {b"a" * 32: solve_minimum_energy(**JOB), b"b" * 32: solve_minimum_energy(**padded)}  # type: ignore[arg-type]
    error = InfeasibleArrivalTimeError("T_con=1 s is infeasible")
    plan_store.write_plans(tmp_path / "1-0.npz", {**plans, b"c" * 32: error})
    read = plan_store.read_plans(tmp_path / "1-0.npz")
    assert list(read) == [b"a" * 32, b"b" * 32, b"c" * 32]
    for key, plan in plans.items():
        assert_same_plan(read[key], plan)  # type: ignore[arg-type]
    assert plans[b"b" * 32].solution.size > 5 * plans[b"b" * 32].intervals + 3  # padded: the plan is a part of it
    assert type(read[b"c" * 32]) is InfeasibleArrivalTimeError and str(read[b"c" * 32]) == str(error)


def rollout_with_store(directory: Path, monkeypatch: pytest.MonkeyPatch) -> tuple[object, int]:
    """robust-pt on two noisy episodes with the store at ``directory``: its result and the plans it solved."""
    monkeypatch.setattr(nmpc, "_MEMO", OrderedDict())  # nothing solved before in this process
    solved = []
    real = solve_minimum_energy
    monkeypatch.setattr(nmpc, "solve_plans", plans_one_by_one(lambda **job: solved.append(job) or real(**job)))  # type: ignore[func-returns-value]
    scenario = Scenario("two", np.array([[-0.8, 0.2, 0.5], [-1.2, -0.4, 3.0]]), np.zeros((2, 3)),
                        {"T_con": 10.0, "observation_noise": 0.01})  # fmt: skip
    policy = ExpertPolicy(make_controller("robust-pt", T_con=10.0, workers=1), 0.5, 2.0)
    with plan_store.opened(directory):
        result = evaluate({"robust-pt": policy}, scenario, seed=3)["robust-pt"]
    return result, len(solved)


def test_a_second_command_takes_the_stored_plans_and_rolls_out_the_same(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv(plan_store.SWITCH, "1")
    first, solves = rollout_with_store(tmp_path, monkeypatch)
    assert solves >= 2 and list(tmp_path.glob("*.npz"))
    second, again = rollout_with_store(tmp_path, monkeypatch)
    assert again == 0
    for field in dataclasses.fields(first):
        a, b = getattr(first, field.name), getattr(second, field.name)
        if isinstance(a, np.ndarray):
            assert a.tobytes() == b.tobytes(), field.name


def test_an_interrupted_command_keeps_what_it_solved(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv(plan_store.SWITCH, "1")
    monkeypatch.setattr(nmpc, "_MEMO", OrderedDict())
    pool = nmpc.PlanPool(workers=1)
    with pytest.raises(KeyboardInterrupt), plan_store.opened(tmp_path):
        pool.map([JOB])
        raise KeyboardInterrupt
    (path,) = tmp_path.glob("*.npz")
    assert_same_plan(plan_store.read_plans(path)[nmpc.job_key(JOB)], nmpc._MEMO[nmpc.job_key(JOB)])  # type: ignore[arg-type]


def test_the_store_is_off_when_asked(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv(plan_store.SWITCH, "0")
    with plan_store.opened(tmp_path) as store:
        assert store is None and plan_store.current() is None
        nmpc.PlanPool(workers=1).map([{**JOB, "arrival_time": 5.5}])
    assert not list(tmp_path.iterdir())


def test_a_changed_solver_has_a_store_of_its_own(monkeypatch: pytest.MonkeyPatch) -> None:
    before = plan_store.default_directory()
    monkeypatch.setattr(plan_store, "STORE_VERSION", plan_store.STORE_VERSION + 1)
    assert plan_store.default_directory() != before and plan_store.default_directory().parent == before.parent


def test_the_store_says_whether_a_command_wrote_plans_before(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    assert not plan_store.has_plans(tmp_path)  # a first run: every plan is solved
    with plan_store.opened(tmp_path):
        nmpc.PlanPool(workers=1).map([{**JOB, "arrival_time": 5.8}])
    assert plan_store.has_plans(tmp_path)
    monkeypatch.setenv(plan_store.SWITCH, "0")
    assert not plan_store.has_plans(tmp_path)  # off: the plans are solved again

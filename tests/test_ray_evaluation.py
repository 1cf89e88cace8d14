"""``compare``/``evaluate --address``: each policy's rollout on a set is one Ray task, with the numbers of a local run."""

from __future__ import annotations

import json
from typing import Any

import pytest

from tests.test_side_process import assert_same_results
from train.evaluation import ray_pool
from train.evaluation.evaluate import evaluate, evaluate_sets
from train.evaluation.scenarios import make_scenario
from train.evaluation.stages import StageClock

POLICIES = {"ptc": "ptc", "astolfi": "astolfi", "fixed-time": "fixed-time"}


class FakeRay:
    """RayPool's interface run in this process, recording what was asked for (Ray itself is slow to start)."""

    made: list[str] = []
    calls: list[str] = []
    shut = 0

    def __init__(self, address: str) -> None:
        FakeRay.made.append(address)
        self.workers = 2

    def run_each(self, function: Any, calls: list[tuple[Any, ...]]) -> list[tuple[Any, float]]:
        FakeRay.calls += [args[0] for args in calls]
        return [(function(*args), 0.25) for args in calls]

    def shutdown(self) -> None:
        FakeRay.shut += 1


def test_with_an_address_every_policy_is_one_task_and_the_numbers_are_a_local_runs(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setattr(FakeRay, "made", [])
    monkeypatch.setattr(FakeRay, "calls", [])
    monkeypatch.setattr(ray_pool, "RayPool", FakeRay)
    scenario = make_scenario("random", n=6, seed=4)
    local = evaluate(POLICIES, scenario, record=True, seed=2)
    clock = StageClock(progress=False)
    on_ray = evaluate(POLICIES, scenario, record=True, seed=2, clock=clock, address="auto")
    assert_same_results(local, on_ray)
    assert FakeRay.made == ["auto"] and FakeRay.calls == list(POLICIES) and FakeRay.shut >= 1
    # each task's time is its stage's, and the bar moves for every one
    assert [(t.stage, t.seconds, t.size) for t in clock.times] == [(label, 0.25, 6) for label in POLICIES]


def test_an_error_in_a_ray_task_reaches_the_command(monkeypatch: pytest.MonkeyPatch) -> None:
    class Failing(FakeRay):
        def run_each(self, function: Any, calls: list[tuple[Any, ...]]) -> list[tuple[Any, float]]:
            raise RuntimeError("task failed on the cluster")

    shut = FakeRay.shut
    monkeypatch.setattr(ray_pool, "RayPool", Failing)
    with pytest.raises(RuntimeError, match="task failed on the cluster"):
        evaluate(POLICIES, make_scenario("random", n=2, seed=1), address="auto")
    assert FakeRay.shut == shut + 1  # the pool is shut down (a cluster it started is stopped)


@pytest.mark.slow
@pytest.mark.own_process
def test_a_tiny_set_on_a_local_ray_cluster_gives_the_local_rows(monkeypatch: pytest.MonkeyPatch, tmp_path: Any) -> None:
    """The real thing: ``--address local`` starts Ray here; the rows equal a local run's but for the seconds."""
    pytest.importorskip("ray")
    monkeypatch.setenv("RAY_raylet_start_wait_time_s", "300")  # a loaded machine starts Ray slowly
    monkeypatch.setenv("DWR_GYM_CACHE", str(tmp_path))
    kwargs: dict[str, Any] = {"T_con": 10.0, "T_con_range": None}
    local = evaluate_sets(POLICIES, ["random"], 3, 7, kwargs)
    on_ray = evaluate_sets(POLICIES, ["random"], 3, 7, kwargs, address="local")
    timing = {"seconds", "optimum_seconds"}

    def without_timing(rows: list[dict[str, Any]]) -> str:  # (as JSON: NaN, where a mean has no episode, equals NaN)
        return json.dumps([{k: v for k, v in row.items() if k not in timing} for row in rows], sort_keys=True)

    assert len(on_ray) == len(POLICIES)
    assert without_timing(on_ray) == without_timing(local)

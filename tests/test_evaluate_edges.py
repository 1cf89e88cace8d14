"""``evaluate`` and ``evaluate_sets`` beyond the stage clock: the defaults, the optimum's stage (advanced per plan
solved), a policy's planner (its failures counted, closed after its rollout), and ``optimal`` on the first
``n_optimal`` episodes of a disturbed set only, with every argument the other sets get.

The optima here are asked for prescribed times too short for any plan: each is "infeasible", known without a solve."""

from __future__ import annotations

import dataclasses
import io
import re
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from dwr_gym.params import EnvParams
from tests.test_evaluation_stages import FakeRay, Still, fake_ray, in_this_process  # noqa: F401 (fixtures)
from train.evaluation import ray_pool
from train.evaluation.evaluate import evaluate, evaluate_sets, max_steps
from train.evaluation.optimum import missing_optima
from train.evaluation.scenarios import make_scenario
from train.evaluation.stages import PLAN_SECONDS, StageClock

#: each episode's T_con drawn in 0.4-0.6 s: no start of the random set can reach its goal so soon
TOO_SHORT = {"T_con_range": (0.4, 0.6)}


class Fractions(StageClock):
    """A silent clock that keeps the fractions done each stage reported (what moves the bar)."""

    def __init__(self) -> None:
        super().__init__(progress=False)
        self.fractions: dict[str, list[float]] = {}

    @contextmanager
    def stage(self, scenario: str, name: str, weight: float, size: int) -> Iterator[Callable[[float], None]]:
        with super().stage(scenario, name, weight, size) as advance:

            def told(fraction: float) -> None:
                self.fractions.setdefault(name, []).append(fraction)
                advance(fraction)

            yield told


def test_the_optimum_is_a_stage_of_its_set_advanced_per_plan_then_each_policy_per_step(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("DWR_GYM_CACHE", str(tmp_path))
    scenario = make_scenario("random", n=3, seed=0, env_kwargs=TOO_SHORT)
    clock = Fractions()
    result = evaluate({"ptc": "ptc"}, scenario, optimum="position", clock=clock, stage_scenario="sets")["ptc"]
    assert [(t.scenario, t.stage, t.size) for t in clock.times] == [("sets", "optimum", 3), ("sets", "ptc", 3)]
    assert clock.fractions["optimum"] == pytest.approx([1 / 3, 2 / 3, 1.0]), clock.fractions["optimum"]
    steps = max_steps(scenario, EnvParams.from_kwargs(**TOO_SHORT))
    assert clock.fractions["ptc"] == pytest.approx([k / steps for k in range(steps)]), (steps, clock.fractions["ptc"])
    (took,) = [t.seconds for t in clock.times if t.stage == "optimum"]
    assert clock.ratio("optimum", "sets") == pytest.approx(took / (3 * PLAN_SECONDS))  # against 3 plans' estimate
    assert len(result.optimum_failures) == 3 and np.isnan(result.optimal_energy).all(), result.optimum_failures
    params = EnvParams.from_kwargs(**TOO_SHORT)
    assert missing_optima(params, scenario.starts, scenario.goals, scenario.T_cons, heading=False) == set()
    again = Fractions()
    evaluate({"ptc": "ptc"}, scenario, optimum="position", clock=again)  # cached: nothing to solve
    evaluate({"ptc": "ptc"}, scenario, optimum="pose", clock=again)  # the poses' optima are others
    assert [t.size for t in again.times if t.stage == "optimum"] == [0, 3]
    assert missing_optima(params, scenario.starts, scenario.goals, scenario.T_cons, heading=True) == set()
    one = Fractions()
    evaluate({"ptc": "ptc"}, make_scenario("random", n=1, seed=1, env_kwargs=TOO_SHORT), optimum="pose", clock=one)
    assert one.fractions["optimum"] == [1.0], one.fractions["optimum"]  # its one plan: the whole stage


class FakeCluster(FakeRay):
    """RayPool's interface in this process, with the part the optima use: ``map`` and ``workers``."""

    workers = 2
    mapped = 0

    def map(self, function: Callable[[Any], Any], items: Any, chunksize: int = 1) -> Iterator[Any]:
        for item in items:
            FakeCluster.mapped += 1
            yield function(item)

    def shutdown(self, *args: Any, **kwargs: Any) -> None:
        pass


def test_with_an_address_the_optima_are_solved_on_the_cluster_too(
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    fake_ray: type[FakeRay],  # noqa: F811
) -> None:
    monkeypatch.setenv("DWR_GYM_CACHE", str(tmp_path))
    monkeypatch.setattr(ray_pool, "RayPool", FakeCluster)
    monkeypatch.setattr(FakeCluster, "mapped", 0)
    monkeypatch.setattr(FakeRay, "took", {"ptc": 4.0})
    scenario = make_scenario("random", n=3, seed=0, env_kwargs=TOO_SHORT)
    result = evaluate({"ptc": "ptc"}, scenario, optimum="position", address="a")["ptc"]
    assert FakeRay.addresses == ["a", "a"] and FakeCluster.mapped == 3, (FakeRay.addresses, FakeCluster.mapped)
    assert len(result.optimum_failures) == 3, result.optimum_failures


def test_evaluate_by_default_is_quiet_records_nothing_asks_no_optimum_and_seeds_with_0(
    capsys: pytest.CaptureFixture[str],
) -> None:
    scenario = make_scenario("disturbed", n=2, seed=0, env_kwargs={"T_con": 5.0})  # a random walk seeded per robot
    default = evaluate({"ptc": "ptc"}, scenario)["ptc"]
    assert capsys.readouterr().err == ""
    assert default.trajectory is None and default.optimal_energy is None and default.optimum_failures == []
    seeded = {seed: evaluate({"ptc": "ptc"}, scenario, seed=seed)["ptc"].energy for seed in (0, 1)}
    np.testing.assert_array_equal(default.energy, seeded[0])
    assert not np.array_equal(seeded[0], seeded[1]), seeded
    recorded = evaluate({"ptc": "ptc"}, scenario, record=True)["ptc"].trajectory
    assert recorded is not None and recorded["x"].shape[1] == 2, recorded
    with pytest.raises(ValueError, match=re.escape("optimum='best' is invalid: expected one of pose, position, none")):
        evaluate({"ptc": "ptc"}, scenario, optimum="best")


def test_the_optimums_own_bar_shows_where_asked_and_the_clock_is_silent_else_the_clocks_alone(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    scenario = make_scenario("random", n=2, seed=0, env_kwargs=TOO_SHORT)
    monkeypatch.setenv("DWR_GYM_CACHE", str(tmp_path / "silent"))
    evaluate({"ptc": "ptc"}, scenario, optimum="position", progress=True, clock=StageClock(progress=False))
    bars = capsys.readouterr().err
    assert "random: optimum" in bars and "random: ptc" in bars, bars
    monkeypatch.setenv("DWR_GYM_CACHE", str(tmp_path / "shown"))
    log = io.StringIO()
    evaluate({"ptc": "ptc"}, scenario, optimum="position", progress=True, clock=StageClock(file=log))
    assert capsys.readouterr().err == "" and log.getvalue().startswith("compare: ")


class Planner:
    """A planning controller's part that evaluate reads: the plans it could not find (one from an earlier set), and
    its process pool."""

    def __init__(self) -> None:
        self.failures = ["no plan on the set before"]
        self.closed = False

    def close(self) -> None:
        self.closed = True


class PlanningAgent(Still):
    def __init__(self) -> None:
        self.controller = Planner()

    def predict(self, observation: Any, *args: Any, **kwargs: Any) -> tuple[Any, Any]:
        if len(self.controller.failures) < 3:  # two robots it finds no plan for on this set
            self.controller.failures.append("no plan from here")
        return super().predict(observation, *args, **kwargs)


def test_a_policys_planner_failures_are_counted_and_its_planner_closed_after_its_rollout() -> None:
    """The failures of the rollout's own (an agent's planner serves every set: not those of the sets before)."""
    agent = PlanningAgent()
    result = evaluate({"agent": agent}, make_scenario("random", n=1, seed=0, env_kwargs={"T_con": 5.0}))["agent"]
    assert result.planner_failures == 2 and agent.controller.closed


def head_of(scenario: Any, n: int) -> Any:
    """The first ``n`` episodes of a set."""
    return dataclasses.replace(scenario, starts=scenario.starts[:n], goals=scenario.goals[:n],
                               labels=scenario.labels[:n], T_cons=scenario.T_cons[:n])  # fmt: skip


def test_optimal_runs_the_first_n_optimal_episodes_of_a_disturbed_set_only_as_evaluate_runs_them() -> None:
    kwargs = {"T_con_range": (4.0, 6.0)}  # drawn per episode: the head keeps its episodes' own
    rows = evaluate_sets({"optimal": Still(), "ptc": "ptc"}, ["random", "disturbed"], 3, 5, kwargs, n_optimal=1)
    for row in rows:
        full = make_scenario(row["scenario"], n=3, seed=5, env_kwargs=kwargs)
        scenario = head_of(full, 1) if (row["scenario"], row["policy"]) == ("disturbed", "optimal") else full
        expected = evaluate({row["policy"]: Still() if row["policy"] == "optimal" else "ptc"}, scenario, seed=5)
        summary = expected[row["policy"]].summary()
        assert {k: row[k] for k in summary} == pytest.approx(summary, nan_ok=True), (row["scenario"], row["policy"])
    assert [(row["scenario"], row["policy"], row["n"]) for row in rows] == [
        ("random", "optimal", 3), ("random", "ptc", 3), ("disturbed", "optimal", 1), ("disturbed", "ptc", 3)
    ]  # fmt: skip
    (row,) = evaluate_sets({"ptc": "ptc"}, ["disturbed"], 3, 5, kwargs, n_optimal=1)  # no optimal: the whole set
    summary = evaluate({"ptc": "ptc"}, make_scenario("disturbed", n=3, seed=5, env_kwargs=kwargs), seed=5)[
        "ptc"
    ].summary()
    assert {k: row[k] for k in summary} == pytest.approx(summary, nan_ok=True)  # with the seed of its random walk
    clock = StageClock(progress=False)  # a set no larger than n_optimal: run as any other, in the policies' order
    evaluate_sets({"optimal": Still(), "ptc": "ptc"}, ["disturbed"], 1, 5, kwargs, n_optimal=1, clock=clock)
    assert [t.stage for t in clock.times] == ["optimal", "ptc"]


def test_optimal_on_its_n_optimal_episodes_gets_the_sets_optimum_bars_and_cluster(
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
    fake_ray: type[FakeRay],  # noqa: F811
) -> None:
    monkeypatch.setenv("DWR_GYM_CACHE", str(tmp_path))
    monkeypatch.setattr(FakeRay, "took", {"ptc": 4.0, "optimal": 2.0})
    policies = {"optimal": Still(), "ptc": "ptc"}
    evaluate_sets(policies, ["disturbed"], 3, 0, TOO_SHORT, n_optimal=1, address="a")
    assert fake_ray.calls == [["ptc"], ["optimal"]], fake_ray.calls  # each a task, as the set's other policies
    rows = evaluate_sets(policies, ["disturbed"], 3, 0, TOO_SHORT, optimum="position", n_optimal=1)
    notes = {row["policy"]: (row["optimum_note"], row["optimum_failures"]) for row in rows}
    assert notes["optimal"][1] == 1 and notes["ptc"][1] == 3 and all("infeasible" in n for n, _ in notes.values())
    capsys.readouterr()
    evaluate_sets(policies, ["disturbed"], 2, 0, {"T_con": 5.0}, progress=True, n_optimal=1,
                  clock=StageClock(progress=False))  # fmt: skip
    bars = capsys.readouterr().err
    assert "disturbed: ptc" in bars and "disturbed: optimal" in bars, bars

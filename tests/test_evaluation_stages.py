"""``evaluate_sets`` and ``evaluate`` on the one stage clock: what is planned before the first stage, what each stage
took, what reaches the rows, and the stages of rollouts run elsewhere (a Ray task, a second process) recorded once.

No Ray and no second process here: stand-ins with their interfaces run the same rollouts in this process."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

from baselines import plan_store
from dwr_gym.params import EnvParams
from train.evaluation import evaluate as evaluate_module
from train.evaluation import ray_pool
from train.evaluation.evaluate import evaluate, evaluate_sets, max_steps, planned_seconds, running_beside
from train.evaluation.optimum import optimal_energies
from train.evaluation.scenarios import make_scenario
from train.evaluation.side_process import SWITCH
from train.evaluation.stages import PLAN_SECONDS, StageClock, StageTime, estimated_seconds

#: 1,200 steps a rollout (1.5 x 40 s / 0.05 s): 0.6 estimated seconds a stage, past the clock's calibration threshold
LONG = {"T_con": 40.0}


@pytest.fixture(autouse=True)
def in_this_process(monkeypatch: pytest.MonkeyPatch) -> None:
    """Every policy in this process, one after the other, unless a test puts a stand-in second process in place."""
    monkeypatch.setenv(SWITCH, "0")


class Still:
    """An agent that stands still (no network to load): cheap under any label, a planner's too."""

    def predict(
        self, observation: Any, state: Any = None, episode_start: Any = None, deterministic: bool = True
    ) -> tuple[Any, Any]:
        return np.zeros((len(observation), 2), np.float32), None


class PlannedClock(StageClock):
    """A silent clock that keeps what each :meth:`plan` was given (the time left is made of it) and whether it was
    closed."""

    made: list[PlannedClock] = []

    def __init__(self, progress: bool = False, **kwargs: Any) -> None:
        super().__init__(progress=False, **kwargs)
        self.asked_progress = progress
        self.plans: list[tuple[dict[tuple[str, str], float], frozenset[str], dict[str, str]]] = []
        self.closed = False
        PlannedClock.made.append(self)

    def plan(self, weight: Any, beside: Any = (), groups: Any = None) -> None:
        stages = list(weight)
        self.plans.append((dict(stages), frozenset(beside), dict(groups or {})))
        super().plan(stages, beside, groups)

    def close(self) -> None:
        self.closed = True
        super().close()


def steps_of(name: str, n: int, env_kwargs: dict[str, Any]) -> int:
    scenario = make_scenario(name, n=n, seed=0, env_kwargs=env_kwargs)
    return max_steps(scenario, EnvParams(**env_kwargs))


def test_each_rows_seconds_are_its_own_stages_also_where_a_set_runs_at_two_T_cons() -> None:
    clock = StageClock(progress=False)
    so_far: list[list[dict[str, Any]]] = []
    rows = evaluate_sets({"ptc": "ptc"}, ["random"], 2, 0, {}, T_cons=[10.0, 20.0], clock=clock, on_rows=so_far.append)
    assert so_far == [rows[:1], rows], so_far  # the rows so far after each (set, T_con): what an interruption keeps
    stages = [t.seconds for t in clock.times if (t.scenario, t.stage) == ("random", "ptc")]
    assert len(stages) == 2, f"the given clock timed {clock.times}"
    seconds = [row["seconds"] for row in rows]
    assert seconds == pytest.approx(stages, abs=0.006), f"rows {seconds} against the stages {stages}"
    assert [row["optimum_seconds"] for row in rows] == [0, 0]  # no optimum asked for
    assert all(row["seconds"] == round(row["seconds"], 2) for row in rows), f"not to hundredths: {seconds}"
    assert clock.left() == 0.0, f"{clock.left()} s left once every planned stage ran"


def test_a_set_drawing_T_con_per_episode_has_no_one_T_con_but_the_range_drawn_from() -> None:
    (row,) = evaluate_sets({"ptc": "ptc"}, ["random"], 2, 0, {"T_con_range": (5.0, 9.0)})
    assert math.isnan(row["T_con"]) and row["T_con_range"] == [5.0, 9.0], (row["T_con"], row["T_con_range"])
    (fixed,) = evaluate_sets({"ptc": "ptc"}, ["random"], 2, 0, {"T_con": 5.0})
    assert fixed["T_con"] == 5.0 and fixed["T_con_range"] is None, (fixed["T_con"], fixed["T_con_range"])


def test_a_rows_optimum_note_is_why_the_first_episode_without_an_optimum_has_none(
    tmp_path: Any, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("DWR_GYM_CACHE", str(tmp_path))  # (infeasible T_con: no solver runs)
    rows = evaluate_sets({"ptc": "ptc"}, ["random"], 3, 0, {"T_con": 1.0}, optimum="position")
    scenario = make_scenario("random", n=3, seed=0, env_kwargs={"T_con": 1.0})
    failures = evaluate({"ptc": "ptc"}, scenario, optimum="position")["ptc"].optimum_failures
    assert len(failures) >= 2 and "infeasible" in failures[0], failures
    assert rows[0]["optimum_note"] == failures[0], (rows[0]["optimum_note"], failures)


def test_the_time_left_learns_the_disturbed_sets_pace_apart_from_the_nominal_sets() -> None:
    """A clock shared with the caller: the sets are grouped "nominal" and "disturbed" (:meth:`StageClock.plan`), so a
    stage the caller planned in either group is corrected by the pace of evaluate_sets' sets of that group."""
    clock = StageClock(progress=False)
    clock.plan([(("mine-nominal", "ptc"), 1.0), (("mine-disturbed", "ptc"), 1.0)],
               groups={"mine-nominal": "nominal", "mine-disturbed": "disturbed"})  # fmt: skip
    evaluate_sets({"ptc": "ptc"}, ["random", "disturbed"], 2, 0, LONG, clock=clock)
    nominal, disturbed = clock.ratio("ptc", "random"), clock.ratio("ptc", "disturbed")
    for name, ratio in (("random", nominal), ("disturbed", disturbed)):
        (took,) = [t.seconds for t in clock.times if (t.scenario, t.stage) == (name, "ptc")]
        estimate = estimated_seconds("ptc", 2, steps_of(name, 2, LONG))
        assert ratio == pytest.approx(took / estimate), f"{name}: ratio {ratio}, its own stage {took / estimate}"
    assert nominal != pytest.approx(disturbed, rel=1e-9), f"one pace for both groups: {nominal}, {disturbed}"
    assert clock.ratio("ptc", "mine-nominal") == nominal, f"{clock.ratio('ptc', 'mine-nominal')} != {nominal}"
    assert clock.ratio("ptc", "mine-disturbed") == disturbed, f"{clock.ratio('ptc', 'mine-disturbed')} != {disturbed}"


def test_the_plan_holds_optimal_on_its_n_optimal_episodes_of_a_disturbed_set_and_no_optimum_not_asked_for() -> None:
    clock = PlannedClock()
    cold = not plan_store.has_plans()  # no plans stored: a planner's first run
    rows = evaluate_sets({"optimal": Still(), "ptc": "ptc"}, ["disturbed"], 3, 0, {}, n_optimal=1, clock=clock)
    ((planned, beside, groups),) = clock.plans
    steps = steps_of("disturbed", 3, {})
    expected = {("disturbed", "optimal"): estimated_seconds("optimal", 1, steps, "disturbed", cold),
                ("disturbed", "ptc"): estimated_seconds("ptc", 3, steps, "disturbed", cold)}  # fmt: skip
    assert planned == pytest.approx(expected), f"planned {planned}, expected {expected}"
    assert beside == frozenset() and groups == {"disturbed": "disturbed"}
    assert {row["policy"]: row["n"] for row in rows} == {"optimal": 1, "ptc": 3}
    assert clock.left() == 0.0, f"{clock.left()} s left once every planned stage ran"


def test_evaluate_sets_is_quiet_unless_asked_then_shows_its_clock_or_else_the_rollouts_own_bars(
    capsys: pytest.CaptureFixture[str],
) -> None:
    short = {"T_con": 5.0}
    evaluate_sets({"ptc": "ptc"}, ["random"], 1, 0, short)
    assert capsys.readouterr().err == ""
    evaluate_sets({"ptc": "ptc"}, ["random"], 1, 0, short, progress=True)  # its own clock: lines (not a terminal)
    lines = capsys.readouterr().err.splitlines()
    assert lines and all(line.startswith("compare: ") for line in lines), lines
    evaluate_sets({"ptc": "ptc"}, ["random"], 1, 0, short, progress=True, clock=StageClock(progress=False))
    assert "random: ptc" in capsys.readouterr().err  # a silent clock: the rollout's own bar


def test_evaluate_sets_closes_the_clock_it_made_and_leaves_a_given_one_open(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(PlannedClock, "made", [])
    monkeypatch.setattr(evaluate_module, "StageClock", PlannedClock)
    evaluate_sets({"ptc": "ptc"}, ["random"], 1, 0, {"T_con": 5.0})
    ((own,),) = [PlannedClock.made]
    assert own.closed and not own.asked_progress
    given = PlannedClock()
    evaluate_sets({"ptc": "ptc"}, ["random"], 1, 0, {"T_con": 5.0}, clock=given)
    assert not given.closed and len(PlannedClock.made) == 2


class ManualTime:
    """A stand-in for ``time.perf_counter`` that moves only when told."""

    def __init__(self, now: float) -> None:
        self.now = now

    def __call__(self) -> float:
        return self.now


class FakeRay:
    """RayPool's interface in this process: each task's wall seconds on its worker by label, and the wall seconds
    this process waits for all of them."""

    calls: list[list[str]] = []
    addresses: list[str] = []
    took = {"ptc": 4.0, "robust": 7.0}
    lose_one = False

    def __init__(self, address: str) -> None:
        FakeRay.addresses.append(address)

    def run_each(self, function: Any, calls: list[tuple[Any, ...]]) -> list[tuple[Any, float]]:
        FakeRay.calls.append([args[0] for args in calls])
        results = [(function(*args), self.took[args[0]]) for args in calls]
        evaluate_module.time.perf_counter.now += 3.0  # type: ignore[attr-defined]
        return results[:-1] if self.lose_one else results

    def shutdown(self) -> None:
        pass


@pytest.fixture
def fake_ray(monkeypatch: pytest.MonkeyPatch) -> type[FakeRay]:
    monkeypatch.setattr(FakeRay, "calls", [])
    monkeypatch.setattr(FakeRay, "addresses", [])
    monkeypatch.setattr(ray_pool, "RayPool", FakeRay)
    monkeypatch.setattr(evaluate_module.time, "perf_counter", ManualTime(100.0))
    return FakeRay


def test_ray_tasks_stages_are_recorded_under_their_set_and_the_wait_is_counted_once(
    fake_ray: type[FakeRay], capsys: pytest.CaptureFixture[str]
) -> None:
    scenario = make_scenario("random", n=2, seed=0, env_kwargs=LONG)
    clock = StageClock(progress=False)
    results = evaluate({"ptc": "ptc", "robust": Still()}, scenario, clock=clock, stage_scenario="sets", address="a")
    assert capsys.readouterr().err == ""  # no bar from a task
    assert fake_ray.calls == [["ptc", "robust"]] and list(results) == ["ptc", "robust"]
    assert fake_ray.addresses == ["a"], f"joined {fake_ray.addresses}"
    assert clock.times == [StageTime("sets", "ptc", 4.0, 2, beside=True), StageTime("sets", "robust", 7.0, 2, True)]
    line = clock.summary()
    assert "policies 3 s (robust 7 s, ptc 4 s each; some in another process)" in line, line
    # each stage's pace against its label's estimate (robust: a planner's cost per episode)
    steps = max_steps(scenario, EnvParams(**LONG))
    for label in ("ptc", "robust"):
        expected = fake_ray.took[label] / estimated_seconds(label, 2, steps)
        assert clock.ratio(label, "sets") == pytest.approx(expected), f"{label}: {clock.ratio(label, 'sets')}"
    local = evaluate({"ptc": "ptc"}, scenario)["ptc"].summary()
    assert results["ptc"].summary() == pytest.approx(local, nan_ok=True)
    assert results["ptc"].trajectory is None
    assert evaluate({"ptc": "ptc"}, scenario, record=True, address="a")["ptc"].trajectory is not None


def test_a_ray_answer_missing_a_result_is_an_error_not_a_missing_row(
    fake_ray: type[FakeRay], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(FakeRay, "lose_one", True)
    with pytest.raises(ValueError, match="zip"):
        evaluate({"ptc": "ptc", "robust": Still()}, make_scenario("random", n=1, seed=0), address="a")


def test_evaluate_sets_with_an_address_runs_each_policy_as_a_task_and_plans_nothing_beside(
    fake_ray: type[FakeRay], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(evaluate_module, "side_process_usable", lambda: True)  # where a second process could run
    clock = PlannedClock()
    rows = evaluate_sets({"ptc": "ptc", "robust": Still()}, ["random"], 1, 0, {}, clock=clock, address="a")
    assert fake_ray.calls == [["ptc", "robust"]], fake_ray.calls
    assert [beside for _, beside, _ in clock.plans] == [frozenset()]
    assert [row["seconds"] for row in rows] == [4.0, 7.0] and not any(math.isnan(row["n"]) for row in rows)


class FakeSide:
    """SideProcess's interface in this process: it starts its first job at once and the next as one ends; ``fast``,
    the job started ends at each step of this process's stage (:meth:`finished`), else only when this process waits
    for it (:meth:`results`, 2 s of waiting). Each job took 5 s there."""

    made: list[FakeSide] = []
    fast = False

    def __init__(self, jobs: dict[str, tuple[Any, tuple[Any, ...]]]) -> None:
        self.jobs, self.order = jobs, list(jobs)
        self.waiting, self.started, self.closed = list(jobs), [], False
        FakeSide.made.append(self)
        self._start()

    def _start(self) -> None:
        if self.waiting:
            self.started.append(self.waiting.pop(0))

    def _ended(self) -> dict[str, tuple[Any, float]]:
        ended = {label: (self.jobs[label][0](*self.jobs[label][1]), 5.0) for label in self.started}
        self.started = []
        return ended

    def take(self, first: bool = False) -> Any:
        if not self.waiting:
            return None
        return self.waiting.pop(0) if first else self.waiting.pop()

    def finished(self) -> dict[str, tuple[Any, float]]:
        if not self.fast:
            return {}
        ended = self._ended()
        self._start()
        return ended

    def results(self, labels: Any = None) -> dict[str, tuple[Any, float]]:
        evaluate_module.time.perf_counter.now += 2.0  # type: ignore[attr-defined]
        ended = self._ended()
        self._start()
        return ended

    def close(self) -> None:
        self.closed = True


#: the agent and two laws beside 'fixed-time', which stands in for a planner (the real ones solve CasADi problems)
BESIDE = {"ptc": "ptc", "agent": Still(), "fixed-time": "fixed-time", "astolfi": "astolfi"}


@pytest.fixture
def fake_side(monkeypatch: pytest.MonkeyPatch) -> type[FakeSide]:
    monkeypatch.setattr(FakeSide, "made", [])
    monkeypatch.setattr(evaluate_module, "SideProcess", FakeSide)
    monkeypatch.setattr(evaluate_module, "side_process_usable", lambda: True)
    monkeypatch.setattr(evaluate_module, "PLANNERS", frozenset({"fixed-time"}))
    monkeypatch.setattr(evaluate_module.time, "perf_counter", ManualTime(100.0))
    return FakeSide


@pytest.mark.parametrize("fast", [False, True], ids=["taken-here", "ended-beside"])
def test_policies_run_beside_the_planners_give_a_run_in_turns_numbers_each_stage_recorded_once(
    fake_side: type[FakeSide], monkeypatch: pytest.MonkeyPatch, fast: bool
) -> None:
    monkeypatch.setattr(FakeSide, "fast", fast)
    scenario = make_scenario("random", n=2, seed=3)
    in_turn = {label: evaluate({label: policy}, scenario, seed=1)[label].summary() for label, policy in BESIDE.items()}
    clock = StageClock(progress=False)
    results = evaluate(BESIDE, scenario, seed=1, clock=clock, record=True)
    (side,) = fake_side.made
    assert all(result.trajectory is not None for result in results.values())
    assert side.order == ["agent", "ptc", "astolfi"] and side.closed  # the agents first: this process takes the last
    assert list(results) == list(BESIDE)
    for label, result in results.items():
        assert result.summary() == pytest.approx(in_turn[label], nan_ok=True), label
    stages = [(t.scenario, t.stage, t.seconds, t.size, t.beside) for t in clock.times]
    if fast:  # each ended beside during the planner's steps here, recorded as it ended
        assert stages == [("random", "agent", 5.0, 2, True), ("random", "ptc", 5.0, 2, True),
                          ("random", "astolfi", 5.0, 2, True), ("random", "fixed-time", 0.0, 2, False)]  # fmt: skip
        assert "policies 0 s (" in clock.summary(), clock.summary()
    else:  # the agent ran beside; this process took the laws not started, from the last, and then waited 2 s
        assert stages == [("random", "fixed-time", 0.0, 2, False), ("random", "astolfi", 0.0, 2, False),
                          ("random", "ptc", 0.0, 2, False), ("random", "agent", 5.0, 2, True)]  # fmt: skip
        assert "policies 2 s (" in clock.summary(), clock.summary()


def test_evaluate_sets_plans_the_policies_without_a_planner_beside_the_planners(fake_side: type[FakeSide]) -> None:
    clock = PlannedClock()
    evaluate_sets(BESIDE, ["random"], 1, 0, {"T_con": 5.0}, clock=clock)
    assert [beside for _, beside, _ in clock.plans] == [frozenset({"ptc", "agent", "astolfi"})], clock.plans


def test_what_runs_beside_the_planners_only_where_there_are_both_and_no_cluster(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setattr(evaluate_module, "side_process_usable", lambda: True)
    assert running_beside({"optimal": "optimal", "ptc": "ptc", "astolfi": "astolfi"}) == {"ptc", "astolfi"}
    assert running_beside({"ptc": "ptc", "astolfi": "astolfi"}) == frozenset()  # no planner to run beside
    assert running_beside({"optimal": "optimal"}) == frozenset()
    assert running_beside({"optimal": "optimal", "ptc": "ptc"}, "auto") == frozenset()  # every policy a Ray task
    monkeypatch.setattr(evaluate_module, "side_process_usable", lambda: False)
    assert running_beside({"optimal": "optimal", "ptc": "ptc"}) == frozenset()


def assert_plan(got: list[tuple[tuple[str, str], float]], expected: list[tuple[tuple[str, str], float]]) -> None:
    assert [stage for stage, _ in got] == [stage for stage, _ in expected], got
    assert [seconds for _, seconds in got] == pytest.approx([seconds for _, seconds in expected]), (got, expected)


def test_the_plan_counts_each_optimum_not_cached_once_and_optimal_on_its_n_optimal_episodes_of_a_disturbed_set(
    tmp_path: Any, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("DWR_GYM_CACHE", str(tmp_path))  # no optimum cached, no plan stored: the planners cold
    sets = [make_scenario(name, n=3, seed=0) for name in ("random", "paper-fig5", "disturbed")]

    def stage(name: str, label: str, episodes: int) -> tuple[tuple[str, str], float]:
        return (name, label), estimated_seconds(label, episodes, 600, name, cold=True)

    assert_plan(planned_seconds({"optimal": Still(), "ptc": "ptc"}, sets, "position", 1), [
        (("random", "optimum"), 3 * PLAN_SECONDS), stage("random", "optimal", 3), stage("random", "ptc", 3),
        (("paper-fig5", "optimum"), 8 * PLAN_SECONDS), stage("paper-fig5", "optimal", 8), stage("paper-fig5", "ptc", 8),
        (("disturbed", "optimum"), 0.0),  # the random set's starts and T_con: its optima are counted there
        stage("disturbed", "optimal", 1), stage("disturbed", "ptc", 3),
    ])  # fmt: skip
    # each episode's T_con drawn, too short for any plan: its optima are solved at once ("infeasible") and cached
    kwargs = {"T_con_range": (0.4, 0.6)}
    drawn = make_scenario("random", n=3, seed=0, env_kwargs=kwargs)
    optimal_energies(EnvParams.from_kwargs(**kwargs), drawn.starts, drawn.goals, drawn.T_cons, heading=False)
    steps = math.ceil(1.5 * max(drawn.T_cons) / 0.05)  # to the horizon of the longest T_con
    for optimum, missing in (("position", 0), ("pose", 3)):
        expected = [
            (("random", "optimum"), missing * PLAN_SECONDS),
            (("random", "ptc"), estimated_seconds("ptc", 3, steps)),
        ]
        assert_plan(planned_seconds({"ptc": "ptc"}, [drawn], optimum, None), expected)


def test_a_stage_run_here_without_a_plan_is_estimated_as_its_labels() -> None:
    scenario = make_scenario("random", n=2, seed=0, env_kwargs=LONG)
    clock = StageClock(progress=False)
    evaluate({"robust": Still()}, scenario, clock=clock)  # an agent labelled robust: a planner's cost per episode
    ((took,),) = [[t.seconds for t in clock.times]]
    estimate = estimated_seconds("robust", 2, max_steps(scenario, EnvParams(**LONG)))
    assert clock.ratio("robust", "random") == pytest.approx(took / estimate), (clock.ratio("robust", "random"), took)

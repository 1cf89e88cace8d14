"""compare's second process (train.evaluation.side_process): the policies without a planner run beside the planners,
and the numbers are those of the policies run one after the other, to the last digit."""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
import pytest

from train.evaluation import evaluate as evaluate_module
from train.evaluation import side_process
from train.evaluation.evaluate import evaluate
from train.evaluation.scenarios import make_scenario
from train.evaluation.stages import StageClock


@pytest.fixture
def forkable() -> None:
    """Skip where this process may not fork a second one (checked as the test runs: another test module may have
    loaded JAX since collection); the fresh-interpreter test below then runs this module's tests there."""
    if not side_process.side_process_usable():
        pytest.skip("needs Linux, 2 cores and no JAX in this process")


needs_fork = pytest.mark.usefixtures("forkable")


def assert_same_results(a: dict[str, Any], b: dict[str, Any]) -> None:
    """Every field of every policy's RolloutResult equal to the last bit (trajectories too), in the same order."""
    assert list(a) == list(b)
    for label in a:
        for field in dataclasses.fields(a[label]):
            x, y = getattr(a[label], field.name), getattr(b[label], field.name)
            if isinstance(x, np.ndarray):
                np.testing.assert_array_equal(x, y, err_msg=f"{label}.{field.name}")
            elif isinstance(x, dict):
                for key in x:
                    np.testing.assert_array_equal(x[key], y[key], err_msg=f"{label}.trajectory[{key}]")
            else:
                assert x == y, f"{label}.{field.name}"


def results_of(monkeypatch: pytest.MonkeyPatch, switch: str) -> tuple[dict, StageClock]:
    monkeypatch.setenv(side_process.SWITCH, switch)
    # 'astolfi' stands in for a planner here (the real ones solve CasADi problems: too slow for a test)
    monkeypatch.setattr(evaluate_module, "PLANNERS", frozenset({"astolfi"}))
    clock = StageClock(progress=False)
    scenario = make_scenario("random", n=12, seed=5)
    policies = {"ptc": "ptc", "astolfi": "astolfi", "fixed-time": "fixed-time"}
    return evaluate(policies, scenario, record=True, seed=3, clock=clock), clock


@needs_fork
def test_the_side_process_gives_the_same_results_in_the_same_order(monkeypatch: pytest.MonkeyPatch) -> None:
    alone, alone_clock = results_of(monkeypatch, "0")
    beside, beside_clock = results_of(monkeypatch, "1")
    assert list(beside) == list(alone) == ["ptc", "astolfi", "fixed-time"]
    assert_same_results(alone, beside)
    # every policy's stage is timed, whichever process ran it
    assert sorted(t.stage for t in beside_clock.times) == sorted(t.stage for t in alone_clock.times)
    assert all(t.seconds > 0 and t.size == 12 for t in beside_clock.times)


@needs_fork
def test_an_error_in_the_side_process_reaches_the_command(monkeypatch: pytest.MonkeyPatch) -> None:
    real = evaluate_module._rollout_one

    def broken(label: str, *args: object) -> object:
        if label == "ptc":  # a policy of the side process (the planner, 'astolfi' here, runs in this one)
            raise RuntimeError("a policy failed in the side process")
        return real(label, *args)

    monkeypatch.setattr(evaluate_module, "_rollout_one", broken)
    with pytest.raises(RuntimeError, match="failed in the side process"):
        results_of(monkeypatch, "1")


def test_the_side_process_is_off_when_asked_or_where_a_fork_is_unsafe(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv(side_process.SWITCH, "0")
    assert not side_process.side_process_usable()
    monkeypatch.setenv(side_process.SWITCH, "1")
    monkeypatch.setitem(__import__("sys").modules, "jax", object())  # JAX's threads do not survive a fork
    assert not side_process.side_process_usable()


def _slow_pid(seconds: float) -> int:
    import os
    import time

    time.sleep(seconds)
    return os.getpid()


@needs_fork
def test_the_command_takes_the_jobs_the_side_process_has_not_started() -> None:
    """Whichever process is free runs the next job: each job runs once, the side process from the first on, the
    command's from the last on."""
    import os

    jobs = {f"job{i}": (_slow_pid, (0.3,)) for i in range(6)}
    side = side_process.SideProcess(jobs)
    try:
        taken = []
        while (label := side.take()) is not None:
            taken.append(label)
            _slow_pid(0.3)
        beside = side.results()
    finally:
        side.close()
    assert sorted(taken + list(beside)) == sorted(jobs)
    assert "job0" in beside and taken[0] == "job5"  # the side process starts at the front, this one at the end
    assert all(pid != os.getpid() for pid, _ in beside.values())
    assert 1 <= len(taken) < len(jobs)


@needs_fork
def test_plain_policies_give_the_same_results_whichever_process_runs_them(monkeypatch: pytest.MonkeyPatch) -> None:
    """With no planner to wait for, the command's process runs plain policies too: the same numbers."""
    monkeypatch.setenv(side_process.SWITCH, "1")
    monkeypatch.setattr(evaluate_module, "PLANNERS", frozenset({"fixed-time"}))
    scenario = make_scenario("random", n=12, seed=5)
    policies = {"fixed-time": "fixed-time", "ptc": "ptc", "astolfi": "astolfi", "fabregas": "fabregas"}
    clock = StageClock(progress=False)
    shared = evaluate(policies, scenario, seed=3, clock=clock)
    monkeypatch.setenv(side_process.SWITCH, "0")
    alone = evaluate(policies, scenario, seed=3)
    assert list(shared) == list(policies)
    for label in policies:
        for field in ("energy", "final_distance", "final_heading_error", "episode_return", "arrival_time"):
            assert getattr(shared[label], field).tobytes() == getattr(alone[label], field).tobytes(), (label, field)
    assert sorted(t.stage for t in clock.times) == sorted(policies)


@needs_fork
def test_the_jobs_that_ended_beside_are_returned_as_they_end_and_once() -> None:
    """The bar counts the side process's stages when they end there: finished() returns those ended since its last
    call, without waiting, and results() the others; every job once."""
    import time

    jobs = {"quick": (_slow_pid, (0.0,)), "slow": (_slow_pid, (1.5,))}
    side = side_process.SideProcess(jobs)
    try:
        assert side.take() == "slow"  # this process would run it: leave it waiting instead
        deadline = time.monotonic() + 30.0
        ended: dict[str, Any] = {}
        while "quick" not in ended and time.monotonic() < deadline:
            ended.update(side.finished())
            time.sleep(0.01)
        assert list(ended) == ["quick"]
        assert side.finished() == {} and side.results() == {}
    finally:
        side.close()


@needs_fork
def test_the_command_can_take_the_job_the_side_process_would_start_next_and_wait_for_some() -> None:
    jobs = {f"job{i}": (_slow_pid, (0.2,)) for i in range(4)}
    side = side_process.SideProcess(jobs)
    try:
        assert side.take(first=True) == "job1"  # job0 started in the side process at once
        assert side.take() == "job3"
        assert side.started() <= {"job0", "job2"}
        some = side.results({"job0"})
        assert list(some) == ["job0"]
        rest = side.results()
    finally:
        side.close()
    assert set(rest) == {"job2"}


def rows_of(monkeypatch: pytest.MonkeyPatch, switch: str) -> list[dict[str, Any]]:
    from train.evaluation.evaluate import evaluate_sets

    monkeypatch.setenv(side_process.SWITCH, switch)
    # 'astolfi' and 'fixed-time' stand in for two planners: one runs here, the other beside, with the laws
    monkeypatch.setattr(evaluate_module, "PLANNERS", frozenset({"astolfi", "fixed-time"}))
    policies = {"ptc": "ptc", "astolfi": "astolfi", "fixed-time": "fixed-time", "fabregas": "fabregas"}
    seen: list[int] = []
    rows = evaluate_sets(policies, ["random", "disturbed", "noise"], 6, 2, {}, on_rows=lambda r: seen.append(len(r)))
    assert seen == [4, 8, 12]  # the rows come set by set
    return rows


@needs_fork
def test_every_set_on_two_processes_gives_the_rows_of_the_sets_in_turn(monkeypatch: pytest.MonkeyPatch) -> None:
    """compare's sets on two processes, the jobs of every set in one queue: the same rows, in the same order, to the
    last digit, as one process running them in turn."""
    import json

    alone, beside = rows_of(monkeypatch, "0"), rows_of(monkeypatch, "1")
    assert [(r["scenario"], r["policy"]) for r in beside] == [(r["scenario"], r["policy"]) for r in alone]
    timing = {"seconds", "optimum_seconds"}
    for a, b in zip(alone, beside, strict=True):
        assert json.dumps({k: v for k, v in a.items() if k not in timing}) == json.dumps(
            {k: v for k, v in b.items() if k not in timing}
        )
        assert b["seconds"] > 0


@needs_fork
def test_the_plans_solved_beside_reach_the_plan_store(monkeypatch: pytest.MonkeyPatch, tmp_path: Any) -> None:
    """A planner run in the side process writes its plans to the store, in files of that process's own: a second
    command takes them instead of solving them again."""
    import os
    from collections import OrderedDict

    pytest.importorskip("casadi")
    from baselines import nmpc, plan_store
    from train.evaluation.evaluate import evaluate_sets

    monkeypatch.setenv("DWR_GYM_CACHE", str(tmp_path))
    monkeypatch.setenv(side_process.SWITCH, "1")
    policies = {"robust-pt": "robust-pt", "optimal": "optimal", "ptc": "ptc"}  # 'optimal' runs beside
    kwargs = {"T_con": 4.0, "T_con_range": None}
    first = evaluate_sets(policies, ["random"], 2, 0, kwargs)
    writers = {path.name.split("-")[0] for path in plan_store.default_directory().glob("*.npz")}
    assert str(os.getpid()) in writers and len(writers) == 2, writers
    monkeypatch.setattr(nmpc, "_MEMO", OrderedDict())
    solved: list[int] = []
    real = nmpc.solve_plans
    monkeypatch.setattr(nmpc, "solve_plans", lambda jobs, workers=1: solved.append(len(jobs)) or real(jobs, workers))
    monkeypatch.setenv(side_process.SWITCH, "0")  # every planner here, where the solves are counted
    second = evaluate_sets(policies, ["random"], 2, 0, kwargs)
    assert sum(solved) == 0, solved  # every plan read from the store, none solved
    for a, b in zip(first, second, strict=True):
        assert a["energy_mean"] == b["energy_mean"] and a["success_rate"] == b["success_rate"], a["policy"]


def test_the_two_process_tests_run_in_a_fresh_interpreter_where_this_one_has_jax() -> None:
    """The default suite loads JAX (other modules) before this module's tests run, and a process with JAX's threads
    must not fork: there, this module's tests run in a fresh interpreter, so that the main job's two processes are
    tested by the default suite wherever it runs on Linux with 2 cores."""
    import os
    import subprocess
    import sys

    if side_process.side_process_usable():
        pytest.skip("this process runs them itself")
    if not sys.platform.startswith("linux") or (os.cpu_count() or 1) < 2 or os.environ.get(side_process.SWITCH) == "0":
        pytest.skip("needs Linux and 2 cores, the second process not turned off")
    test = "not test_the_two_process_tests_run_in_a_fresh_interpreter"
    done = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider",
                           __file__, "-k", test], capture_output=True, text=True, timeout=900)  # fmt: skip
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-2000:]
    assert " passed" in done.stdout and "skipped" not in done.stdout, done.stdout[-1000:]

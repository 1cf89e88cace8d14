"""The minimum-energy planner's edges (baselines.optimal, baselines.nmpc): what a failed or infeasible solve reports,
the fallbacks (fatrop to IPOPT, an infeasible re-plan to a late plan), the re-plan tolerance and the batch of searches."""

from __future__ import annotations

import re
import sys
import threading
from collections import OrderedDict
from typing import Any

import gymnasium as gym
import numpy as np
import pytest

from baselines import ExpertPolicy, make_controller, minimum_energy_nlp
from baselines.optimal import (
    InfeasibleArrivalTimeError,
    OptimalControlError,
    Plan,
    default_solver,
    least_arrival_time,
    solve_minimum_energy,
)
from tests.solving import plans_one_by_one

ca = pytest.importorskip("casadi")
LIMITS = {"dt": 0.05, "u_max": 0.5, "omega_max": 2.0}


@pytest.mark.parametrize("solver", ["ipopt", "fatrop"])
def test_a_failed_solve_is_an_optimal_control_error_naming_the_solver_the_time_and_the_status(
    solver: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A solve that does not converge is a scenario's failure (OptimalControlError, which the planners catch), never
    another exception that would stop a whole evaluation; fatrop's failure falls back to IPOPT first. The message
    names the time the plan had (16 intervals of 0.25 s) and why the solver stopped."""
    if solver == "fatrop" and not ca.has_nlpsol("fatrop"):
        pytest.skip("this CasADi ships no fatrop")
    # fatrop keeps max_iter only until its solver's first success, which first_call is: here a solver not called first,
    # on a thread of its own (a thread's solvers are its own)
    monkeypatch.setattr(minimum_energy_nlp, "first_call", lambda *args: None)
    outcome: list[object] = []

    def solve() -> None:
        try:
            solve_minimum_energy((-1.0, 0.5, 0.0), 4.0, **LIMITS, hold_steps=5, max_iter=1, solver=solver)  # type: ignore[arg-type]
        except OptimalControlError as error:
            outcome.append(error)

    thread = threading.Thread(target=solve)
    thread.start()
    thread.join()
    assert len(outcome) == 1 and re.fullmatch(rf"{solver} found no plan from start=\(-1.0, 0.5, 0.0\) in 4 s "
                                              r"\(last status: Maximum_Iterations_Exceeded\)", str(outcome[0])), outcome  # fmt: skip


def test_a_turn_longer_than_the_time_is_infeasible_when_the_heading_counts() -> None:
    """From 0.1 m with the heading 3 rad off, the turn alone takes 3 / omega_max = 1.5 s: 1 s is refused up front for
    the full pose, while the position alone is reachable in it."""
    with pytest.raises(InfeasibleArrivalTimeError, match=r"T_con=1 s is infeasible.*needs at least 1.5 s"):
        solve_minimum_energy((0.1, 0.0, 3.0), 1.0, **LIMITS)  # type: ignore[arg-type]
    assert solve_minimum_energy((0.1, 0.0, 3.0), 1.0, **LIMITS, heading=False).intervals == 20  # type: ignore[arg-type]


def test_without_fatrop_the_default_solver_is_ipopt(monkeypatch: pytest.MonkeyPatch) -> None:
    """An older CasADi without fatrop still plans: the default falls back to IPOPT, which every CasADi ships."""
    monkeypatch.setattr(ca, "has_nlpsol", lambda name: name != "fatrop")
    assert default_solver() == "ipopt"
    monkeypatch.setattr(ca, "has_nlpsol", lambda name: True)
    assert default_solver() == "fatrop"


def drive(controller: Any, start: tuple[float, float, float], steps: int, **env_kwargs: Any) -> float:
    """Run the expert of ``controller`` from ``start`` (T_con 5 s) for up to ``steps``; the final distance [m]."""
    env = gym.make("DWRPointStabilization-v1", **env_kwargs)
    expert = ExpertPolicy(controller, 0.5, 2.0)
    observation, info = env.reset(seed=0, options={"start": start, "T_con": 5.0})
    for _ in range(steps):
        observation, _, terminated, truncated, info = env.step(expert.predict(observation)[0])
        if terminated or truncated:
            break
    env.close()
    return float(info["distance"])


def test_a_replan_found_infeasible_becomes_a_late_plan_from_where_the_robot_is(monkeypatch: pytest.MonkeyPatch) -> None:
    """Noise can leave too little time on the plan's grid: such a re-plan is infeasible, and the robot then gets a new
    plan from where it is, arriving in 1.5 times the least time plus one interval, instead of a failure (a robot
    whose planner failed stands still)."""
    import baselines.nmpc as nmpc

    real = solve_minimum_energy
    late: list[dict[str, Any]] = []

    def infeasible_replans(**job: Any) -> Plan:
        if job.get("warm_start") is not None:  # every shrinking-horizon re-plan
            raise InfeasibleArrivalTimeError("too little time left (injected)")
        if job.get("intervals", 0) is None:
            late.append(job)
        return real(**job)

    monkeypatch.setattr(nmpc, "solve_plans", plans_one_by_one(infeasible_replans))
    monkeypatch.setattr(nmpc, "_MEMO", OrderedDict())
    controller = make_controller("optimal", workers=1)
    distance = drive(controller, (-1.0, 0.3, 0.0), 60, actuation_noise=0.05)
    assert late and not controller.failures
    for job in late:
        least = least_arrival_time(job["start"], 0.5, 2.0, True)
        assert job["arrival_time"] == pytest.approx(1.5 * least + 0.05 * 5, rel=1e-12)
        assert job["frozen"] == 0 and job["warm_start"] is None
    assert distance < 0.6  # it drove on (from 1.04 m) on the late plans


def test_a_zero_replan_tolerance_replans_on_schedule_and_the_default_spares_an_exact_robot() -> None:
    """replan_tolerance 0 re-plans at every scheduled re-plan; the default skips the re-plans of a noise-free robot,
    which is where its plan puts it (to the solver's tolerance)."""
    always = make_controller("optimal", workers=1, replan_tolerance=0.0, replan_every=20)
    drive(always, (-1.0, 0.3, 0.0), 60)
    spared = make_controller("optimal", workers=1, replan_every=20)
    drive(spared, (-1.0, 0.3, 0.0), 60)
    assert spared.solves == 1
    assert always.solves == 3  # the first plan, then at steps 20 and 40


def test_a_batch_solves_the_plans_of_the_searches_one_by_one_and_a_failure_is_its_own(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Every episode's search of a step solved at once on two threads (warm starts and cold guesses together) gives
    each the plan of its search alone, to the last bit; a search that fails (here: its guesses cut to one iteration)
    or is infeasible is named by its error and leaves the others' plans intact; no NaN in a plan."""
    from baselines.optimal import solve_plans

    jobs: list[dict[str, Any]] = [{"start": (-0.4 - 0.2 * k, 0.1 * k, 2.5 * (-1) ** k), "arrival_time": 4.0,
                                   "hold_steps": 5, **LIMITS} for k in range(6)]  # fmt: skip
    first = solve_minimum_energy(**jobs[0])
    jobs.append({**jobs[0], "frozen": 2, "intervals": first.intervals, "warm_start": first.solution})  # a re-plan
    jobs.append({**jobs[1], "max_iter": 1, "solver": "ipopt"})  # fails from every guess
    jobs.append({**jobs[2], "arrival_time": 0.5})  # infeasible
    alone: list[Any] = []
    for job in jobs:
        try:
            alone.append(solve_minimum_energy(**job))
        except (OptimalControlError, InfeasibleArrivalTimeError) as error:
            alone.append(error)
    batch = solve_plans(jobs, workers=2)
    assert isinstance(batch[-2], OptimalControlError) and "found no plan" in str(batch[-2])
    assert isinstance(batch[-1], InfeasibleArrivalTimeError) and "T_con=0.5 s is infeasible" in str(batch[-1])
    for one, many in zip(alone[:-2], batch[:-2], strict=True):
        assert isinstance(many, Plan) and isinstance(one, Plan)
        assert np.array_equal(one.solution, many.solution) and np.isfinite(many.solution).all()
        assert (one.energy, one.candidate, one.tried, one.iterations) == (many.energy, many.candidate, many.tried,
                                                                          many.iterations)  # fmt: skip
    assert batch[6].tried == 1  # the re-plan converged from its warm start: no cold guess solved
    assert {one.tried for one in batch[:6]} == {4}  # each facing away: both ways round, forward and reverse


def _energies_in_a_batch(jobs: list[dict[str, Any]]) -> list[float]:
    from baselines.optimal import solve_plans

    return [plan.energy for plan in solve_plans(jobs, workers=2)]  # type: ignore[union-attr]


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="fork is Linux's start method here")
def test_a_forked_process_solves_on_threads_of_its_own() -> None:
    """A process forked after this one solved on threads (the command's second process is forked) has none of them:
    its batch starts threads of its own and returns the parent's plans, instead of waiting on threads that are gone."""
    import multiprocessing

    jobs = [{"start": (-0.5 - 0.1 * k, 0.2, 0.0), "arrival_time": 3.0, "hold_steps": 5, **LIMITS} for k in range(4)]
    here = _energies_in_a_batch(jobs)
    with multiprocessing.get_context("fork").Pool(1) as pool:
        there = pool.apply_async(_energies_in_a_batch, (jobs,)).get(timeout=120)
    assert there == here

"""Minimum-energy point stabilization by the prescribed time: the optimum every law is measured against.

Over commands held constant for ``dt`` (the env's zero-order hold, integrated exactly as
:func:`dwr_gym.model.unicycle_step_exact` does), within the actuator limits, the plan minimises the
env's ``energy`` = sum of (u^2 + omega^2) dt subject to reaching the goal position, and the goal
heading unless ``heading=False`` (the paper's position-only task), at the arrival time (T_con by
default). The problem, its solvers (IPOPT, fatrop) and why they run on threads: :mod:`baselines.minimum_energy_nlp`.

The problem is not convex: each search solves it from a few guesses and keeps the cheapest plan. :func:`solve_plans`
solves many searches at once (every episode's plan of a control step, every optimum of a batch), all their guesses on
a few threads; :func:`solve_minimum_energy` is one search.

CasADi is an optional dependency: ``pip install "dwr-gym[optimal]"``.
"""

from __future__ import annotations

import functools
import math
import os
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from baselines.minimum_energy_nlp import (
    SMALL_HALF_TURN,
    SOLVERS,
    casadi_step_exact,
    default_solver,
    fill_stage_states,
    minimum_energy_solver,
    require_casadi,
    stage_order,
    thread_solver,
)
from dwr_gym import model

#: Relative margin on the feasibility bound below which a plan is not attempted.
FEASIBILITY_MARGIN = 1e-9
#: The planners' solver tolerance (``tol`` of :func:`solve_minimum_energy`): their plans' energies to some 1e-7, a
#: tenth fewer iterations than the optimum's 1e-10; a closed loop that re-plans from measured poses needs no more.
PLAN_TOLERANCE = 1e-8


class OptimalControlError(RuntimeError):
    """The solver did not find a plan (reported as a failure of that scenario, never a crash of an evaluation)."""


class InfeasibleArrivalTimeError(ValueError):
    """The arrival time is shorter than the least time in which the robot can reach the goal."""


def least_arrival_time(start: tuple[float, float, float], u_max: float, omega_max: float, heading: bool) -> float:
    """A lower bound of the time in which the robot can reach the goal (origin, heading 0) from ``start``:
    d_0 / u_max, and |psi_0| / omega_max when the heading must reach 0 too [s]."""
    bound = math.hypot(start[0], start[1]) / u_max
    if heading:
        bound = max(bound, abs(float(model.wrap_angle(start[2]))) / omega_max)
    return bound


@dataclass(frozen=True)
class Plan:
    """A minimum-energy plan in the goal frame: command k is held over [k h, (k + 1) h)."""

    commands: NDArray[np.float64]  # (intervals, 2): u [m/s], omega [rad/s]
    states: NDArray[np.float64]  # (intervals + 1, 3): x, y, psi (unwrapped) [m, m, rad]
    interval: float  # h [s]
    energy: float  # sum of (u^2 + omega^2) h over the plan
    iterations: int
    solve_time: float  # [s]
    solution: NDArray[np.float64]  # the raw decision vector, to warm-start the next solve
    candidate: int = -1  # the guess of the search it was solved from (0: the warm start, where one was given)
    tried: int = 0  # how many guesses the search solved (1 where a hint named the guess)

    @property
    def intervals(self) -> int:
        return int(self.commands.shape[0])


def initial_guess(
    start: tuple[float, float, float], intervals: int, h: float, target_heading: float, reverse: bool
) -> NDArray[np.float64]:
    """A straight line to the goal at constant speed, the heading turning uniformly to ``target_heading``."""
    s = np.linspace(0.0, 1.0, intervals + 1)
    states = np.stack([start[0] * (1.0 - s), start[1] * (1.0 - s), start[2] + (target_heading - start[2]) * s])
    speed = math.hypot(start[0], start[1]) / (intervals * h)
    commands = np.stack(
        [
            np.full(intervals, -speed if reverse else speed),
            np.full(intervals, (target_heading - start[2]) / (intervals * h)),
        ]
    )
    return np.concatenate([states.T.ravel(), commands.T.ravel()])


@dataclass(frozen=True)
class MinimumEnergyProblem:
    """One search of :func:`solve_minimum_energy`: the bounds and parameters of its NLP and the guesses it solves."""

    intervals: int  # the solver's size (padded)
    planned: int  # the plan's intervals, the padding cut off
    h: float  # [s]
    lower: NDArray[np.float64]
    upper: NDArray[np.float64]
    parameters: Any
    candidates: tuple[tuple[NDArray[np.float64], float | None], ...]  # each guess with its final heading (None: free)
    warm: bool  # candidate 0 is the warm start: the cold guesses are only its fallback
    response: bool
    max_iter: int
    solver: str
    start: tuple[float, float, float]
    tol: float = 1e-10  # the solver's convergence tolerance
    stage: int = 1  # fatrop's intervals per stage (minimum_energy_solver)


def minimum_energy_problem(
    start: tuple[float, float, float],
    arrival_time: float,
    dt: float,
    u_max: float,
    omega_max: float,
    *,
    heading: bool = True,
    hold_steps: int = 1,
    frozen: int = 0,
    intervals: int | None = None,
    warm_start: NDArray[np.float64] | None = None,
    guesses: int = 2,
    response: tuple[float, float, float, float] | None = None,
    pad_to: int = 1,
    max_iter: int = 1000,
    solver: str | None = None,
    tol: float = 1e-10,
    stage: int = 1,
) -> MinimumEnergyProblem:
    """The search of :func:`solve_minimum_energy` (same keywords), unsolved; raises
    :class:`InfeasibleArrivalTimeError` where the time left is too short."""
    h = dt * hold_steps
    if intervals is None:
        intervals = math.floor(arrival_time / h + 1e-9)
    moving = intervals - frozen
    reach = (u_max, omega_max)
    if response is not None:  # the speeds the robot keeps at most, whatever it turns (a lower bound of the time)
        b_u, b_w, a, _ = response
        reach = (max(a * u_max + abs(b_u), 1e-9), max(a * omega_max + abs(b_w), 1e-9))
    least = least_arrival_time(start, *reach, heading)
    if moving < 1 or moving * h < least * (1.0 + FEASIBILITY_MARGIN):
        smallest = math.ceil(least / h - 1e-9) * h + frozen * h
        raise InfeasibleArrivalTimeError(
            f"T_con={arrival_time:g} s is infeasible: from d_0={math.hypot(start[0], start[1]):.4g} m "
            f"the robot needs at least {smallest:.4g} s at u_max={u_max:g} m/s, omega_max={omega_max:g} rad/s "
            f"(dt={dt:g} s); expected T_con >= {smallest:.4g}"
        )
    planned = intervals
    intervals = -(-intervals // pad_to) * pad_to  # the next multiple of pad_to
    if isinstance(stage, bool) or not isinstance(stage, int) or stage < 1 or intervals % stage or (
            stage > 1 and response is not None):  # fmt: skip
        raise ValueError(f"stage={stage!r} is invalid: expected an integer >= 1 that divides the {intervals} intervals "
                         "(1 with response)")  # fmt: skip
    parameters = h if response is None else [h, *response]
    n_states = 3 * (intervals + 1)
    lower, upper = np.full(n_states + 2 * intervals, -np.inf), np.full(n_states + 2 * intervals, np.inf)
    lower[:3] = upper[:3] = start
    lower[3 * intervals : 3 * intervals + 2] = upper[3 * intervals : 3 * intervals + 2] = 0.0
    lower[n_states::2], upper[n_states::2] = -u_max, u_max
    lower[n_states + 1 :: 2], upper[n_states + 1 :: 2] = -omega_max, omega_max
    lower[n_states : n_states + 2 * frozen] = upper[n_states : n_states + 2 * frozen] = 0.0
    if response is not None:  # held still the robot moves with its disturbance: the padding commands cancel it
        b_u, b_w, a, g = response
        padding_command = np.tile([-b_u / a, (-b_w + g * b_u / a) / a], intervals - planned)
    else:
        padding_command = np.zeros(2 * (intervals - planned))
    lower[n_states + 2 * planned :] = upper[n_states + 2 * planned :] = padding_command

    candidates: list[tuple[NDArray[np.float64], float | None]] = []
    if warm_start is not None:
        # the warm start keeps the turn it chose (its final heading, 0 or +-2 pi)
        candidates.append((warm_start, float(warm_start[3 * intervals + 2]) if heading else None))
    targets = [0.0]
    if heading and abs(start[2]) > math.pi / 2:  # from behind, turning the other way round may be cheaper
        targets.append(math.copysign(2.0 * math.pi, start[2]))
    for target in targets:
        for reverse in (False, True)[:guesses]:
            guess = frozen_guess(start, planned, frozen, h, target, reverse)
            if intervals > planned:  # the padding: the robot at the goal, holding still
                states, commands = guess[: 3 * (planned + 1)], guess[3 * (planned + 1) :]
                goal = np.tile(states[-3:], intervals - planned)
                guess = np.concatenate([states, goal, commands, padding_command])
            candidates.append((guess, target if heading else None))
    return MinimumEnergyProblem(intervals, planned, h, lower, upper, parameters, tuple(candidates),
                                warm_start is not None, response is not None, max_iter, solver or default_solver(),
                                tuple(start), tol, stage)  # fmt: skip


def solve_minimum_energy(
    start: tuple[float, float, float],
    arrival_time: float,
    dt: float,
    u_max: float,
    omega_max: float,
    **options: Any,
) -> Plan:
    """The minimum-energy plan from ``start`` (goal frame: goal at the origin, heading 0) to the goal.

    The plan has ``intervals`` commands (default: as many whole periods of ``hold_steps * dt`` as fit
    in ``arrival_time``), each held for ``hold_steps`` control periods; the first ``frozen`` are held
    at zero (the time already spent when re-planning over a shrinking horizon), so the robot arrives
    at the end of the last interval. Raises :class:`InfeasibleArrivalTimeError` when the time left is below
    :func:`least_arrival_time`, and :class:`OptimalControlError` when the solver fails.

    The problem is not convex: it is solved from ``guesses`` cold starts (driving forward, then in
    reverse; both ways round for the heading when the robot starts facing away) and the cheapest
    converged plan is kept; with ``warm_start`` (a previous plan's solution) that one is tried first.

    With ``response`` (b_u, b_omega, a, g) the robot does (a u + b_u, a omega + g u + b_omega) with the planned
    commands (u, omega), which stay within the limits; the plan's energy is that of the robot's velocities.
    ``pad_to`` solves a problem of the next multiple of ``pad_to`` intervals whose last ones hold the robot still
    at the goal, and returns the plan without them: the same plan from fewer solvers to build and cache.
    ``max_iter`` bounds the solver's iterations per guess (a re-plan in a control loop must not take seconds); ``tol``
    is the solver's convergence tolerance (the planners' 1e-8 saves an iteration of some ten where the plan's energy
    to 1e-7 is all a closed loop needs; the optimum keeps 1e-10).
    ``solver`` is "ipopt" or "fatrop" (:data:`SOLVERS`; default :func:`default_solver`); where fatrop converges
    from no guess, IPOPT tries them too; ``stage`` is fatrop's intervals per stage (:func:`minimum_energy_solver`).
    The keywords are those of :func:`minimum_energy_problem`; many searches at once: :func:`solve_plans`, the same
    plans to the last bit.
    """
    (result,) = solve_plans([{"start": start, "arrival_time": arrival_time, "dt": dt, "u_max": u_max,
                              "omega_max": omega_max, **options}])  # fmt: skip
    if isinstance(result, Exception):
        raise result
    return result


def solve_plans(jobs: list[dict[str, Any]], workers: int = 1) -> list[Plan | Exception]:
    """:func:`solve_minimum_energy` of each job's keywords, in order, its error returned (one failure leaves the other
    plans intact): every guess of every search at once, on ``workers`` threads (the solver releases the GIL; each
    thread keeps its own solvers, :func:`thread_solver`), in rounds: the warm starts and every guess of the cold
    searches; the cold guesses of the searches whose warm start failed; then, with IPOPT, the searches fatrop found no
    plan in. Each solve is a pure function of its guess, so the plans are the one-by-one
    search's to the last bit, whatever the threads and the batch.

    A job with ``coarse`` = k > 1 (a long horizon on a fine grid: the optimum's 400-1,200 intervals) is searched on a
    grid k times coarser first (each command held k times as long, ``pad_to`` divided by k), every guess there; the
    cheapest coarse plan, each command repeated k times, is then the fine search's warm start, its cold guesses only
    the fallback. The coarse plan is a feasible point of the fine problem (k exact steps of one command are its
    exact step over k dt), so the fine search converges in a few iterations instead of a search from each of 2-4
    guesses. On the 1,009 default optima (k = 20, 4 intervals a stage) the energies equal the shipped ones to 4.7e-7
    (``python -m benchmarks run optimum-speed``); where the refinement stops at fatrop's own tolerance more than 1e-6
    above, ``dwr-gym optimum verify`` decides by the whole fine search."""
    results: list[Plan | Exception | None] = [None] * len(jobs)
    problems: dict[int, MinimumEnergyProblem] = {}
    jobs = _refined(jobs, workers)
    for i, job in enumerate(jobs):
        try:
            problems[i] = minimum_energy_problem(**job)
        except InfeasibleArrivalTimeError as error:
            results[i] = error
    searches = {i: _Search() for i in problems}
    _search(sorted(problems), problems, searches, workers)
    fallback = [i for i, s in searches.items() if s.best is None and problems[i].solver != "ipopt"]
    for i in fallback:  # fatrop's failures are rare: IPOPT from the same guesses, a search of its own
        searches[i] = _Search(iterations=searches[i].iterations, seconds=searches[i].seconds)
    _search(fallback, problems, searches, workers, "ipopt")
    for i, problem in problems.items():
        search = searches[i]
        if search.best is None:
            solver = problem.solver
            results[i] = OptimalControlError(
                f"{solver} found no plan from start={tuple(round(v, 4) for v in problem.start)} in "
                f"{problem.intervals * problem.h:g} s (last status: {search.status})"
            )
            continue
        best, planned = search.best, problem.planned
        results[i] = Plan(best.commands[:planned], best.states[: planned + 1], problem.h, best.energy,
                          search.iterations, search.seconds, best.solution, best.candidate, search.tried)  # fmt: skip
    return results  # type: ignore[return-value]


def _refined(jobs: list[dict[str, Any]], workers: int) -> list[dict[str, Any]]:
    """The jobs with their ``coarse`` stage solved: each such job warm-started from its coarse plan (see
    :func:`solve_plans`); the job unchanged where the coarse search found no plan."""
    refined = [{k: v for k, v in job.items() if k != "coarse"} for job in jobs]
    staged = {i: job for i, job in enumerate(jobs) if job.get("coarse", 1) != 1}
    coarse_jobs = []
    for i, job in staged.items():
        k, pad_to = job["coarse"], job.get("pad_to", 1)
        if isinstance(k, bool) or not isinstance(k, int) or k < 1 or pad_to % k:
            raise ValueError(f"coarse={k!r} is invalid: expected an integer >= 1 that divides pad_to={pad_to}")
        coarse_jobs.append({**refined[i], "hold_steps": job.get("hold_steps", 1) * k, "pad_to": pad_to // k,
                            "stage": 1})  # fmt: skip
    if not staged:
        return refined
    for (i, job), plan in zip(staged.items(), solve_plans(coarse_jobs, workers), strict=True):
        if isinstance(plan, Plan):
            refined[i] = {**refined[i], **_fine_warm_start(plan, job)}
    return refined


def _fine_warm_start(plan: Plan, job: dict[str, Any]) -> dict[str, Any]:
    """The keywords that make ``job`` (fine) start from the coarse ``plan``: each coarse command held over k fine
    intervals, the states between by the exact step, then the robot still at the goal up to the fine problem's end."""
    k, dt = job["coarse"], job["dt"] * job.get("hold_steps", 1)
    padded_coarse = (plan.solution.size - 3) // 5
    coarse = plan_from_solution(plan.solution, padded_coarse, plan.interval, plan.energy)
    planned = math.floor(job["arrival_time"] / dt + 1e-9)
    pad_to = job.get("pad_to", 1)
    padded = -(-planned // pad_to) * pad_to
    commands = np.repeat(coarse.commands, k, axis=0)
    origins = np.repeat(coarse.states[:-1], k, axis=0)
    into = np.tile(np.arange(k), padded_coarse) * dt  # the time into each coarse interval [s]
    x, y, psi = model.unicycle_step_exact(origins[:, 0], origins[:, 1], origins[:, 2], commands[:, 0],
                                          commands[:, 1], into)  # fmt: skip
    still = padded - commands.shape[0]  # the fine problem's intervals past the coarse one's: at the goal
    states = np.concatenate([np.stack([x, y, psi], axis=1), np.tile(coarse.states[-1], (still + 1, 1))])
    commands = np.concatenate([commands, np.zeros((still, 2))])
    return {"intervals": planned, "warm_start": np.concatenate([states.ravel(), commands.ravel()])}


@dataclass
class _Search:
    """One search's state over the rounds of :func:`solve_plans`: the cheapest plan so far, as the guesses come in
    their order."""

    best: Plan | None = None
    iterations: int = 0
    status: str = ""
    tried: int = 0
    seconds: float = 0.0


def _search(ids: list[int], problems: dict[int, MinimumEnergyProblem], searches: dict[int, _Search], workers: int,
            solver: str | None = None) -> None:  # fmt: skip
    """The searches ``ids`` with their own solver (or ``solver``): the warm starts and the cold searches' guesses,
    then the cold guesses of the searches whose warm start did not converge (it is the re-plan where it does)."""
    name = {i: solver or problems[i].solver for i in ids}
    _run_round([(i, c, name[i]) for i in ids for c in range(1 if problems[i].warm else len(problems[i].candidates))],
               problems, searches, workers)  # fmt: skip
    _run_round([(i, c, name[i]) for i in ids if searches[i].best is None and problems[i].warm
                for c in range(1, len(problems[i].candidates))], problems, searches, workers)  # fmt: skip


def _run_round(tasks: list[tuple[int, int, str]], problems: dict[int, MinimumEnergyProblem],
               searches: dict[int, _Search], workers: int) -> None:  # fmt: skip
    """Solve every (search, guess, solver) of ``tasks`` and fold each result into its search in the guesses' order:
    the cheapest wins, the first of equals. The threads take the tasks in units of one problem size (and solver), the
    largest first, so that a size is built by one thread where it can be (a solver of 1,000 intervals takes longer to
    build than a few solves with it); a size with more tasks than a fair share of one thread is split."""
    if not tasks:
        return
    solve = functools.partial(_solve_guess, problems)
    if workers > 1 and len(tasks) > 1:
        share = -(-len(tasks) // (2 * workers))
        sizes: dict[tuple[int, bool, int, float, str, int], list[int]] = {}
        for t, (i, _, solver_name) in enumerate(tasks):
            p = problems[i]
            sizes.setdefault((p.intervals, p.response, p.max_iter, p.tol, solver_name, p.stage), []).append(t)
        units = [group[start : start + share] for _, group in sorted(sizes.items(), key=lambda kv: -kv[0][0])
                 for start in range(0, len(group), share)]  # fmt: skip
        futures = [_threads(workers).submit(lambda unit: [solve(tasks[t]) for t in unit], unit) for unit in units]
        try:
            outcomes = {t: outcome for unit, future in zip(units, futures, strict=True)
                        for t, outcome in zip(unit, future.result(), strict=True)}  # fmt: skip
        except BaseException:  # Ctrl-C: the threads finish the units they are in, no other
            for future in futures:
                future.cancel()
            raise
    else:
        outcomes = {t: solve(task) for t, task in enumerate(tasks)}
    for t, (i, index, _) in enumerate(tasks):
        plan, iterations, status, seconds = outcomes[t]
        search = searches[i]
        search.seconds += seconds
        search.iterations += iterations
        search.status = status
        search.tried = max(search.tried, index + 1)
        if plan is not None and (search.best is None or plan.energy < search.best.energy - 1e-12):
            search.best = replace(plan, candidate=index)


def _solve_guess(problems: dict[int, MinimumEnergyProblem], task: tuple[int, int, str]
                 ) -> tuple[Plan | None, int, str, float]:  # fmt: skip
    """The plan of one guess of one search (None where the solver did not converge), its iterations, its status, the
    seconds it took."""
    began = time.perf_counter()
    i, index, solver_name = task
    problem = problems[i]
    intervals = problem.intervals
    guess, target = problem.candidates[index]
    lower, upper = problem.lower, problem.upper
    if target is not None:
        lower, upper = lower.copy(), upper.copy()
        lower[3 * intervals + 2] = upper[3 * intervals + 2] = target
    stage = problem.stage if solver_name == "fatrop" else 1  # IPOPT, the fallback: one stage per interval
    solver = thread_solver(intervals, problem.max_iter, problem.response, solver_name, problem.tol, stage)
    order = stage_order(intervals, stage) if solver_name == "fatrop" else slice(None)
    solution = solver(x0=guess[order], lbx=lower[order], ubx=upper[order], lbg=0.0, ubg=0.0, p=problem.parameters)
    stats = solver.stats()
    plan = None
    if stats["success"]:
        unknowns = np.empty(lower.shape)
        unknowns[order] = np.asarray(solution["x"]).ravel()
        fill_stage_states(unknowns, intervals, stage, problem.h)
        plan = plan_from_solution(unknowns, intervals, problem.h, float(solution["f"]))
    return plan, int(stats.get("iter_count", 0)), str(stats.get("return_status", "")), time.perf_counter() - began


_THREADS: dict[int, ThreadPoolExecutor] = {}
# A forked child has none of its parent's threads: it starts its own (an executor that believes it has some would hang).
os.register_at_fork(after_in_child=_THREADS.clear)


def _threads(workers: int) -> ThreadPoolExecutor:
    """The solving threads, kept for the process (their solvers with them)."""
    if workers not in _THREADS:
        _THREADS[workers] = ThreadPoolExecutor(workers, thread_name_prefix="minimum-energy")
    return _THREADS[workers]


def new_threads() -> None:
    """End the solving threads (their solvers with them): the next batch starts threads that have built nothing."""
    for executor in _THREADS.values():
        executor.shutdown()
    _THREADS.clear()


def frozen_guess(
    start: tuple[float, float, float], intervals: int, frozen: int, h: float, target: float, reverse: bool
) -> NDArray[np.float64]:
    """:func:`initial_guess` over the moving intervals, the robot still during the ``frozen`` ones."""
    moving = initial_guess(start, intervals - frozen, h, target, reverse)
    n_states = 3 * (intervals - frozen + 1)
    return np.concatenate([np.tile(start, frozen), moving[:n_states], np.zeros(2 * frozen), moving[n_states:]])


def plan_from_solution(solution: NDArray[np.float64], intervals: int, h: float, energy: float) -> Plan:
    """Unpack IPOPT's decision vector into a :class:`Plan`."""
    n_states = 3 * (intervals + 1)
    return Plan(solution[n_states:].reshape(intervals, 2), solution[:n_states].reshape(intervals + 1, 3), h, energy, 0,
                0.0, solution)  # fmt: skip


__all__ = ["PLAN_TOLERANCE", "SMALL_HALF_TURN", "SOLVERS", "InfeasibleArrivalTimeError", "MinimumEnergyProblem",
           "OptimalControlError", "Plan", "casadi_step_exact", "default_solver", "least_arrival_time",
           "minimum_energy_problem", "minimum_energy_solver", "new_threads", "require_casadi", "solve_minimum_energy",
           "solve_plans", "stage_order", "thread_solver"]  # fmt: skip

"""The ``optimal`` controller: minimum-energy plans to the prescribed deadline, re-planned over the shrinking horizon.

At the first step of an episode it plans (:func:`baselines.optimal.solve_minimum_energy`) from the
observed pose to the goal by T_con (read from the observation, like the other prescribed-time laws),
then plays the plan open loop and re-plans every ``replan_every`` control periods from the pose it
observes, warm-started from its previous plan, with T_con as the terminal time (NMPC with a
shrinking horizon). So it also works under the env's observation and actuation noise. A batch of
robots is planned at once: every robot's search of a control step, all their guesses on a few threads
(:func:`baselines.optimal.solve_plans`).

Needs CasADi: ``pip install "dwr-gym[optimal]"``.
"""

from __future__ import annotations

import hashlib
import math
import os
import pickle
from collections import OrderedDict
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from baselines.base import Controller, ControllerInput, ControllerParams, prescribed_time
from baselines.optimal import (
    PLAN_TOLERANCE,
    InfeasibleArrivalTimeError,
    OptimalControlError,
    Plan,
    least_arrival_time,
    require_casadi,
    solve_plans,
)
from dwr_gym.model import FloatArray, wrap_angle
from dwr_gym.params import check_range

#: A re-plan on the episode's grid needs at least this many intervals left (fewer: the plan is kept).
MIN_REPLAN_INTERVALS = 4
#: Plans are solved on problems of a multiple of this many intervals, the robot still at the goal in the extra ones
#: (:func:`baselines.optimal.solve_minimum_energy`'s ``pad_to``): the same plan to the solver's tolerance, from an eighth
#: of the solvers to build (a build costs as much as some ten solves; each episode's T_con is a size of its own).
PAD_TO = 8
#: Plans (or their errors) kept by :class:`PlanPool`, by job, least recently used out: some 10 kB each.
MEMO_SIZE = 8192


def check_count(name: str, value: Any, low: int, high: int) -> int:
    """An integer in [low, high], or a ValueError naming the parameter."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or not low <= int(value) <= high:
        raise ValueError(f"{name}={value!r} is invalid: expected an integer in [{low}, {high}]")
    return int(value)


@dataclass(frozen=True)
class OptimalParams(ControllerParams):
    """Parameters of the minimum-energy NMPC controller; the limits and dt must be the env's."""

    T_con: float = 20.0  # [s]
    """Prescribed time, used when the caller does not observe it (an expert reads it from the observation)."""
    dt: float = 0.05  # [s]
    """The env's control period: each planned command is held for a whole number of periods."""
    u_max: float = 0.5  # [m/s]
    """The env's linear-velocity limit."""
    omega_max: float = 2.0  # [rad/s]
    """The env's angular-velocity limit."""
    heading: bool = True
    """Reach the goal heading too (Theorem 8's final yaw); False is the paper's position-only task."""
    arrival_time: float | None = None  # [s]
    """Plan to arrive at this time instead of T_con (None: at T_con, the minimum-energy choice)."""
    arrival_fraction: float = 1.0
    """Without ``arrival_time``, plan to arrive at this fraction of each episode's T_con (below 1: a margin)."""
    hold_steps: int = 5
    """Plan grid: each planned command is held for this many control periods (5 x 0.05 s = 0.25 s)."""
    replan_every: int = 20
    """Re-plan from the observed pose every this many control periods; 0 plans once per episode."""
    replan_tolerance: float = 1e-3  # [m, rad]
    """Skip a scheduled re-plan when the observed pose is within this of the plan's (0: always re-plan)."""
    workers: int = 0
    """Threads that solve a batch of plans in parallel; 0 uses every core (at most 8), 1 none."""

    def validate(self) -> None:
        for name in ("T_con", "dt", "u_max", "omega_max"):
            object.__setattr__(self, name, check_range(name, getattr(self, name), 0.0, 1e6, low_inclusive=False))
        if not isinstance(self.heading, (bool, np.bool_)):
            raise ValueError(f"heading={self.heading!r} is invalid: expected True or False")
        if self.arrival_time is not None:
            check_range("arrival_time", self.arrival_time, 0.0, 1e6, low_inclusive=False)
        check_range("arrival_fraction", self.arrival_fraction, 0.0, 1.0, low_inclusive=False)
        check_count("hold_steps", self.hold_steps, 1, 10_000)
        check_count("replan_every", self.replan_every, 0, 1_000_000)
        if self.replan_every % self.hold_steps:
            raise ValueError(
                f"replan_every={self.replan_every!r} is invalid: expected a multiple of hold_steps={self.hold_steps}"
            )
        check_count("workers", self.workers, 0, 256)
        check_range("replan_tolerance", self.replan_tolerance, 0.0, 1e6)


#: The plans solved in this process, by :func:`job_key`: a planner that meets a problem again takes the plan solved
#: before. A solve is a pure function of its job (the same plan to the last bit in any process, whatever was solved
#: before it), so this changes no result: it saves the plans that ``dwr-gym compare`` meets on several scenario sets
#: (``robust-pt``'s and ``optimal``'s first plans from the same starts on the random set and the imperfect robots'
#: sets, every plan of the figures' replay of paper-fig5).
_MEMO: OrderedDict[bytes, Plan | Exception] = OrderedDict()


def job_key(job: dict[str, Any]) -> bytes:
    """A digest of every keyword of a :func:`baselines.optimal.solve_minimum_energy` job, bit for bit (0.0 and -0.0,
    a float and a numpy float are different jobs here)."""
    return hashlib.sha256(pickle.dumps(sorted(job.items()), protocol=5)).digest()


def clear_memo() -> None:
    """Forget the plans solved so far (:data:`_MEMO`)."""
    _MEMO.clear()


class PlanPool:
    """Solves batches of plans at once, every guess of every search on ``workers`` threads
    (:func:`baselines.optimal.solve_plans`); errors are returned, not raised. A plan solved before in this process is not solved again (:data:`_MEMO`), nor one stored on disk by an earlier
    command while a :mod:`baselines.plan_store` is open."""

    def __init__(self, workers: int = 0) -> None:
        self.workers = workers or min(os.cpu_count() or 1, 8)

    def map(self, jobs: list[dict[str, Any]]) -> list[Plan | Exception]:
        """:func:`baselines.optimal.solve_minimum_energy` of each job's keywords, in order."""
        from baselines import plan_store

        keys = [job_key(job) for job in jobs]
        store = plan_store.current()
        todo: dict[bytes, dict[str, Any]] = {}
        for key, job in zip(keys, jobs, strict=True):
            if key in _MEMO:
                _MEMO.move_to_end(key)
            elif store is not None and (stored := store.get(key)) is not None:
                _MEMO[key] = stored
            else:
                todo[key] = job
        order = list(todo)
        solved = dict(zip(order, self._solve([todo[key] for key in order]), strict=True))
        results = [solved[key] if key in solved else _MEMO[key] for key in keys]
        for key, result in solved.items():
            _MEMO[key] = result
            if store is not None:
                store.add(key, result)
        while len(_MEMO) > MEMO_SIZE:
            _MEMO.popitem(last=False)
        return results

    def _solve(self, jobs: list[dict[str, Any]]) -> list[Plan | Exception]:
        return solve_plans(jobs, self.workers)

    def close(self) -> None:
        """Nothing to stop: the threads are shared (:func:`baselines.optimal.solve_plans`)."""


def remaining_guess(plan: Plan, played: int, start: tuple[float, float, float]) -> NDArray[np.float64]:
    """The unknowns of a plan from ``start`` over the intervals of ``plan`` after its first ``played``, padded to a
    multiple of :data:`PAD_TO` (the robot still at the goal): the rest of ``plan``'s padded solution from ``start``."""
    padded_before = (plan.solution.size - 3) // 5
    states = plan.solution[: 3 * (padded_before + 1)].reshape(-1, 3)[played:]
    commands = plan.solution[3 * (padded_before + 1) :].reshape(-1, 2)[played:]
    padded = -(-(plan.intervals - played) // PAD_TO) * PAD_TO
    states = np.concatenate([states, np.repeat(states[-1:], max(padded + 1 - len(states), 0), axis=0)])[: padded + 1]
    commands = np.concatenate([commands, np.zeros((max(padded - len(commands), 0), 2))])[:padded]
    states[0] = start
    return np.concatenate([states.ravel(), commands.ravel()])


class OptimalController(Controller):
    """Minimum-energy NMPC to the prescribed deadline (``make_controller("optimal")``)."""

    name = "optimal"

    def __init__(self, params: OptimalParams | None = None, **kwargs: Any) -> None:
        require_casadi()
        self.params: OptimalParams = params if params is not None else OptimalParams.from_kwargs(**kwargs)
        self._size = 0
        self._pool = PlanPool(self.params.workers)
        self.failures: list[str] = []
        """One message per plan IPOPT could not find (the robot then stands still)."""
        self.solves = 0

    def reset(self, mask: ArrayLike | None = None) -> None:
        if self._size == 0:
            return
        index = np.arange(self._size) if mask is None else np.flatnonzero(np.asarray(mask, dtype=bool))
        for i in index:
            self._plans[i] = None
            self._failed[i] = False
            self._last_step[i] = -1
            self._frozen[i] = False

    def freeze(self, mask: ArrayLike) -> None:
        """Neither plan for nor command the robots in ``mask`` (their episodes ended) until their next reset."""
        mask = np.asarray(mask, dtype=bool)
        if mask.shape == (self._size,):
            self._frozen |= mask

    def _resize(self, n: int) -> None:
        self._size = n
        self._plans: list[Plan | None] = [None] * n
        self._origin = np.zeros(n, dtype=np.int64)  # the control period at which the plan's interval 0 begins
        self._next_replan = np.zeros(n, dtype=np.int64)
        self._failed = np.zeros(n, dtype=bool)
        self._last_step = np.full(n, -1, dtype=np.int64)
        self._frozen = np.zeros(n, dtype=bool)

    def compute(self, inputs: ControllerInput) -> tuple[FloatArray, FloatArray]:
        p = self.params
        n = inputs.distance.shape[0]
        if n != self._size:
            self._resize(n)
        step = np.rint(np.asarray(inputs.time, dtype=np.float64) / p.dt).astype(np.int64)
        # A robot whose clock went back started a new episode, even if the caller did not say so. (The clock
        # stands still past horizon_factor * T_con, where the observation's time fraction is clipped.)
        self.reset(step < self._last_step)
        self._last_step = step
        T_con = np.broadcast_to(np.asarray(prescribed_time(inputs, p.T_con), dtype=np.float64), (n,))
        x = -inputs.distance * np.cos(inputs.azimuth)  # goal-frame position from eq. (2)-(3): alpha = atan2(-y, -x)
        y = -inputs.distance * np.sin(inputs.azimuth)
        jobs: dict[int, dict[str, Any]] = {}
        for i in range(n):
            if self._failed[i] or self._frozen[i]:
                continue
            plan = self._plans[i]
            if (
                plan is not None
                and step[i] == 0
                and not self._on_plan(i, (float(x[i]), float(y[i]), float(inputs.heading[i])), 0)
            ):
                plan = self._plans[i] = None  # reset twice without a step: a new start, a new plan
            end = -1 if plan is None else self._origin[i] + plan.intervals * p.hold_steps
            if plan is not None and step[i] < end and (p.replan_every == 0 or step[i] < self._next_replan[i]):
                continue
            start = (float(x[i]), float(y[i]), float(inputs.heading[i]))
            if plan is not None and step[i] < end and self._on_plan(i, start, int(step[i])):
                self._next_replan[i] = step[i] + p.replan_every
                continue
            job = self._job(i, start, int(step[i]), float(T_con[i]), plan)
            if job is None:
                self._next_replan[i] = step[i] + p.replan_every
            else:
                jobs[i] = job
        if jobs:
            self._run(jobs, step)
        u, omega = np.zeros(n), np.zeros(n)
        for i in range(n):
            plan = self._plans[i]
            if plan is None or self._failed[i] or self._frozen[i]:
                continue
            k = (step[i] - self._origin[i]) // p.hold_steps
            if 0 <= k < plan.intervals:
                u[i], omega[i] = plan.commands[k]
        return u, omega

    def _on_plan(self, i: int, pose: tuple[float, float, float], step: int) -> bool:
        """Whether robot i is where its plan puts it at ``step``, within ``replan_tolerance`` (then re-planning is moot)."""
        p = self.params
        offset = step - self._origin[i]
        plan = self._plans[i]
        if plan is None or p.replan_tolerance == 0.0 or offset % p.hold_steps:
            return False
        planned = plan.states[offset // p.hold_steps]
        gap = max(abs(pose[0] - planned[0]), abs(pose[1] - planned[1]), abs(float(wrap_angle(pose[2] - planned[2]))))
        return gap <= p.replan_tolerance

    def _job(
        self, i: int, start: tuple[float, float, float], step: int, T_con: float, plan: Plan | None
    ) -> dict[str, Any] | None:
        """The solve that re-plans robot i at control period ``step``: on the episode's grid if time is left, else late."""
        p = self.params
        arrival = p.arrival_time if p.arrival_time is not None else T_con * p.arrival_fraction
        job: dict[str, Any] = {"start": start, "arrival_time": arrival, "dt": p.dt, "u_max": p.u_max,
                               "omega_max": p.omega_max, "heading": p.heading, "hold_steps": p.hold_steps,
                               "tol": PLAN_TOLERANCE, "pad_to": PAD_TO}  # fmt: skip
        h = p.dt * p.hold_steps
        least = least_arrival_time(start, p.u_max, p.omega_max, p.heading)
        running = plan is not None and step < self._origin[i] + plan.intervals * p.hold_steps
        if plan is not None and running and (step - self._origin[i]) % p.hold_steps == 0:
            frozen = int((step - self._origin[i]) // p.hold_steps)
            moving = plan.intervals - frozen
            if moving < MIN_REPLAN_INTERVALS:
                return None  # too close to the plan's end for a re-plan to change anything: keep the plan
            if moving * h >= least * 1.05 + h:  # time is left on the same grid: shrink the horizon
                # The intervals already played are not the new plan's (held at zero they were the same problem, a
                # solve some frozen / moving times longer): the plan from here, warm-started from the rest of the last.
                job.update(intervals=moving, warm_start=remaining_guess(plan, frozen, start), origin=step)
                return job
        # A new grid from now: the first plan of an episode, or once a plan ran out before arrival (noise), late.
        remaining = arrival - step * p.dt
        if remaining < least * 1.05 + h:
            remaining = max(1.5 * least + h, 20.0 * p.dt)
        job.update(intervals=max(1, math.floor(remaining / h + 1e-9)), origin=step)
        return job

    def _run(self, jobs: dict[int, dict[str, Any]], step: np.ndarray) -> None:
        origins = {i: job.pop("origin") for i, job in jobs.items()}
        results = self._map([jobs[i] for i in jobs])
        self.solves += len(results)
        for (i, job), result in zip(jobs.items(), results, strict=True):
            if isinstance(result, Plan):
                self._plans[i] = result
                self._origin[i] = origins[i]
                self._next_replan[i] = step[i] + max(self.params.replan_every, 1)
            elif isinstance(result, InfeasibleArrivalTimeError) and "intervals" in job:
                # Too little time left for this grid (noise): a plan that arrives late is better than none.
                retry = dict(job, intervals=None, frozen=0, warm_start=None)
                retry["arrival_time"] = 1.5 * least_arrival_time(job["start"], job["u_max"], job["omega_max"],
                                                                 job["heading"]) + job["dt"] * job["hold_steps"]  # fmt: skip
                (late,) = self._map([retry])
                if isinstance(late, Plan):
                    self._plans[i], self._origin[i] = late, step[i]
                    self._next_replan[i] = step[i] + max(self.params.replan_every, 1)
                else:
                    self._fail(i, late)
            elif isinstance(result, OptimalControlError) and "warm_start" in job:
                # A failed re-plan keeps the previous plan, which is still feasible without disturbances.
                self._next_replan[i] = step[i] + max(self.params.replan_every, 1)
            else:
                self._fail(i, result)

    def _fail(self, i: int, error: Exception) -> None:
        self._failed[i] = True
        self._plans[i] = None
        self.failures.append(f"robot {i}: {error}")

    def _map(self, jobs: list[dict[str, Any]]) -> list[Plan | Exception]:
        return self._pool.map(jobs)

    def close(self) -> None:
        """Nothing to stop: the solving threads are shared."""
        pool = getattr(self, "_pool", None)  # absent if __init__ failed (no CasADi)
        if pool is not None:
            pool.close()

    def __del__(self) -> None:
        self.close()


__all__ = ["OptimalController", "OptimalParams", "PlanPool", "clear_memo", "job_key", "remaining_guess"]

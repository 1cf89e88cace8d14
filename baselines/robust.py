"""The robust prescribed-time expert ``robust-pt``: keep the deadline despite disturbances, at near-minimum energy.

The plans of ``optimal`` arrive exactly at T_con and the laws scaled to the deadline arrive just before it, so
anything that slows the robot makes them late. PTC keeps its deadline by arriving early at 2-3 times the
optimum's energy. This controller treats the deadline as a constraint with a time margin that it spends only
when the robot falls behind:

1. **Estimate** (:mod:`baselines.estimation`): an extended Kalman filter on eq. (1) turns noisy or dropped
   pose measurements into a smooth estimate, and its disturbance states (b_u, b_omega) are cancelled from
   the command (a disturbance observer).
2. **Cruise**: at an episode's first step, the minimum-energy plan to the goal pose (:mod:`baselines.optimal`)
   arriving at ``plan_arrival`` * T_con, tracked by Kanayama's feedback on the error in the robot's frame,

       u = u_r cos e_psi + k_along e_x,   omega = omega_r + k_lateral u_r e_y + k_heading |u_r| sin e_psi.

   Leaving the tube of radius ``tube`` around the plan re-plans from the estimate to the same arrival.
3. **Finish**: when the plan ends, or when a re-plan cannot arrive by then, Astolfi's pose law on the time scale of
   eq. (12) with T = ``finish_arrival`` * T_con (:class:`~baselines.polar.PrescribedTimeAstolfiController`):
   its gain 1 / (T - t) rises to the deadline, as the paper's scaling function does, and is capped at
   ``max_gain`` (an unbounded gain under sampling and delay chatters: Aldana-Lopez et al. 2020). It drives in
   reverse when the goal is behind, with hysteresis so that it does not switch to and fro at |alpha| = pi / 2.

Nominally the robot arrives with the plan at ``plan_arrival`` * T_con; the time between that and T_con is the
margin. Needs CasADi (``pip install "dwr-gym[optimal]"``) for the cruise; ``plan=False`` runs the finish from the
start, which needs nothing.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from baselines.base import K_MAX, Controller, ControllerInput, ControllerParams, prescribed_time
from baselines.estimation import (
    NOMINAL_RESPONSE,
    PoseFilter,
    PoseFilterParams,
    compensated_commands,
    measured_pose,
    robot_velocities,
    with_pose,
)
from baselines.polar import astolfi_commands
from dwr_gym import model
from dwr_gym.model import FloatArray
from dwr_gym.validation import as_bool, as_choice, as_float, as_int

CRUISE, FINISH, LEARNED = 0, 1, 2
FINISH_LAWS: tuple[str, ...] = ("pt-astolfi", "ptc")
#: A plan (or re-plan) has at least this many intervals; with less time left the finish law takes over.
MIN_PLAN_INTERVALS = 4
#: Plans are solved on problems of a multiple of this many intervals (fewer solvers to build; see solve_minimum_energy).
PAD_TO = 8
#: IPOPT's iterations per guess of a plan (a converging plan takes 10-60; one that takes more rarely converges).
MAX_ITERATIONS = 150
#: Tries of a plan, each with 1.3 times the time of the one before, before the finish law takes over.
PLAN_ATTEMPTS = 3
#: A plan longer than this many intervals (T_con 60 s at the defaults needs 192) is not solved: the finish law drives.
MAX_PLAN_INTERVALS = 1000
#: Nor is a plan longer than this many T_con (the env ends an episode at 1.5 T_con by default): a robot that slow (a
#: failing wheel) gets the finish law at once instead of searches of hundreds of intervals that rarely converge.
LONGEST_PLAN = 2.0


@dataclass(frozen=True)
class RobustPTParams(ControllerParams):
    """Parameters of ``robust-pt``; ``dt``, ``u_max`` and ``omega_max`` must be the env's."""

    T_con: float = 20.0  # [s]
    """Prescribed time when the input does not carry it (an expert reads it from the observation)."""
    dt: float = 0.05  # [s]
    u_max: float = 0.5  # [m/s]
    omega_max: float = 2.0  # [rad/s]
    plan: bool = True
    """Cruise on a minimum-energy plan (needs CasADi); False: the finish law from the start."""
    plan_arrival: float = 0.8
    """The plan arrives at this fraction of T_con; the rest is the margin, spent only when the robot falls behind."""
    finish_arrival: float = 0.92
    """The finish law's prescribed time T, as a fraction of T_con; in (plan_arrival, 1]."""
    hold_steps: int = 5
    """Plan grid: each planned command is held for this many control periods."""
    tube: float = 0.05  # [m]
    """Re-plan when the estimated position is further than this from the plan's (or the plan ended short)."""
    max_replans: int = 20
    near_goal: float = 0.1  # [m]
    """Re-plans from within this distance of the goal aim at its position alone: a plan that must also turn to the
    goal heading in the last centimetres and second swings the robot to and fro (it arrives with the heading it has,
    which the plans up to there made close to the goal's)."""
    """Re-plans per episode; after them a robot that leaves the tube is handed to the finish law."""
    k_along: float = 1.0  # [1/s]
    k_lateral: float = 4.0  # [1/m^2]
    k_heading: float = 2.0  # [1/m]
    k_rho: float = 1.5
    """Finish: Astolfi's gains in the scaled time s = ln(T / (T - t)) (see PrescribedTimeAstolfiParams)."""
    k_alpha: float = 4.7
    k_beta: float = -1.7
    finish: str = "pt-astolfi"
    """The finish law: 'pt-astolfi' (the full pose, Astolfi's law on the time scale of eq. (12)) or 'ptc' (the
    paper's law, eqs. (16)-(19): the position by its own schedule, whatever the heading)."""
    reverse_hysteresis: float = 0.3  # [rad]
    """Finish: drive in reverse once |alpha| > pi/2 + this, forward again once |alpha| < pi/2 - this."""
    max_gain: float = 1.0  # [1/s]
    """Guard: cap of the finish law's 1 / (T - t), which is infinite at T; k_alpha * max_gain * dt well below 1
    keeps the sampled loop, and one with some input delay, stable."""
    estimator: PoseFilterParams | None = field(default_factory=PoseFilterParams)
    """The state estimate the law acts on (None: the measurement as it comes)."""
    cancel_disturbance: bool = True
    """Correct the command by the robot's estimated response (a disturbance observer; needs ``estimator``)."""
    workers: int = 0
    """Threads that solve a batch of plans in parallel; 0 uses every core (at most 8), 1 none."""
    k: float = K_MAX
    """The env's arcsine gain of eq. (6), for the observation a learned cruise reads."""
    handover_time: float = 0.7
    """With a learned cruise: the planner takes over once t > handover_time * T_con ..."""
    handover_margin: float = 1.5
    """... or once the time left is under handover_margin times the straight-line time d / u_max (behind)."""

    def validate(self) -> None:
        for name in ("T_con", "dt", "u_max", "omega_max"):
            as_float(name, getattr(self, name), 0.0, 1e6, low_inclusive=False)
        as_bool("plan", self.plan)
        as_float("plan_arrival", self.plan_arrival, 0.0, 1.0, low_inclusive=False, high_inclusive=False)
        as_float("finish_arrival", self.finish_arrival, self.plan_arrival, 1.0, low_inclusive=False)
        as_int("hold_steps", self.hold_steps, 1, 10_000)
        as_float("tube", self.tube, 0.0, 1e3, low_inclusive=False)
        as_int("max_replans", self.max_replans, 0, 1_000)
        as_float("near_goal", self.near_goal, 0.0, 1e3)
        for name in ("k_along", "k_lateral", "k_heading", "k_rho"):
            as_float(name, getattr(self, name), 0.0, 1e9, low_inclusive=False)
        as_float("k_beta", self.k_beta, -1e9, 0.0, high_inclusive=False)
        as_float("k_alpha", self.k_alpha, self.k_rho, 1e9, low_inclusive=False)
        as_choice("finish", self.finish, FINISH_LAWS)
        as_float("reverse_hysteresis", self.reverse_hysteresis, 0.0, 0.5 * math.pi, high_inclusive=False)
        as_float("max_gain", self.max_gain, 1.0 / self.T_con, 1e9, low_inclusive=False)
        if self.estimator is not None and not isinstance(self.estimator, PoseFilterParams):
            raise ValueError(f"estimator={self.estimator!r} is invalid: expected PoseFilterParams or None")
        as_bool("cancel_disturbance", self.cancel_disturbance)
        as_int("workers", self.workers, 0, 256)
        as_float("k", self.k, 0.0, K_MAX)
        as_float("handover_time", self.handover_time, 0.0, 1.0, low_inclusive=False)
        as_float("handover_margin", self.handover_margin, 0.0, 1e6)


def tracking_commands(
    pose: NDArray[np.float64], reference: NDArray[np.float64], command: NDArray[np.float64], p: RobustPTParams
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Kanayama's tracking law for poses (N, 3) and reference poses (N, 3) with reference commands (N, 2).

    Returns (u, omega, the position error [m]).
    """
    dx, dy = reference[:, 0] - pose[:, 0], reference[:, 1] - pose[:, 1]
    cos_psi, sin_psi = np.cos(pose[:, 2]), np.sin(pose[:, 2])
    along, lateral = cos_psi * dx + sin_psi * dy, -sin_psi * dx + cos_psi * dy  # the error in the robot's frame
    heading = model.wrap_angle(reference[:, 2] - pose[:, 2])
    u_r, omega_r = command[:, 0], command[:, 1]
    u = u_r * np.cos(heading) + p.k_along * along
    omega = omega_r + p.k_lateral * u_r * lateral + p.k_heading * np.abs(u_r) * np.sin(heading)
    return u, omega, np.hypot(dx, dy)


class RobustPTController(Controller):
    """The robust prescribed-time expert (``make_controller("robust-pt")``); see the module's docstring."""

    name = "robust-pt"

    def __init__(self, params: RobustPTParams | None = None, cruise: Any = None, **kwargs: Any) -> None:
        self.params: RobustPTParams = params if params is not None else RobustPTParams.from_kwargs(**kwargs)
        self.cruise = cruise
        """A learned cruise (anything with stable-baselines3's ``predict`` on the env's observations, e.g. a network
        cloned by train.learning.imitation.robust_dagger) that drives on the estimate until the planner takes over;
        None: plan from the start."""
        p = self.params
        self._pool: Any = None
        if p.plan:
            from baselines.nmpc import PlanPool
            from baselines.optimal import require_casadi

            require_casadi()
            self._pool = PlanPool(p.workers)
        self._filter = PoseFilter(p.estimator, p.dt) if p.estimator is not None else None
        self._ptc: Controller | None = None
        if p.finish == "ptc":
            from baselines.controllers import PTCController

            self._ptc = PTCController(T_con=p.T_con)
        self._limits = np.array([p.u_max, p.omega_max])
        self.failures: list[str] = []
        """One message per plan IPOPT could not find (that robot cruises with the finish law instead)."""
        self.solves = 0
        self._resize(0)

    def _resize(self, n: int) -> None:
        self._n = n
        self._last_step = np.full(n, -1, dtype=np.int64)
        self._phase = np.full(n, CRUISE, dtype=np.int8)
        self._planned = np.zeros(n, dtype=bool)
        self._replans = np.zeros(n, dtype=np.int64)
        self._origin = np.zeros(n, dtype=np.int64)
        self._intervals = np.zeros(n, dtype=np.int64)
        self._direction = np.zeros(n)  # finish: +1 forward, -1 reverse, 0 not decided
        self._command = np.zeros((n, 2))
        self._frozen = np.zeros(n, dtype=bool)
        self._states = np.zeros((n, 1, 3))  # plan states at the interval boundaries, padded with the goal
        self._commands = np.zeros((n, 1, 2))  # plan commands per interval, padded with zeros

    def reset(self, mask: ArrayLike | None = None) -> None:
        index = slice(None) if mask is None else np.asarray(mask, dtype=bool)
        if mask is not None and np.shape(index) != (self._n,):
            return
        self._last_step[index] = -1
        self._phase[index] = LEARNED if self.cruise is not None else CRUISE if self.params.plan else FINISH
        self._planned[index] = False
        self._replans[index] = 0
        self._direction[index] = 0.0
        self._command[index] = 0.0
        self._frozen[index] = False
        if self._filter is not None:
            self._filter.reset(None if mask is None else index)

    def freeze(self, mask: ArrayLike) -> None:
        """Neither plan for nor command the robots in ``mask`` (their episodes ended) until their next reset."""
        mask = np.asarray(mask, dtype=bool)
        if mask.shape == (self._n,):
            self._frozen |= mask

    def compute(self, inputs: ControllerInput) -> tuple[FloatArray, FloatArray]:
        p = self.params
        n = inputs.distance.shape[0]
        if n != self._n:
            self._resize(n)
            self.reset()
        step = np.rint(np.asarray(inputs.time, dtype=np.float64) / p.dt).astype(np.int64)
        self.reset(step < self._last_step)  # a clock that goes back is a new episode
        self._last_step = step
        T_con = np.broadcast_to(np.asarray(prescribed_time(inputs, p.T_con), dtype=np.float64), (n,))
        measured = measured_pose(inputs)
        pose = measured if self._filter is None else self._filter.update(measured, self._command)
        estimate = with_pose(inputs, pose)

        u, omega = np.zeros(n), np.zeros(n)
        learned = (self._phase == LEARNED) & ~self._frozen
        if learned.any():
            self._learned_cruise(np.flatnonzero(learned), estimate, T_con, u, omega)
        cruise = (self._phase == CRUISE) & ~self._frozen
        new = cruise & ~self._planned
        if new.any():
            self._plan(np.flatnonzero(new), pose, step, T_con)
        cruise = (self._phase == CRUISE) & ~self._frozen
        if cruise.any():
            index = np.flatnonzero(cruise)
            u_c, omega_c, ended, off = self._track(index, pose[index], step[index])
            u[index], omega[index] = u_c, omega_c
            stray = ended | off  # a plan that ended before arrival, or a robot out of the tube: plan again
            self._phase[index[stray & (self._replans[index] >= p.max_replans)]] = FINISH
            replan = index[stray & (self._replans[index] < p.max_replans)]
            if replan.size:
                self._replans[replan] += 1
                self._plan(replan, pose, step, T_con)
                again = replan[(self._phase[replan] == CRUISE) & (self._origin[replan] == step[replan])]
                if again.size:
                    u[again], omega[again], _, _ = self._track(again, pose[again], step[again])
        finish = (self._phase == FINISH) & ~self._frozen
        if finish.any():
            index = np.flatnonzero(finish)
            sub = ControllerInput(*(None if v is None else np.asarray(v)[index] for v in estimate))
            u[index], omega[index] = self._finish(index, sub, T_con[index])
        if self._filter is not None and p.cancel_disturbance:
            u, omega = compensated_commands(u, omega, self._filter.response, self._limits)
        command = np.clip(np.stack([u, omega], axis=1), -self._limits, self._limits)
        command[self._frozen] = 0.0
        self._command = np.nan_to_num(command)  # Guard: the filter's prediction must never see a NaN
        return self._command[:, 0].copy(), self._command[:, 1].copy()

    def _learned_cruise(
        self,
        index: NDArray[np.intp],
        estimate: ControllerInput,
        T_con: NDArray[np.float64],
        u: FloatArray,
        omega: FloatArray,
    ) -> None:
        """The learned cruise's velocities for the robots ``index`` (into ``u``, ``omega``), until the planner takes over
        (past handover_time * T_con, or behind schedule)."""
        p = self.params
        time, distance = np.asarray(estimate.time)[index], estimate.distance[index]
        late = (time > p.handover_time * T_con[index]) | (T_con[index] - time < p.handover_margin * distance / p.u_max)
        self._phase[index[late]] = CRUISE if p.plan else FINISH
        keep = index[~late]
        if keep.size:
            d, alpha, psi = estimate.distance[keep], estimate.azimuth[keep], estimate.heading[keep]
            T = T_con[keep]
            obs = np.stack([d, np.cos(alpha), np.sin(alpha), np.cos(psi), np.sin(psi),
                            model.orientation_error(alpha, psi, d, p.k), np.asarray(estimate.time)[keep] / T, T,
                            np.asarray(estimate.initial_distance)[keep], np.asarray(estimate.initial_orientation_error)[keep]],
                           axis=1).astype(np.float32)  # fmt: skip
            actions, _ = self.cruise.predict(obs, deterministic=True)
            velocities = np.clip(np.asarray(actions, dtype=np.float64).reshape(-1, 2), -1.0, 1.0) * self._limits
            u[keep], omega[keep] = velocities[:, 0], velocities[:, 1]

    def _plan(
        self, index: NDArray[np.intp], pose: NDArray[np.float64], step: NDArray[np.int64], T_con: NDArray[np.float64]
    ) -> None:
        """Plan the robots ``index`` from their estimated poses, with their estimated responses, to arrive at
        plan_arrival * T_con, or, with too little time left for that, as early as the limits allow: the margin is
        spent only as far as the robot is behind. A plan that proves infeasible (a failing wheel slows the robot more
        than the bound of the time needed assumes) is tried again with more time; a robot with no plan at all goes to
        the finish law (a late plan beats that law's asymptotic approach)."""
        from baselines.optimal import PLAN_TOLERANCE, Plan, least_arrival_time

        p = self.params
        h = p.dt * p.hold_steps
        responses = dict(zip(index.tolist(), self._responses(index), strict=True))
        jobs: dict[int, dict[str, Any]] = {}
        for i, response in responses.items():
            start = (float(pose[i, 0]), float(pose[i, 1]), float(pose[i, 2]))
            reach = (response[2] * p.u_max - abs(response[0]), response[2] * p.omega_max - abs(response[1]))
            near = math.hypot(start[0], start[1]) < p.near_goal  # the last centimetres: the position alone
            least = least_arrival_time(start, max(reach[0], 1e-3), max(reach[1], 1e-3), not near)
            left = max(p.plan_arrival * T_con[i] - step[i] * p.dt, 1.1 * least, MIN_PLAN_INTERVALS * h)
            if (
                left * 1.3 ** (PLAN_ATTEMPTS - 1) > MAX_PLAN_INTERVALS * h  # Guard: far away, a solve would not end
                or left > LONGEST_PLAN * T_con[i]
            ):  # Guard: so slow (a failing wheel) the search rarely ends
                self._phase[i] = FINISH
                continue
            jobs[i] = {"start": start, "arrival_time": left, "dt": p.dt, "u_max": p.u_max, "omega_max": p.omega_max,
                       "heading": not near, "hold_steps": p.hold_steps, "response": tuple(float(v) for v in response),
                       "pad_to": PAD_TO, "max_iter": MAX_ITERATIONS, "tol": PLAN_TOLERANCE}  # fmt: skip
        for attempt in range(PLAN_ATTEMPTS):
            if not jobs:
                break
            results = self._pool.map(list(jobs.values()))
            self.solves += len(results)
            retry: dict[int, dict[str, Any]] = {}
            for (i, job), result in zip(jobs.items(), results, strict=True):
                if isinstance(result, Plan):
                    self._store(i, result, np.asarray(responses[i]), int(step[i]))
                elif attempt + 1 < PLAN_ATTEMPTS:
                    retry[i] = {**job, "arrival_time": job["arrival_time"] * 1.3}
                else:
                    self.failures.append(f"robot {i}: {result}")
                    self._phase[i] = FINISH
            jobs = retry

    def _store(self, i: int, plan: Any, response: NDArray[np.float64], step: int) -> None:
        """Keep robot i's plan from control period ``step`` on, with the velocities the robot will have as its reference."""
        intervals = plan.intervals
        if intervals + 1 > self._states.shape[1]:
            grow = intervals + 1 - self._states.shape[1]
            self._states = np.concatenate([self._states, np.repeat(self._states[:, -1:], grow, axis=1)], axis=1)
            self._commands = np.concatenate([self._commands, np.zeros((self._n, grow, 2))], axis=1)
        self._states[i] = 0.0  # the goal, where the padding holds the robot
        self._states[i, : intervals + 1] = plan.states
        self._commands[i] = 0.0
        velocities = robot_velocities(plan.commands[:, 0], plan.commands[:, 1], np.tile(response, (intervals, 1)))
        self._commands[i, :intervals] = np.stack(velocities, axis=1)
        self._origin[i], self._intervals[i] = step, intervals
        self._planned[i] = True

    def _responses(self, index: NDArray[np.intp]) -> NDArray[np.float64]:
        """The estimated responses (len(index), 4) of the robots ``index``, which their plans take into account."""
        if self._filter is None or not self.params.cancel_disturbance:
            return np.tile(NOMINAL_RESPONSE, (index.size, 1))
        return self._filter.response[index].copy()

    def _track(
        self, index: NDArray[np.intp], pose: NDArray[np.float64], step: NDArray[np.int64]
    ) -> tuple[FloatArray, FloatArray, NDArray[np.bool_], NDArray[np.bool_]]:
        """Tracking commands of the robots ``index``, whether their plans ended and whether they left the tube."""
        p = self.params
        offset = step - self._origin[index]
        interval = np.minimum(offset // p.hold_steps, self._intervals[index])
        ended = offset >= self._intervals[index] * p.hold_steps
        start = self._states[index, interval]
        command = self._commands[index, interval]
        since = (offset - interval * p.hold_steps) * p.dt  # time into the interval [s]
        x, y, psi = model.unicycle_step_exact(
            start[:, 0], start[:, 1], start[:, 2], command[:, 0], command[:, 1], since
        )
        reference = np.stack([x, y, psi], axis=1)
        u, omega, error = tracking_commands(pose, reference, command, p)
        return u, omega, ended, error > p.tube

    def _finish(
        self, index: NDArray[np.intp], inputs: ControllerInput, T_con: NDArray[np.float64]
    ) -> tuple[FloatArray, FloatArray]:
        """Astolfi's law scaled to T = finish_arrival * T_con, with the reverse decision held by hysteresis (or PTC)."""
        p = self.params
        if self._ptc is not None:
            return self._ptc.compute(inputs)
        bearing = np.abs(model.bearing_error(inputs.azimuth, inputs.heading))
        direction = self._direction[index]
        undecided = direction == 0.0
        direction = np.where(undecided, np.where(bearing > 0.5 * np.pi, -1.0, 1.0), direction)
        direction = np.where(bearing > 0.5 * np.pi + p.reverse_hysteresis, -1.0, direction)
        direction = np.where(bearing < 0.5 * np.pi - p.reverse_hysteresis, 1.0, direction)
        self._direction[index] = direction
        u, omega = astolfi_commands(inputs, p.k_rho, p.k_alpha, p.k_beta, True, direction)
        T = p.finish_arrival * T_con
        rate = np.minimum(model.conventional_scaling(inputs.time, T, max_gain=1e12) / T, p.max_gain)  # (12) / T
        return u * rate, omega * rate

    def close(self) -> None:
        """Nothing to stop: the solving threads are shared."""
        if self._pool is not None:
            self._pool.close()


__all__ = ["RobustPTController", "RobustPTParams", "tracking_commands"]

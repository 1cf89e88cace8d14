"""Minimum-energy point stabilization by the prescribed time: the optimum every law is measured against.

Over commands held constant for ``dt`` (the env's zero-order hold, integrated exactly as
:func:`dwr_gym.model.unicycle_step_exact` does), within the actuator limits, the plan minimises the
env's ``energy`` = sum of (u^2 + omega^2) dt subject to reaching the goal position, and the goal
heading unless ``heading=False`` (the paper's position-only task), at the arrival time (T_con by
default). Direct multiple shooting: the states and commands of every interval are the unknowns, the
exact step of eq. (1) links them. The problem is built once per number of intervals as a CasADi
``nlpsol`` Function and called per start with a warm start; the start, the limits and the frozen intervals are
bounds, the interval length a parameter. Two solvers of the same problem: IPOPT (the default) and fatrop, an
interior-point method that exploits the stages of an optimal control problem (a Riccati recursion instead of a
sparse factorisation of the whole KKT system); on the optimum cache's plans fatrop is some 3x faster and finds the
same energies to 1e-10 (``python -m benchmarks run optimum-speed``). fatrop sees the unknowns in stage order (x_0, u_0, x_1,
..., x_N); the caller's decision vector stays the states then the commands, permuted on the way in and out.

CasADi is an optional dependency: ``pip install "dwr-gym[optimal]"``.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, replace
from functools import lru_cache
from typing import Any

import numpy as np
from numpy.typing import NDArray

from dwr_gym import model

#: Below |omega dt / 2| of this, sin(h)/h is its Taylor polynomial: smooth derivatives for IPOPT, same value to 1e-24.
SMALL_HALF_TURN = 1e-6
#: Relative margin on the feasibility bound below which a plan is not attempted.
FEASIBILITY_MARGIN = 1e-9
#: The nonlinear programming solvers of :func:`minimum_energy_solver`.
SOLVERS = ("ipopt", "fatrop")


class OptimalControlError(RuntimeError):
    """IPOPT did not find a plan (reported as a failure of that scenario, never a crash of an evaluation)."""


class InfeasibleArrivalTimeError(ValueError):
    """The arrival time is shorter than the least time in which the robot can reach the goal."""


def require_casadi() -> Any:
    """The casadi module, or an ImportError naming the extra that installs it."""
    try:
        import casadi
    except ImportError as error:
        raise ImportError('the optimal controller needs CasADi: pip install "dwr-gym[optimal]"') from error
    return casadi


def casadi_step_exact(state: Any, command: Any, h: Any) -> Any:
    """The exact zero-order-hold step of eq. (1) on CasADi symbols, the same arc as
    :func:`dwr_gym.model.unicycle_step_exact` (a test holds the two together to 1e-12), without wrapping psi."""
    ca = require_casadi()
    half_turn = 0.5 * h * command[1]
    small = ca.fabs(half_turn) < SMALL_HALF_TURN
    safe = ca.if_else(small, 1.0, half_turn)
    # Guard: sin(h)/h is 0/0 at omega = 0; its Taylor polynomial keeps the derivatives smooth there.
    sinc = ca.if_else(small, 1.0 - half_turn * half_turn / 6.0, ca.sin(safe) / safe)
    chord = command[0] * h * sinc
    mid_heading = state[2] + half_turn
    return ca.vertcat(
        state[0] + chord * ca.cos(mid_heading), state[1] + chord * ca.sin(mid_heading), state[2] + 2.0 * half_turn
    )


@lru_cache(maxsize=64)
def minimum_energy_solver(
    intervals: int, max_iter: int = 1000, tol: float = 1e-10, response: bool = False, solver: str = "ipopt"
) -> Any:
    """The ``solver`` (IPOPT or fatrop) of the multiple-shooting problem with ``intervals`` held commands (built once,
    cached).

    Decision vector: the states (3, intervals + 1) then the commands (2, intervals), column-major (for fatrop in stage
    order instead: :func:`stage_order`); parameter: the interval length h [s]; constraints: the exact steps. With
    ``response`` the parameter is (h, b_u, b_omega, a, g) and the robot moves with (a u + b_u, a omega + g u + b_omega)
    for the command (u, omega) (:func:`baselines.estimation.robot_velocities`; a disturbance, a failing wheel), whose
    energy is minimised.
    """
    ca = require_casadi()
    if solver not in SOLVERS:
        raise ValueError(f"solver={solver!r} is invalid: expected one of {', '.join(SOLVERS)}")
    s, c, h_sym = ca.SX.sym("s", 3), ca.SX.sym("c", 2), ca.SX.sym("h")
    step = ca.Function("step", [s, c, h_sym], [casadi_step_exact(s, c, h_sym)])
    if solver == "fatrop":  # stage order: (x_k, u_k) for each interval, then x_N
        unknowns = ca.MX.sym("x", 5 * intervals + 3)
        stages = ca.reshape(unknowns[: 5 * intervals], 5, intervals)
        states, commands = ca.horzcat(stages[:3, :], unknowns[5 * intervals :]), stages[3:, :]
    else:
        states, commands = ca.MX.sym("X", 3, intervals + 1), ca.MX.sym("U", 2, intervals)
        unknowns = ca.veccat(states, commands)
    h = ca.MX.sym("h")
    parameters, velocities = h, commands
    if response:
        b_u, b_w, a, g = (ca.MX.sym(name) for name in ("b_u", "b_omega", "a", "g"))
        parameters = ca.vertcat(h, b_u, b_w, a, g)
        velocities = ca.vertcat(a * commands[0, :] + b_u, a * commands[1, :] + g * commands[0, :] + b_w)
    defects = states[:, 1:] - step.map(intervals)(states[:, :-1], velocities, h)
    problem = {"x": unknowns, "f": h * ca.sumsqr(velocities), "g": ca.vec(defects), "p": parameters}
    options: dict[str, Any] = {"print_time": False, "expand": True}
    if solver == "fatrop":
        options.update({"structure_detection": "manual", "N": intervals, "nx": [3] * (intervals + 1),
                        "nu": [2] * intervals + [0], "ng": [0] * (intervals + 1), "equality": [True] * (3 * intervals),
                        "fatrop.print_level": 0, "fatrop.max_iter": max_iter, "fatrop.tol": tol})  # fmt: skip
    else:
        options.update({"ipopt.print_level": 0, "ipopt.sb": "yes", "ipopt.max_iter": max_iter, "ipopt.tol": tol})
    return ca.nlpsol("minimum_energy", solver, problem, options)


@lru_cache(maxsize=64)
def stage_order(intervals: int) -> NDArray[np.intp]:
    """The indices of the decision vector (states, then commands) in fatrop's stage order (x_0, u_0, ..., x_N):
    ``vector[stage_order(n)]`` is the stage-ordered vector."""
    n_states = 3 * (intervals + 1)
    states = np.arange(n_states).reshape(intervals + 1, 3)
    commands = np.arange(n_states, n_states + 2 * intervals).reshape(intervals, 2)
    return np.concatenate([np.hstack([states[:-1], commands]).ravel(), states[-1]])


def default_solver() -> str:
    """fatrop where this CasADi ships it (3.6.6 on), else IPOPT."""
    return "fatrop" if require_casadi().has_nlpsol("fatrop") else "ipopt"


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


def solve_minimum_energy(
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
    solver: str = "ipopt",
    only: int | None = None,
) -> Plan:
    """The minimum-energy plan from ``start`` (goal frame: goal at the origin, heading 0) to the goal.

    The plan has ``intervals`` commands (default: as many whole periods of ``hold_steps * dt`` as fit
    in ``arrival_time``), each held for ``hold_steps`` control periods; the first ``frozen`` are held
    at zero (the time already spent when re-planning over a shrinking horizon), so the robot arrives
    at the end of the last interval. Raises :class:`InfeasibleArrivalTimeError` when the time left is below
    :func:`least_arrival_time`, and :class:`OptimalControlError` when IPOPT fails.

    The problem is not convex: it is solved from ``guesses`` cold starts (driving forward, then in
    reverse; both ways round for the heading when the robot starts facing away) and the cheapest
    converged plan is kept; with ``warm_start`` (a previous plan's solution) that one is tried first.

    With ``response`` (b_u, b_omega, a, g) the robot does (a u + b_u, a omega + g u + b_omega) with the planned
    commands (u, omega), which stay within the limits; the plan's energy is that of the robot's velocities.
    ``pad_to`` solves a problem of the next multiple of ``pad_to`` intervals whose last ones hold the robot still
    at the goal, and returns the plan without them: the same plan from fewer solvers to build and cache.
    ``max_iter`` bounds the solver's iterations per guess (a re-plan in a control loop must not take seconds).
    ``solver`` is "ipopt" or "fatrop" (:data:`SOLVERS`); where fatrop converges from no guess, IPOPT tries them too.
    ``only`` solves that guess of the search alone (the one the whole search keeps, :mod:`baselines.plan_hints`): the
    same plan to the last bit, the search's other solves saved; the whole search where it does not converge.
    """
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
    began = time.perf_counter()
    best, iterations, status = None, 0, ""
    if only is not None and 0 <= only < len(candidates):
        best, iterations, status = _cheapest([candidates[only]], lower, upper, parameters, intervals, h, max_iter,
                                             response is not None, solver, False)  # fmt: skip
        best = None if best is None else replace(best, candidate=only)
    if best is None:
        best, more, status = _cheapest(candidates, lower, upper, parameters, intervals, h, max_iter,
                                       response is not None, solver, warm_start is not None)  # fmt: skip
        iterations += more
    if best is None and solver != "ipopt":  # fatrop's failures are rare: IPOPT from the same guesses
        best, more, status = _cheapest(candidates, lower, upper, parameters, intervals, h, max_iter,
                                       response is not None, "ipopt", warm_start is not None)  # fmt: skip
        iterations += more
    if best is None:
        raise OptimalControlError(
            f"{solver} found no plan from start={tuple(round(v, 4) for v in start)} in {intervals * h:g} s "
            f"(last status: {status})"
        )
    elapsed = time.perf_counter() - began
    return Plan(
        best.commands[:planned],
        best.states[: planned + 1],
        h,
        best.energy,
        iterations,
        elapsed,
        best.solution,
        best.candidate,
        best.tried,
    )


def _cheapest(
    candidates: list[tuple[NDArray[np.float64], float | None]],
    lower: NDArray[np.float64],
    upper: NDArray[np.float64],
    parameters: Any,
    intervals: int,
    h: float,
    max_iter: int,
    response: bool,
    solver_name: str,
    warm: bool,
) -> tuple[Plan | None, int, str]:
    """The cheapest converged plan of the candidate guesses (each with its final heading; the first is the warm start
    where ``warm``), the iterations spent and the solver's last status."""
    solver = minimum_energy_solver(intervals, max_iter=max_iter, response=response, solver=solver_name)
    order = stage_order(intervals) if solver_name == "fatrop" else slice(None)
    lower, upper = lower.copy(), upper.copy()
    best: Plan | None = None
    iterations = 0
    status = ""
    for index, (guess, target) in enumerate(candidates):
        if target is not None:
            lower[3 * intervals + 2] = upper[3 * intervals + 2] = target
        solution = solver(x0=guess[order], lbx=lower[order], ubx=upper[order], lbg=0.0, ubg=0.0, p=parameters)
        stats = solver.stats()
        iterations += int(stats.get("iter_count", 0))
        status = str(stats.get("return_status", ""))
        if stats["success"]:
            unknowns = np.empty(lower.shape)
            unknowns[order] = np.asarray(solution["x"]).ravel()
            plan = plan_from_solution(unknowns, intervals, h, float(solution["f"]))
            if best is None or plan.energy < best.energy - 1e-12:
                best = replace(plan, candidate=index)
        if index == 0 and warm and best is not None:
            break  # a converged warm start is the re-plan; the cold guesses are only its fallback
    return (None if best is None else replace(best, tried=index + 1)), iterations, status


def frozen_guess(
    start: tuple[float, float, float], intervals: int, frozen: int, h: float, target: float, reverse: bool
) -> NDArray[np.float64]:
    """:func:`initial_guess` over the moving intervals, the robot still during the ``frozen`` ones."""
    moving = initial_guess(start, intervals - frozen, h, target, reverse)
    n_moving = intervals - frozen
    states = np.concatenate([np.tile(start, frozen), moving[: 3 * (n_moving + 1)]])
    commands = np.concatenate([np.zeros(2 * frozen), moving[3 * (n_moving + 1) :]])
    return np.concatenate([states, commands])


def plan_from_solution(solution: NDArray[np.float64], intervals: int, h: float, energy: float) -> Plan:
    """Unpack IPOPT's decision vector into a :class:`Plan`."""
    n_states = 3 * (intervals + 1)
    states = solution[:n_states].reshape(intervals + 1, 3)
    commands = solution[n_states:].reshape(intervals, 2)
    return Plan(commands, states, h, energy, 0, 0.0, solution)


__all__ = [
    "SOLVERS",
    "InfeasibleArrivalTimeError",
    "OptimalControlError",
    "Plan",
    "casadi_step_exact",
    "default_solver",
    "least_arrival_time",
    "minimum_energy_solver",
    "require_casadi",
    "solve_minimum_energy",
]

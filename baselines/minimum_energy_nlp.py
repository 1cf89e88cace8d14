"""The minimum-energy problem as a CasADi NLP: the exact step of eq. (1) on symbols, the solver built once per size.

Direct multiple shooting: the states and commands of every interval are the unknowns, the exact step of eq. (1) links
them. The problem is built once per number of intervals as a CasADi ``nlpsol`` Function and called per start; the
start, the limits and the frozen intervals are bounds, the interval length a parameter. Two solvers of the same
problem: IPOPT and fatrop (the default where CasADi ships it), an interior-point method that exploits the stages of an
optimal control problem (a Riccati recursion instead of a sparse factorisation of the whole KKT system): on the
optimum's and the planners' problems some 3x faster, the same energies to 1e-10 (``python -m benchmarks run
optimum-speed``). fatrop sees the unknowns in stage order (x_0, u_0, x_1, ..., x_N); the caller's decision vector
stays the states then the commands, permuted on the way in and out.

A solver's buffers serve one call at a time (two threads calling one solver crash it): each solving thread builds and
keeps its own (:func:`thread_solver`); the builds and the calls release the GIL, so threads build and solve in parallel
(:func:`baselines.optimal.solve_plans`). fatrop runs at its own default tolerance and iterations, whatever ``tol`` and
``max_iter`` say (:func:`first_call`).

CasADi is an optional dependency: ``pip install "dwr-gym[optimal]"``.
"""

from __future__ import annotations

import contextlib
import os
import threading
from functools import lru_cache
from typing import Any

import numpy as np
from numpy.typing import NDArray

from dwr_gym.model import unicycle_step_exact

#: Below |omega dt / 2| of this, sin(h)/h is its Taylor polynomial: smooth derivatives for IPOPT, same value to 1e-24.
SMALL_HALF_TURN = 1e-6
#: The nonlinear programming solvers of :func:`minimum_energy_solver`.
SOLVERS = ("ipopt", "fatrop")


def require_casadi() -> Any:
    """The casadi module, or an ImportError naming the extra that installs it."""
    try:
        import casadi
    except ImportError as error:
        raise ImportError('the optimal controller needs CasADi: pip install "dwr-gym[optimal]"') from error
    return casadi


def default_solver() -> str:
    """fatrop where this CasADi ships it (3.6.6 on), else IPOPT."""
    return "fatrop" if require_casadi().has_nlpsol("fatrop") else "ipopt"


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
    intervals: int, max_iter: int = 1000, tol: float = 1e-10, response: bool = False, solver: str = "ipopt",
    stage: int = 1,
) -> Any:  # fmt: skip
    """The ``solver`` (IPOPT or fatrop) of the multiple-shooting problem with ``intervals`` held commands (built once,
    cached).

    Decision vector: the states (3, intervals + 1) then the commands (2, intervals), column-major (for fatrop in stage
    order instead: :func:`stage_order`); parameter: the interval length h [s]; constraints: the exact steps. With
    ``response`` the parameter is (h, b_u, b_omega, a, g) and the robot moves with (a u + b_u, a omega + g u + b_omega)
    for the command (u, omega) (:func:`baselines.estimation.robot_velocities`; a disturbance, a failing wheel), whose
    energy is minimised.

    fatrop with ``stage`` > 1 sees ``stage`` intervals as one stage: the states inside it are not unknowns but the exact
    steps from the stage's first state (:func:`stage_order`). The same problem in fewer, larger stages: fewer blocks
    for fatrop's Riccati recursion and for the interface to lay out (its build grows faster than the intervals). On the
    1,009 default optima, 4 per stage take 30 % less CPU time than 1, the energies equal to 5e-7 (``python -m
    benchmarks run optimum-speed``). Without ``response`` only.
    """
    ca = require_casadi()
    if solver not in SOLVERS:
        raise ValueError(f"solver={solver!r} is invalid: expected one of {', '.join(SOLVERS)}")
    if stage != 1 and (solver != "fatrop" or response or stage < 1 or intervals % stage):
        raise ValueError(f"stage={stage!r} is invalid: expected 1, or with fatrop and no response a divisor of "
                         f"intervals={intervals}")  # fmt: skip
    n_stages, width = intervals // stage, 3 + 2 * stage
    # one stage: its first state and its commands; the end state is the exact steps through them
    s, c, h_sym = ca.SX.sym("s", 3), ca.SX.sym("c", 2 * stage), ca.SX.sym("h")
    end = s
    for k in range(stage):
        end = casadi_step_exact(end, c[2 * k : 2 * k + 2], h_sym)
    step = ca.Function("step", [s, c, h_sym], [end])
    if solver == "fatrop":  # stage order: (x_k, u_k) for each stage, then x_N
        unknowns = ca.MX.sym("x", width * n_stages + 3)
        stages = ca.reshape(unknowns[: width * n_stages], width, n_stages)
        states, commands = ca.horzcat(stages[:3, :], unknowns[width * n_stages :]), stages[3:, :]
    else:
        states, commands = ca.MX.sym("X", 3, intervals + 1), ca.MX.sym("U", 2, intervals)
        unknowns = ca.veccat(states, commands)
    h = ca.MX.sym("h")
    parameters, velocities = h, commands
    if response:
        b_u, b_w, a, g = (ca.MX.sym(name) for name in ("b_u", "b_omega", "a", "g"))
        parameters = ca.vertcat(h, b_u, b_w, a, g)
        velocities = ca.vertcat(a * commands[0, :] + b_u, a * commands[1, :] + g * commands[0, :] + b_w)
    defects = states[:, 1:] - step.map(n_stages)(states[:, :-1], velocities, h)
    problem = {"x": unknowns, "f": h * ca.sumsqr(velocities), "g": ca.vec(defects), "p": parameters}
    options: dict[str, Any] = {"print_time": False, "expand": True}
    if solver == "fatrop":
        options.update({"structure_detection": "manual", "N": n_stages, "nx": [3] * (n_stages + 1),
                        "nu": [2 * stage] * n_stages + [0], "ng": [0] * (n_stages + 1),
                        "equality": [True] * (3 * n_stages),
                        "fatrop.print_level": 0, "fatrop.max_iter": max_iter, "fatrop.tol": tol})  # fmt: skip
    else:
        options.update({"ipopt.print_level": 0, "ipopt.sb": "yes", "ipopt.max_iter": max_iter, "ipopt.tol": tol})
    return ca.nlpsol("minimum_energy", solver, problem, options)


@lru_cache(maxsize=64)
def stage_order(intervals: int, stage: int = 1) -> NDArray[np.intp]:
    """The indices of the decision vector (states, then commands) in fatrop's stage order (x_0, u_0, ..., x_N):
    ``vector[stage_order(n)]`` is the stage-ordered vector; with ``stage`` intervals per stage, the states inside a
    stage left out (:func:`fill_stage_states`)."""
    n_states = 3 * (intervals + 1)
    states = np.arange(n_states).reshape(intervals + 1, 3)[::stage]
    commands = np.arange(n_states, n_states + 2 * intervals).reshape(intervals // stage, 2 * stage)
    return np.concatenate([np.hstack([states[:-1], commands]).ravel(), states[-1]])


def fill_stage_states(unknowns: NDArray[np.float64], intervals: int, stage: int, h: float) -> None:
    """Write into the decision vector ``unknowns`` (states, then commands) the states inside each stage of ``stage``
    intervals, by the exact steps of eq. (1) from the stage's first state (the heading unwrapped, as the solver's)."""
    states = unknowns[: 3 * (intervals + 1)].reshape(intervals + 1, 3)
    commands = unknowns[3 * (intervals + 1) :].reshape(intervals, 2)
    for k in range(1, stage):  # the k-th state of every stage from the one before it, all stages at once
        before, command = states[k - 1 : -1 : stage], commands[k - 1 :: stage]
        x, y, _ = unicycle_step_exact(before[:, 0], before[:, 1], before[:, 2], command[:, 0], command[:, 1], h)
        states[k::stage] = np.stack([x, y, before[:, 2] + h * command[:, 1]], axis=1)


_LOCAL = threading.local()
#: Where CasADi is built without thread-safe symbolics, one thread builds a solver at a time (solving runs in parallel).
_BUILDING = threading.Lock()


@lru_cache(maxsize=1)
def builds_in_parallel() -> bool:
    """Whether this CasADi builds solvers on several threads at once: built with thread-safe symbolics (the PyPI
    wheels: 3.8.2 checked), whose builds release the GIL. Elsewhere the builds take turns (:data:`_BUILDING`)."""
    return "CASADI_WITH_THREADSAFE_SYMBOLICS" in require_casadi().CasadiMeta.compiler_flags()


def _new_lock_in_child() -> None:
    """A forked child gets a free lock: the thread that held its parent's is not in the child to release it."""
    global _BUILDING
    _BUILDING = threading.Lock()


os.register_at_fork(after_in_child=_new_lock_in_child)


def thread_solver(intervals: int, max_iter: int, response: bool, solver: str, tol: float = 1e-10, stage: int = 1
                  ) -> Any:  # fmt: skip
    """This thread's own :func:`minimum_energy_solver` (a solver's buffers serve one call at a time), built once."""
    solvers = _LOCAL.__dict__.setdefault("solvers", {})
    key = (intervals, max_iter, response, solver, tol, stage)
    if key not in solvers:
        with contextlib.nullcontext() if builds_in_parallel() else _BUILDING:
            solvers[key] = minimum_energy_solver.__wrapped__(intervals, max_iter=max_iter, tol=tol, response=response,
                                                             solver=solver, stage=stage)  # fmt: skip
        if solver == "fatrop":
            first_call(solvers[key], stage_order(intervals, stage).size, response)
    return solvers[key]


def first_call(solver: Any, size: int, response: bool) -> None:
    """Call a new fatrop ``solver`` once on the robot already at rest at the goal (a success at its first point), so
    that every search after runs with the same settings.

    fatrop (as CasADi 3.8 ships it) applies the options it was built with (``tol``, ``max_iter``) only until its
    solver's first success; every solve after runs at fatrop's own defaults (measured: ``max_iter`` = 3 is kept by a
    fresh solver, ignored after one success). Without this call a thread's first search of each size ran at
    ``tol`` = 1e-10 and the others at the default, so a plan depended on which search its thread met first, in its
    last digits (by up to 1.6e-6 of the energy on 3 of the 1,009 default optima, a stage per interval)."""
    parameters = [0.05, 0.0, 0.0, 1.0, 0.0] if response else 0.05  # h; with response: b_u, b_omega, a = 1, g
    solver(x0=np.zeros(size), lbx=-np.inf, ubx=np.inf, lbg=0.0, ubg=0.0, p=parameters)


__all__ = ["SMALL_HALF_TURN", "SOLVERS", "builds_in_parallel", "casadi_step_exact", "default_solver",
           "fill_stage_states", "first_call", "minimum_energy_solver", "require_casadi", "stage_order",
           "thread_solver"]  # fmt: skip

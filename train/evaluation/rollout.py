"""Batched rollouts and their metrics: the honest comparison of controllers and agents.

A rollout steps all N scenarios of a set as one batch through :func:`dwr_gym.core.transition`,
the same function the environments use, with the policy acting on the env's observations.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np
from numpy.typing import NDArray

from dwr_gym import core
from dwr_gym.disturbances import make_perturbation, split_env_kwargs
from dwr_gym.params import EnvParams


class Policy(Protocol):
    """Anything with stable-baselines3's ``predict``."""

    def predict(
        self, observation: Any, state: Any = None, episode_start: Any = None, deterministic: bool = True
    ) -> tuple[Any, Any]: ...


@dataclass
class RolloutResult:
    """Per-robot outcomes of a batched rollout (arrays of shape (N,)) and, if recorded, trajectories."""

    params: EnvParams
    T_con: NDArray[np.float64]  # each episode's prescribed time [s]
    success: NDArray[np.bool_]  # arrived (within the tolerances) at or before T_con
    arrived: NDArray[np.bool_]  # arrived at any time before the horizon
    arrival_time: NDArray[np.float64]  # [s], NaN where the robot did not arrive
    final_distance: NDArray[np.float64]
    final_heading_error: NDArray[np.float64]  # |psi - psi_d| at the end [rad]
    peak_linear_velocity: NDArray[np.float64]
    peak_angular_velocity: NDArray[np.float64]
    energy: NDArray[np.float64]  # integral of u^2 + omega^2
    path_length: NDArray[np.float64]
    command_rate_rms: NDArray[np.float64]  # RMS of the change of the commanded (u, omega) per second: lower is smoother
    velocity_rate_rms: NDArray[
        np.float64
    ]  # the same of the velocities the robot had (with actuation noise, delay, ...)
    episode_return: NDArray[np.float64]
    left_arena: NDArray[np.bool_]
    trajectory: dict[str, NDArray[np.float64]] | None = None
    """With ``record=True``: arrays (steps + 1, N) of time, x, y, psi, distance, orientation_error,
    lyapunov, and (steps, N) of linear_velocity, angular_velocity."""
    optimal_energy: NDArray[np.float64] | None = None
    """The minimum energy of each episode (NaN where there is none), when the optimum was asked for."""
    planner_failures: int = 0
    """Plans the ``optimal`` controller could not find (those robots stood still)."""
    optimum_failures: list[str] = field(default_factory=list)
    """Why some episodes have no optimum (an infeasible T_con, an IPOPT failure), one message each."""

    def energy_ratio(self) -> NDArray[np.float64]:
        """energy / optimal energy per episode, NaN where the episode failed or has no optimum."""
        if self.optimal_energy is None:
            return np.full(self.success.shape, np.nan)
        valid = self.success & np.isfinite(self.optimal_energy) & (self.optimal_energy > 0.0)
        return np.where(valid, self.energy / np.where(valid, self.optimal_energy, 1.0), np.nan)

    def summary(self) -> dict[str, float]:
        """Aggregate metrics over the N robots (means and worst cases)."""
        arrived = np.isfinite(self.arrival_time)
        arrival = self.arrival_time[arrived]
        T = self.T_con[arrived]
        ratio = self.energy_ratio()

        def stat(values: NDArray[np.float64], fn: Callable[..., Any]) -> float:
            return float(fn(values)) if values.size else float("nan")

        return {
            "n": float(self.success.size),
            "success_rate": float(np.mean(self.success)),
            "arrival_rate": float(np.mean(self.arrived)),
            "arrival_time_mean": stat(arrival, np.mean),
            "arrival_time_max": stat(arrival, np.max),
            "arrival_fraction_mean": stat(arrival / T, np.mean),
            "arrival_fraction_max": stat(arrival / T, np.max),
            "final_distance_mean": float(np.mean(self.final_distance)),
            "final_distance_max": float(np.max(self.final_distance)),
            "final_heading_error_mean": float(np.mean(self.final_heading_error)),
            "final_heading_error_max": float(np.max(self.final_heading_error)),
            "peak_u_max": float(np.max(self.peak_linear_velocity)),
            "peak_u_mean": float(np.mean(self.peak_linear_velocity)),
            "peak_omega_max": float(np.max(self.peak_angular_velocity)),
            "energy_mean": float(np.mean(self.energy)),
            "path_length_mean": float(np.mean(self.path_length)),
            "command_rate_rms_mean": float(np.mean(self.command_rate_rms)),
            "velocity_rate_rms_mean": float(np.mean(self.velocity_rate_rms)),
            "return_mean": float(np.mean(self.episode_return)),
            "energy_ratio_mean": stat(ratio[np.isfinite(ratio)], np.mean),
            "energy_ratio_max": stat(ratio[np.isfinite(ratio)], np.max),
            "energy_ratio_episodes": float(np.isfinite(ratio).sum()),  # the episodes behind E/opt: in time, optimum known
            "optimal_energy_mean": float("nan") if self.optimal_energy is None
            else stat(self.optimal_energy[np.isfinite(self.optimal_energy)], np.mean),
            "planner_failures": float(self.planner_failures),
            "optimum_failures": float(len(self.optimum_failures)),
        }  # fmt: skip


def rollout(
    policy: Policy,
    params: EnvParams,
    starts: NDArray[np.float64],
    goals: NDArray[np.float64],
    *,
    record: bool = False,
    seed: int = 0,
    progress: bool = False,
    description: str = "rollout",
    T_con: NDArray[np.float64] | None = None,
    env_kwargs: dict[str, Any] | None = None,
    discount: float = 1.0,
    on_step: Callable[[float], None] | None = None,
) -> RolloutResult:
    """Run ``policy`` from N start poses to N goals (world frame, (N, 3)) until every episode ends.

    ``T_con`` (N,) gives each episode its prescribed time (default: ``params.T_con``). Robots that
    have terminated are held still with zero actions and no longer counted. The ``robot`` and
    ``disturbances`` of ``env_kwargs`` act as in the envs (robot i's random disturbances seeded with
    (seed, i)); its other keywords are those of ``params``. ``episode_return`` sums the rewards discounted by
    ``discount`` per step (1: the undiscounted return). ``on_step`` receives the fraction of the steps done after each
    step.
    """
    starts, goals = np.asarray(starts, dtype=np.float64), np.asarray(goals, dtype=np.float64)
    if starts.ndim != 2 or starts.shape[1] != 3 or goals.shape != starts.shape:
        raise ValueError(f"starts {starts.shape} and goals {goals.shape} are invalid: expected two (N, 3) arrays")
    n = starts.shape[0]
    space = core.observation_space(params)
    state = core.TaskState.zeros(n)
    core.reset_robots(state, slice(None), tuple(starts.T), tuple(goals.T), params, T_con)  # type: ignore[arg-type]
    rng = np.random.default_rng(seed)

    def noise(size: int, sigma: float) -> NDArray[np.float64] | None:
        return rng.standard_normal((n, size)) if sigma > 0 else None

    coords = state.coordinates(params.k)
    obs = core.observe(state, coords, params, space, noise(3, params.observation_noise))
    _, drive, disturbances = split_env_kwargs(env_kwargs or {})
    perturbation = make_perturbation(drive, disturbances, params, n)
    if perturbation is not None:
        perturbation.seed(list(range(n)), [(seed, i) for i in range(n)])
        perturbation.reset(slice(None), obs)
    active = np.ones(n, dtype=bool)
    arrival_time = np.full(n, np.nan)
    success = np.zeros(n, dtype=bool)
    left_arena = np.zeros(n, dtype=bool)
    peak_u, peak_w, path, rate_sq, velocity_rate_sq, ret = (np.zeros(n) for _ in range(6))
    final_distance, final_heading = coords.distance.copy(), np.abs(coords.psi)
    final_energy = np.zeros(n)
    steps_taken = np.zeros(n)
    prev_u, prev_w = np.zeros(n), np.zeros(n)
    prev_command = np.zeros((n, 2))
    limits = np.array([params.u_max, params.omega_max])
    trajectory: dict[str, list[NDArray[np.float64]]] = {}
    if record:
        x, y, psi = state.world_pose()
        trajectory = {"time": [np.zeros(n)], "x": [x], "y": [y], "psi": [psi], "distance": [coords.distance],
                      "orientation_error": [coords.orientation_error], "lyapunov": [state.lyapunov.copy()],
                      "linear_velocity": [], "angular_velocity": []}  # fmt: skip

    steps = range(int(state.max_steps.max()))
    if progress:
        from train.progress import Progress

        steps = Progress(steps, desc=description, unit="step", leave=False)
    episode_start = np.ones(n, dtype=bool)
    weight = 1.0  # discount ** steps: every episode starts at step 0
    for index in steps:
        if on_step is not None:
            on_step(index / len(steps))
        actions, _ = policy.predict(obs, episode_start=episode_start, deterministic=True)
        episode_start = np.zeros(n, dtype=bool)
        actions = np.where(active[:, None], np.asarray(actions, dtype=np.float64).reshape(n, 2), 0.0)
        action_noise = noise(2, params.actuation_noise)
        result = core.transition(state, actions, params, space,
                                 None if action_noise is None else action_noise * active[:, None],
                                 noise(3, params.observation_noise), perturbation)  # fmt: skip
        obs = result.observation
        u, w = result.linear_velocity, result.angular_velocity
        live = active
        peak_u = np.where(live, np.maximum(peak_u, np.abs(u)), peak_u)
        peak_w = np.where(live, np.maximum(peak_w, np.abs(w)), peak_w)
        path += np.where(live, np.abs(u) * params.dt, 0.0)
        command = np.clip(actions, -1.0, 1.0) * limits  # what the policy asked for (the env clips it so)
        rate_sq += np.where(live, np.sum((command - prev_command) ** 2, axis=1) / params.dt**2, 0.0)
        velocity_rate_sq += np.where(live, ((u - prev_u) ** 2 + (w - prev_w) ** 2) / params.dt**2, 0.0)
        prev_command = command
        steps_taken += live
        prev_u, prev_w = u, w
        ret += np.where(live, result.reward, 0.0) * weight
        weight *= discount
        final_distance = np.where(live, result.coords.distance, final_distance)
        final_heading = np.where(live, np.abs(result.coords.psi), final_heading)
        final_energy = np.where(live, state.energy, final_energy)
        ended = live & (result.terminated | result.truncated)
        time = state.step_count * params.dt
        # the first time at the goal: where the episode ends in v0 and v1, at or before T_con in v2 (held to it)
        arrival_time = np.where(live & result.is_success & np.isnan(arrival_time), time, arrival_time)
        # as the env counts "in time": arrived by T_con (v0, v1), at the goal at T_con (v2)
        success |= ended & result.is_success & (state.step_count <= state.prescribed_steps)
        # the arena's bound, not 'terminated without success': v2 also terminates a miss at T_con
        left_arena |= ended & (result.coords.distance > params.arena_radius)
        if record:
            x, y, psi = state.world_pose()
            for key, value in (("time", time), ("x", x), ("y", y), ("psi", psi), ("distance", result.coords.distance),
                               ("orientation_error", result.coords.orientation_error), ("lyapunov", state.lyapunov),
                               ("linear_velocity", u), ("angular_velocity", w)):  # fmt: skip
                trajectory[key].append(np.array(value, dtype=np.float64))
        active = active & ~ended
        freeze = getattr(getattr(policy, "controller", None), "freeze", None)
        if freeze is not None:  # a planning controller need not plan for robots whose episodes ended
            freeze(~active)
        if not active.any():
            break
    return RolloutResult(
        params=params,
        T_con=state.T_con.copy(),
        success=success,
        arrived=np.isfinite(arrival_time),
        arrival_time=arrival_time,
        final_distance=final_distance,
        final_heading_error=final_heading,
        peak_linear_velocity=peak_u,
        peak_angular_velocity=peak_w,
        energy=final_energy,
        path_length=path,
        command_rate_rms=np.sqrt(rate_sq / np.maximum(steps_taken, 1)),
        velocity_rate_rms=np.sqrt(velocity_rate_sq / np.maximum(steps_taken, 1)),
        episode_return=ret,
        left_arena=left_arena,
        trajectory={k: np.array(v) for k, v in trajectory.items()} if record else None,
    )

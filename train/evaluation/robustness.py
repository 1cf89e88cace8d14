"""``dwr-gym robustness``: sweep each disturbance's magnitude and measure who still arrives by T_con.

For every disturbance of :data:`SWEEPS` and each of its magnitudes, every controller and agent is
run from the same seeded random start poses (the 'random' set) on the imperfect robot. The result
is one row per (disturbance, magnitude, policy) with the metrics of
:meth:`train.evaluation.rollout.RolloutResult.summary`, and :func:`tolerated`, the largest magnitude up to which each
policy still succeeds in at least 95 % of the episodes (its table and figures are drawn by
:mod:`train.reporting`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from dwr_gym.disturbances import (
    ActuatorFault,
    InputDelay,
    MeasurementDropout,
    VelocityBias,
    VelocityRandomWalk,
    VelocitySinusoid,
    WheelSlip,
)
from train.evaluation.disturbance_sets import UNLIMITED_BURGER
from train.evaluation.evaluate import evaluate
from train.evaluation.rollout import Policy
from train.evaluation.scenarios import Scenario, make_scenario

#: Success rate that counts as "still arrives by T_con".
SUCCESS_LEVEL = 0.95
#: A policy whose success rate falls below this at one magnitude is not run at the larger ones of the same sweep
#: (its tolerance is already known, and its curve has shown the fall; a planner there re-plans at every step).
GIVE_UP_LEVEL = 0.5


@dataclass(frozen=True)
class Sweep:
    """One disturbance swept over its magnitudes; ``env_kwargs(magnitude, T_con)`` builds the robot."""

    name: str
    magnitude: str
    """What the magnitude is, with its unit (the figure's x label)."""
    magnitudes: tuple[float, ...]
    env_kwargs: Callable[[float, float], dict[str, Any]]


SWEEPS: dict[str, Sweep] = {
    sweep.name: sweep
    for sweep in (
        Sweep("bias", "constant angular velocity bias [rad/s]", (0.0, 0.1, 0.2, 0.5, 1.0, 1.5),
              lambda m, T: {"disturbances": [VelocityBias(angular=m)]}),
        Sweep("sinusoid", "amplitude of a 4 s sinusoid on u [m/s] (and 4x on omega [rad/s])",
              (0.0, 0.1, 0.2, 0.3, 0.4, 0.5),
              lambda m, T: {"disturbances": [VelocitySinusoid(m, 4.0 * m, period=4.0)]}),
        Sweep("random-walk", "random-walk intensity on omega [rad/s/sqrt(s)] (u: a quarter of it in m/s)",
              (0.0, 0.025, 0.05, 0.1, 0.2, 0.4),
              lambda m, T: {"disturbances": [VelocityRandomWalk(m / 4.0, m)]}),
        Sweep("slip", "slip of both wheels: 1 - efficiency [-]", (0.0, 0.2, 0.4, 0.6, 0.7, 0.8),
              lambda m, T: {"robot": UNLIMITED_BURGER, "disturbances": [WheelSlip(1.0 - m, 1.0 - m)]}),
        Sweep("fault", "right motor's lost fraction from T_con/4 [-]", (0.0, 0.25, 0.5, 0.6, 0.75, 0.9),
              lambda m, T: {"robot": UNLIMITED_BURGER,
                            "disturbances": [ActuatorFault("right", 1.0 - m, start_time=T / 4.0)]}),
        Sweep("delay", "input delay [control periods of 0.05 s]", (0, 4, 8, 16, 24, 32),
              lambda m, T: {"disturbances": [InputDelay(int(m))]}),
        Sweep("dropout", "probability of a lost pose measurement [-]", (0.0, 0.5, 0.75, 0.9, 0.95, 0.98),
              lambda m, T: {"disturbances": [MeasurementDropout(m)]}),
        Sweep("noise", "pose measurement noise, std [m and rad]", (0.0, 0.01, 0.02, 0.05, 0.1, 0.2),
              lambda m, T: {"observation_noise": m}),
    )
}  # fmt: skip


def _magnitude_rows(
    policies: dict[str, Policy | str],
    base: Scenario,
    name: str,
    magnitude: float,
    seed: int,
    n_optimal: int,
    progress: bool = False,
) -> list[dict[str, Any]]:
    """Every policy's row at one magnitude of one sweep (``optimal`` on the first ``n_optimal`` starts only)."""
    if not policies:
        return []
    spec = SWEEPS[name]
    T_con = float(base.env_kwargs.get("T_con", 20.0))
    kwargs = {**base.env_kwargs, **spec.env_kwargs(magnitude, T_con)}
    groups: list[tuple[dict[str, Policy | str], int]] = [
        ({k: v for k, v in policies.items() if k != "optimal"}, base.size),
        ({k: v for k, v in policies.items() if k == "optimal"}, min(base.size, n_optimal)),
    ]
    results = {}
    for group, size in groups:
        if group:
            scenario = Scenario(f"{name}={magnitude:g}", base.starts[:size], base.goals[:size], kwargs)
            results.update(evaluate(group, scenario, seed=seed, progress=progress))
    return [{"disturbance": name, "magnitude": float(magnitude), "policy": label, "T_con": result.params.T_con,
             **result.summary()} for label, result in results.items()]  # fmt: skip


_WORKER: dict[str, Any] = {}


def _load_policies(controllers: list[str], agents: list[str], env_id: str | None, threads: int = 1) -> None:
    """A worker's policies, loaded once per process (agents from their run directories); torch on ``threads``
    threads in this process of ours (a fresh interpreter would take one per core: train.threads says why not)."""
    import torch

    from train.learning.agents import load_agent

    torch.set_num_threads(threads)

    policies: dict[str, Any] = {name: name for name in controllers}
    for path in agents:
        label, policy = load_agent(path)
        policies[label] = policy
    _WORKER["policies"] = policies


def _sweep_rows(
    policies: dict[str, Policy | str],
    base: Scenario,
    name: str,
    seed: int,
    n_optimal: int,
    progress: bool = False,
    log: Callable[[str], None] | None = None,
    give_up: float = GIVE_UP_LEVEL,
) -> list[dict[str, Any]]:
    """The rows of one sweep, its magnitudes in increasing order; a policy below ``give_up`` at one magnitude is left
    out of the larger ones."""
    rows: list[dict[str, Any]] = []
    running = dict(policies)
    for magnitude in SWEEPS[name].magnitudes:
        found = _magnitude_rows(running, base, name, magnitude, seed, n_optimal, progress)
        rows += found
        for row in found:
            if row["success_rate"] < give_up:
                running.pop(row["policy"], None)
            if log is not None:
                log(f"{name:12s} {magnitude:6g} {row['policy']:18s} success {row['success_rate']:.3f}  "
                    f"d_end mean {row['final_distance_mean']:.4f}")  # fmt: skip
    return rows


def _job(job: tuple[str, Scenario, int, int, float]) -> list[dict[str, Any]]:
    name, base, seed, n_optimal, give_up = job
    return _sweep_rows(_WORKER["policies"], base, name, seed, n_optimal, give_up=give_up)


def sweep_parallel(
    controllers: list[str],
    agents: list[str],
    names: list[str] | tuple[str, ...],
    n: int = 200,
    seed: int = 0,
    env_kwargs: dict[str, Any] | None = None,
    workers: int = 2,
    progress: bool = True,
    n_optimal: int = 20,
    on_rows: Callable[[list[dict[str, Any]]], None] | None = None,
    give_up: float = GIVE_UP_LEVEL,
    threads: int = 1,
) -> list[dict[str, Any]]:
    """:func:`sweep` of the controllers named and the agents at the run directories given, each disturbance a job of
    a pool of ``workers`` processes (each loads the policies once, and runs torch on ``threads`` threads); ``on_rows`` gets the rows found so far after each
    job (to save them: a long sweep can be cut short). Rows come in the order of :func:`sweep`'s, whatever order the
    jobs end in."""
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor, as_completed

    base = make_scenario("random", n=n, seed=seed, env_kwargs=env_kwargs)
    jobs = [(name, base, seed, n_optimal, give_up) for name in names]
    done: dict[int, list[dict[str, Any]]] = {}
    context = multiprocessing.get_context("spawn")  # a fresh interpreter: no torch or OpenMP state inherited
    with ProcessPoolExecutor(workers, mp_context=context, initializer=_load_policies,
                             initargs=(list(controllers), list(agents), None, threads)) as pool:  # fmt: skip
        futures = {pool.submit(_job, job): i for i, job in enumerate(jobs)}
        pending = as_completed(futures)
        if progress:
            from tqdm.auto import tqdm

            pending = tqdm(pending, total=len(jobs), desc="robustness: disturbances", unit="sweep")
        for future in pending:
            done[futures[future]] = future.result()
            if on_rows is not None:
                on_rows([row for i in sorted(done) for row in done[i]])
    return [row for i in sorted(done) for row in done[i]]


def sweep(
    policies: dict[str, Policy | str],
    names: list[str] | tuple[str, ...],
    n: int = 200,
    seed: int = 0,
    env_kwargs: dict[str, Any] | None = None,
    progress: bool = False,
    log: Callable[[str], None] | None = None,
    n_optimal: int = 20,
    give_up: float = GIVE_UP_LEVEL,
) -> list[dict[str, Any]]:
    """Rows (disturbance, magnitude, policy, metrics...) of each sweep in ``names`` over its magnitudes.

    The ``optimal`` controller (one CasADi plan per robot and re-plan, about 1 s per disturbed
    episode) runs on the first ``n_optimal`` of the ``n`` start poses. A policy whose success rate falls below
    ``give_up`` at a magnitude is not run at the larger ones of that sweep.
    """
    base = make_scenario("random", n=n, seed=seed, env_kwargs=env_kwargs)
    return [row for name in names for row in _sweep_rows(policies, base, name, seed, n_optimal, progress, log, give_up)]


def tolerated(rows: list[dict[str, Any]], level: float = SUCCESS_LEVEL) -> dict[tuple[str, str], float | None]:
    """(disturbance, policy) -> the largest magnitude up to which every swept magnitude had success >= level.

    None where the policy falls below ``level`` already without the disturbance (magnitude 0).
    """
    table: dict[tuple[str, str], float | None] = {}
    for key in dict.fromkeys((row["disturbance"], row["policy"]) for row in rows):
        points = sorted((row["magnitude"], row["success_rate"]) for row in rows
                        if (row["disturbance"], row["policy"]) == key)  # fmt: skip
        best = None
        for magnitude, rate in points:
            if rate < level:
                break
            best = magnitude
        table[key] = best
    return table


__all__ = ["SUCCESS_LEVEL", "SWEEPS", "Sweep", "sweep", "sweep_parallel", "tolerated"]

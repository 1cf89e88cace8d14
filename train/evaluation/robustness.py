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


def sweep(
    policies: dict[str, Policy | str],
    names: list[str] | tuple[str, ...],
    n: int = 200,
    seed: int = 0,
    env_kwargs: dict[str, Any] | None = None,
    progress: bool = False,
    log: Callable[[str], None] | None = None,
    n_optimal: int = 20,
) -> list[dict[str, Any]]:
    """Rows (disturbance, magnitude, policy, metrics...) of each sweep in ``names`` over its magnitudes.

    The ``optimal`` controller (one CasADi plan per robot and re-plan, about 1 s per disturbed
    episode) runs on the first ``n_optimal`` of the ``n`` start poses.
    """
    base = make_scenario("random", n=n, seed=seed, env_kwargs=env_kwargs)
    T_con = float(base.env_kwargs.get("T_con", 20.0))
    few = min(n, n_optimal)
    groups: list[tuple[dict[str, Policy | str], int]] = [
        ({k: v for k, v in policies.items() if k != "optimal"}, n),
        ({"optimal": "optimal"}, few),
    ]
    rows = []
    for name in names:
        spec = SWEEPS[name]
        for magnitude in spec.magnitudes:
            kwargs = {**base.env_kwargs, **spec.env_kwargs(magnitude, T_con)}
            results = {}
            for group, size in groups:
                if group and (group.keys() != {"optimal"} or "optimal" in policies):
                    scenario = Scenario(f"{name}={magnitude:g}", base.starts[:size], base.goals[:size], kwargs)
                    results.update(evaluate(group, scenario, seed=seed, progress=progress))
            for label, result in results.items():
                summary = result.summary()
                rows.append({"disturbance": name, "magnitude": float(magnitude), "policy": label,
                             "T_con": result.params.T_con, **summary})  # fmt: skip
                if log is not None:
                    log(f"{name:12s} {magnitude:6g} {label:18s} success {summary['success_rate']:.3f}  "
                        f"d_end mean {summary['final_distance_mean']:.4f}")  # fmt: skip
    return rows


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


__all__ = ["SUCCESS_LEVEL", "SWEEPS", "Sweep", "sweep", "tolerated"]

"""Where a policy's energy goes on an env id, and how far the analytic laws get by their gains alone.

Two measurements that tell the size of the residual-on-PTC goal (:data:`train.goals.RESIDUAL_ON_PTC`):

- :func:`energy_split`: each policy's energy ``E = int u^2 + omega^2 dt`` (the env's, counted until the episode ends:
  on v2 until T_con) split into its linear part (``u^2``) and its turning part (``omega^2``), and its share in each
  fifth of T_con. The minimum-energy plan spreads it evenly over the time; PTC (16)-(19) spends it early.
- :func:`law_gains`: each law over a grid of its gains, on the same episodes, with E/opt against the cached optimum
  of the goal pose: the lowest E/opt each law reaches in time, with and without the heading goal.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from train.env_ids import env_keywords
from train.evaluation.incentives import controller_policy, random_episodes
from train.goals import RESIDUAL_ON_PTC

V2 = "DWRPointStabilization-v2"
#: Parts of T_con the energy is shared over (fifths).
PARTS = 5
#: The gains of each law tried by :func:`law_gains` (the paper's defaults among them); the rest of its params default.
GAIN_GRIDS: dict[str, dict[str, tuple[float, ...]]] = {
    "ptc": {"K1": (1.2, 1.5, 2.0, 3.0), "K2": (2.0, 5.0, 10.0)},
    "pt-astolfi": {"k_rho": (1.0, 1.2, 1.5), "k_alpha": (4.7, 7.0, 10.0), "k_beta": (-0.5, -1.0, -1.7, -3.0)},
}
#: The residual-on-PTC goal's bounds: in time and final heading [rad].
GOAL_IN_TIME, GOAL_HEADING = RESIDUAL_ON_PTC.in_time, RESIDUAL_ON_PTC.final_heading


def energy_split(
    policies: Mapping[str, Any], env_id: str = V2, n: int = 100, seed: int = 4042, parts: int = PARTS
) -> dict[str, Any]:
    """Each policy's mean energy, its linear and turning parts, and the share of it in each of ``parts`` equal parts
    of T_con, on ``n`` random episodes of ``env_id`` (the same for all); a policy is a name of :mod:`baselines` or
    an object with ``predict``."""
    from train.evaluation.rollout import rollout

    if n < 1 or parts < 1:
        raise ValueError(f"n={n!r} and parts={parts!r} are invalid: expected integers >= 1")
    scenario, params = random_episodes(env_id, n, seed)
    rows = []
    for name, policy in policies.items():
        acting = controller_policy(policy, params) if isinstance(policy, str) else policy
        result = rollout(acting, params, scenario.starts, scenario.goals, T_con=scenario.T_cons, seed=seed,
                         record=True)  # fmt: skip
        close = getattr(getattr(acting, "controller", None), "close", None)
        if close is not None:
            close()
        trajectory = result.trajectory or {}
        u, omega = trajectory["linear_velocity"], trajectory["angular_velocity"]  # (steps, N), 0 once ended
        linear, turning = u * u * params.dt, omega * omega * params.dt
        energy = linear + turning
        part = np.minimum((trajectory["time"][:-1] / result.T_con * parts).astype(np.int64), parts - 1)
        total = float(np.sum(energy))
        shares = [float(np.sum(energy[part == i]) / total) if total > 0 else 0.0 for i in range(parts)]
        rows.append({"policy": name, "in_time": float(np.mean(result.success)),
                     "energy_mean": float(np.mean(result.energy)),
                     "linear_mean": float(np.mean(np.sum(linear, axis=0))),
                     "turning_mean": float(np.mean(np.sum(turning, axis=0))), "shares": shares,
                     "final_heading_mean": float(np.mean(result.final_heading_error))})  # fmt: skip
    return {"env_id": env_id, "episodes": n, "seed": seed, "parts": parts, "rows": rows}


def gain_settings(grid: Mapping[str, Sequence[float]]) -> list[dict[str, float]]:
    """Every combination of ``grid``'s values ({gain: values}), as keyword dicts, in the grid's order."""
    for gain, values in grid.items():
        if not values:
            raise ValueError(f"grid[{gain!r}]={values!r} is invalid: expected at least one value")
    names = list(grid)
    return [dict(zip(names, map(float, values), strict=True)) for values in itertools.product(*grid.values())]


def _law_policy(law: str, gains: dict[str, float], params: Any) -> tuple[dict[str, float], Any] | None:
    """``gains`` completed so the law accepts them (PTC's K capped at min(1.2, 0.6 K1, K2), Table 1) and the law acting
    with them in an env of ``params``, or None where the law refuses them."""
    if law == "ptc":
        gains = {**gains, "K": round(min(1.2, 0.6 * gains["K1"], gains["K2"]), 12)}
    try:
        return gains, controller_policy(law, params, **gains)
    except ValueError:
        return None


def law_gains(
    grids: Mapping[str, Mapping[str, Sequence[float]]] | None = None,
    env_id: str = V2,
    n: int = 100,
    seed: int = 0,
    progress: bool = False,
) -> dict[str, Any]:
    """Each law of ``grids`` ({law: {gain: values}}, default :data:`GAIN_GRIDS`) at every setting its grid spans, on
    the ``n`` episodes of the random set (``seed``) of ``env_id``: in time, E/opt (the pose's optimum) and final
    heading; settings the law refuses are left out. ``best`` names, per law, the lowest E/opt in time on >= 99.5 %
    of the episodes, without and with a final heading <= 0.15 rad (None where no setting is)."""
    from dwr_gym.params import EnvParams
    from train.evaluation.evaluate import evaluate_sets

    if n < 1:
        raise ValueError(f"n={n!r} is invalid: expected an integer >= 1")
    kwargs = env_keywords(env_id, {})
    params = EnvParams.from_kwargs(**{k: v for k, v in kwargs.items() if k in EnvParams.__dataclass_fields__})
    rows, policies, settings = [], {}, {}
    for law, grid in (grids or GAIN_GRIDS).items():
        for gains in gain_settings(grid):
            accepted = _law_policy(law, gains, params)
            if accepted is None:
                continue
            full, policy = accepted
            label = f"{law} " + ", ".join(f"{k}={v:g}" for k, v in full.items())
            policies[label], settings[label] = policy, (law, full)
    for row in evaluate_sets(policies, ["random"], n, seed, kwargs, progress=progress, optimum="pose"):
        law, gains = settings[row["policy"]]
        ratio = row["energy_ratio_mean"]
        rows.append({"law": law, "gains": gains, "in_time": row["success_rate"],
                     "energy_ratio": ratio if math.isfinite(ratio) else None,
                     "final_heading": row["final_heading_error_mean"], "energy": row["energy_mean"]})  # fmt: skip
    best: dict[str, dict[str, Any]] = {}
    for law in dict.fromkeys(row["law"] for row in rows):
        mine = [r for r in rows if r["law"] == law and r["in_time"] >= GOAL_IN_TIME and r["energy_ratio"] is not None]
        heading = [r for r in mine if r["final_heading"] <= GOAL_HEADING]
        best[law] = {"any_heading": min(mine, key=lambda r: r["energy_ratio"], default=None),
                     "heading_goal": min(heading, key=lambda r: r["energy_ratio"], default=None)}  # fmt: skip
    return {"env_id": env_id, "episodes": n, "seed": seed, "in_time_goal": GOAL_IN_TIME,
            "heading_goal": GOAL_HEADING, "rows": rows, "best": best}  # fmt: skip


__all__ = ["GAIN_GRIDS", "PARTS", "energy_split", "gain_settings", "law_gains"]

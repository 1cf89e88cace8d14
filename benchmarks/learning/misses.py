"""Where the learned agents miss on v2: the final distance of the episodes not at the goal at T_con, per T_con.

    python -m benchmarks run misses --docs     # the four shipped APG agents of 30 minutes, 300 starts a T_con
    python -m benchmarks run misses train/pretrained/apg_v2 --n 50   # any agents (printed, nothing written)

Each agent plays ``--n`` random episodes of DWRPointStabilization-v2 (seed ``--seed``) at each T_con of 10, 20, 40
and 60 s (train/evaluation/rollout.py). For the episodes not within the goal tolerance at T_con it reports how far
from the goal they end (median, the largest, and the share within 2 cm), whether they left the arena, and how far
they started. ``--docs`` writes docs/rl_benchmark/misses.json, from which the table ``misses`` of
docs/rl-apg-levers.md is rendered (the section "Near misses").
"""

from __future__ import annotations

import platform
import time
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks.core.commands import parser_for
from benchmarks.core.docs import Schema, table
from benchmarks.core.record import write_json

ROOT = Path(__file__).resolve().parents[2]
JSON_PATH = ROOT / "docs" / "rl_benchmark" / "misses.json"
ENV_ID = "DWRPointStabilization-v2"
T_CONS = (10.0, 20.0, 40.0, 60.0)
DEFAULT_AGENTS = tuple(
    f"train/pretrained/apg_{name}_time_scaled_30min_v2"
    for name in ("teacher", "near_miss", "hold", "hold_heading", "hold_heading10")
)


def misses(policy: Any, n: int, seed: int, T_con: float) -> dict[str, Any]:
    """In time, and the misses' final distance, arena exits and start distance, on ``n`` random episodes at
    ``T_con``."""
    from train.evaluation.incentives import random_episodes
    from train.evaluation.rollout import rollout

    scenario, params = random_episodes(ENV_ID, n, seed)
    result = rollout(policy, params, scenario.starts, scenario.goals, T_con=np.full(n, T_con), seed=seed)
    missed = ~result.success
    start = np.hypot(*(scenario.starts[:, :2] - scenario.goals[:, :2]).T)
    final = result.final_distance[missed]
    row: dict[str, Any] = {"T_con": T_con, "n": n, "in_time": float(np.mean(result.success)),
                           "misses": int(missed.sum()), "left_arena": int(result.left_arena.sum())}  # fmt: skip
    if missed.any():
        row.update(final_distance_median=float(np.median(final)), final_distance_max=float(np.max(final)),
                   within_2cm=float(np.mean(final <= 0.02)),
                   start_distance_median=float(np.median(start[missed])))  # fmt: skip
    return row


def main(argv: list[str] | None = None) -> int:
    from train.learning.agents import load_agent

    parser = parser_for("misses", __doc__)
    parser.add_argument("agents", nargs="*", default=list(DEFAULT_AGENTS), help="run directories or shipped agents")
    parser.add_argument("--n", type=int, default=300, help="random episodes at each T_con (default: 300)")
    parser.add_argument("--seed", type=int, default=7, help="seed of the episodes (default: 7)")
    parser.add_argument("--docs", action="store_true", help=f"write {JSON_PATH.relative_to(ROOT)} (and its table)")
    args = parser.parse_args(argv)
    if args.n < 1:
        parser.error(f"--n {args.n} is invalid: expected an integer >= 1")
    start = time.time()
    agents = []
    for path in args.agents:
        _, policy = load_agent(path)
        rows = [misses(policy, args.n, args.seed, T_con) for T_con in T_CONS]
        for row in rows:
            print(Path(path).name, {k: round(v, 4) if isinstance(v, float) else v for k, v in row.items()})
        agents.append({"agent": Path(path).name, "rows": rows})
    data = {"env_id": ENV_ID, "seed": args.seed, "agents": agents,
            "machine": {"python": platform.python_version(), "seconds": round(time.time() - start)}}  # fmt: skip
    if args.docs:
        write_json(JSON_PATH, data)
    return 0


SCHEMA = Schema({"env_id": str, "seed": int, "agents": list, "machine": dict})
BLOCKS = (table("misses", SCHEMA),)

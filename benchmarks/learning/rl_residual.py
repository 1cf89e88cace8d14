"""What a residual agent learned: where it acts on top of its expert, and what that buys.

Runs a residual agent (a run directory of ``dwr-gym train --residual``) and its expert alone on the benchmark's
nominal set and reports the in-time rate, the energy, E/opt and the final heading of both, and the residual's
mean |correction| of the linear and angular command (SI units) by the share of T_con elapsed and by the distance
to the goal.

    python -m benchmarks run rl-residual train/pretrained/residual_ppo_v1 --n 200 --docs
"""

from __future__ import annotations

import itertools
import json
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks.core.commands import parser_for
from benchmarks.core.docs import Schema, table
from benchmarks.core.record import write_json

ROOT = Path(__file__).resolve().parents[2]

TIME_BINS = (0.0, 0.25, 0.5, 0.75, 1.0, 1.5)
DISTANCE_BINS = (0.01, 0.1, 0.3, 1.0, 3.5)


class Recorder:
    """A residual policy that records, per step and robot still moving, the distance, the time fraction and the
    residual's correction of the commands."""

    def __init__(self, policy: Any, u_max: float, omega_max: float) -> None:
        self.policy, self.limits = policy, np.array([u_max, omega_max])
        self.rows: list[np.ndarray] = []

    def predict(self, obs: Any, state: Any = None, episode_start: Any = None, deterministic: bool = True) -> Any:
        actions, state = self.policy.predict(obs, state, episode_start, deterministic)
        expert, _ = self.policy.expert.predict(obs, episode_start=episode_start)
        correction = (np.asarray(actions) - np.clip(np.asarray(expert), -1.0, 1.0)) * self.limits
        live = (obs[:, 0] > 0.01) & (obs[:, 6] < 1.5)
        self.rows.append(np.column_stack([obs[live, 0], obs[live, 6], np.abs(correction[live])]))
        return actions, state


def binned(rows: np.ndarray, column: int, bins: tuple[float, ...]) -> list[dict[str, float]]:
    out = []
    for low, high in itertools.pairwise(bins):
        inside = rows[(rows[:, column] >= low) & (rows[:, column] < high)]
        out.append({"low": low, "high": high, "steps": len(inside),
                    "du": float(inside[:, 2].mean()) if len(inside) else None,
                    "domega": float(inside[:, 3].mean()) if len(inside) else None})  # fmt: skip
    return out


def main(argv: list[str] | None = None) -> int:
    parser = parser_for("rl-residual", __doc__)
    parser.add_argument("agents", nargs="+", help="run directories of residual agents")
    parser.add_argument("--n", type=int, default=200, help="episodes of the benchmark's nominal set (default 200)")
    parser.add_argument("--docs", action="store_true", help="write docs/rl_benchmark/residual.json (and its table)")
    args = parser.parse_args(argv)

    from train.env_ids import TASK_ENV_ID, env_keywords
    from train.evaluation.benchmark import EVAL_SEED, metrics_of
    from train.evaluation.evaluate import evaluate
    from train.evaluation.scenarios import make_scenario
    from train.learning.agents import load_agent
    from train.learning.runs import load_config

    scenario = make_scenario("random", n=args.n, seed=EVAL_SEED, env_kwargs=env_keywords(TASK_ENV_ID, {}))
    data: dict[str, Any] = {"n": args.n, "seed": EVAL_SEED, "agents": {}}
    for path in args.agents:
        config = load_config(Path(path))
        params = config.env_params()
        _, policy = load_agent(path)
        recorder = Recorder(policy, params.u_max, params.omega_max)
        results = evaluate({"agent": recorder, "expert": config.expert}, scenario, optimum="pose")
        rows = np.concatenate(recorder.rows)
        data["agents"][Path(path).name] = {
            "expert": config.expert,
            "agent": metrics_of(results["agent"].summary()),
            "expert_alone": metrics_of(results["expert"].summary()),
            "by_time_fraction": binned(rows, 1, TIME_BINS),
            "by_distance": binned(rows, 0, DISTANCE_BINS),
        }
        print(json.dumps(data["agents"][Path(path).name], indent=1))
    if args.docs:
        write_json(ROOT / "docs" / "rl_benchmark" / "residual.json", data)
    return 0


BLOCKS = (table("rl-residual", Schema({"n": int, "seed": int, "agents": dict})),)

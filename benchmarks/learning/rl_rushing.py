"""How much of an agent's excess energy is its timing (issue 32's diagnosis): E/opt split into two factors.

An agent that arrives at ``t_arr`` before T_con pays twice: the least energy to arrive by ``t_arr`` is more than the
least energy to arrive by T_con (``timing = E_opt(t_arr) / E_opt(T_con)``), and its motion costs more than that
least energy (``motion = E / E_opt(t_arr)``). Per episode that arrives in time, ``E/opt = timing x motion``
exactly. Both optima are the same minimum-energy problem (``optimal_energies``, CasADi, cached), one with the
agent's own arrival time as the deadline. Run on the benchmark's nominal set (seed 3232) for agents and
controllers:

    python -m benchmarks run rl-rushing train/pretrained/ppo_jax_v1 --controllers ptc pt-astolfi --n 50 --docs
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks.core.commands import parser_for
from benchmarks.core.docs import Schema, table
from benchmarks.core.record import write_json

ROOT = Path(__file__).resolve().parents[2]
JSON_PATH = ROOT / "docs" / "rl_benchmark" / "rushing.json"


def decomposition(result: Any, optimum_at_arrival: np.ndarray) -> dict[str, Any]:
    """The two factors of E/opt over the episodes that arrive in time with both optima (geometric means, since the
    factors multiply), and the arrival time as a share of T_con."""
    ok = result.success & np.isfinite(result.optimal_energy) & np.isfinite(optimum_at_arrival)
    ok &= (result.optimal_energy > 0) & (optimum_at_arrival > 0)
    if not ok.any():
        return {"episodes": 0}
    energy, at_deadline, at_arrival = result.energy[ok], result.optimal_energy[ok], optimum_at_arrival[ok]

    def gmean(values: np.ndarray) -> float:
        return float(np.exp(np.mean(np.log(values))))

    return {
        "episodes": int(ok.sum()),
        "arrival_share": float(np.mean(result.arrival_time[ok] / result.T_con[ok])),
        "energy_ratio": gmean(energy / at_deadline),
        "timing": gmean(at_arrival / at_deadline),
        "motion": gmean(energy / at_arrival),
        "energy": float(np.mean(energy)),
        "optimum_energy": float(np.mean(at_deadline)),
    }


def main(argv: list[str] | None = None) -> int:
    parser = parser_for("rl-rushing", __doc__)
    parser.add_argument("agents", nargs="*", help="run directories (or model .zip) of agents")
    parser.add_argument("--controllers", nargs="*", default=["ptc"], help="controllers beside them (default: ptc)")
    parser.add_argument("--n", type=int, default=50, help="episodes of the benchmark's nominal set (default 50)")
    parser.add_argument("--docs", action="store_true", help=f"write {JSON_PATH.relative_to(ROOT)} (and its table)")
    args = parser.parse_args(argv)
    if args.n < 1:
        parser.error(f"--n {args.n} is invalid: expected >= 1")

    from train.env_ids import TASK_ENV_ID, env_keywords
    from train.evaluation.benchmark import EVAL_SEED
    from train.evaluation.evaluate import evaluate
    from train.evaluation.optimum import optimal_energies
    from train.evaluation.scenarios import make_scenario
    from train.learning.agents import load_agent

    scenario = make_scenario("random", n=args.n, seed=EVAL_SEED, env_kwargs=env_keywords(TASK_ENV_ID, {}))
    policies: dict[str, Any] = {name: name for name in args.controllers}
    for path in args.agents:
        policies[Path(path).name] = load_agent(path)[1]
    results = evaluate(policies, scenario, optimum="pose", progress=True)
    rows: dict[str, Any] = {}
    for name, result in results.items():
        arrival = np.where(result.success, result.arrival_time, result.T_con)  # the deadline where none arrived
        at_arrival, _ = optimal_energies(result.params, scenario.starts, scenario.goals, arrival, progress=True,
                                         description=f"optimum by {name}'s arrival")  # fmt: skip
        rows[name] = decomposition(result, at_arrival)
        print(name, json.dumps(rows[name]))
    data = {"n": args.n, "seed": EVAL_SEED, "policies": rows}
    if args.docs:
        write_json(JSON_PATH, data)
    return 0


BLOCKS = (table("rl-rushing", Schema({"n": int, "seed": int, "policies": dict})),)

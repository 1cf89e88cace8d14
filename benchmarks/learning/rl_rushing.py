"""How much of an agent's excess energy is its timing (the RL benchmark's diagnosis): E/opt split into two factors.

An agent that arrives at ``t_arr`` before T_con pays twice: the least energy to arrive by ``t_arr`` is more than the
least energy to arrive by T_con (``timing = E_opt(t_arr) / E_opt(T_con)``), and its motion costs more than that
least energy (``motion = E / E_opt(t_arr)``). Per episode that arrives in time, ``E/opt = timing x motion``
exactly. Both optima are the same minimum-energy problem (``optimal_energies``, CasADi, cached), one with the
agent's own arrival time as the deadline. Run on the benchmark's nominal set (seed 3232) for agents and
controllers:

    python -m benchmarks run rl-rushing train/pretrained/ppo_jax_v1 --controllers ptc pt-astolfi --n 50 --docs
    python -m benchmarks run rl-rushing train/pretrained/es_residual_v2 --env DWRPointStabilization-v2 --docs
    python -m benchmarks run rl-rushing train/pretrained/es_arena50_v1 --controllers --add --docs   # one row more

``--add`` keeps the rows already in the JSON (same n, seed and env) and adds or replaces this run's.

On v2 (``--env``, written to rushing_v2.json) the energy counts until T_con and "in time" is at the goal at T_con;
the arrival is the first time at the goal, so ``motion`` includes what the robot spends holding the goal.
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
    parser.add_argument("--env", default=None, help="env id (default: the task's, DWRPointStabilization-v1)")
    parser.add_argument("--docs", action="store_true", help=f"write {JSON_PATH.relative_to(ROOT)} (rushing_v2.json "
                        "with --env DWRPointStabilization-v2) and its table")  # fmt: skip
    parser.add_argument("--add", action="store_true",
                        help="keep the JSON's other rows (same --n and env), adding or replacing this run's")  # fmt: skip
    args = parser.parse_args(argv)
    if args.n < 1:
        parser.error(f"--n {args.n} is invalid: expected >= 1")

    from train.env_ids import TASK_ENV_ID, env_keywords
    from train.evaluation.benchmark import EVAL_SEED
    from train.evaluation.evaluate import evaluate
    from train.evaluation.optimum import optimal_energies
    from train.evaluation.scenarios import make_scenario
    from train.learning.agents import load_agent

    env_id = args.env or TASK_ENV_ID
    try:
        env_kwargs = env_keywords(env_id, {})
    except ValueError as error:
        parser.error(str(error))
    path = JSON_PATH if env_id == TASK_ENV_ID else JSON_PATH.with_name(f"rushing_{env_id.rsplit('-', 1)[-1]}.json")
    earlier = json.loads(path.read_text()) if args.add and path.is_file() else None
    if earlier is not None:
        if (earlier["n"], earlier["seed"], earlier.get("env_id", TASK_ENV_ID)) != (args.n, EVAL_SEED, env_id):
            parser.error(f"--add: {path.name} holds n={earlier['n']} on {earlier.get('env_id', TASK_ENV_ID)}, "
                         f"not n={args.n} on {env_id}")  # fmt: skip
    scenario = make_scenario("random", n=args.n, seed=EVAL_SEED, env_kwargs=env_kwargs)
    policies: dict[str, Any] = {name: name for name in args.controllers}
    for agent in args.agents:
        policies[Path(agent).name] = load_agent(agent)[1]
    results = evaluate(policies, scenario, optimum="pose", progress=True)
    rows: dict[str, Any] = {}
    for name, result in results.items():
        arrival = np.where(result.success, result.arrival_time, result.T_con)  # the deadline where none arrived
        at_arrival, _ = optimal_energies(result.params, scenario.starts, scenario.goals, arrival, progress=True,
                                         description=f"optimum by {name}'s arrival")  # fmt: skip
        rows[name] = decomposition(result, at_arrival)
        print(name, json.dumps(rows[name]))
    if earlier is not None:
        rows = {**earlier["policies"], **rows}
    data = {"n": args.n, "seed": EVAL_SEED, "env_id": env_id, "policies": rows}
    if args.docs:
        write_json(path, data)
    return 0


BLOCKS = (table("rl-rushing", Schema({"n": int, "seed": int, "policies": dict})),
          table("rl-rushing-v2", Schema({"n": int, "seed": int, "policies": dict})))  # fmt: skip

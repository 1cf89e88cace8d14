"""Where a learner misses the deadline at each T_con: far from the goal, beside it, or with it ahead.

    python -m benchmarks run constraint-misses --docs   # docs/rl_benchmark/constrained_misses.json, its table

Each run directory's exported policy (default: the Lagrangian APG's seeds that benchmarks/recipes/rl_constrained.sh
trains, results/rl-constrained/runs/apg-lagrangian-v2-seed* and apg-lagrangian-averaged-v2-seed*, and the shipped
apg_v2) on ``--n`` random starts (seed 2026) of its env id at each T_con of the benchmark. A miss is an episode not
within the goal tolerance at T_con; by where it ends: *far*, over 2 cm from the goal (and of those, how many were
still closing in, more than 1 cm nearer in the last second: late); *beside*, within 2 cm with the goal to its side
(|sin| of the bearing from its heading to the goal over 0.7: an offset a unicycle closes only by turning away from
the goal's heading and back); *ahead*, within 2 cm with the goal ahead or behind.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from benchmarks.core.commands import parser_for
from benchmarks.core.docs import Block, Schema
from benchmarks.core.record import report, torch_machine

ROOT = Path(__file__).resolve().parents[2]
JSON_PATH = ROOT / "docs" / "rl_benchmark" / "constrained_misses.json"


def kinds_of_misses(result: Any, goals: np.ndarray, steps_per_second: int) -> dict[str, Any]:
    """The misses of one rollout (``record=True``, every episode ending at T_con) by kind, the far ones still closing
    in, and the median final distance of the ``beside`` ones."""
    distance, miss, end = result.trajectory["distance"], ~result.success, result.final_distance
    x, y, psi = (result.trajectory[key][-1] for key in ("x", "y", "psi"))
    side = np.abs(np.sin(np.arctan2(goals[:, 1] - y, goals[:, 0] - x) - psi)) > 0.7
    far, near = miss & (end > 0.02), miss & (end <= 0.02)
    closing = far & (distance[max(0, distance.shape[0] - 1 - steps_per_second)] - end > 0.01)
    beside = near & side
    return {"in_time": float(np.mean(result.success)), "misses": int(miss.sum()), "closing_in": int(closing.sum()),
            "far": int(far.sum()), "beside": int(beside.sum()), "ahead": int((near & ~side).sum()),
            "beside_distance": float(np.median(end[beside])) if beside.any() else None}  # fmt: skip


def measure(agents: dict[str, Path], n: int, seed: int) -> dict[str, Any]:
    from benchmarks.learning.per_t_con import agent_env_id
    from train.env_ids import env_keywords
    from train.evaluation.benchmark import PER_T_CON
    from train.evaluation.evaluate import evaluate
    from train.evaluation.scenarios import make_scenario
    from train.learning.agents import load_agent

    rows = []
    for name, run_dir in agents.items():
        env_id, policy = agent_env_id(run_dir), load_agent(run_dir)[1]
        cells = {}
        for T_con in PER_T_CON:
            kwargs = {**env_keywords(env_id), "T_con": T_con, "T_con_range": None}
            scenario = make_scenario("random", n=n, seed=seed, env_kwargs=kwargs)
            result = evaluate({name: policy}, scenario, record=True)[name]
            cells[str(T_con)] = kinds_of_misses(result, scenario.goals, round(1.0 / result.params.dt))
        rows.append({"policy": name, "env_id": env_id, "T_con": cells})
        print(name, cells, flush=True)
    return {"machine": torch_machine(), "n": n, "seed": seed, "T_con": [float(t) for t in PER_T_CON], "rows": rows}


def render(data: dict[str, Any]) -> str:
    def cell(c: dict[str, Any]) -> str:
        return f"{c['in_time']:.1%}: {c['far']} ({c['closing_in']}) / {c['beside']} / {c['ahead']}"

    keys = [str(float(t)) for t in data["T_con"]]
    lines = ["| policy | " + " | ".join(f"T_con {t:g} s" for t in data["T_con"]) + " | *beside*: final distance |",
             "|---" * (len(keys) + 2) + "|"]  # fmt: skip
    for row in data["rows"]:
        ends = [c["beside_distance"] for c in row["T_con"].values() if c["beside_distance"] is not None]
        span = f"{min(ends) * 100:.1f}-{max(ends) * 100:.1f} cm" if ends else "-"
        lines.append(f"| `{row['policy']}` | " + " | ".join(cell(row["T_con"][k]) for k in keys) + f" | {span} |")
    caption = (f"*Each cell: in time: misses far (of them still closing in) / beside the goal / with the goal ahead; "
               f"{data['n']} random starts (seed {data['seed']}) per T_con; the last column: the median final distance "
               f"of the beside misses, over the T_cons; {data['machine']}; "
               "`python -m benchmarks run constraint-misses --docs`.*")  # fmt: skip
    return "\n" + "\n".join(lines) + "\n\n" + caption + "\n"


def main(argv: list[str] | None = None) -> int:
    parser = parser_for("constraint-misses", __doc__)
    parser.add_argument("--agents", nargs="*", default=None, help="run directories (default: the module's docstring)")
    parser.add_argument("--n", type=int, default=600, help="starts per T_con (default: 600)")
    parser.add_argument("--docs", action="store_true", help=f"write {JSON_PATH.relative_to(ROOT)} (and its table)")
    args = parser.parse_args(argv)
    if args.n < 1:
        parser.error(f"--n {args.n} is invalid: expected an integer >= 1")
    runs = ROOT / "results" / "rl-constrained" / "runs"
    paths = ([Path(p) for p in args.agents] if args.agents is not None else
             [*(path for entry in ("apg-lagrangian-v2", "apg-lagrangian-averaged-v2")
                for path in sorted(runs.glob(f"{entry}-seed*"))), ROOT / "train" / "pretrained" / "apg_v2"])  # fmt: skip
    missing = [str(p) for p in paths if not (p / "model.zip").is_file()]
    if missing or not paths:
        parser.error(f"no exported policy (model.zip) in {', '.join(missing) or 'the default run directories'}: "
                     "train them with `python -m benchmarks run rl-constrained`, or give --agents")  # fmt: skip
    data = measure({p.name: p for p in paths}, args.n, seed=2026)
    return report([render(data)], data, JSON_PATH if args.docs else None)


BLOCKS = (Block("constrained-misses", "docs/rl_benchmark/constrained_misses.json", render,
                Schema({"machine": str, "n": int, "seed": int, "T_con": list, "rows": list})),)  # fmt: skip

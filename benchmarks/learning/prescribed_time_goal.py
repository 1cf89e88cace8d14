"""The prescribed-time goal of the learned agents, measured: any T_con, the full pose, less energy than PTC.

    python -m benchmarks run prescribed-time-goal runs/dagger_handover_s0
    python -m benchmarks run prescribed-time-goal runs/dagger_handover_s0 runs/dagger_handover_s1 runs/dagger_handover_s2
    python -m benchmarks run prescribed-time-goal runs/dagger_handover_s0 --n 200 --docs   # goal.json, table

(runs/dagger_handover_s0 ... are the hand-over agents of benchmarks/recipes/dagger_agents.sh.)

On random starts 0.3-3 m away (500 per T_con, seed 0), at each T_con in {10, 20, 40, 60} s, it
evaluates the given agents (several run directories are treated as training seeds of one agent:
mean +- sd), PTC, pt-astolfi and Astolfi, states the optimum of the same episodes (its plans reach the pose exactly,
heading 0, at T_con), and checks the goal for the agents: arrival by T_con in
>= 99 % of episodes, mean final heading error <= 0.1 rad, energy no more than PTC's on the same starts
(stretch: mean energy / optimum <= 1.5). It prints one table and one verdict line per criterion.
"""

from __future__ import annotations

from collections import defaultdict
from pathlib import Path

import numpy as np

from benchmarks.core import docs
from benchmarks.core.commands import add_json_output, parser_for
from benchmarks.core.record import write_json
from train.evaluation.evaluate import evaluate_sets
from train.learning.agents import load_agent

DOCS_JSON = "docs/prescribed_time/goal.json"
T_CONS = [10.0, 20.0, 40.0, 60.0]
ENV_KWARGS = {"start_distance": (0.3, 3.0)}
KEYS = ("success_rate", "final_heading_error_mean", "energy_mean", "energy_ratio_mean")


def main(argv: list[str] | None = None) -> None:
    parser = parser_for("prescribed-time-goal", __doc__)
    parser.add_argument("agents", nargs="+", help="run directories: the training seeds of one agent")
    parser.add_argument("--n", type=int, default=500)
    add_json_output(parser, DOCS_JSON, "--out")
    args = parser.parse_args(argv)
    policies = {f"seed{i}": load_agent(path)[1] for i, path in enumerate(args.agents)}
    policies.update({name: name for name in ("ptc", "pt-astolfi", "astolfi")})
    rows = evaluate_sets(policies, ["random"], args.n, 0, ENV_KWARGS, progress=True, optimum="pose", T_cons=T_CONS)
    table: dict[tuple[str, float], dict[str, list[float]]] = defaultdict(lambda: defaultdict(list))
    for row in rows:
        name = "agent" if row["policy"].startswith("seed") else row["policy"]
        for key in KEYS:
            table[(name, row["T_con"])][key].append(row[key])
        if row["policy"] == "ptc":  # the optimum of the same episodes (pose by T_con), from the E/opt reference
            optimum = table[("optimum", row["T_con"])]
            optimum["success_rate"].append(1.0)
            optimum["final_heading_error_mean"].append(0.0)
            optimum["energy_mean"].append(row["optimal_energy_mean"])
            optimum["energy_ratio_mean"].append(1.0)
    print(f"\n{'policy':<9} {'T_con':>5} {'success':>15} {'|psi_end| [rad]':>17} {'energy':>15} {'E/opt':>13}")
    for (name, T_con), values in table.items():
        cells = []
        for key, width in zip(KEYS, (15, 17, 15, 13), strict=True):
            v = np.array(values[key])
            text = f"{v.mean():.3f}" + (f" +- {v.std(ddof=1):.3f}" if v.size > 1 else "")
            cells.append(f"{text:>{width}}")
        print(f"{name:<9} {T_con:>5.0f} " + " ".join(cells))
    checks = {
        "arrival by T_con >= 99 %": lambda a, p: min(a["success_rate"]) >= 0.99,
        "mean final heading error <= 0.1 rad": lambda a, p: max(a["final_heading_error_mean"]) <= 0.1,
        "energy <= PTC's": lambda a, p: max(a["energy_mean"]) <= p["energy_mean"][0],
        "stretch: energy / optimum <= 1.5": lambda a, p: max(a["energy_ratio_mean"]) <= 1.5,
    }
    print()
    found = {}
    for text, check in checks.items():
        verdicts = [check(table[("agent", T)], table[("ptc", T)]) for T in T_CONS]
        detail = ", ".join(f"T_con {T:.0f}: {'yes' if ok else 'no'}" for T, ok in zip(T_CONS, verdicts, strict=True))
        print(f"[{'met' if all(verdicts) else 'not met':>7}] {text} (every seed): {detail}")
        found[text] = dict(zip((f"{T:g}" for T in T_CONS), verdicts, strict=True))
    if args.out:
        data = {"agents": args.agents, "n": args.n, "rows": rows, "verdicts": found}
        write_json(Path(args.out), data, safe=True)


BLOCKS = (docs.table("prescribed-time-goal", docs.Schema({"agents": list, "n": int, "rows": list, "verdicts": dict})),)

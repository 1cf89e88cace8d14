"""The robust goal, measured: the deadline under disturbances at near-minimum energy.

On fresh seeded starts 0.3-3 m away, at T_con in {10, 20, 40, 60} s, on the nominal set (`random`) and the four
disturbed sets as shipped (`disturbed`, `fault`, `delay`, `noise`), it evaluates the agent (or agents) given, beside
PTC (the paper's law: the energy bar) and `robust-pt` (the expert), and prints each criterion with its verdict:

- arrival within 1 cm by T_con on >= 99 % of nominal starts and >= 97 % of each disturbed set;
- mean final heading error <= 0.1 rad nominal and <= 0.2 rad on the disturbed sets;
- energy no more than PTC's on every set, and <= 1.3 times the optimum nominal (stretch; the optimum is solved per
  episode with CasADi and cached);
- under `noise`, a command-rate RMS <= 2 times its nominal one.

    python -m benchmarks run robust-goal --n 200 --docs      # docs/robust/goal.json and its table

An agent is a run directory, optionally with ``#network`` (the network alone) or ``#no-plan`` (the network with
``robust-pt``'s analytic finish but no planner); the default is the shipped ``train/pretrained/robust`` whole, its
network alone and its network without the planner, so that each part is reported beside the whole.

Each (T_con, set) is one job; ``--workers`` jobs run at once in separate processes.
"""

from __future__ import annotations

import os
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from typing import Any

from benchmarks.core.commands import add_json_output, parser_for
from benchmarks.core.docs import NUMBER, Schema, table
from benchmarks.core.record import write_json

DOCS_JSON = "docs/robust/goal.json"
SETS = ("random", "disturbed", "fault", "delay", "noise")
T_CONS = (10.0, 20.0, 40.0, 60.0)
START_DISTANCE = (0.3, 3.0)


def job(args: tuple[float, str, list[str], list[str], int, int]) -> list[dict[str, Any]]:
    """Every policy on one (T_con, set): one row each."""
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    T_con, name, agents, controllers, n, seed = args
    from train.evaluation.evaluate import evaluate
    from train.evaluation.scenarios import make_scenario
    from train.learning.agents import load_agent

    policies: dict[str, Any] = {c: c for c in controllers}
    for spec in agents:
        path, _, part = spec.partition("#")
        label, policy = load_agent(path, part or "whole")
        policies[label] = policy
    scenario = make_scenario(name, n=n, seed=seed, env_kwargs={"T_con": T_con, "start_distance": START_DISTANCE})
    optimum = "pose" if name == "random" else "none"
    results = evaluate(policies, scenario, seed=seed, optimum=optimum)
    rows = []
    for label, result in results.items():
        summary = result.summary()
        rows.append({"T_con": T_con, "set": name, "policy": label, "n": n, **{k: summary[k] for k in (
            "success_rate", "final_heading_error_mean", "energy_mean", "energy_ratio_mean", "command_rate_rms_mean",
            "velocity_rate_rms_mean", "arrival_fraction_max")}})  # fmt: skip
    return rows


def verdicts(rows: list[dict[str, Any]], agent: str) -> list[dict[str, Any]]:
    """Each criterion of the goal for ``agent``, with the measured figure and met or not."""
    by = {(r["T_con"], r["set"], r["policy"]): r for r in rows}
    out = []
    for T in sorted({r["T_con"] for r in rows}):
        nominal = by[(T, "random", agent)]
        out.append({"criterion": f"T_con {T:g}: in time, nominal >= 99 %", "measured": nominal["success_rate"],
                    "met": nominal["success_rate"] >= 0.99})  # fmt: skip
        out.append({"criterion": f"T_con {T:g}: heading, nominal <= 0.1 rad",
                    "measured": nominal["final_heading_error_mean"], "met": nominal["final_heading_error_mean"] <= 0.1})  # fmt: skip
        ratio = nominal["energy_ratio_mean"]
        out.append({"criterion": f"T_con {T:g}: energy / optimum, nominal <= 1.3 (stretch)", "measured": ratio,
                    "met": ratio == ratio and ratio <= 1.3})  # fmt: skip
        for name in SETS:
            row, ptc = by[(T, name, agent)], by.get((T, name, "ptc"))
            if name != "random":
                out.append({"criterion": f"T_con {T:g}: in time, {name} >= 97 %", "measured": row["success_rate"],
                            "met": row["success_rate"] >= 0.97})  # fmt: skip
                out.append({"criterion": f"T_con {T:g}: heading, {name} <= 0.2 rad",
                            "measured": row["final_heading_error_mean"], "met": row["final_heading_error_mean"] <= 0.2})  # fmt: skip
            if ptc is not None:
                out.append({"criterion": f"T_con {T:g}: energy <= PTC's, {name}", "measured": row["energy_mean"],
                            "bar": ptc["energy_mean"], "met": row["energy_mean"] <= ptc["energy_mean"]})  # fmt: skip
        noisy, calm = by[(T, "noise", agent)]["command_rate_rms_mean"], nominal["command_rate_rms_mean"]
        out.append({"criterion": f"T_con {T:g}: command-rate RMS under noise <= 2x nominal", "measured": noisy,
                    "bar": 2.0 * calm, "met": noisy <= 2.0 * calm})  # fmt: skip
    return out


def main(argv: list[str] | None = None) -> None:
    parser = parser_for("robust-goal", __doc__, allow_abbrev=False)
    parser.add_argument("agents", nargs="*", help="run directories of agents (default: train/pretrained/robust)")
    parser.add_argument("--controllers", nargs="*", default=["ptc", "robust-pt"])
    parser.add_argument("--n", type=int, default=500, help="starts per (T_con, set) (default: 500)")
    parser.add_argument("--seed", type=int, default=2026, help="seed of the starts and robots (default: 2026)")
    parser.add_argument("--T-con", type=float, nargs="+", default=list(T_CONS))
    parser.add_argument("--sets", nargs="+", default=list(SETS), choices=SETS)
    parser.add_argument("--workers", type=int, default=2)
    add_json_output(parser, DOCS_JSON)
    args = parser.parse_args(argv)
    if args.n < 1 or args.workers < 1:
        parser.error(f"--n {args.n} and --workers {args.workers} are invalid: expected integers >= 1")
    agents = args.agents or [f"train/pretrained/robust{part}" for part in ("", "#no-plan", "#network")]
    jobs = [(T, name, agents, args.controllers, args.n, args.seed) for T in args.T_con for name in args.sets]
    from tqdm.auto import tqdm

    began = time.time()
    rows: list[dict[str, Any]] = []
    with ProcessPoolExecutor(args.workers) as pool:
        for result in tqdm(pool.map(job, jobs), total=len(jobs), desc="(T_con, set)", unit="job", file=sys.stderr):
            rows.extend(result)
    print(
        f"{'T_con':>5} {'set':9} {'policy':22} {'in time':>8} {'|psi|':>6} {'energy':>7} {'E/opt':>6} {'cmd rate':>8}"
    )
    for r in rows:
        print(f"{r['T_con']:5g} {r['set']:9} {r['policy']:22} {100 * r['success_rate']:7.1f}% "
              f"{r['final_heading_error_mean']:6.3f} {r['energy_mean']:7.3f} {r['energy_ratio_mean']:6.2f} "
              f"{r['command_rate_rms_mean']:8.2f}")  # fmt: skip
    report: dict[str, Any] = {"rows": rows, "seed": args.seed, "n": args.n, "seconds": round(time.time() - began)}
    for agent in dict.fromkeys(r["policy"] for r in rows if r["policy"] != "ptc"):
        checks = verdicts(rows, agent)
        report[f"verdicts:{agent}"] = checks
        print(f"\n{agent}: {sum(c['met'] for c in checks)}/{len(checks)} criteria met")
        for c in checks:
            if not c["met"]:
                print(
                    f"  not met: {c['criterion']}: {c['measured']:.3f}"
                    + (f" (bar {c['bar']:.3f})" if "bar" in c else "")
                )
    if args.json:
        write_json(args.json, report, safe=True)


#: The rows and each policy's verdicts per criterion (keys "verdicts:<policy>").
BLOCKS = (table("robust-goal", Schema({"rows": list, "seed": int, "n": int, "seconds": NUMBER})),)

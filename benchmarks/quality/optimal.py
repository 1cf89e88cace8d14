"""Seconds per episode of the optimum: the cached reference plans and the NMPC controller ``optimal``.

    python -m benchmarks run optimal                                        # paper-fig5, paper-fig7 and random --n 1000
    python -m benchmarks run optimal --n 200                                # a quicker look
    python -m benchmarks run optimal --n 200 --docs                         # the rows of the docs' table

For each scenario set it times (1) solving the reference optimum of every episode on the env's grid
(what ``evaluate``/``compare`` cache for the E/opt columns; the cache is bypassed here) and (2) a
whole rollout of the ``optimal`` controller, and prints the seconds per episode, the solver count and
the quality (success, final heading error, energy / optimum). Wall-clock times depend on the
machine and its load; the table says how many worker processes were used.
"""

from __future__ import annotations

import os
import platform
import tempfile
import time
from pathlib import Path

import numpy as np

from baselines.expert import ExpertPolicy
from benchmarks.core.commands import add_json_output, parser_for
from benchmarks.core.docs import NUMBER, Schema, table
from benchmarks.core.record import write_json
from dwr_gym.params import EnvParams
from train.evaluation.optimum import optimal_energies
from train.evaluation.rollout import rollout
from train.evaluation.scenarios import controller_for, make_scenario

DOCS_JSON = "docs/benchmarks/optimal.json"


def main(argv: list[str] | None = None) -> None:
    parser = parser_for("optimal", __doc__)
    parser.add_argument("--n", type=int, default=1000, help="random episodes (default: 1000)")
    parser.add_argument("--workers", type=int, default=0, help="solver processes (default: every core)")
    add_json_output(parser, DOCS_JSON, "--out")
    args = parser.parse_args(argv)
    os.environ["DWR_GYM_CACHE"] = tempfile.mkdtemp(prefix="dwr-gym-bench-")  # time the solves, not the cache
    workers = args.workers or min(os.cpu_count() or 1, 8)
    print(f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores, {workers} worker processes")
    header = f"{'scenario':<11} {'n':>5} {'ref s/ep':>9} {'nmpc s/ep':>9} {'solves/ep':>9} {'success':>7} {'|psi_end|':>9} {'E/opt':>6}"
    print(header)
    print("-" * len(header))
    rows = []
    for name in ("paper-fig5", "paper-fig7", "random"):
        scenario = make_scenario(name, n=args.n, seed=0)
        params = EnvParams.from_kwargs(**scenario.env_kwargs)
        began = time.perf_counter()
        reference, failures = optimal_energies(params, scenario.starts, scenario.goals, workers=workers, progress=True)
        reference_time = time.perf_counter() - began
        controller = controller_for("optimal", scenario, params, workers=workers)
        policy = ExpertPolicy(controller, params.u_max, params.omega_max)
        began = time.perf_counter()
        result = rollout(policy, params, scenario.starts, scenario.goals, progress=True)
        nmpc_time = time.perf_counter() - began
        controller.close()
        result.optimal_energy = reference
        ratio = result.energy_ratio()
        n = scenario.size
        print(f"{name:<11} {n:>5} {reference_time / n:>9.3f} {nmpc_time / n:>9.3f} {controller.solves / n:>9.2f} "
              f"{result.success.mean():>7.3f} {result.final_heading_error.mean():>9.4f} {np.nanmean(ratio):>6.3f}"
              + (f"  ({len(failures)} episodes without optimum)" if failures else ""))  # fmt: skip
        rows.append({"scenario": name, "n": n, "reference_seconds_per_episode": reference_time / n,
                     "controller_seconds_per_episode": nmpc_time / n, "solves_per_episode": controller.solves / n,
                     "success_rate": float(result.success.mean()),
                     "final_heading_error_mean": float(result.final_heading_error.mean()),
                     "energy_ratio_mean": float(np.nanmean(ratio)), "episodes_without_optimum": len(failures),
                     "workers": workers, "cores": os.cpu_count()})  # fmt: skip
    if args.out:
        write_json(Path(args.out), rows)


BLOCKS = (table("optimal-timing", Schema({"scenario": str, "n": int, "reference_seconds_per_episode": NUMBER,
                                          "controller_seconds_per_episode": NUMBER, "solves_per_episode": NUMBER,
                                          "success_rate": NUMBER, "energy_ratio_mean": NUMBER, "workers": int,
                                          "cores": int}, rows=True)),)  # fmt: skip

"""How fast the optimum of `dwr-gym compare`'s episodes is solved: plans per CPU second before and after, same energies.

    nice -n 10 python python -m benchmarks run optimum-speed --n 100      # writes docs/compare/optimum_speed.json

A seeded sample of the ``--n`` distinct optima of compare's default sets (the random set's 1,000 starts, which the
four disturbed sets share, and the paper's nine) is solved in this one process three ways: as before this
benchmark (IPOPT, one problem built per episode, in episode order), as the optimum cache now solves them (IPOPT on
problems padded to a multiple of ``PAD_TO`` intervals, the longest first, so that few solvers are built), and with
fatrop on the padded problems. It records the CPU seconds (the figure a loaded machine does not distort much), the
wall seconds, plans per CPU second, and the largest relative difference of each way's energies from the first
(the goal: 1e-6). A compare solves with every core, so its plans per wall second are about the cores times these.
"""

from __future__ import annotations

import json
import os
import time
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks.core.commands import parser_for

ROOT = Path(__file__).resolve().parents[2]
JSON_PATH = ROOT / "docs" / "compare" / "optimum_speed.json"
SETS = ("paper-fig5", "paper-fig7", "random")  # the disturbed sets' optima are the random set's


def default_jobs() -> list[tuple[tuple[float, float, float], float]]:
    """The distinct (start in the goal frame, T_con) of compare's default sets, in the order compare meets them."""
    from train.env_ids import TASK_ENV_ID, env_keywords
    from train.evaluation.optimum import goal_frame_starts
    from train.evaluation.scenarios import make_scenario

    jobs: dict[tuple[tuple[float, float, float], float], None] = {}
    for name in SETS:
        scenario = make_scenario(name, n=1000, seed=0, env_kwargs=env_keywords(TASK_ENV_ID, {}))
        T_cons = scenario.T_cons if scenario.T_cons is not None else [scenario.env_kwargs["T_con"]] * scenario.size
        for start, T_con in zip(goal_frame_starts(scenario.starts, scenario.goals), T_cons, strict=True):
            jobs[(tuple(map(float, start)), float(T_con))] = None  # type: ignore[assignment]
    return list(jobs)


def solve_all(jobs: list[tuple[tuple[float, float, float], float]], pad_to: int, solver: str, longest_first: bool
              ) -> dict[str, Any]:  # fmt: skip
    """Solve ``jobs`` one after the other in a fresh solver cache; energies in the jobs' order, the times."""
    from baselines.optimal import OptimalControlError, minimum_energy_solver, solve_minimum_energy

    minimum_energy_solver.cache_clear()
    order = sorted(range(len(jobs)), key=lambda i: -jobs[i][1]) if longest_first else list(range(len(jobs)))
    energies = np.full(len(jobs), np.nan)
    cpu, wall = time.process_time(), time.perf_counter()
    for i in order:
        start, T_con = jobs[i]
        try:
            energies[i] = solve_minimum_energy(start, T_con, 0.05, 0.5, 2.0, pad_to=pad_to, solver=solver).energy
        except OptimalControlError:
            pass
    return {"cpu_seconds": time.process_time() - cpu, "wall_seconds": time.perf_counter() - wall,
            "energies": energies}  # fmt: skip


def measure(n: int, seed: int, fatrop: bool) -> dict[str, Any]:
    from train.evaluation.optimum import PAD_TO

    every = default_jobs()
    chosen = sorted(np.random.default_rng(seed).choice(len(every), size=min(n, len(every)), replace=False))
    jobs = [every[i] for i in chosen]
    ways = {"before: IPOPT, a problem per episode": (1, "ipopt", False),
            f"now: IPOPT, padded to {PAD_TO} intervals, longest first": (PAD_TO, "ipopt", True)}  # fmt: skip
    if fatrop:
        ways[f"fatrop, padded to {PAD_TO} intervals, longest first"] = (PAD_TO, "fatrop", True)
    results: dict[str, Any] = {}
    reference = None
    for label, (pad_to, solver, longest_first) in ways.items():
        found = solve_all(jobs, pad_to, solver, longest_first)
        energies = found.pop("energies")
        if reference is None:
            reference = energies
        difference = np.abs(energies - reference) / reference
        results[label] = {**{k: round(v, 2) for k, v in found.items()},
                          "plans_per_cpu_second": round(len(jobs) / found["cpu_seconds"], 3),
                          "max_relative_energy_difference": float(np.nanmax(difference)),
                          "failures": int(np.isnan(energies).sum())}  # fmt: skip
        print(label, results[label], flush=True)
    return {"plans": len(jobs), "of": len(every), "seed": seed, "load_average_1min_at_end": round(os.getloadavg()[0], 2),
            "ways": results}  # fmt: skip


def main(argv: list[str] | None = None) -> None:
    parser = parser_for("optimum-speed", __doc__)
    parser.add_argument("--n", type=int, default=100, help="optima sampled from the 1,009 (default: 100)")
    parser.add_argument("--seed", type=int, default=0, help="seed of the sample (default: 0)")
    parser.add_argument("--no-fatrop", action="store_true", help="leave out the fatrop way")
    parser.add_argument(
        "--out", default=str(JSON_PATH), help=f"the JSON written (default: {JSON_PATH.relative_to(ROOT)})"
    )
    args = parser.parse_args(argv)
    if not 1 <= args.n <= 1009:
        parser.error(f"--n {args.n} is invalid: expected an integer in [1, 1009]")
    results = measure(args.n, args.seed, not args.no_fatrop)
    Path(args.out).write_text(json.dumps(results, indent=1) + "\n")
    print(f"wrote {args.out}")

"""How fast the optimum of `dwr-gym compare`'s episodes is solved: plans per second before and now, the same energies.

    python -m benchmarks run optimum-speed --n 1009 --before-n 100   # writes docs/compare/optimum_speed.json

A seeded sample of the ``--n`` distinct optima of compare's default sets (the random set's 1,000 starts, which the
four disturbed sets share, and the paper's nine), solved in this one process as now
(:func:`train.evaluation.optimum.solve_uncached`: a batch on ``--workers`` threads, fatrop, ``STAGE`` intervals a
stage, padded to ``PAD_TO``, a grid ``COARSE`` times coarser first), with ``--stages``' other intervals a stage, and,
its first ``--before-n``, as before (IPOPT, padded to ``BEFORE_PAD_TO``, one search after another, every guess on the
fine grid): CPU and wall seconds, plans per second, the load, and each optimum whose energy differs from the shipped
one by more than 1e-6. Each way starts threads that have built no solver yet.
"""

from __future__ import annotations

import functools
import json
import os
import time
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from benchmarks.core.commands import parser_for
from benchmarks.core.record import cpu_model

ROOT = Path(__file__).resolve().parents[2]
JSON_PATH = ROOT / "docs" / "compare" / "optimum_speed.json"
SETS = ("paper-fig5", "paper-fig7", "random")  # the disturbed sets' optima are the random set's
#: The padding of the optimum cache's problems before (now :data:`train.evaluation.optimum.PAD_TO`).
BEFORE_PAD_TO = 20


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


def solve_before(jobs: list[tuple[tuple[float, float, float], float]]) -> NDArray[np.float64]:
    """Each job as the optimum cache solved it before: IPOPT, padded problems, the longest first, one after another."""
    from baselines.optimal import OptimalControlError, solve_minimum_energy

    energies = np.full(len(jobs), np.nan)
    for i in sorted(range(len(jobs)), key=lambda i: -jobs[i][1]):
        try:
            energies[i] = solve_minimum_energy(*jobs[i], 0.05, 0.5, 2.0, pad_to=BEFORE_PAD_TO, solver="ipopt").energy
        except OptimalControlError:
            pass
    return energies


def solve_now(jobs: list[tuple[tuple[float, float, float], float]], workers: int, stage: int) -> NDArray[np.float64]:
    """The jobs as ``dwr-gym compare`` solves a missing optimum now (with ``stage`` intervals per fatrop stage)."""
    from train.evaluation.optimum import solve_uncached

    solved = solve_uncached([(start, T_con, 0.05, 0.5, 2.0, True) for start, T_con in jobs], workers, stage=stage)
    return np.array([e if isinstance(e, float) else np.nan for e in solved])


def shipped(jobs: list[tuple[tuple[float, float, float], float]]) -> NDArray[np.float64]:
    """The shipped optimum of each job (NaN where none is shipped)."""
    from train.evaluation.optimum import _start_key
    from train.evaluation.shipped_optima import read_shipped, shipped_files

    known: dict[str, float | str] = {}
    for path in shipped_files():
        problem, energies = read_shipped(path)
        if problem["heading"] and problem["dt"] == 0.05:
            known.update(energies)
    values = [known.get(_start_key(np.asarray(start), T_con)) for start, T_con in jobs]
    return np.array([v if isinstance(v, float) else np.nan for v in values])


def measure(n: int, seed: int, workers: int, before: bool, before_n: int | None = None, stages: tuple = ()) -> dict:
    from baselines.minimum_energy_nlp import minimum_energy_solver
    from baselines.optimal import new_threads
    from train.evaluation.optimum import COARSE, PAD_TO, STAGE

    every = default_jobs()
    chosen = sorted(np.random.default_rng(seed).choice(len(every), size=min(n, len(every)), replace=False))
    jobs = [every[i] for i in chosen]
    reference = shipped(jobs)
    ways = {f"{'now' if s == STAGE else 'other'}: fatrop, {s} interval{'s' * (s > 1)} a stage, padded to {PAD_TO}, "
            f"coarse {COARSE}x then fine, a batch on {workers} threads": functools.partial(solve_now, jobs, workers, s)
            for s in dict.fromkeys((STAGE, *stages))}  # fmt: skip
    if before:  # the slow way on the sample's first ``before_n``
        ways[f"before: IPOPT, padded to {BEFORE_PAD_TO} intervals, one search after another"] = lambda: solve_before(
            jobs[:before_n])  # fmt: skip
    results: dict[str, Any] = {}
    for label, solve in ways.items():
        minimum_energy_solver.cache_clear()
        new_threads()
        cpu, wall = time.process_time(), time.perf_counter()
        energies = solve()
        cpu, wall = time.process_time() - cpu, time.perf_counter() - wall
        difference = np.abs(energies - reference[: len(energies)]) / reference[: len(energies)]
        above = [[*jobs[i][0], jobs[i][1], float(difference[i])] for i in np.flatnonzero(difference > 1e-6)]
        results[label] = {"plans": len(energies), "cpu_seconds": round(cpu, 2), "wall_seconds": round(wall, 2),
                          "plans_per_cpu_second": round(len(energies) / cpu, 3),
                          "plans_per_wall_second": round(len(energies) / wall, 3),
                          "max_relative_energy_difference_from_shipped": float(np.nanmax(difference)),
                          "above_1e-6": above, "failures": int(np.isnan(energies).sum()),
                          "load_average_1min_at_end": round(os.getloadavg()[0], 2)}  # fmt: skip
        print(label, results[label], flush=True)
    return {"plans": len(jobs), "of": len(every), "seed": seed, "cpu": cpu_model(), "ways": results}


def main(argv: list[str] | None = None) -> None:
    parser = parser_for("optimum-speed", __doc__)
    parser.add_argument("--n", type=int, default=100, help="optima sampled from the 1,009 (default: 100)")
    parser.add_argument("--seed", type=int, default=0, help="seed of the sample (default: 0)")
    parser.add_argument("--workers", type=int, default=2, help="threads of the batch (default: 2)")
    parser.add_argument("--no-before", action="store_true", help="leave out the way of before (the slow one)")
    parser.add_argument("--before-n", type=int, default=None, help="the way of before on the first N (default: --n)")
    parser.add_argument("--stages", type=int, nargs="*", default=[], help="also these intervals per fatrop stage")
    parser.add_argument("--out", default=str(JSON_PATH), help="the JSON (default: docs/compare/optimum_speed.json)")
    args = parser.parse_args(argv)
    if not 1 <= args.n <= 1009:
        parser.error(f"--n {args.n} is invalid: expected an integer in [1, 1009]")
    if not 1 <= args.workers <= 64:
        parser.error(f"--workers {args.workers} is invalid: expected an integer in [1, 64]")
    if args.before_n is not None and not 1 <= args.before_n <= args.n:
        parser.error(f"--before-n {args.before_n} is invalid: expected an integer in [1, --n = {args.n}]")
    if any(not 1 <= s <= 200 or 200 % s for s in args.stages):
        parser.error(f"--stages {args.stages} is invalid: expected divisors of the padding, 200")
    results = measure(args.n, args.seed, args.workers, not args.no_before, args.before_n, tuple(args.stages))
    Path(args.out).write_text(json.dumps(results, indent=1) + "\n")
    print(f"wrote {args.out}")

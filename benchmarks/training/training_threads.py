"""`dwr-gym train` on a busy machine: its defaults against `OMP_NUM_THREADS=1`, under the same load, in one run.

    nice -n 10 python -m benchmarks run training-threads --docs   # docs/training/threads.json and its block, ~10 min

The threads goal: with two busy processes beside it (``python -c 'while True: pass'``), `dwr-gym train` with its
default settings runs at >= 0.8x the speed of the same command under ``OMP_NUM_THREADS=1``, for PPO and SAC.
Each run is the command as a user types it (a fresh process: imports, the step-0 evaluation, training,
checkpoints), timed from start to exit; the two settings alternate in each of ``--repeats`` rounds, and the ratio
is the median of the per-round ratios. A third setting, ``--threads N`` with N the number of cores (torch's own
default, what `dwr-gym train` used before --threads), is timed once per algorithm as the reference of the
collapse. The busy processes are started before the first run and stopped after the last.
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from benchmarks.core.commands import parser_for
from benchmarks.core.docs import NUMBER, Schema, fenced
from benchmarks.core.record import load_average, torch_machine, write_json
from benchmarks.core.timing import background_load, median_ratio, medians

ROOT = Path(__file__).resolve().parents[2]
JSON_PATH = ROOT / "docs" / "training" / "threads.json"
GOAL = 0.8
STEPS = {"ppo": 32_768, "sac": 4_096}
"""Env steps per run: PPO's are two rollouts of 256 robots; SAC's pass learning_starts (2,000) so that it trains."""
REFERENCE_LIMIT = 900.0  # [s]
"""A reference run (``--threads <cores>``) stopped after this long gives a bound: at most steps / limit per second."""
SETTINGS = {
    "defaults": {},
    "OMP_NUM_THREADS=1": {"OMP_NUM_THREADS": "1"},
}


def timed_run(
    algo: str, steps: int, environment: dict[str, str], extra: list[str], limit: float | None = None
) -> float:
    """Seconds of one `dwr-gym train` process, start to exit (``limit`` if it was stopped there)."""
    env = {k: v for k, v in os.environ.items() if k not in ("OMP_NUM_THREADS", "MKL_NUM_THREADS")}
    env.update({"PYTHONPATH": str(ROOT), **environment})
    with tempfile.TemporaryDirectory() as tmp:
        command = [sys.executable, "-m", "train.cli", "train", "--algo", algo, "--total-timesteps", str(steps),
                   "--run-dir", f"{tmp}/run", "--no-progress", *extra]  # fmt: skip
        began = time.perf_counter()
        try:
            subprocess.run(command, env=env, check=True, stdout=subprocess.DEVNULL, cwd=tmp, timeout=limit)
        except subprocess.TimeoutExpired:
            return float(limit)  # type: ignore[arg-type]
        return time.perf_counter() - began


def run(repeats: int, busy: int, reference: bool, save: Any = None) -> dict[str, Any]:
    """The rounds, under ``busy`` busy processes; the medians and ratios (given to ``save`` after each round too,
    so that a run cut short keeps what it measured)."""
    with background_load(busy, 6 * 3600.0):  # (ended with the block, a SIGTERM included)
        rounds: list[dict[str, Any]] = []
        for index in range(repeats):
            entry: dict[str, Any] = {}
            for algo, steps in STEPS.items():
                order = list(SETTINGS) if index % 2 == 0 else list(reversed(SETTINGS))
                for name in order:
                    entry[f"{algo} {name}"] = steps / timed_run(algo, steps, SETTINGS[name], [])
            rounds.append(entry)
            print(f"round {index + 1}/{repeats}: " + ", ".join(f"{k} {v:,.0f} steps/s" for k, v in entry.items()),
                  flush=True)  # fmt: skip
            if save is not None:
                save(summarize(rounds, {}, busy))
        collapse: dict[str, float] = {}
        if reference:
            cores = os.cpu_count() or 1
            for algo, steps in STEPS.items():
                collapse[algo] = steps / timed_run(algo, steps, {}, ["--threads", str(cores)], REFERENCE_LIMIT)
                print(f"{algo} --threads {cores}: {collapse[algo]:,.0f} steps/s", flush=True)
                if save is not None:
                    save(summarize(rounds, collapse, busy))
    return summarize(rounds, collapse, busy)


def summarize(rounds: list[dict[str, Any]], collapse: dict[str, float], busy: int) -> dict[str, Any]:
    """The results of the rounds so far: medians, ratios, the verdict."""
    ratios = {algo: median_ratio(rounds, f"{algo} defaults", f"{algo} OMP_NUM_THREADS=1") for algo in STEPS}
    return {
        "machine": torch_machine(),
        "busy_processes": busy,
        "load_average_1min_at_end": load_average(),
        "steps": STEPS,
        "rounds": rounds,
        "median_fps": medians(rounds),
        "threads_cores_fps": collapse,
        "reference_limit_seconds": REFERENCE_LIMIT,
        "cores": os.cpu_count(),
        "ratio_defaults_to_omp1": ratios,
        "goal": GOAL,
        "met": all(ratio >= GOAL for ratio in ratios.values()),
    }


def render(results: dict[str, Any]) -> list[str]:
    """The docs block: rates per setting, the ratios and the goal, from the JSON."""
    fps, cores = results["median_fps"], results["cores"]
    lines = [f"{results['machine']}; {results['busy_processes']} busy processes beside each run; load average "
             f"{results['load_average_1min_at_end']} (1 min, at the end)",
             f"{len(results['rounds'])} rounds, the settings alternating; medians; each run a fresh `dwr-gym train` "
             "process, start to exit", "",
             f"{'algo':<6}{'env steps':>10}{'defaults':>11}{'OMP_NUM_THREADS=1':>19}{'ratio':>8}"
             f"{f'--threads {cores}':>14}"]  # fmt: skip
    for algo, steps in results["steps"].items():
        collapse = results["threads_cores_fps"].get(algo)
        if collapse is not None and collapse <= steps / results["reference_limit_seconds"] * 1.0001:
            collapse_text = f"< {collapse:,.1f}"  # stopped at the limit: a bound
        else:
            collapse_text = "" if collapse is None else f"{collapse:,.0f}"
        lines.append(f"{algo:<6}{steps:>10,}{fps[f'{algo} defaults']:>11,.0f}{fps[f'{algo} OMP_NUM_THREADS=1']:>19,.0f}"
                     f"{results['ratio_defaults_to_omp1'][algo]:>7.2f}x"
                     f"{collapse_text:>14}")  # fmt: skip
    return [*lines, "", *footer(results)]


def footer(results: dict[str, Any]) -> list[str]:
    """The block's last lines: what the columns are, and the goal with its verdict."""
    worst = min(results["ratio_defaults_to_omp1"].values())
    return [f"steps/s; ratio: defaults / OMP_NUM_THREADS=1, median of the per-round ratios; --threads {results['cores']}: "
            "torch's own default (before --threads), one run, stopped after "
            f"{results['reference_limit_seconds']:.0f} s "
            "('<': a bound)",
        f"the threads goal, defaults >= {results['goal']}x OMP_NUM_THREADS=1 under the same load for "
            f"PPO and SAC: {worst:.2f}x at worst, {'met' if results['met'] else 'NOT met'}"]  # fmt: skip


def main(argv: list[str] | None = None) -> None:
    parser = parser_for("training-threads", __doc__)
    parser.add_argument("--repeats", type=int, default=3, help="alternating rounds (default: 3)")
    parser.add_argument("--busy", type=int, default=2, help="busy background processes (default: 2)")
    parser.add_argument("--no-reference", action="store_true", help="skip the --threads <cores> runs (slow)")
    parser.add_argument("--docs", action="store_true", help=f"write {JSON_PATH.relative_to(ROOT)} (after each round)")
    args = parser.parse_args(argv)
    for name in ("repeats", "busy"):
        if getattr(args, name) < (1 if name == "repeats" else 0):
            parser.error(f"--{name}={getattr(args, name)} is invalid: expected a positive integer")
    save = (lambda results: write_json(JSON_PATH, results)) if args.docs else None  # a run cut short keeps its rounds
    results = run(args.repeats, args.busy, not args.no_reference, save)
    print("\n".join(render(results)))
    if save is not None:
        save(results)


#: The block of docs/training.md.
BLOCKS = (fenced("training-threads", "docs/training/threads.json", render,
                 Schema({"machine": str, "busy_processes": int, "load_average_1min_at_end": NUMBER, "steps": dict,
                         "rounds": list, "median_fps": dict, "threads_cores_fps": dict,
                         "reference_limit_seconds": NUMBER, "cores": int, "ratio_defaults_to_omp1": dict,
                         "goal": NUMBER, "met": bool})),)  # fmt: skip

"""`dwr-gym train` on a busy machine: its defaults against `OMP_NUM_THREADS=1`, under the same load, in one run.

    nice -n 10 python benchmarks/training_threads.py --docs     # writes docs/training/threads.json, ~10 min on 2 cores
    python benchmarks/training_threads.py --render               # docs/training.md's block from the JSON

Issue 35's goal: with two busy processes beside it (``python -c 'while True: pass'``), `dwr-gym train` with its
default settings runs at >= 0.8x the speed of the same command under ``OMP_NUM_THREADS=1``, for PPO and SAC.
Each run is the command as a user types it (a fresh process: imports, the step-0 evaluation, training,
checkpoints), timed from start to exit; the two settings alternate in each of ``--repeats`` rounds, and the ratio
is the median of the per-round ratios. A third setting, ``--threads N`` with N the number of cores (torch's own
default, what `dwr-gym train` used before issue 35), is timed once per algorithm as the reference of the
collapse. The busy processes are started before the first run and stopped after the last.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
JSON_PATH = ROOT / "docs" / "training" / "threads.json"
DOCS = ROOT / "docs" / "training.md"
BLOCK = "training-threads"
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
    loads = [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(busy)]
    try:
        time.sleep(1.0)
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
    finally:
        for process in loads:
            process.kill()
            process.wait()
    return summarize(rounds, collapse, busy)


def summarize(rounds: list[dict[str, Any]], collapse: dict[str, float], busy: int) -> dict[str, Any]:
    """The results of the rounds so far: medians, ratios, the verdict."""
    import torch

    load = os.getloadavg()[0]
    ratios = {algo: statistics.median(r[f"{algo} defaults"] / r[f"{algo} OMP_NUM_THREADS=1"] for r in rounds)
              for algo in STEPS}  # fmt: skip
    return {
        "machine": f"{platform.machine()}, {os.cpu_count()} cores, torch {torch.__version__}",
        "busy_processes": busy,
        "load_average_1min_at_end": round(load, 2),
        "steps": STEPS,
        "rounds": rounds,
        "median_fps": {key: statistics.median(r[key] for r in rounds) for key in rounds[0]},
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
    verdict = "met" if results["met"] else "NOT met"
    worst = min(results["ratio_defaults_to_omp1"].values())
    lines += ["", "steps/s; ratio: defaults / OMP_NUM_THREADS=1, median of the per-round ratios; "
              f"--threads {cores}: torch's own default (before issue 35), one run, stopped after "
              f"{results['reference_limit_seconds']:.0f} s ('<': a bound)",
              f"issue 35 goal, defaults >= {results['goal']}x OMP_NUM_THREADS=1 under the same load for PPO and SAC: "
              f"{worst:.2f}x at worst, {verdict}"]  # fmt: skip
    return lines


def rendered_block(results: dict[str, Any]) -> str:
    return "\n```\n" + "\n".join(render(results)) + "\n```\n"


def docs_block(name: str = BLOCK) -> str:
    """The text between the markers of block ``name`` in docs/training.md."""
    from train.reporting.doc_tables import block

    return block(DOCS.read_text(), name)


def write_docs(results: dict[str, Any]) -> None:
    from train.reporting.doc_tables import with_block

    DOCS.write_text(with_block(DOCS.read_text(), BLOCK, rendered_block(results)))
    print(f"wrote {DOCS}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3, help="alternating rounds (default: 3)")
    parser.add_argument("--busy", type=int, default=2, help="busy background processes (default: 2)")
    parser.add_argument("--no-reference", action="store_true", help="skip the --threads <cores> runs (slow)")
    parser.add_argument("--docs", action="store_true", help=f"write {JSON_PATH.relative_to(ROOT)} and the docs block")
    parser.add_argument("--render", action="store_true", help="only render the docs block from the JSON")
    args = parser.parse_args()
    for name in ("repeats", "busy"):
        if getattr(args, name) < (1 if name == "repeats" else 0):
            parser.error(f"--{name}={getattr(args, name)} is invalid: expected a positive integer")
    if args.render:
        write_docs(json.loads(JSON_PATH.read_text()))
        return

    import signal

    signal.signal(signal.SIGTERM, lambda signum, frame: sys.exit(143))  # a timeout still stops the busy processes

    def save(results: dict[str, Any]) -> None:
        JSON_PATH.parent.mkdir(parents=True, exist_ok=True)
        JSON_PATH.write_text(json.dumps(results, indent=1) + "\n")
        write_docs(results)

    results = run(args.repeats, args.busy, not args.no_reference, save if args.docs else None)
    print("\n".join(render(results)))
    if args.docs:
        save(results)
        print(f"wrote {JSON_PATH}")


if __name__ == "__main__":
    main()

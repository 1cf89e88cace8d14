"""How long the main job, `dwr-gym compare` with its defaults, takes: cold and warm, alone and beside busy processes.

    nice -n 10 python benchmarks/compare_time.py --docs       # writes docs/compare/timing.json and the README's line
    python benchmarks/compare_time.py --render                  # the README's line from the JSON
    python benchmarks/compare_time.py --n 100 --busy 0          # a quicker look: 100 random episodes, alone

Runs `dwr-gym compare --out <tmp>` as a user would (a fresh process), first with an empty optimum cache (cold: a
fresh clone's first run, every optimum solved) then again with the cache it filled (warm), for each ``--busy``
count of busy processes beside it. Each run records its wall time, the CPU time of the command and its solver
processes, the load average before and after (the machine may be shared: the load says how quiet it was), the
optima it solved, and where its time went: the optimum and each policy over all sets, from the ``seconds`` and
``optimum_seconds`` of its ``comparison.json``, and the closing ``time:`` line it printed.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
JSON_PATH = ROOT / "docs" / "compare" / "timing.json"
README = ROOT / "README.md"
BLOCK = "compare-time"


def cached_optima(cache: Path) -> int:
    """Optima in the cache ``cache`` now."""
    total = 0
    for path in cache.glob("optimal-energy-*.json"):
        try:
            total += len(json.loads(path.read_text()))
        except (OSError, ValueError):
            pass
    return total


def stage_seconds(rows: list[dict[str, Any]]) -> dict[str, float]:
    """Wall seconds by stage over every set: ``optimum`` and each policy (from comparison.json's rows)."""
    seconds: dict[str, float] = {"optimum": 0.0}
    counted = set()
    for row in rows:
        if (row["scenario"], row["T_con"]) not in counted:  # the set's optimum is on each of its rows
            counted.add((row["scenario"], row["T_con"]))
            seconds["optimum"] += row["optimum_seconds"]
        seconds[row["policy"]] = seconds.get(row["policy"], 0.0) + row["seconds"]
    return {k: round(v, 1) for k, v in sorted(seconds.items(), key=lambda item: -item[1])}


def run_compare(cache: Path, busy: int, n: int | None, timeout: float) -> dict[str, Any]:
    """One `dwr-gym compare` with ``busy`` busy processes beside it, the optimum cache in ``cache``."""
    loads = [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(busy)]
    try:
        before_cache, load_before = cached_optima(cache), os.getloadavg()[0]
        env = {**os.environ, "PYTHONPATH": str(ROOT), "MPLBACKEND": "Agg", "DWR_GYM_CACHE": str(cache)}
        with tempfile.TemporaryDirectory() as tmp:
            command = [sys.executable, "-m", "train.cli", "compare", "--out", f"{tmp}/out", "--no-progress",
                       *(["--n", str(n)] if n else [])]  # fmt: skip
            before = resource.getrusage(resource.RUSAGE_CHILDREN)
            began = time.perf_counter()
            done = subprocess.run(command, env=env, check=True, capture_output=True, text=True, cwd=tmp,
                                  timeout=timeout)  # fmt: skip
            wall = time.perf_counter() - began
            after = resource.getrusage(resource.RUSAGE_CHILDREN)
            rows = json.loads(Path(f"{tmp}/out/comparison.json").read_text())
        load_after = os.getloadavg()[0]
    finally:
        for process in loads:
            process.kill()
            process.wait()
    return {
        "command": "dwr-gym compare" + (f" --n {n}" if n else ""),
        "busy_processes": busy,
        "wall_seconds": round(wall, 1),
        "cpu_seconds": round((after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime), 1),
        "load_average_1min_before": round(load_before, 2),
        "load_average_1min_after": round(load_after, 2),
        "optima_cached_before": before_cache,
        "optima_solved": cached_optima(cache) - before_cache,
        "stage_seconds": stage_seconds(rows),
        "time_line": done.stdout.strip().splitlines()[-1],
    }


def measure(busy_counts: list[int], n: int | None, timeout: float) -> dict[str, Any]:
    import torch

    runs = []
    for busy in busy_counts:
        with tempfile.TemporaryDirectory() as cache:
            for state in ("cold", "warm"):
                result = {"cache": state, **run_compare(Path(cache), busy, n, timeout)}
                print(json.dumps(result), flush=True)
                runs.append(result)
    return {"machine": f"{platform.machine()}, {os.cpu_count()} cores, torch {torch.__version__}", "runs": runs}


def render(results: dict[str, Any]) -> str:
    """The README's line: cold and warm wall times for each busy count, with the load they ran at."""
    parts = []
    for busy in dict.fromkeys(run["busy_processes"] for run in results["runs"]):
        runs = {run["cache"]: run for run in results["runs"] if run["busy_processes"] == busy}
        beside = "alone" if busy == 0 else f"beside {busy} busy processes"
        loads = ", ".join(f"{run['load_average_1min_before']:g}" for run in runs.values())
        parts.append(f"{beside}: cold {runs['cold']['wall_seconds'] / 60:.1f} min, warm "
                     f"{runs['warm']['wall_seconds'] / 60:.1f} min (load average before: {loads})")  # fmt: skip
    return (
        f"\nMeasured ({results['machine']}, `benchmarks/compare_time.py`, `docs/compare/timing.json`), cold (an "
        f"empty optimum cache) and warm: {'; '.join(parts)}. The command ends with a line of where its time went.\n"
    )


def write_readme(results: dict[str, Any]) -> None:
    from train.reporting.doc_tables import with_block

    README.write_text(with_block(README.read_text(), BLOCK, render(results)))
    print(f"wrote {README}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--busy", type=int, nargs="+", default=[0, 2], help="busy processes beside it (default: 0 2)")
    parser.add_argument("--n", type=int, default=None, help="random episodes (default: compare's, 1000)")
    parser.add_argument("--timeout", type=float, default=7200.0, help="seconds one run may take (default: 7200)")
    parser.add_argument("--docs", action="store_true", help=f"write {JSON_PATH.relative_to(ROOT)} and the README line")
    parser.add_argument("--render", action="store_true", help="only render the README's line from the JSON")
    args = parser.parse_args()
    if any(busy < 0 for busy in args.busy):
        parser.error(f"--busy={args.busy} is invalid: expected integers >= 0")
    if args.render:
        write_readme(json.loads(JSON_PATH.read_text()))
        return
    results = measure(args.busy, args.n, args.timeout)
    print(render(results))
    if args.docs:
        JSON_PATH.write_text(json.dumps(results, indent=1) + "\n")
        print(f"wrote {JSON_PATH}")
        write_readme(results)


if __name__ == "__main__":
    main()

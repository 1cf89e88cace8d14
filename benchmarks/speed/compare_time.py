"""How long the main job, `dwr-gym compare` with its defaults, takes: wall clock and CPU time, the cache's state.

    nice -n 10 python benchmarks/compare_time.py --docs      # writes docs/compare/timing.json and the block
    python benchmarks/compare_time.py --render                 # docs/results.md's block from the JSON

docs/results.md needs a ``<!-- compare-time:begin -->`` ``<!-- compare-time:end -->`` pair for ``--docs`` to fill.

Runs `dwr-gym compare --out <tmp>` as a user would (a fresh process, the shared optimum cache of
``$DWR_GYM_CACHE`` or ``~/.cache/dwr-gym``), with ``--busy`` busy processes beside it, and records the wall time,
the CPU time of the command and its solver processes, the load average, and how many optima the cache held before
and after (a warm cache: none solved; a fresh clone: every episode's).
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
DOCS = ROOT / "docs" / "results.md"
BLOCK = "compare-time"


def cached_optima() -> int:
    """Optima in the cache now."""
    from train.evaluation.optimum import cache_dir

    total = 0
    for path in cache_dir().glob("optimal-energy-*.json"):
        try:
            total += len(json.loads(path.read_text()))
        except (OSError, ValueError):
            pass
    return total


def measure(busy: int) -> dict[str, Any]:
    loads = [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(busy)]
    try:
        before_cache = cached_optima()
        env = {**os.environ, "PYTHONPATH": str(ROOT), "MPLBACKEND": "Agg"}
        with tempfile.TemporaryDirectory() as tmp:
            before = resource.getrusage(resource.RUSAGE_CHILDREN)
            began = time.perf_counter()
            subprocess.run([sys.executable, "-m", "train.cli", "compare", "--out", f"{tmp}/out", "--no-progress"],
                           env=env, check=True, stdout=subprocess.DEVNULL, cwd=tmp)  # fmt: skip
            wall = time.perf_counter() - began
            after = resource.getrusage(resource.RUSAGE_CHILDREN)
        load = os.getloadavg()[0]
    finally:
        for process in loads:
            process.kill()
            process.wait()
    import torch

    return {
        "machine": f"{platform.machine()}, {os.cpu_count()} cores, torch {torch.__version__}",
        "command": "dwr-gym compare",
        "busy_processes": busy,
        "wall_seconds": round(wall, 1),
        "cpu_seconds": round((after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime), 1),
        "load_average_1min_at_end": round(load, 2),
        "optima_cached_before": before_cache,
        "optima_solved": cached_optima() - before_cache,
    }


def render(results: dict[str, Any]) -> str:
    cache = "a warm optimum cache (none solved)" if results["optima_solved"] == 0 else (
        f"{results['optima_solved']:,} optima solved and cached")  # fmt: skip
    return (
        f"\n`{results['command']}` with its defaults, {cache}, {results['busy_processes']} busy processes beside it: "
        f"{results['wall_seconds'] / 60:.1f} min of wall time at a load average of "
        f"{results['load_average_1min_at_end']:g} (1 min, at the end), {results['cpu_seconds'] / 60:.1f} min of CPU "
        f"time over its processes ({results['machine']}; `benchmarks/compare_time.py`, `docs/compare/timing.json`).\n"
    )


def docs_block() -> str:
    from train.reporting.doc_tables import block

    return block(DOCS.read_text(), BLOCK)


def write_docs(results: dict[str, Any]) -> None:
    from train.reporting.doc_tables import with_block

    DOCS.write_text(with_block(DOCS.read_text(), BLOCK, render(results)))
    print(f"wrote {DOCS}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--busy", type=int, default=2, help="busy background processes (default: 2)")
    parser.add_argument("--docs", action="store_true", help=f"write {JSON_PATH.relative_to(ROOT)} and the block")
    parser.add_argument("--render", action="store_true", help="only render the block from the JSON")
    args = parser.parse_args()
    if args.busy < 0:
        parser.error(f"--busy={args.busy} is invalid: expected an integer >= 0")
    if args.render:
        write_docs(json.loads(JSON_PATH.read_text()))
        return
    results = measure(args.busy)
    print(render(results))
    if args.docs:
        JSON_PATH.write_text(json.dumps(results, indent=1) + "\n")
        print(f"wrote {JSON_PATH}")
        write_docs(results)


if __name__ == "__main__":
    main()

"""How long the main job, `dwr-gym compare` with its defaults, takes: wall clock and CPU time, the cache's state.

    nice -n 10 python -m benchmarks run compare-time --docs      # writes docs/compare/timing.json, renders the block

A page shows the block where it holds the pair ``<!-- generated: compare-time by compare-time (python -m benchmarks
run compare-time --docs) -->`` and ``<!-- /generated -->`` (on one line each).

Runs `dwr-gym compare --out <tmp>` as a user would (a fresh process, the shared optimum cache of
``$DWR_GYM_CACHE`` or ``~/.cache/dwr-gym``), with ``--busy`` busy processes beside it, and records the wall time,
the CPU time of the command and its solver processes, the load average, and how many optima the cache held before
and after (a warm cache: none solved; a fresh clone: every episode's).
"""

from __future__ import annotations

import json
import resource
import subprocess
import tempfile
import time
from pathlib import Path
from typing import Any

from benchmarks.core.commands import dwr_gym, parser_for
from benchmarks.core.docs import NUMBER, Block, Schema
from benchmarks.core.record import load_average, torch_machine, write_json
from benchmarks.core.timing import background_load

ROOT = Path(__file__).resolve().parents[2]
JSON_PATH = ROOT / "docs" / "compare" / "timing.json"


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
    with background_load(busy, 6 * 3600.0):
        before_cache = cached_optima()
        with tempfile.TemporaryDirectory() as tmp:
            before = resource.getrusage(resource.RUSAGE_CHILDREN)
            began = time.perf_counter()
            dwr_gym(["compare", "--out", f"{tmp}/out", "--no-progress"], cwd=tmp, stdout=subprocess.DEVNULL)
            wall = time.perf_counter() - began
            after = resource.getrusage(resource.RUSAGE_CHILDREN)
        load = load_average()
    return {
        "machine": torch_machine(),
        "command": "dwr-gym compare",
        "busy_processes": busy,
        "wall_seconds": round(wall, 1),
        "cpu_seconds": round((after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime), 1),
        "load_average_1min_at_end": load,
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
        f"time over its processes ({results['machine']}; `python -m benchmarks run compare-time`, `docs/compare/timing.json`).\n"
    )


def main(argv: list[str] | None = None) -> None:
    parser = parser_for("compare-time", __doc__)
    parser.add_argument("--busy", type=int, default=2, help="busy background processes (default: 2)")
    parser.add_argument(
        "--docs", action="store_true", help=f"write {JSON_PATH.relative_to(ROOT)} (and render the block)"
    )
    args = parser.parse_args(argv)
    if args.busy < 0:
        parser.error(f"--busy={args.busy} is invalid: expected an integer >= 0")
    results = measure(args.busy)
    print(render(results))
    if args.docs:
        write_json(JSON_PATH, results)


#: A sentence of docs/results.md.
BLOCKS = (Block("compare-time", "docs/compare/timing.json", render,
                Schema({"command": str, "busy_processes": int, "wall_seconds": NUMBER, "cpu_seconds": NUMBER,
                        "load_average_1min_at_end": NUMBER, "optima_solved": int, "machine": str})),)  # fmt: skip

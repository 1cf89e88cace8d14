"""How long the main job, `dwr-gym compare` with its defaults, takes: wall clock and CPU time, the cache's state.

    nice -n 10 python -m benchmarks run compare-time --cache cold --busy 0 --docs   # a fresh clone, a quiet machine
    nice -n 10 python -m benchmarks run compare-time --cache warm --busy 2 --docs   # the optima cached, 2 busy processes
    nice -n 10 python -m benchmarks run compare-time --cache cold --no-shipped --busy 0 --docs   # every optimum solved

A fresh clone's user cache is empty, but dwr-gym ships the optima of the default sets (train/optima/, read where the
user's cache has none): ``--no-shipped`` turns them off (``DWR_GYM_SHIPPED_OPTIMA=0``), so that every optimum is solved.
The planners solve every plan they meet (a second run reads the plans the first stored, :mod:`baselines.plan_store`).

Each run replaces the measurement of its case (the cache's state, the shipped optima, the busy processes) in
docs/compare/timing.json, whatever machine measured it before: the block is one row per case on the current code,
each with the CPU model it was measured on.

A page shows the block where it holds the pair ``<!-- generated: compare-time by compare-time (python -m benchmarks
run compare-time --docs) -->`` and ``<!-- /generated -->`` (on one line each).

Runs `dwr-gym compare --out <tmp>` as a user would (a fresh process; ``--cache warm``: the shared optimum cache of
``$DWR_GYM_CACHE`` or ``~/.cache/dwr-gym``, ``--cache cold``: an empty one in a temporary directory), with ``--busy`` busy processes beside it, and records the wall time,
the CPU time of the command and its solver processes, the load average, and how many optima the cache held before
and after (a warm cache: none solved; a fresh clone: every episode's).
"""

from __future__ import annotations

import json
import re
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from benchmarks.core.commands import checkout_env, parser_for
from benchmarks.core.docs import Block, Schema
from benchmarks.core.record import cpu_model, load_average, torch_machine, write_json
from benchmarks.core.timing import background_load

ROOT = Path(__file__).resolve().parents[2]
JSON_PATH = ROOT / "docs" / "compare" / "timing.json"


def cached_optima(env: dict[str, str]) -> int:
    """Optima in the cache the environment ``env`` names now."""
    directory = Path(env.get("DWR_GYM_CACHE") or Path.home() / ".cache" / "dwr-gym")
    total = 0
    for path in directory.glob("optimal-energy-*.json"):
        try:
            total += len(json.loads(path.read_text()))
        except (OSError, ValueError):
            pass
    return total


def measure(busy: int, cache: str, shipped: bool = True, out: Path | None = None) -> dict[str, Any]:
    with background_load(busy, 6 * 3600.0), tempfile.TemporaryDirectory() as tmp:
        env = checkout_env(DWR_GYM_CACHE=f"{tmp}/cache") if cache == "cold" else checkout_env()
        env["DWR_GYM_SHIPPED_OPTIMA"] = "1" if shipped else "0"
        before_cache = cached_optima(env)
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        began = time.perf_counter()
        out = (out or Path(tmp) / "out").resolve()
        said = run_logged(["compare", "--out", str(out)], cwd=tmp, env=env)
        wall = time.perf_counter() - began
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        load = load_average()
        solved = cached_optima(env) - before_cache
        rows = json.loads((out / "comparison.json").read_text())
    return {
        "machine": torch_machine(),
        "cpu": cpu_model(),
        "command": "dwr-gym compare",
        "busy_processes": busy,
        "wall_seconds": round(wall, 1),
        "cpu_seconds": round((after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime), 1),
        "load_average_1min_at_end": load,
        "cache": cache,
        "shipped_optima": shipped,
        "optima_cached_before": before_cache,
        "optima_solved": solved,
        "stages": stage_seconds(rows),
        # the bar's time left as a redirected log says it every 10 %: [percent, at (s), said left (s), true left (s)]
        "time_left": [[percent, round(at, 1), left, round(wall - at, 1)] for percent, at, left in said],
    }


#: A redirected log's progress line: ``compare: 40% after 1.2 min, about 2.0 min left``.
PROGRESS_LINE = re.compile(r"^compare: (\d+)% after .*, about (\S+ (?:s|min|h)|\?) left")


def as_seconds(text: str) -> float:
    """``42 s``, ``3.5 min``, ``1.2 h`` (train.evaluation.stages.format_seconds) in seconds; ``?`` is NaN."""
    if text == "?":
        return float("nan")
    value, unit = text.split()
    return float(value) * {"s": 1.0, "min": 60.0, "h": 3600.0}[unit]


def run_logged(args: list[str], cwd: str, env: dict[str, str]) -> list[tuple[int, float, float]]:
    """``dwr-gym ARGS`` with its stderr a pipe (a redirected log: a progress line every 10 % of the work), stdout
    discarded: (percent, seconds since the start, time left it said) of each progress line, as it came."""
    began = time.perf_counter()
    said = []
    with subprocess.Popen([sys.executable, "-m", "train.cli", *args], cwd=cwd, env=env, text=True,
                          stdout=subprocess.DEVNULL, stderr=subprocess.PIPE) as process:  # fmt: skip
        assert process.stderr is not None
        for line in process.stderr:
            if match := PROGRESS_LINE.match(line):
                said.append((int(match[1]), time.perf_counter() - began, as_seconds(match[2])))
    if process.returncode:
        raise subprocess.CalledProcessError(process.returncode, args)
    return said


def stage_seconds(rows: list[dict[str, Any]]) -> dict[str, float]:
    """Where the time went: the wall seconds of each policy over every set, and of the optima, slowest first."""
    totals: dict[str, float] = {}
    for row in rows:
        totals[row["policy"]] = totals.get(row["policy"], 0.0) + float(row.get("seconds", 0.0))
    # each set's rows repeat its optimum's seconds: once per (set, T_con)
    optimum = {(row["scenario"], str(row["T_con"])): float(row.get("optimum_seconds", 0.0)) for row in rows}
    totals["optimum"] = float(sum(optimum.values()))
    return {k: round(v, 1) for k, v in sorted(totals.items(), key=lambda kv: -kv[1])}


def render_one(result: dict[str, Any]) -> str:
    if result["cache"] == "cold":
        cache = (f"a fresh clone: an empty cache, the shipped optima read ({result['optima_solved']:,} solved)"
                 if result["shipped_optima"] else
                 f"an empty cache, no shipped optima ({result['optima_solved']:,} optima solved)")  # fmt: skip
    else:
        cache = f"a second run: the optima and the planners' plans of an earlier one cached ({result['optima_solved']:,} optima solved)"
    stages = result.get("stages")
    slowest = ", ".join(f"{k} {v / 60:.1f}" for k, v in list(stages.items())[:4]) if stages else "-"
    return (
        f"| {result['cpu']} | {cache} | {result['busy_processes']} | {result['wall_seconds'] / 60:.1f} | "
        f"{result['cpu_seconds'] / 60:.1f} | {result['load_average_1min_at_end']:g} | {slowest} | "
        f"{said_left(result)} |"
    )


def said_left(result: dict[str, Any], at: tuple[int, ...] = (20, 50, 80)) -> str:
    """The bar's time left at 20, 50 and 80 % of the work, and the true one in brackets (min); - where not logged."""
    lines = result.get("time_left") or []
    parts = []
    for percent in at:
        line = next((line for line in lines if line[0] >= percent), None)
        parts.append("-" if line is None else f"{line[2] / 60:.1f} ({line[3] / 60:.1f})")
    return " / ".join(parts) if lines else "-"


def render(results: dict[str, Any]) -> str:
    runs = sorted(results["runs"], key=lambda r: (r["cache"] != "cold", r["shipped_optima"], r["busy_processes"]))
    machine = runs[0]["machine"] if runs else "no run"
    return "\n".join([
        "",
        "| CPU | `dwr-gym compare`, defaults | busy processes beside it | wall time (min) | CPU time (min) | load (1 min, at the end) | slowest stages (min) | time left said at 20 / 50 / 80 % (true), min |",
        "|---|---|---:|---:|---:|---:|---|---|",
        *(render_one(r) for r in runs),
        "",
        f"*{machine}; `python -m benchmarks run compare-time --cache cold|warm [--no-shipped] --busy N "
        "--docs`, "
        "`docs/compare/timing.json`.*",
        "",
    ])  # fmt: skip


def merged(previous: dict[str, Any] | None, result: dict[str, Any]) -> dict[str, Any]:
    """``previous``'s runs with ``result`` added, replacing the run of the same case (cache state, shipped optima, busy
    processes) on whatever CPU it was measured: one row per case, on the code that measured it last."""

    def key(run: dict[str, Any]) -> tuple[Any, ...]:
        return (run["cache"], run["shipped_optima"], run["busy_processes"])

    runs = [r for r in (previous or {}).get("runs", []) if key(r) != key(result)]
    return {"runs": [*runs, result]}


def main(argv: list[str] | None = None) -> None:
    parser = parser_for("compare-time", __doc__)
    parser.add_argument("--busy", type=int, default=2, help="busy background processes (default: 2)")
    parser.add_argument("--cache", choices=("cold", "warm"), default="warm",
                        help="cold: an empty optimum cache (a fresh clone); warm: the shared one (default)")  # fmt: skip
    parser.add_argument("--no-shipped", action="store_true",
                        help="do not read the optima shipped for the default sets (every missing one is solved)")  # fmt: skip
    parser.add_argument("--out", type=Path, help="keep compare's output there (default: a temporary directory)")
    parser.add_argument("--docs", action="store_true", help="write docs/compare/timing.json (and render its block)")
    args = parser.parse_args(argv)
    if args.busy < 0:
        parser.error(f"--busy={args.busy} is invalid: expected an integer >= 0")
    result = measure(args.busy, args.cache, shipped=not args.no_shipped, out=args.out)
    previous = json.loads(JSON_PATH.read_text()) if JSON_PATH.exists() else None
    results = merged(previous if previous and "runs" in previous else None, result)
    print(render({"runs": [result]}))
    if args.docs:
        write_json(JSON_PATH, results)


#: A table of docs/results.md, a row per measurement.
BLOCKS = (Block("compare-time", "docs/compare/timing.json", render, Schema({"runs": list})),)

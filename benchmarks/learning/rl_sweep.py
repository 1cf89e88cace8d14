"""The trials of a ``dwr-gym sweep`` as the JSON of a docs table: hyperparameters and final evaluation per trial.

    python -m benchmarks run rl-sweep results/sweep-residual --docs                           # sweep.json
    python -m benchmarks run rl-sweep results/sweep-ppo-jax --json sweep_ppo_jax.json --docs  # and so on

Copies the sweep's ``trials.csv`` (in the ``--out`` of ``dwr-gym sweep``) into docs/rl_benchmark/; the sweeps
themselves, and the commands that ran them, are on docs/rl-benchmark.md.
"""

from __future__ import annotations

import csv
from pathlib import Path

from benchmarks.core.commands import parser_for
from benchmarks.core.docs import Schema, table
from benchmarks.core.record import write_json

ROOT = Path(__file__).resolve().parents[2]
FILES = ("sweep.json", "sweep_ppo_jax.json", "sweep_sac.json", "sweep_tqc.json")


def main(argv: list[str] | None = None) -> int:
    parser = parser_for("rl-sweep", __doc__)
    parser.add_argument("sweep", type=Path, help="the --out of dwr-gym sweep")
    parser.add_argument("--json", default="sweep.json", choices=FILES, help="the file under docs/rl_benchmark/")
    parser.add_argument("--docs", action="store_true", help="write it (and render its table)")
    args = parser.parse_args(argv)
    if not (args.sweep / "trials.csv").is_file():
        parser.error(f"sweep {str(args.sweep)!r} is invalid: expected the --out of dwr-gym sweep, with a trials.csv")
    with (args.sweep / "trials.csv").open() as handle:
        trials = list(csv.DictReader(handle))
    print(f"{len(trials)} trials in {args.sweep}")
    if args.docs:
        write_json(ROOT / "docs" / "rl_benchmark" / args.json, {"out": str(args.sweep), "trials": trials})
    return 0


TRIALS = Schema({"out": str, "trials": list})
BLOCKS = tuple(table(name, TRIALS) for name in ("rl-sweep", "rl-sweep-jax", "rl-sweep-sac", "rl-sweep-tqc"))

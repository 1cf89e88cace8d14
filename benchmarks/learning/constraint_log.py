"""The constraint's per-T_con log of a constrained benchmark's runs: each seed's violation rate and multipliers per T_con
bin at its end, and a figure of both over the run (from each run's constraint.csv).

    python -m benchmarks run constraint-log results/rl-constrained [--json docs/rl_benchmark/constrained_log.json]
"""

from __future__ import annotations

import csv
import json
import sys
from pathlib import Path
from typing import Any

from benchmarks.core.commands import parser_for
from benchmarks.core.docs import Schema, table
from train.reporting.rl_doc_tables import constraint_log_table as log_table

LOG = Schema({"runs": list})
BLOCKS = (table("rl-constrained-log", LOG),)


def read_log(path: Path) -> list[dict[str, float]]:
    """The rows of one run's constraint.csv, as numbers."""
    with path.open(newline="") as handle:
        return [{key: float(value) for key, value in row.items()} for row in csv.DictReader(handle)]


def summarise(out: Path) -> dict[str, Any]:
    """Per run (entry and seed) under ``out/runs``: its last row per T_con bin, and the row count."""
    runs = []
    for path in sorted(out.glob("runs/*/constraint.csv")):
        rows = read_log(path)
        if not rows:
            continue
        last_step = max(row["timesteps"] for row in rows)
        runs.append({"run": path.parent.name, "rows": len(rows), "timesteps": int(last_step),
                     "bins": [row for row in rows if row["timesteps"] == last_step]})  # fmt: skip
    return {"runs": runs}


def plot(out: Path, figure: Path) -> None:
    """Violation rate (a moving mean over 20 log rows) and deadline multiplier per T_con bin against env steps, a row
    of panels per entry, a colour per bin, a line per seed."""
    import matplotlib.pyplot as plt
    import numpy as np

    paths = sorted(out.glob("runs/*/constraint.csv"))
    entry_of = {path: path.parent.name.rsplit("-seed", 1)[0] for path in paths}  # the run's name less its seed
    entries = sorted(set(entry_of.values()))
    fig, axes = plt.subplots(len(entries), 2, figsize=(11, 2.4 * len(entries)), squeeze=False, sharex="row")
    for path in paths:
        rows = read_log(path)
        rate_ax, lam_ax = axes[entries.index(entry_of[path])]
        for k, low in enumerate(sorted({row["T_con_low"] for row in rows})):
            mine = [row for row in rows if row["T_con_low"] == low]
            steps = np.array([row["timesteps"] / 1e6 for row in mine])
            rate = np.array([row["violation_rate"] for row in mine])
            window = min(20, len(rate))
            smooth = np.convolve(rate, np.ones(window) / window, mode="valid")
            label = f"T_con {low:g}+ s" if path.parent.name.endswith("seed0") else None
            rate_ax.plot(steps[window - 1 :], smooth, color=f"C{k}", lw=0.8, label=label)
            lam_ax.plot(steps, [row["deadline_multiplier"] for row in mine], color=f"C{k}", lw=0.8)
    for (rate_ax, lam_ax), entry in zip(axes, entries, strict=True):
        rate_ax.axhline(0.01, color="k", ls="--", lw=0.8)
        rate_ax.set(ylabel="violation rate", title=f"{entry}: violations (the budget dashed)", ylim=(0, 1))
        lam_ax.set(ylabel="multiplier", title=f"{entry}: deadline multiplier")
        rate_ax.legend(fontsize=6, ncol=5, loc="upper right")
    for ax in axes[-1]:
        ax.set_xlabel("env steps [M]")
    fig.tight_layout()
    fig.savefig(figure, dpi=100)


def main(argv: list[str] | None = None) -> int:
    parser = parser_for("constraint-log", __doc__)
    parser.add_argument("out", type=Path, help="a dwr-gym benchmark --out directory with constrained runs")
    parser.add_argument("--json", type=Path, default=None, help="write the summary here")
    parser.add_argument("--figure", type=Path, default=None, help="write the figure here (PNG)")
    args = parser.parse_args(argv)
    if not args.out.is_dir():
        print(f"out={str(args.out)!r} is invalid: expected a dwr-gym benchmark --out directory", file=sys.stderr)
        return 2
    data = summarise(args.out)
    if not data["runs"]:
        print(
            f"out={str(args.out)!r} has no runs/*/constraint.csv: expected runs of a constrained entry", file=sys.stderr
        )
        return 2
    print(log_table(data), end="")
    if args.json is not None:
        args.json.write_text(json.dumps(data, indent=1) + "\n")
    if args.figure is not None:
        plot(args.out, args.figure)
    return 0

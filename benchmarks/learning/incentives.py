"""What v1's and v2's returns pay for, side by side: the optimum ranks first, and no pay for rushing.

    python -m benchmarks run incentives --docs   # 200 episodes (ranking), 100 a cell (rushing): about an hour, 2 cores
    python -m benchmarks run incentives --n 20 --n-rush 4 --sigmas 0  # a quick look (printed, nothing written)

``--docs`` writes docs/rl_benchmark/incentives.json (the measurements it leaves out with ``--skip`` or ``--env-ids``,
and the rushing rows of the sigmas it does not run, kept from it),
from which the tables ``incentives-ranking`` and ``incentives-rushing`` of docs/rl-v2.md are rendered.
What is measured and how: train/evaluation/incentives.py.
"""

from __future__ import annotations

import json
import platform
import sys
import time
from pathlib import Path
from typing import Any

from benchmarks.core.commands import parser_for
from benchmarks.core.docs import Schema, table
from benchmarks.core.record import write_json

ROOT = Path(__file__).resolve().parents[2]
JSON_PATH = ROOT / "docs" / "rl_benchmark" / "incentives.json"
ENV_IDS = ("DWRPointStabilization-v1", "DWRPointStabilization-v2")


def main(argv: list[str] | None = None) -> int:
    from train.evaluation.incentives import return_ranking, rushing_returns

    parser = parser_for("incentives", __doc__)
    parser.add_argument("--n", type=int, default=200, help="episodes of the ranking (default: 200)")
    parser.add_argument("--n-rush", type=int, default=100, help="episodes of each rushing cell (default: 100)")
    parser.add_argument("--replan-every", type=int, default=5,
                        help="control periods between re-plans from the measured pose (default: 5)")  # fmt: skip
    parser.add_argument(
        "--sigmas", type=float, nargs="+", default=[0.0, 0.1, 0.3], help="action noise (default: 0 0.1 0.3)"
    )
    parser.add_argument("--fractions", type=float, nargs="+", default=[0.3, 0.5, 0.8, 1.0],
                        help="arrival time / T_con of the plans (default: 0.3 0.5 0.8 1)")  # fmt: skip
    parser.add_argument("--workers", type=int, default=2, help="processes solving plans (default: 2)")
    parser.add_argument("--env-ids", nargs="+", choices=ENV_IDS, default=list(ENV_IDS), metavar="ENV_ID",
                        help="the env ids measured (default: both; the others' kept from the JSON)")  # fmt: skip
    parser.add_argument("--skip", choices=["ranking", "rushing"], help="leave one measurement out (kept from the JSON)")
    parser.add_argument("--docs", action="store_true", help=f"write {JSON_PATH.relative_to(ROOT)} (and its tables)")
    args = parser.parse_args(argv)
    for name in ("n", "n_rush", "workers", "replan_every"):
        if getattr(args, name) < 1:
            parser.error(f"--{name.replace('_', '-')} {getattr(args, name)} is invalid: expected an integer >= 1")
    data = json.loads(JSON_PATH.read_text()) if JSON_PATH.is_file() else {}
    start = time.time()
    for env_id in args.env_ids:
        entry = data.setdefault(env_id, {})
        if args.skip != "ranking":
            entry["ranking"] = return_ranking(env_id, n=args.n, progress=sys.stderr.isatty())
            print(
                env_id, "ranking:", [(row["policy"], round(row["return_mean"], 3)) for row in entry["ranking"]["rows"]]
            )
        if args.skip != "rushing":
            rushing = rushing_returns(env_id, tuple(args.fractions), tuple(args.sigmas), args.n_rush,
                                      workers=args.workers, replan_every=args.replan_every)  # fmt: skip
            entry["rushing"] = merged_rushing(entry.get("rushing"), rushing)
            print(env_id, "rushing: latest arrival pays most:", entry["rushing"]["latest_pays_most"])
    data["machine"] = {"python": platform.python_version(), "platform": platform.platform(),
                       "seconds": round(time.time() - start)}  # fmt: skip
    if args.docs:
        write_json(JSON_PATH, data)
    return 0


def merged_rushing(old: dict[str, Any] | None, new: dict[str, Any]) -> dict[str, Any]:
    """``new`` with the rows (and verdicts) of ``old``'s other sigmas kept, each row with its own episodes and re-plan
    interval (rows written before those were recorded take their run's: ``old``'s episodes, 20 control periods)."""
    if not old:
        return new
    sigmas = {row["sigma"] for row in new["rows"]}
    kept = [{"episodes": old["episodes"], "replan_every": old.get("replan_every", 20), **row}
            for row in old["rows"] if row["sigma"] not in sigmas]  # fmt: skip
    merged = {**new, "rows": sorted(kept + new["rows"], key=lambda row: (row["sigma"], row["fraction"]))}
    for key in ("latest_pays_most", "latest_margin"):
        merged[key] = {**{k: v for k, v in old.get(key, {}).items() if float(k) not in sigmas}, **new[key]}
        merged[key] = dict(sorted(merged[key].items(), key=lambda item: float(item[0])))
    return merged


SCHEMA = Schema({"machine": dict})
BLOCKS = (table("incentives-ranking", SCHEMA), table("incentives-rushing", SCHEMA))

"""The leaderboard: a row per method family's best recipe, from the JSON each row's own command wrote.

    python -m benchmarks run leaderboard --docs      # docs/leaderboard.json, the README's and docs/leaderboard.md's tables

Reads only archived results (seconds); each row names the command that regenerates its numbers.
"""

from __future__ import annotations

import json
import sys

from benchmarks.core.commands import parser_for
from benchmarks.core.docs import ROOT, Schema, table
from train.reporting.leaderboard import leaderboard, leaderboard_table

DOCS_JSON = "docs/leaderboard.json"
LEADERBOARD = Schema({"rows": list, "missing": list, "T_cons": list})
BLOCKS = tuple(table(name, LEADERBOARD) for name in ("leaderboard", "leaderboard-per-T_con"))


def main(argv: list[str] | None = None) -> int:
    parser = parser_for("leaderboard", __doc__)
    parser.add_argument("--docs", action="store_true", help=f"write {DOCS_JSON} and render the tables")
    args = parser.parse_args(argv)
    data = leaderboard(ROOT)
    print(leaderboard_table(data), end="")
    for missing in data["missing"]:
        print(f"left out (no result yet): {missing}", file=sys.stderr)
    if args.docs:
        (ROOT / DOCS_JSON).write_text(json.dumps(data, indent=1) + "\n")
        from benchmarks.core.docs import render

        render(only=["leaderboard"])
    return 0

"""APG from an open-loop teacher, time-scaled, its lesson fitted longer and its near misses clipped wider, on
DWRPointStabilization-v2 at 30 minutes a seed.

    python -m benchmarks run rl-apg-near-miss

Runs ``rl_apg_near_miss.sh`` (beside this module) in the repository; read it for the steps and their times.
"""

from __future__ import annotations

from benchmarks.core.commands import recipe_main
from benchmarks.core.docs import Schema, table

main = recipe_main(__file__)

V2 = Schema({"budget": dict, "machine": str, "summary": dict, "references": dict, "best_seed": dict})
BLOCKS = tuple(table(name, V2) for name in ("rl-apg-near-miss", "rl-apg-near-miss-per-T_con"))

"""APG holding the goal before T_con with the heading's error in the same window at twice the weight
(hold_heading_weight 10), on DWRPointStabilization-v2 at 30 minutes a seed.

    python -m benchmarks run rl-apg-hold-heading10

Runs ``rl_apg_hold_heading10.sh`` (beside this module) in the repository; read it for the steps and their times.
"""

from __future__ import annotations

from benchmarks.core.commands import recipe_main
from benchmarks.core.docs import Schema, table

main = recipe_main(__file__)

V2 = Schema({"budget": dict, "machine": str, "summary": dict, "references": dict, "best_seed": dict})
BLOCKS = tuple(table(name, V2) for name in ("rl-apg-hold-heading10", "rl-apg-hold-heading10-per-T_con"))

"""APG holding the goal over the last 20 control periods before T_con with the heading's error in that window
(hold_heading_weight 10) and a smooth stand-in for the arrival bonus there (hold_bonus 10, then 3), on
DWRPointStabilization-v2 at 560 M env steps a seed.

    python -m benchmarks run rl-apg-hold-bonus

Runs ``rl_apg_hold_bonus.sh`` (beside this module) in the repository; read it for the steps and their times.
"""

from __future__ import annotations

from benchmarks.core.commands import recipe_main
from benchmarks.core.docs import Schema, table

main = recipe_main(__file__)

V2 = Schema({"budget": dict, "machine": str, "summary": dict, "references": dict, "best_seed": dict})
BLOCKS = tuple(table(f"rl-apg-hold-bonus{weight}{kind}", V2) for weight in ("", "3") for kind in ("", "-per-T_con"))

"""APG holding the goal over the last tenth of each episode's T_con (hold_fraction 0.1) with the heading's error in
that window (hold_heading_weight 10), on DWRPointStabilization-v2 at 560 M env steps a seed.

    python -m benchmarks run rl-apg-hold-fraction

Runs ``rl_apg_hold_fraction.sh`` (beside this module) in the repository; read it for the steps and their times.
"""

from __future__ import annotations

from benchmarks.core.commands import recipe_main
from benchmarks.core.docs import Schema, table

main = recipe_main(__file__)

V2 = Schema({"budget": dict, "machine": str, "summary": dict, "references": dict, "best_seed": dict})
BLOCKS = tuple(table(name, V2) for name in ("rl-apg-hold-fraction", "rl-apg-hold-fraction-per-T_con"))

"""APG from an open-loop teacher, time-scaled, with the near-miss changes and the miss before T_con in the gradient
(hold_steps), on DWRPointStabilization-v2 at 30 minutes a seed.

    python -m benchmarks run rl-apg-hold

Runs ``rl_apg_hold.sh`` (beside this module) in the repository; read it for the steps and their times.
"""

from __future__ import annotations

from benchmarks.core.commands import recipe_main
from benchmarks.core.docs import Schema, table

main = recipe_main(__file__)

V2 = Schema({"budget": dict, "machine": str, "summary": dict, "references": dict, "best_seed": dict})
BLOCKS = tuple(table(name, V2) for name in ("rl-apg-hold", "rl-apg-hold-per-T_con"))

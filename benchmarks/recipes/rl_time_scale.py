"""ES from reward on DWRPointStabilization-v2 with and without time-scaled actions, five seeds each, then at 4x the budget.

    python -m benchmarks run rl-time-scale

Runs ``rl_time_scale.sh`` (beside this module) in the repository; read it for the steps and their times.
"""

from __future__ import annotations

from benchmarks.core.commands import recipe_main
from benchmarks.core.docs import Schema, table

main = recipe_main(__file__)

V2 = Schema({"budget": dict, "machine": str, "summary": dict, "references": dict, "best_seed": dict})
BLOCKS = tuple(
    table(name, V2)
    for name in ("rl-time-scale", "rl-time-scale-per-T_con", "rl-time-scale-long", "rl-time-scale-long-per-T_con")
)

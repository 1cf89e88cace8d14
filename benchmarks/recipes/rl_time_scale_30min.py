"""The time-scaled ES from reward on DWRPointStabilization-v2 at the goal's budget: 30 minutes of training a seed, two seeds.

    python -m benchmarks run rl-time-scale-30min

Runs ``rl_time_scale_30min.sh`` (beside this module) in the repository; read it for the steps and their times.
"""

from __future__ import annotations

from benchmarks.core.commands import recipe_main
from benchmarks.core.docs import Schema, table

main = recipe_main(__file__)

V2 = Schema({"budget": dict, "machine": str, "summary": dict, "references": dict, "best_seed": dict})
BLOCKS = tuple(table(name, V2) for name in ("rl-time-scale-30min", "rl-time-scale-30min-per-T_con"))

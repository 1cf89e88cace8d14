"""The learners on DWRPointStabilization-v2, five seeds each, per T_con too, and the best seed of each shipped.

    python -m benchmarks run rl-v2

Runs ``rl_v2.sh`` (beside this module) in the repository; read it for the steps and their times.
"""

from __future__ import annotations

from benchmarks.core.commands import recipe_main
from benchmarks.core.docs import Schema, table

main = recipe_main(__file__)

V2 = Schema({"budget": dict, "machine": str, "summary": dict, "references": dict, "best_seed": dict})
BLOCKS = tuple(table(name, V2) for name in ("rl-v2", "rl-v2-per-T_con"))

"""The deadline and the heading as constraints (Lagrangian APG, from the reward and the cost; and the residual on PTC
under the same constraints) on DWRPointStabilization-v2, per T_con, with the multipliers' log.

    python -m benchmarks run rl-constrained

Runs ``rl_constrained.sh`` (beside this module) in the repository; read it for the steps and their times.
"""

from __future__ import annotations

from benchmarks.core.commands import recipe_main
from benchmarks.core.docs import Schema, table

main = recipe_main(__file__)

V2 = Schema({"budget": dict, "machine": str, "summary": dict, "references": dict, "best_seed": dict})
BLOCKS = tuple(table(name, V2) for name in ("rl-constrained", "rl-constrained-per-T_con"))

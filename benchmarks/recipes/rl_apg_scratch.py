"""Analytic policy gradients (APG) from scratch on DWRPointStabilization-v2, five seeds.

    python -m benchmarks run rl-apg-scratch

Runs ``rl_apg_scratch.sh`` (beside this module) in the repository; read it for the steps and their times.
"""

from __future__ import annotations

from benchmarks.core.commands import recipe_main
from benchmarks.core.docs import Schema, table

main = recipe_main(__file__)

V2 = Schema({"budget": dict, "machine": str, "summary": dict, "references": dict, "best_seed": dict})
BLOCKS = tuple(table(name, V2) for name in ("rl-apg-scratch", "rl-apg-scratch-per-T_con"))

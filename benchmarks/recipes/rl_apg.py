"""Analytic policy gradients on DWRPointStabilization-v2: the residual on PTC, five seeds, per T_con too, the best
seed shipped.

    python -m benchmarks run rl-apg

Runs ``rl_apg.sh`` (beside this module) in the repository; read it for the steps and their times.
"""

from __future__ import annotations

from benchmarks.core.commands import recipe_main
from benchmarks.core.docs import Schema, table

main = recipe_main(__file__)

APG = Schema({"budget": dict, "machine": str, "summary": dict, "references": dict, "best_seed": dict})
BLOCKS = tuple(table(name, APG) for name in ("rl-apg", "rl-apg-per-T_con"))

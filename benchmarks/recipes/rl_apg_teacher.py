"""Analytic policy gradients (APG) from an open-loop teacher on DWRPointStabilization-v2, five seeds.

    python -m benchmarks run rl-apg-teacher

Runs ``rl_apg_teacher.sh`` (beside this module) in the repository; read it for the steps and their times.
"""

from __future__ import annotations

from benchmarks.core.commands import recipe_main
from benchmarks.core.docs import Schema, table

main = recipe_main(__file__)

V2 = Schema({"budget": dict, "machine": str, "summary": dict, "references": dict, "best_seed": dict})
NAMES = (
    "rl-apg-teacher",
    "rl-apg-teacher-per-T_con",
    "rl-apg-teacher-time-scaled",
    "rl-apg-teacher-time-scaled-per-T_con",
)
BLOCKS = tuple(table(name, V2) for name in NAMES)

"""Annealing the exploration noise and no discount: one seed each of PPO's variants on the benchmark's sets.

    python -m benchmarks run rl-anneal

Runs ``rl_anneal.sh`` (beside this module) in the repository; read it for the steps and their times.
"""

from __future__ import annotations

from benchmarks.core.commands import recipe_main
from benchmarks.core.docs import Schema, table

main = recipe_main(__file__)

BLOCKS = (table("rl-anneal", Schema({"budget": dict, "machine": str, "summary": dict, "references": dict})),)

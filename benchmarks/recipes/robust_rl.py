"""The `robust` agent's network fine-tuned by PPO under disturbances, five seeds, and its goal.

    python -m benchmarks run robust-rl

Runs ``robust_rl.sh`` (beside this module) in the repository; read it for the steps and their times.
"""

from __future__ import annotations

from benchmarks.core.commands import recipe_main
from benchmarks.core.docs import NUMBER, Schema, table

main = recipe_main(__file__)

BLOCKS = (table("rl-robust", Schema({"rows": list, "seed": int, "n": int, "seconds": NUMBER})),)

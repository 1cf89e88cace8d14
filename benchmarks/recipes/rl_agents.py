"""The RL benchmark and the agents it ships; then the residual, diagnosis and rushing tables.

    python -m benchmarks run rl-agents

Runs ``rl_agents.sh`` (beside this module) in the repository; read it for the steps and their times.
"""

from __future__ import annotations

from benchmarks.core.commands import recipe_main
from benchmarks.core.docs import Schema, table

main = recipe_main(__file__)

BENCHMARK = Schema({"budget": dict, "machine": str, "summary": dict, "references": dict, "best_seed": dict})
BLOCKS = tuple(
    table(name, BENCHMARK) for name in ("rl-benchmark", "rl-goals", "rl-benchmark-readme", "rl-benchmark-disturbed")
)

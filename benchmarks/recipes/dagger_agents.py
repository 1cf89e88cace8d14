"""The DAgger hand-over agents, three seeds, then their prescribed-time goal.

    python -m benchmarks run dagger-agents

Runs ``dagger_agents.sh`` (beside this module) in the repository; read it for the steps and their times.
"""

from __future__ import annotations

from benchmarks.core.commands import recipe_main

main = recipe_main(__file__)

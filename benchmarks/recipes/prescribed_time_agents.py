"""The agents cloned from the optimal controller (`dwr-gym imitate`), three seeds, then their goal.

    python -m benchmarks run prescribed-time-agents

Runs ``prescribed_time_agents.sh`` (beside this module) in the repository; read it for the steps and their times.
"""

from __future__ import annotations

from benchmarks.core.commands import recipe_main

main = recipe_main(__file__)

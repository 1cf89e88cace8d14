"""The training runs behind the README's v0 agents: residual PPO on PTC and PPO, seeds 0-2, then compare.

    python -m benchmarks run agents-v0

Runs ``agents_v0.sh`` (beside this module) in the repository; read it for the steps and their times.
"""

from __future__ import annotations

from benchmarks.core.commands import recipe_main

main = recipe_main(__file__)

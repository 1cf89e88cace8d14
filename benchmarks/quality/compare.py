"""The results tables: every shipped agent and controller on the paper's scenarios, random starts and disturbances.

    python -m benchmarks run compare --docs       # dwr-gym compare --out docs/compare

The suite's name for ``dwr-gym compare`` as the README's and docs' tables run it: its defaults (the laws on v2, each
agent on the env id it was trained on); other arguments go to the command.
"""

from __future__ import annotations

from benchmarks.core.commands import command_main
from benchmarks.core.docs import NUMBER, OPTIONAL_NUMBER, Schema, table

main = command_main(["compare"], ["--out", "docs/compare"])

ROWS = Schema({"scenario": str, "policy": str, "n": NUMBER, "T_con": OPTIONAL_NUMBER, "success_rate": NUMBER,
               "final_heading_error_mean": NUMBER, "energy_mean": NUMBER, "energy_ratio_mean": OPTIONAL_NUMBER,
               "energy_ratio_max": OPTIONAL_NUMBER}, rows=True)  # fmt: skip
BLOCKS = tuple(table(name, ROWS) for name in ("compare", "compare-fig7", "robust-headline"))

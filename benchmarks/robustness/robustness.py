"""The robustness sweep: the largest magnitude of each disturbance up to which each policy still arrives by T_con.

    python -m benchmarks run robustness --docs    # dwr-gym robustness --env DWRPointStabilization-v1 --n 100 \
        --give-up-below 0.95 --out docs/robustness

The suite's name for ``dwr-gym robustness`` as docs/robustness.md runs it, on v1, the env its tables were made on
(the command's default env is v2); other arguments go to the command.
"""

from __future__ import annotations

from benchmarks.core.commands import command_main
from benchmarks.core.docs import NUMBER, OPTIONAL_NUMBER, Schema, table
from train.env_ids import TASK_ENV_ID

main = command_main(
    ["robustness", "--env", TASK_ENV_ID], ["--n", "100", "--give-up-below", "0.95", "--out", "docs/robustness"]
)

BLOCKS = (table("robustness", Schema({"disturbance": str, "magnitude": NUMBER, "policy": str, "success_rate": NUMBER,
                                      "energy_ratio_mean": OPTIONAL_NUMBER}, rows=True)),)  # fmt: skip

"""The paper's claims, each measured, with a verdict (and Figures 5-9 and an animation beside them).

    python -m benchmarks run reproduce --docs     # dwr-gym reproduce --out docs/reproduce

The suite's name for ``dwr-gym reproduce`` as docs/paper.md runs it; other arguments go to the command.
"""

from __future__ import annotations

from benchmarks.core.commands import command_main
from benchmarks.core.docs import NUMBER, Schema, table

main = command_main(["reproduce"], ["--out", "docs/reproduce"])

BLOCKS = (table("claims", Schema({"dt": NUMBER, "claims": list})),)

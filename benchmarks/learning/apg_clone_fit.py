"""The fit of APG's lesson: the cloned policy alone after one round, per length of the fit and size of the network.

    python -m benchmarks run apg-clone-fit --docs     # 4,000 and 16,000 steps, 64x64 and 256x256 (about 15 min, 1 core)

The lesson of train/learning/jitted/apg_teacher.py (one round of 256 episodes, seed 0, time-scaled actions), fitted with
``clone_steps`` least-squares steps on a network of ``net_arch``, its clone played on 512 fresh episodes, as
:mod:`benchmarks.learning.apg_clone_rounds` measures it. ``--docs`` writes
docs/rl_benchmark/apg_teacher_probes/clone_fit.json, from which the table ``apg-clone-fit`` of docs/rl-apg-levers.md is
rendered (the section "Near misses").
"""

from __future__ import annotations

from pathlib import Path

from benchmarks.core.commands import parser_for
from benchmarks.core.docs import table
from benchmarks.learning import apg_clone_rounds

ROOT = Path(__file__).resolve().parents[2]
JSON_PATH = ROOT / "docs" / "rl_benchmark" / "apg_teacher_probes" / "clone_fit.json"
CLONE_STEPS = ("4000", "16000")
NETWORKS = ("64x64", "256x256")


def main(argv: list[str] | None = None) -> int:
    parser = parser_for("apg-clone-fit", __doc__)
    parser.add_argument("--docs", action="store_true", help=f"write {JSON_PATH.relative_to(ROOT)} (and its table)")
    args = parser.parse_args(argv)
    grid = ["--rounds", "1", "--clone-steps", *CLONE_STEPS, "--net-arch", *NETWORKS]
    return apg_clone_rounds.main(grid + (["--json", str(JSON_PATH)] if args.docs else []))


BLOCKS = (table("apg-clone-fit", apg_clone_rounds.SCHEMA),)

"""What a residual on PTC could reach at all: each episode's residual sequence optimised on its own (open loop).

    python -m benchmarks run open-loop-bound --docs      # 32 episodes, 1,000 Adam steps each (about 6 min, 1 core)
    python -m benchmarks run open-loop-bound --n 4 --iterations 50   # a quick look (printed, nothing written)

A residual policy is one map from observation to action for every episode; on each episode it does at most what the
best residual *sequence* for that episode does. This finds such sequences (train/learning/jitted/open_loop_bound.py: Adam on the
episode's v2 return through the JAX env and the law, the gradient APG follows, without its per-step clip or its
policy) for the residual on PTC and on pt-astolfi at the training's scale 0.5, and for the action itself without a
law (how close the optimiser comes to the optimum). ``--docs`` writes docs/rl_benchmark/open_loop_bound.json, from
which the table ``open-loop-bound`` of docs/rl-benchmark.md is rendered.
"""

from __future__ import annotations

import platform
import time
from pathlib import Path

from benchmarks.core.commands import parser_for
from benchmarks.core.docs import Schema, table
from benchmarks.core.record import write_json

ROOT = Path(__file__).resolve().parents[2]
JSON_PATH = ROOT / "docs" / "rl_benchmark" / "open_loop_bound.json"
#: (law under the sequence or None, residual scale): the residual recipes' scale, and the action alone.
VARIANTS: tuple[tuple[str | None, float], ...] = (("ptc", 0.5), ("pt-astolfi", 0.5), (None, 1.0))


def main(argv: list[str] | None = None) -> int:
    from train.evaluation.open_loop import energy_ratios, summary
    from train.learning.jitted.open_loop_bound import open_loop_bound

    parser = parser_for("open-loop-bound", __doc__)
    parser.add_argument("--n", type=int, default=32, help="episodes, each optimised on its own (default: 32)")
    parser.add_argument("--iterations", type=int, default=1000, help="Adam steps per episode (default: 1000)")
    parser.add_argument("--learning-rate", type=float, default=0.02, help="Adam's step size (default: 0.02)")
    parser.add_argument("--docs", action="store_true", help=f"write {JSON_PATH.relative_to(ROOT)} (and its table)")
    args = parser.parse_args(argv)
    if args.n < 1 or args.iterations < 1:
        parser.error(f"--n {args.n} and --iterations {args.iterations} are invalid: expected integers >= 1")
    if not 0 < args.learning_rate <= 1:
        parser.error(f"--learning-rate {args.learning_rate} is invalid: expected a number in (0, 1]")
    start = time.time()
    variants = []
    for law, scale in VARIANTS:
        result = energy_ratios(open_loop_bound(law, scale, n=args.n, iterations=args.iterations,
                                               learning_rate=args.learning_rate, progress=True))  # fmt: skip
        for which in ("law", "best"):
            print(law or "no law", which, {k: round(v, 3) for k, v in summary(result[which]).items()})
        variants.append(result)
    data = {"variants": variants, "machine": {"python": platform.python_version(), "platform": platform.platform(),
                                              "seconds": round(time.time() - start)}}  # fmt: skip
    if args.docs:
        write_json(JSON_PATH, data)
    return 0


SCHEMA = Schema({"variants": list, "machine": dict})
BLOCKS = (table("open-loop-bound", SCHEMA),)

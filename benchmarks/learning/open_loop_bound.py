"""What a residual on PTC could reach at all: each episode's residual sequence optimised on its own (open loop).

    python -m benchmarks run open-loop-bound --docs      # 32 episodes, 1,000 Adam steps each (about 6 min, 1 core)
    python -m benchmarks run open-loop-bound --n 4 --iterations 50   # a quick look (printed, nothing written)
    python -m benchmarks run open-loop-bound --variants ptc:1 --docs  # one variant more, the others kept

A residual policy is one map from observation to action for every episode; on each episode it does at most what the
best residual *sequence* for that episode does. This finds such sequences (train/learning/jitted/open_loop_bound.py: Adam on the
episode's v2 return through the JAX env and the law, the gradient APG follows, without its per-step clip or its
policy) for the residual on PTC and on pt-astolfi at the training's scale 0.5, and for the action itself without a
law (how close the optimiser comes to the optimum). ``--docs`` writes docs/rl_benchmark/open_loop_bound.json, from
which the table ``open-loop-bound`` of docs/rl-apg.md is rendered.
"""

from __future__ import annotations

import json
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
    parser.add_argument("--variants", nargs="+", metavar="LAW:SCALE", default=[variant_name(*v) for v in VARIANTS],
                        help="the laws under the sequences and the residual scales, 'none' for the action alone "
                             "(default: ptc:0.5 pt-astolfi:0.5 none:1); --docs keeps the JSON's others")  # fmt: skip
    parser.add_argument("--docs", action="store_true", help=f"write {JSON_PATH.relative_to(ROOT)} (and its table)")
    args = parser.parse_args(argv)
    if args.n < 1 or args.iterations < 1:
        parser.error(f"--n {args.n} and --iterations {args.iterations} are invalid: expected integers >= 1")
    if not 0 < args.learning_rate <= 1:
        parser.error(f"--learning-rate {args.learning_rate} is invalid: expected a number in (0, 1]")
    try:
        chosen = [parse_variant(text) for text in args.variants]
    except ValueError as error:
        parser.error(str(error))
    start = time.time()
    variants = []
    for law, scale in chosen:
        result = energy_ratios(open_loop_bound(law, scale, n=args.n, iterations=args.iterations,
                                               learning_rate=args.learning_rate, progress=True))  # fmt: skip
        for which in ("law", "best"):
            print(law or "no law", which, {k: round(v, 3) for k, v in summary(result[which]).items()})
        variants.append(result)
    if args.docs and JSON_PATH.is_file():  # the variants not run again kept, in the default's order first
        kept = {variant_name(v["settings"]["expert"], v["settings"]["residual_scale"]): v
                for v in json.loads(JSON_PATH.read_text())["variants"]}  # fmt: skip
        kept.update({variant_name(v["settings"]["expert"], v["settings"]["residual_scale"]): v for v in variants})
        variants = list(kept.values())
    data = {"variants": variants, "machine": {"python": platform.python_version(), "platform": platform.platform(),
                                              "seconds": round(time.time() - start)}}  # fmt: skip
    if args.docs:
        write_json(JSON_PATH, data)
    return 0


def variant_name(law: str | None, scale: float) -> str:
    """``LAW:SCALE`` of a variant (``none`` for the action alone)."""
    return f"{law or 'none'}:{scale:g}"


def parse_variant(text: str) -> tuple[str | None, float]:
    """(law or None, scale) of ``LAW:SCALE``; a clear error for anything else."""
    from baselines.registry import CONTROLLERS

    law, _, scale_text = text.partition(":")
    try:
        scale = float(scale_text)
    except ValueError:
        scale = float("nan")
    if (law != "none" and law not in CONTROLLERS) or not 0 < scale <= 2:
        raise ValueError(f"--variants {text!r} is invalid: expected LAW:SCALE with LAW 'none' or one of "
                         f"{sorted(CONTROLLERS)} and SCALE in (0, 2] (as --residual-scale), e.g. ptc:1")  # fmt: skip
    return (None if law == "none" else law), scale


SCHEMA = Schema({"variants": list, "machine": dict})
BLOCKS = (table("open-loop-bound", SCHEMA),)

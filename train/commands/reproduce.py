"""``dwr-gym reproduce``: the paper's Figures 5-9, an animation, and a report of its claims with measured verdicts."""

from __future__ import annotations

import argparse
from typing import Any

from train.commands.shared import UsageError, check_writable_dir


def add_parser(sub: Any) -> None:
    """The ``reproduce`` subcommand."""
    p = sub.add_parser("reproduce", help="regenerate the paper's Figures 5-9 and a report of its claims")
    p.add_argument("--out", default="results/reproduce", help="output directory (default: results/reproduce)")
    p.add_argument("--dt", type=float, default=0.01, help="control period of the simulation [s] (default: 0.01)")
    p.add_argument("--no-gif", action="store_true", help="skip the animated GIF")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Regenerate the paper's figures and the report of its claims."""
    from pathlib import Path

    if not 0.0 < args.dt <= 0.1:
        raise UsageError(f"--dt {args.dt} is invalid: expected a control period in (0, 0.1] s")
    try:
        import matplotlib  # noqa: F401
    except ImportError as error:
        raise UsageError('matplotlib is not installed: pip install "dwr-gym[plots]"') from error
    check_writable_dir("--out", args.out)
    from train.evaluation.reproduce import claims, measure, optimum_lines
    from train.reporting.paper import plot_paper_figures, write_claims, write_report

    out = Path(args.out)
    runs = measure(args.dt, log=lambda stage: print(f"running {stage} ...", flush=True))
    found = claims(runs)
    print("drawing the figures" + (" and the animation" if not args.no_gif else "") + " ...", flush=True)
    out.mkdir(parents=True, exist_ok=True)
    plot_paper_figures(runs, out, gif=not args.no_gif)
    write_report(found, out / "report.md", args.dt, optimum_lines(runs))
    write_claims(found, out / "claims.json", args.dt, optimum_lines(runs))
    print()
    width = max(len(c.verdict) for c in found)
    for claim in found:
        print(f"[{claim.verdict:<{width}}] {claim.claim}\n    {claim.measured}")
    print(f"wrote figures, report.md and claims.json to {args.out}")
    return 0

"""``dwr-gym optimum``: the optima dwr-gym ships for its default scenario sets, listed and checked.

``dwr-gym optimum list`` names the shipped files and the user's cache; ``dwr-gym optimum verify`` solves the shipped
optima again with CasADi and compares the energies (exit 1 on a mismatch), all of them or ``--sample N`` per file.
"""

from __future__ import annotations

import argparse
import math
from typing import Any

from train.commands.shared import UsageError, count


def add_parser(sub: Any) -> None:
    """The ``optimum`` subcommand."""
    p = sub.add_parser("optimum", help="list or verify the optima shipped for the default scenario sets",
                       description="dwr-gym ships the minimum-energy optimum of every episode of compare's and "
                       "evaluate's default sets (train/optima/), read where the user's cache "
                       "($DWR_GYM_CACHE or ~/.cache/dwr-gym) has none; DWR_GYM_SHIPPED_OPTIMA=0 turns them off. "
                       "'verify' solves them again and compares.")  # fmt: skip
    actions = p.add_subparsers(dest="action", required=True, metavar="ACTION")
    listing = actions.add_parser("list", help="the shipped optimum files and the user's cache")
    listing.set_defaults(func=run_list)
    verify = actions.add_parser("verify", help="solve the shipped optima again and compare the energies (CasADi)")
    verify.add_argument("--sample", type=count, default=0,
                        help="re-solve a seeded random sample of this many optima per file (default: 0, all)")  # fmt: skip
    verify.add_argument("--seed", type=count, default=0, help="seed of --sample (default: 0)")
    verify.add_argument("--rtol", type=float, default=1e-6,
                        help="largest relative difference of an energy that passes (default: 1e-6)")  # fmt: skip
    verify.add_argument("--workers", type=count, default=0, help="solver processes (default: 0, every core, at most 8)")
    verify.add_argument("--no-progress", action="store_true", help="no progress bar")
    verify.set_defaults(func=run_verify)


def run_list(args: argparse.Namespace) -> int:
    """Print each shipped file with its problem and size, and the user's cache."""
    from train.evaluation.optimum import cache_dir
    from train.evaluation.shipped_optima import SWITCH, read_shipped, shipped_enabled, shipped_files

    for path in shipped_files():
        problem, energies = read_shipped(path)
        print(f"{path.name}: {len(energies)} optima; {', '.join(f'{k}={v}' for k, v in problem.items())}")
    state = "read" if shipped_enabled() else f"not read ({SWITCH}=0)"
    print(f"shipped optima: {state}; the user's cache: {cache_dir()}")
    return 0


def run_verify(args: argparse.Namespace) -> int:
    """Re-solve the shipped optima; exit 0 when every energy matches to ``--rtol``, else 1 with the mismatches."""
    from train.evaluation.optimum import casadi_available
    from train.evaluation.shipped_optima import ShippedOptimaError, shipped_files
    from train.evaluation.verify_optima import verify_shipped
    from train.progress import Progress

    if not (math.isfinite(args.rtol) and args.rtol > 0):
        raise UsageError(f"--rtol={args.rtol} is invalid: expected a finite number > 0")
    if not casadi_available():
        raise UsageError('verifying the optima solves them with CasADi: pip install "dwr-gym[optimal]"')
    if not shipped_files():
        raise UsageError("no shipped optima are installed (train/optima/ is empty)")
    bar: Any = None

    def solved(done: int, total: int) -> None:
        nonlocal bar
        if args.no_progress:
            return
        if bar is None:
            bar = Progress(total=total, desc="optimum verify", unit="plan")
        bar.update(done - bar.n)

    try:
        report = verify_shipped(args.sample, args.seed, args.rtol, args.workers, on_solved=solved)
    except ShippedOptimaError as error:
        print(f"dwr-gym optimum: error: {error}")
        return 1
    except KeyboardInterrupt:
        print("\ninterrupted: nothing verified was kept (verify writes nothing)")
        return 130
    finally:
        if bar is not None:
            bar.close()
    print(f"verified {report.checked} shipped optima of {len(report.files)} file(s) with CasADi: largest relative "
          f"difference {report.largest:.2e} (tolerance {args.rtol:g})")  # fmt: skip
    if report.whole_search:
        print(f"{len(report.whole_search)} optima reproduced by the whole fine search where the batched search landed "
              "above the tolerance (stopped at fatrop's own tolerance):")  # fmt: skip
        for line in report.whole_search:
            print(f"  {line}")
    for line in report.mismatches:
        print(f"mismatch: {line}")
    return 0 if report.ok else 1

"""``dwr-gym robustness``: sweep each disturbance's magnitude and measure who still arrives by T_con; the
tolerance table, CSV, JSON, Markdown and one figure per disturbance."""

from __future__ import annotations

import argparse
import json
import math
import os
from pathlib import Path
from typing import Any

from train.commands.shared import (
    UsageError,
    add_agents_argument,
    add_env_arguments,
    add_threads_argument,
    check_agent_paths,
    checked_env,
    checked_selection,
    command_threads,
    count,
    load_agents,
    validated_env_params,
)


def add_parser(sub: Any) -> None:
    """The ``robustness`` subcommand."""
    from baselines.registry import CONTROLLER_NAMES
    from train.evaluation.robustness import SWEEPS

    p = sub.add_parser("robustness", help="sweep disturbance magnitudes: who still arrives by T_con")
    p.add_argument(
        "--disturbances",
        nargs="+",
        default=list(SWEEPS),
        metavar="NAME",
        help=f"disturbances to sweep: any of {', '.join(SWEEPS)} (default: all)",
    )
    p.add_argument(
        "--controllers",
        nargs="+",
        default=["all"],
        metavar="NAME",
        help=f"controllers: 'all' or any of {', '.join(CONTROLLER_NAMES)} (default: all; "
        "'optimal' needs the optimal extra and is slow: it re-plans from the measured pose)",
    )
    add_agents_argument(p, "swept too, beside the shipped ones")
    p.add_argument("--no-shipped-agents", action="store_true", help="leave out the shipped agents (the leaderboard's)")
    p.add_argument("--n", type=count, default=200, help="random start poses per magnitude (default: 200)")
    p.add_argument(
        "--n-optimal",
        type=count,
        default=20,
        help="start poses for the (slow) optimal controller, the first of the n (default: 20)",
    )
    p.add_argument(
        "--from-json",
        nargs="+",
        metavar="FILE",
        help="run nothing: table and figures of the rows in these robustness.json files",
    )
    p.add_argument("--seed", type=count, default=0, help="seed of the start poses and disturbances (default: 0)")
    p.add_argument("--T-con", type=float, metavar="SECONDS",
                   help="the prescribed time of every episode, replacing the env's T_con_range (default: 20, or T_con of "
                   "--env-kwargs)")  # fmt: skip
    add_env_arguments(p, "observation_noise=0.01")
    p.add_argument("--out", default="results/robustness", help="output directory (default: results/robustness)")
    p.add_argument("--workers", type=count, default=0,
                   help="processes that sweep (disturbance, magnitude) jobs in parallel, each loading the policies "
                   "once; 0 (default): every core, at most 8; 1: this process, with a log line per policy")  # fmt: skip
    p.add_argument("--give-up-below", type=float, default=0.5, metavar="RATE",
                   help="a policy arriving in time in fewer than this share of the episodes at one magnitude is not run "
                   "at the larger ones of that disturbance; 0.95 gives the tolerance table alone, fastest (default: 0.5)")  # fmt: skip
    p.add_argument("--no-plots", action="store_true", help="write no figures")
    p.add_argument("--no-progress", action="store_true", help="no progress bars")
    add_threads_argument(p)
    p.set_defaults(func=run)  # fmt: skip


def run(args: argparse.Namespace) -> int:
    """Sweep disturbances for the controllers and agents; print the tolerance table, write CSV, JSON, PNG, MD. Every
    argument is checked first, before the heavy imports (torch, the agents), so that bad input is answered at once."""
    out = Path(args.out)
    if args.from_json:  # tables and figures of earlier runs, e.g. of disturbances swept in parallel
        rows = []
        for path in args.from_json:
            try:
                rows += json.loads(Path(path).read_text())
            except (OSError, ValueError) as error:
                raise UsageError(f"--from-json {path!r} is invalid: {error}") from error
        return report(rows, out, args.no_plots)
    env_id, env_kwargs, names = _checked(args)
    with command_threads(args):
        return _run(args, env_id, env_kwargs, names)


def _checked(args: argparse.Namespace) -> tuple[str, dict[str, Any], list[str]]:
    """The env id, the env's keywords at the one T_con of the sweep, and the controllers; bad input a UsageError."""
    from train.evaluation.robustness import SWEEPS

    env_id, env_kwargs = checked_env(args)
    T_con = args.T_con if args.T_con is not None else float(env_kwargs.get("T_con", 20.0))
    if not 0.0 < T_con <= 1e6:
        raise UsageError(f"--T-con {T_con} is invalid: expected a prescribed time in (0, 1e6] s")
    # one prescribed time for every episode: a fault starts at T_con / 4, and the sweep's rows are per T_con
    env_kwargs = {**env_kwargs, "T_con": T_con, "T_con_range": None}
    validated_env_params(env_kwargs)
    for name in args.disturbances:
        if name not in SWEEPS:
            raise UsageError(f"--disturbances {name!r} is invalid: expected any of {', '.join(SWEEPS)}")
    args.scenarios, args.T_con = [], None
    names = checked_selection(args)
    args.agents = check_agent_paths(args.agents)
    if args.n_optimal < 1:
        raise UsageError(f"--n-optimal {args.n_optimal} is invalid: expected an integer >= 1")
    if not 0.0 <= args.give_up_below <= 1.0:
        raise UsageError(f"--give-up-below {args.give_up_below} is invalid: expected a share in [0, 1]")
    return env_id, env_kwargs, names


def _run(args: argparse.Namespace, env_id: str, env_kwargs: dict[str, Any], names: list[str]) -> int:
    from train.evaluation.robustness import sweep
    from train.reporting.results import write_results

    out = Path(args.out)
    policies: dict[str, Any] = {name: name for name in names}
    paths = list(args.agents or [])
    if not args.no_shipped_agents:
        from train.learning.agents import default_agents

        paths = [str(path) for path in default_agents().values()] + paths
    policies.update(load_agents(paths, env_id))
    workers = args.workers or min(os.cpu_count() or 1, 8)
    if workers > 1:
        from train.evaluation.robustness import sweep_parallel
        from train.threads import check_threads

        def save(found: list[dict[str, Any]]) -> None:
            write_results([{**row, "env_id": env_id} for row in found], str(out), "robustness")

        found = sweep_parallel([k for k, v in policies.items() if isinstance(v, str)], paths, args.disturbances,
                               n=args.n, seed=args.seed, env_kwargs=env_kwargs, workers=workers,
                               progress=not args.no_progress, n_optimal=args.n_optimal, on_rows=save,
                               give_up=args.give_up_below, threads=check_threads(args.threads))  # fmt: skip
        return report([{**row, "env_id": env_id} for row in found], out, args.no_plots)
    rows: list[dict[str, Any]] = []
    for name in args.disturbances:  # the rows so far are saved after each disturbance: a long sweep can be cut short
        found = sweep(policies, [name], n=args.n, seed=args.seed, env_kwargs=env_kwargs,
                      progress=not args.no_progress, log=print, n_optimal=args.n_optimal,
                      give_up=args.give_up_below)  # fmt: skip
        rows += [{**row, "env_id": env_id} for row in found]
        write_results(rows, str(out), "robustness")
    return report(rows, out, args.no_plots)


def report(rows: list[dict[str, Any]], out: Path, no_plots: bool) -> int:
    """Print the tolerance table; write the rows (CSV, JSON), the table (Markdown) and the figures."""
    from train.evaluation.robustness import SUCCESS_LEVEL
    from train.reporting.results import write_results
    from train.reporting.robustness_figures import plot_robustness
    from train.reporting.tables import tolerance_markdown

    keys = list(dict.fromkeys(key for row in rows for key in row))  # rows of several runs may differ in columns
    rows = [{key: math.nan if row.get(key) is None else row[key] for key in keys} for row in rows]  # JSON's null: NaN
    markdown = tolerance_markdown(rows)
    print(f"\nlargest magnitude with success >= {SUCCESS_LEVEL:.0%} by T_con (n: episodes per point):\n{markdown}")
    for path in write_results(rows, str(out), "robustness"):
        print(f"wrote {path}")
    (out / "robustness.md").write_text(markdown)
    print(f"wrote {out / 'robustness.md'}")
    if not no_plots:
        for figure in plot_robustness(rows, out):
            print(f"wrote {figure}")
    return 0

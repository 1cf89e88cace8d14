"""``dwr-gym evaluate``: controllers and saved agents on named scenario sets; a table, CSV and JSON."""

from __future__ import annotations

import argparse
from typing import Any

from train.code_paths import describe as describe_code_paths
from train.commands.shared import (
    add_agents_argument,
    add_scenario_arguments,
    check_agent_paths,
    checked_env,
    checked_optimum,
    checked_selection,
    command_threads,
    interrupted,
    load_agents,
)


def add_parser(sub: Any) -> None:
    """The ``evaluate`` subcommand."""
    p = sub.add_parser("evaluate", help="evaluate controllers and agents on named scenario sets")
    add_scenario_arguments(p, "results/evaluate")
    add_agents_argument(p, "evaluated beside the controllers")
    p.set_defaults(func=run)  # fmt: skip


def run(args: argparse.Namespace) -> int:
    """Evaluate controllers (and saved agents) on named scenario sets; every argument is checked first, before the
    heavy imports (torch, the agents), so that bad input is answered at once."""
    env_id, env_kwargs = checked_env(args)
    names = checked_selection(args)
    args.agents = check_agent_paths(args.agents)
    with command_threads(args):
        return _run(args, env_id, env_kwargs, names)


def _run(args: argparse.Namespace, env_id: str, env_kwargs: dict[str, Any], names: list[str]) -> int:
    policies: dict[str, Any] = {name: name for name in names}
    policies.update(load_agents(args.agents, env_id))
    from train.evaluation.evaluate import evaluate_sets
    from train.evaluation.stages import StageClock
    from train.reporting.results import write_results
    from train.reporting.tables import EVAL_COLUMNS, asked_columns, print_blocks, table_notes

    done: list[dict[str, Any]] = []  # the rows of the scenario sets finished so far

    def keep(found: list[dict[str, Any]]) -> None:
        done[:] = found

    clock = StageClock(progress=not args.no_progress, description="evaluate")
    optimum = checked_optimum(args)
    try:
        rows = evaluate_sets(policies, args.scenarios, args.n, args.seed, env_kwargs, progress=not args.no_progress,
                             optimum=optimum, T_cons=args.T_con, n_optimal=args.n_optimal,
                             on_rows=keep, clock=clock, address=args.address)  # fmt: skip
    except KeyboardInterrupt:
        clock.close()
        return interrupted(done, env_id, args.out, "evaluation")
    clock.close()
    rows = [{**row, "env_id": env_id} for row in rows]
    print(f"env: {env_id}")
    print(f"code paths: {describe_code_paths()}")
    print_blocks(rows, asked_columns(EVAL_COLUMNS, optimum))
    if table_notes(rows):
        print(table_notes(rows))
    for path in write_results(rows, args.out, "evaluation"):
        print(f"wrote {path}")
    print(clock.summary())
    return 0

"""``dwr-gym compare``: trained agents against the PTC expert and the other controllers; a table, CSV, JSON and
figures."""

from __future__ import annotations

import argparse
from typing import Any

from train.code_paths import describe as describe_code_paths
from train.commands.shared import (
    UsageError,
    add_agents_argument,
    add_scenario_arguments,
    check_agent_paths,
    checked_env,
    checked_optimum,
    checked_selection,
    command_threads,
    interrupted,
    load_agents,
    parse_env_kwargs,
)

#: compare's default sets: the paper's Figures 5 and 7, the random starts nominal, and the four disturbed sets (the robust
#: headline); ``--scenarios`` chooses others.
COMPARE_SETS = ("paper-fig5", "paper-fig7", "random", "disturbed", "fault", "delay", "noise")


def add_parser(sub: Any) -> None:
    """The ``compare`` subcommand."""

    p = sub.add_parser("compare", help="compare trained agents with the PTC expert and the other controllers")
    add_scenario_arguments(p, "results/compare", COMPARE_SETS)
    add_agents_argument(p, "compared with the controllers, each on the env id it was trained on, or a shipped "
                           "agent's name (default: the leaderboard's shipped agents; the paper's reward's record only "
                           "by name: --agents ppo residual-ppo)")  # fmt: skip
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Evaluate agents and controllers on the same scenarios; print the table, write CSV, JSON and plots. Every
    argument is checked first, before the heavy imports (torch, the agents), so that bad input is answered at once."""
    env_id, env_kwargs = checked_env(args)
    controllers = checked_selection(args)
    args.agents = check_agent_paths(args.agents)
    with command_threads(args):
        return _run(args, env_id, env_kwargs, controllers)


def _run(args: argparse.Namespace, env_id: str, env_kwargs: dict[str, Any], controllers: list[str]) -> int:
    from pathlib import Path

    try:
        import matplotlib  # noqa: F401
        import stable_baselines3  # noqa: F401
    except ImportError as error:
        raise UsageError(f'{error.name} is not installed: pip install "dwr-gym[train,plots]"') from error
    from train.env_ids import env_keywords
    from train.evaluation.compare import compare
    from train.evaluation.stages import StageClock
    from train.learning.agents import AgentLoadError, default_agents, find_run_dir, trained_env_id
    from train.reporting.compare_figures import plot_learning_curves, plot_time_series, plot_trajectories
    from train.reporting.results import write_results
    from train.reporting.robust_headline import DISTURBED, headline_table, plot_pareto
    from train.reporting.tables import EVAL_COLUMNS, asked_columns, print_blocks, table_notes

    paths = [Path(p) for p in args.agents] if args.agents else list(default_agents().values())
    if not paths:
        raise UsageError("no agents given and no pretrained agent is installed: pass --agents PATH")
    agents = load_agents([str(p) for p in paths])
    run_dirs, agent_envs = {}, {}
    for label, path in zip(agents, paths, strict=True):
        try:
            run_dirs[label] = find_run_dir(path if path.is_dir() else path.parent)
            agent_envs[label] = trained_env_id(path)
        except AgentLoadError:
            pass
    # each agent on the env id it was trained on, with --env-kwargs on top; the controllers on --env
    elsewhere = {other: {label: agents.pop(label) for label, trained in agent_envs.items() if trained == other}
                 for other in dict.fromkeys(agent_envs.values()) if other != env_id}  # fmt: skip
    groups = [(group, env_keywords(other, parse_env_kwargs(args.env_kwargs))) for other, group in elsewhere.items()]
    done: list[dict[str, Any]] = []  # the rows of the scenario sets finished so far

    def keep(found: list[dict[str, Any]]) -> None:
        done[:] = [{**row, "env_id": agent_envs.get(row["policy"], env_id)} for row in found]

    clock = StageClock(progress=not args.no_progress)
    optimum = checked_optimum(args)
    try:
        rows, recorded, labels = compare(agents, controllers, args.scenarios, args.n, args.seed, env_kwargs,
                                         progress=not args.no_progress, optimum=optimum,
                                         T_cons=args.T_con, n_optimal=args.n_optimal, on_rows=keep,
                                         clock=clock, address=args.address, elsewhere=groups)  # fmt: skip
    except KeyboardInterrupt:
        clock.close()
        return interrupted(done, env_id, args.out, "comparison")
    clock.close()
    rows = [{**row, "env_id": agent_envs.get(row["policy"], env_id)} for row in rows]  # each row's own env
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    figures = [out / "trajectories.png", out / "time_series.png"]
    plot_trajectories(recorded, labels, figures[0])
    plot_time_series(recorded, figures[1])
    if run_dirs:
        figures.append(out / "learning_curves.png")
        plot_learning_curves(run_dirs, figures[2])
    print(f"env: {env_id}")
    print(f"code paths: {describe_code_paths()}")
    for other, group in elsewhere.items():
        print(f"env of {', '.join(group)}: {other}, the env id they were trained on")
    print_blocks(rows, asked_columns(EVAL_COLUMNS, optimum))
    if table_notes(rows):
        print(table_notes(rows))
    if any(r["scenario"] == "random" for r in rows) and any(r["scenario"] in DISTURBED for r in rows):
        asked = optimum != "none"
        print("\nthe robust headline (in time, final heading error and energy on each set"
              + ("; E/opt on the nominal one):" if asked else "):"))  # fmt: skip
        print(headline_table(rows, energy_ratio=asked))
        if asked:  # E/opt against the worst in-time rate: nothing to draw without the optimum
            figures.append(out / "pareto.png")
            plot_pareto(rows, figures[-1])
    for path in write_results(rows, args.out, "comparison"):
        print(f"wrote {path}")
    for figure in figures:
        print(f"wrote {figure}")
    print(clock.summary())
    return 0

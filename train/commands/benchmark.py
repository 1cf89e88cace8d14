"""``dwr-gym benchmark``: agents x seeds trained from v1's reward, evaluated on fixed sets, aggregated with rliable
(docs/rl-benchmark.md)."""

from __future__ import annotations

import argparse
import json
import os
import platform
import sys
from pathlib import Path
from typing import Any

from train.commands.shared import UsageError, count

DOCS_DIR = Path("docs/rl_benchmark")


def add_parser(sub: Any) -> None:
    """The ``benchmark`` subcommand."""
    from train.learning.benchmark import ENTRIES

    p = sub.add_parser("benchmark", help="RL protocol: agents x seeds, IQM with 95 %% CIs (rliable), learning curves",
                       description="Train each agent with each seed on its entry's env id and reward (v1's for a "
                       "NAME:KEY=VALUE agent that names none), evaluate the learning curve on a fixed set and the final agent on the nominal and disturbed sets, and "
                       "aggregate over seeds (IQM, stratified bootstrap).")  # fmt: skip
    p.add_argument("--agents", nargs="+", default=["ppo", "sac", "tqc", "residual-ppo"], metavar="AGENT",
                   help=f"entries: {', '.join(ENTRIES)}, or NAME:KEY=VALUE,... with options of dwr-gym train "
                   "(default: ppo sac tqc residual-ppo)")  # fmt: skip
    p.add_argument("--seeds", type=count, default=5, help="seeds per agent: 0 .. N-1 (default: 5)")
    p.add_argument("--env-steps", type=count, help="env steps per run (default: each algorithm's own budget)")
    p.add_argument("--time-limit", type=float, help="stop each run after this many seconds (default: none)")
    p.add_argument("--eval-freq", type=count, default=100_000, help="env steps between evaluations (default: 100000)")
    p.add_argument("--eval-episodes", type=count, default=1000, help="nominal evaluation episodes (default: 1000)")
    p.add_argument("--disturbed-episodes", type=count, default=200, help="episodes per disturbed set (default: 200)")
    p.add_argument("--optimum-episodes", type=count, default=50,
                   help="E/opt on the nominal set's draw of this many episodes, none on the disturbed sets (0: every "
                   "episode of every set; default: 50)")  # fmt: skip
    p.add_argument("--references", nargs="*", default=["ptc", "pt-astolfi"], metavar="CONTROLLER",
                   help="controllers evaluated beside the agents (default: ptc pt-astolfi)")  # fmt: skip
    p.add_argument("--jobs", type=count, default=1, help="runs in parallel processes (default: 1)")
    p.add_argument("--ray", action="store_true", help="run the agent x seed grid as Ray tasks on a Ray started here "
                   "instead of --jobs processes (extra 'sweep')")  # fmt: skip
    p.add_argument("--address", help="run the grid as Ray tasks on the running Ray cluster at this address (auto, or "
                   "ray://host:10001); its workers need dwr-gym and --out at the same path (default: none)")  # fmt: skip
    p.add_argument("--resources-per-run", default="cpu=1", metavar="KEY=N,...",
                   help="Ray resources of one run, e.g. cpu=2 or cpu=1,gpu=0.25 (default: cpu=1)")  # fmt: skip
    p.add_argument("--out", default="results/rl-benchmark", help="output directory (default: results/rl-benchmark)")
    p.add_argument(
        "--report-only",
        action="store_true",
        help="train nothing: aggregate the results already in --out (e.g. of an interrupted benchmark)",
    )
    p.add_argument("--docs", action="store_true", help=f"also write the JSON and figures to {DOCS_DIR}/ and "
                   "regenerate the docs' tables; the agents already there that this run lacks are kept, so that "
                   "several runs (each with its own budget) fill one table")  # fmt: skip
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Run every (agent, seed) not yet done in --out, then aggregate and write benchmark.json and the figures."""
    from train.learning.benchmark import parse_entry, run_benchmark
    from train.learning.config import ConfigError

    if args.seeds < 1 or args.jobs < 1 or args.eval_episodes < 1 or args.disturbed_episodes < 1:
        raise UsageError("--seeds, --jobs, --eval-episodes and --disturbed-episodes must be >= 1")
    if args.time_limit is not None and not args.time_limit > 0:
        raise UsageError(f"--time-limit {args.time_limit!r} is invalid: expected seconds > 0")
    try:
        entries = [parse_entry(text) for text in args.agents]
    except ConfigError as error:
        raise UsageError(str(error)) from error
    for entry in entries if args.env_steps else []:  # an entry's own budget wins (its schedules are sized to it)
        if "total_timesteps" in entry.options:
            print(f"--env-steps {args.env_steps} leaves {entry.name} at its own {entry.options['total_timesteps']:,} "
                  f"env steps: {entry.name}:total_timesteps=N changes it", file=sys.stderr)  # fmt: skip
    budget = {"env_steps": args.env_steps, "time_limit": args.time_limit, "eval_freq": args.eval_freq,
              "eval_episodes": args.eval_episodes, "disturbed_episodes": args.disturbed_episodes,
              "optimum_episodes": args.optimum_episodes}  # fmt: skip
    out = Path(args.out)
    if args.report_only:
        results = [json.loads(path.read_text()) for entry in entries for seed in range(args.seeds)
                   if (path := out / "results" / f"{entry.name}-seed{seed}.json").is_file()]  # fmt: skip
        if not results:
            raise UsageError(f"--out {str(out)!r} holds no results of these agents: run without --report-only")
    else:
        from train.learning.sweep import parse_resources

        try:
            resources = parse_resources(args.resources_per_run, "--resources-per-run")
            results = run_benchmark(entries, list(range(args.seeds)), out, budget, jobs=args.jobs, ray=args.ray,
                                    address=args.address, resources=resources)  # fmt: skip
        except ConfigError as error:
            raise UsageError(str(error)) from error
    for result in results:  # env steps and training seconds as the run itself counted them (a resumed run too)
        state_path = out / "runs" / f"{result['entry']}-seed{result['seed']}" / "run_state.json"
        if state_path.is_file():
            state = json.loads(state_path.read_text())
            result["env_steps"] = state.get("timesteps", 0) * result.get("action_repeat", 1)
            result["seconds"] = state.get("wall_time", result["seconds"])
    data = report(results, out, budget, tuple(args.references), env_id=references_env(entries))
    if args.docs:
        report(results, DOCS_DIR, budget, tuple(args.references), merged_with_docs(data))
        from train.reporting.doc_tables import main as regenerate_tables

        regenerate_tables([])
    return 0


def references_env(entries: list[Any]) -> str:
    """The env id the reference controllers are evaluated on: the agents' when they all train on one, else v1."""
    from train.env_ids import TASK_ENV_ID

    ids = {entry.options.get("env_id", TASK_ENV_ID) for entry in entries}
    return ids.pop() if len(ids) == 1 else TASK_ENV_ID


def report(
    results: list[dict[str, Any]], out: Path, budget: dict[str, Any], references: tuple[str, ...],
    data: dict[str, Any] | None = None, env_id: str | None = None,
) -> dict[str, Any]:  # fmt: skip
    """Aggregate, print the tables, and write benchmark.json and the two figures of learning curves in ``out``;
    the reference controllers run on ``env_id`` (default v1)."""
    from train.evaluation.benchmark import reference_controllers
    from train.reporting.rl_benchmark import aggregate, best_seed, disturbed_table, per_T_con_table, plot_curves, table

    if data is None:
        from train.env_ids import TASK_ENV_ID

        env_id = env_id or TASK_ENV_ID
        refs = reference_controllers(references, env_id, n=budget["eval_episodes"],
                                     n_disturbed=budget["disturbed_episodes"],
                                     n_optimum=budget.get("optimum_episodes") or None)  # fmt: skip
        summary = aggregate(results)
        data = {"budget": budget, "machine": machine(), "versions": versions(), "summary": summary, "references": refs,
                "references_env": env_id, "best_seed": {name: best_seed(results, name) for name in summary}}  # fmt: skip
    out.mkdir(parents=True, exist_ok=True)
    (out / "benchmark.json").write_text(json.dumps(data, indent=1))
    plot_curves(data["summary"], out / "curves_steps.png", "env_steps")
    plot_curves(data["summary"], out / "curves_wall.png", "wall_time")
    print(table(data["summary"], data["references"]))
    print(disturbed_table(data["summary"], data["references"]))
    print(per_T_con_table(data["summary"], data["references"], data.get("references_env")))
    print(f"wrote {out / 'benchmark.json'}, {out / 'curves_steps.png'}, {out / 'curves_wall.png'}")
    return data


def merged_with_docs(data: dict[str, Any], docs: Path = DOCS_DIR) -> dict[str, Any]:
    """``data`` plus the agents of ``docs``/benchmark.json that it lacks (their summaries, best seeds and budgets:
    each agent keeps the budget and package versions it ran with, under "budgets" and "agent_versions"); the
    references are ``data``'s."""
    path = docs / "benchmark.json"
    if not path.is_file():
        return data
    old = json.loads(path.read_text())
    budgets = {name: old.get("budgets", {}).get(name, old.get("budget")) for name in old.get("summary", {})}
    budgets.update({name: data["budget"] for name in data["summary"]})
    agent_versions = {
        name: old.get("agent_versions", {}).get(name, old.get("versions")) for name in old.get("summary", {})
    }
    agent_versions.update({name: data.get("versions") for name in data["summary"]})
    summary = {**{k: v for k, v in old.get("summary", {}).items() if k not in data["summary"]}, **data["summary"]}
    best = {**{k: v for k, v in old.get("best_seed", {}).items() if k not in data["summary"]}, **data["best_seed"]}
    return {**data, "summary": summary, "best_seed": best, "budgets": budgets, "agent_versions": agent_versions}


def machine() -> str:
    """The machine the benchmark ran on, in one line."""
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    return f"{platform.machine()}, {os.cpu_count()} cores, load average {load:.1f} (1 min, at the end)"


def versions() -> dict[str, str | None]:
    """Python's and the learning packages' versions (None where one is not installed): a seed's outcome depends on
    them, so the JSON records them beside the results."""
    from importlib.metadata import PackageNotFoundError, version

    found: dict[str, str | None] = {"python": platform.python_version()}
    for name in (
        "numpy",
        "gymnasium",
        "torch",
        "stable-baselines3",
        "sb3-contrib",
        "jax",
        "jaxlib",
        "flax",
        "optax",
        "sbx-rl",
    ):
        try:
            found[name] = version(name)
        except PackageNotFoundError:
            found[name] = None
    return found

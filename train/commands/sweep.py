"""``dwr-gym sweep``: seeds and hyperparameter searches on Ray Tune (local, or a cluster), each trial the training
of ``dwr-gym train``; the table of trials, the best configuration as rl-zoo3 YAML and the learning curves."""

from __future__ import annotations

import argparse
import csv
import json
from pathlib import Path
from typing import Any

from train.commands.shared import (
    UsageError,
    add_env_arguments,
    add_threads_argument,
    command_threads,
    count,
    parse_env_kwargs,
)
from train.learning.config import ALGO_HELP, BUDGET_HELP, TrainConfig
from train.learning.sweep import METRICS, SEARCHES

EVAL_FREQ = TrainConfig.eval_freq


def add_parser(sub: Any) -> None:
    """The ``sweep`` subcommand."""
    p = sub.add_parser("sweep", help="seeds and hyperparameter searches on Ray Tune (local, or a cluster)",
                       description="Each trial runs the training of `dwr-gym train`; needs the extra [sweep].")  # fmt: skip
    p.add_argument("--algo", default="ppo", help=f"{ALGO_HELP}; a backend other than sb3 with --option backend=NAME "
                   "(default: ppo)")  # fmt: skip
    p.add_argument("--residual", action="store_true", help="residual agents on the PTC expert")
    p.add_argument("--time-limit", type=float, help="stop each run after this many seconds (default: none)")
    p.add_argument("--option", action="append", default=[], metavar="KEY=VALUE",
                   help="an option of dwr-gym train for every run, e.g. action_repeat=5 or normalize_obs=true; "
                   "repeatable")  # fmt: skip
    p.add_argument("--total-timesteps", type=count, help=f"env steps per run (default: {BUDGET_HELP['n_timesteps']})")
    p.add_argument("--num-envs", type=count, help=f"robots per vector env (default: {BUDGET_HELP['n_envs']})")
    add_env_arguments(p, "heading_weight=5")
    p.add_argument("--hyperparams", help="rl-zoo3 YAML the configurations start from (default: train/hyperparams/)")
    p.add_argument("--eval-freq", type=count, default=EVAL_FREQ,
                   help=f"evaluate every this many env steps (default: {EVAL_FREQ})")  # fmt: skip
    p.add_argument("--eval-episodes", type=count, default=100, help="scenarios per evaluation (default: 100)")
    p.add_argument("--seeds", type=count, default=3, help="seeds per configuration: 0 .. N-1 (default: 3)")
    p.add_argument(
        "--param",
        action="append",
        default=[],
        metavar="KEY=SPEC",
        help="a hyperparameter to search: KEY=v1,v2,... or KEY=uniform|loguniform|int:LOW:HIGH; repeatable",
    )
    p.add_argument(
        "--search",
        choices=SEARCHES,
        default="grid",
        help="grid: every combination of choices; random: --num-samples draws; optuna: Optuna's TPE "
        "through Ray Tune, each trial training all its seeds (default: grid)",
    )
    p.add_argument("--num-samples", type=count, default=8, help="configurations drawn by random/optuna (default: 8)")
    p.add_argument("--search-seed", type=count, default=0, help="seed of the random/optuna search (default: 0)")
    p.add_argument(
        "--metric",
        choices=METRICS,
        default="return_mean",
        help="what the best configuration maximises (minimises for energy/time/distance)",
    )
    p.add_argument("--address", help="join a running Ray cluster (e.g. auto or ray://host:10001); default: local Ray")
    p.add_argument("--resources-per-trial", default="cpu=1", help="Ray resources of one trial (default: cpu=1)")
    p.add_argument("--out", default="results/sweep", help="output directory (default: results/sweep)")
    p.add_argument(
        "--name",
        help="prefix of the run directories <out>/runs/<name>-<config>-seed<seed>, which label "
        "the agents in `dwr-gym compare` (default: ppo, ppo-residual, ...)",
    )
    p.add_argument("--resume", action="store_true", help="continue an interrupted sweep in --out")
    add_threads_argument(p)
    p.set_defaults(func=run)  # fmt: skip


def run(args: argparse.Namespace) -> int:
    """Run the sweep, then write trials.csv, best.yml and learning_curves.png in --out; every argument is checked
    first, before Ray and torch are imported."""
    checked = _checked(args)
    from importlib.util import find_spec

    if find_spec("ray") is None or find_spec("ray.tune") is None:
        raise UsageError('Ray Tune is not installed: pip install "dwr-gym[sweep]"')
    with command_threads(args):
        return _run(args, *checked)


def _checked(args: argparse.Namespace) -> tuple[Path, dict[str, Any], dict[str, Any], dict[str, float], list[int],
                                                list[dict[str, Any]]]:  # fmt: skip
    """--out, the base configuration, the search space, a trial's resources, the seeds and the configurations; bad
    input a UsageError."""
    from train.learning.config import ConfigError
    from train.learning.sweep import parse_param, parse_resources, sample_configurations, trial_config

    out = Path(args.out).resolve()
    base = {"algo": args.algo, "residual": args.residual, "total_timesteps": args.total_timesteps,
            "num_envs": args.num_envs, "env_id": args.env, "env_kwargs": parse_env_kwargs(args.env_kwargs),
            "eval_freq": args.eval_freq, "eval_episodes": args.eval_episodes, "threads": args.threads,
            "time_limit": args.time_limit}  # fmt: skip
    base = {key: value for key, value in base.items() if value is not None}  # unset: the YAML's, else the defaults
    if args.hyperparams:
        base["hyperparams"] = str(Path(args.hyperparams).resolve())
    for item in args.option:
        key, sep, value = item.partition("=")
        if not sep or key not in TrainConfig.__dataclass_fields__ or key in base:
            raise UsageError(f"--option {item!r} is invalid: expected KEY=VALUE with KEY an option of dwr-gym train "
                             "not set by another flag")  # fmt: skip
        import yaml

        base[key] = yaml.safe_load(value)
    try:
        for name in ("seeds", "num_samples"):
            if getattr(args, name) < 1:
                raise ConfigError(f"--{name.replace('_', '-')} {getattr(args, name)!r} is invalid: expected >= 1")
        space = dict(parse_param(item) for item in args.param)
        resources = parse_resources(args.resources_per_trial)
        seeds = list(range(args.seeds))
        if args.search == "optuna":
            if not space:
                raise ConfigError("--search optuna needs at least one --param")
            configs = sample_configurations(space, "random", 1, args.search_seed)  # to validate the keys
        else:
            configs = sample_configurations(space, args.search, args.num_samples, args.search_seed) if space else [{}]
        for hp in configs:
            trial_config(base, hp, 0, out / "runs" / "check")
    except ConfigError as error:
        raise UsageError(str(error)) from error
    if not args.resume and (out / "runs").exists():
        raise UsageError(f"--out {str(out)!r} already holds a sweep: use --resume to continue it, or another --out")
    return out, base, space, resources, seeds, configs


def _run(
    args: argparse.Namespace, out: Path, base: dict[str, Any], space: dict[str, Any], resources: dict[str, float],
    seeds: list[int], configs: list[dict[str, Any]],
) -> int:  # fmt: skip
    import ray
    from ray import tune

    from train.learning.sweep import optuna_space, trainable

    experiment = out / "ray"
    name = args.name or f"{args.algo}{'-residual' if args.residual else ''}"
    ray.init(address=args.address, include_dashboard=False, configure_logging=False, log_to_driver=False)
    metric = args.metric
    mode = "max" if metric in ("return_mean", "success_rate") else "min"
    runner = tune.with_resources(trainable, resources)
    if args.resume and tune.Tuner.can_restore(str(experiment / "sweep")):
        tuner = tune.Tuner.restore(str(experiment / "sweep"), runner, resume_unfinished=True, resume_errored=True)
    elif args.search == "optuna":
        from optuna.samplers import TPESampler
        from ray.tune.search.optuna import OptunaSearch

        tuner = tune.Tuner(
            runner,
            param_space={**optuna_space(space), "out": str(out), "base": base, "seeds": seeds, "name": name},
            tune_config=tune.TuneConfig(num_samples=args.num_samples, metric=metric, mode=mode,
                                        search_alg=OptunaSearch(sampler=TPESampler(seed=args.search_seed))),
            run_config=tune.RunConfig(name="sweep", storage_path=str(experiment), verbose=1),
        )  # fmt: skip
    else:
        trials = [{**hp, "config_id": f"c{i:03d}", "seed": seed, "out": str(out), "base": base, "name": name}
                  for i, hp in enumerate(configs) for seed in seeds]  # fmt: skip
        tuner = tune.Tuner(
            runner,
            param_space={"trial": tune.grid_search(trials)},
            tune_config=tune.TuneConfig(metric=metric, mode=mode),
            run_config=tune.RunConfig(name="sweep", storage_path=str(experiment), verbose=1),
        )
    results = tuner.fit()
    errors = results.errors
    ray.shutdown()
    report(out, metric, base)
    if errors:
        raise UsageError(f"{len(errors)} trial(s) failed, the first with: {str(errors[0]).splitlines()[-1]}")
    return 0


def report(out: Path, metric: str, base: dict[str, Any]) -> None:
    """Print and write the table of trials, the best configuration (rl-zoo3 YAML) and the learning curves."""
    from train.learning.sweep import TABLE_COLUMNS, collect, summarize, trial_config, zoo_yaml
    from train.reporting.learning_curves import plot_sweep_curves
    from train.reporting.tables import format_trials

    groups = collect(out)
    if not groups:
        print("no finished runs")
        return
    table = summarize(groups, metric)
    print(format_trials(table, TABLE_COLUMNS))
    with (out / "trials.csv").open("w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=list(table[0]))
        writer.writeheader()
        writer.writerows({**row, "hyperparams": json.dumps(row["hyperparams"])} for row in table)
    best = trial_config(base, table[0]["hyperparams"], 0, out / "runs" / "best")
    (out / "best.yml").write_text(zoo_yaml(best))
    plot_sweep_curves(groups, out / "learning_curves.png", ("return_mean", "success_rate"))
    print(f"best: {table[0]['config']} by {metric}; wrote {out / 'trials.csv'}, {out / 'best.yml'}, "
          f"{out / 'learning_curves.png'}")  # fmt: skip

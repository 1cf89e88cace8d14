"""``dwr-gym imitate``: behaviour cloning of the optimal planner (or a Minari dataset's policy) into a network."""

from __future__ import annotations

import argparse
from typing import Any

from train.commands.shared import UsageError, validated_env_params


def add_parser(sub: Any) -> None:
    """The ``imitate`` subcommand, generated from :class:`train.learning.imitation.cloning.ImitationConfig`."""
    import dataclasses

    from train.learning.imitation.cloning import ImitationConfig

    p = sub.add_parser("imitate", help="clone the optimal planner into a network policy for any T_con",
                       description="Record the optimal controller on the env's task (T_con drawn per episode) and fit "
                       "a PPO MlpPolicy to its actions (behaviour cloning with noise injection); with --dataset ID, fit it to the "
                       "actions of a Minari dataset of dwr-gym dataset instead.")  # fmt: skip
    for f in dataclasses.fields(ImitationConfig):
        flag = f.metadata.get("flag", "--" + f.name.replace("_", "-"))
        if isinstance(f.default, tuple):
            kind = int if f.name == "net_arch" else float
            p.add_argument(flag, dest=f.name, type=kind, nargs="+", default=argparse.SUPPRESS,
                           help=f"{f.metadata['help']} (default: {' '.join(map(str, f.default))})")  # fmt: skip
        else:
            p.add_argument(flag, dest=f.name, type=type(f.default), default=argparse.SUPPRESS,
                           help=f"{f.metadata['help']} (default: {f.default})")  # fmt: skip
    p.add_argument("--run-dir", default=None,
                   help="output directory (default: runs/bc-optimal-seed<seed>, or runs/bc-<name>-seed<seed> of --dataset)")  # fmt: skip
    p.add_argument("--no-progress", action="store_true", help="no progress bars")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Behaviour cloning of the optimal controller; bad input ends before any work starts."""
    from pathlib import Path

    from train.env_ids import check_env_id
    from train.evaluation.optimum import casadi_available
    from train.learning.imitation.cloning import ImitationConfig, env_kwargs, imitate

    given = {k: v for k, v in vars(args).items() if k not in ("func", "command", "run_dir", "no_progress")}
    for key in ("T_con_range", "start_distance", "net_arch"):
        if key in given:
            given[key] = tuple(given[key])
    config = ImitationConfig(**given)
    try:
        config.env_id = check_env_id(config.env_id)
    except ValueError as error:
        raise UsageError(str(error)) from None
    positive = {"episodes": 1, "epochs": 1, "batch_size": 1, "eval_episodes": 1, "eval_every": 1, "threads": 1}
    for key, low in positive.items():
        if getattr(config, key) < low:
            raise UsageError(
                f"--{key.replace('_', '-')} {getattr(config, key)} is invalid: expected an integer >= {low}"
            )
    if not 0.0 <= config.action_noise <= 1.0:
        raise UsageError(f"--action-noise {config.action_noise} is invalid: expected a number in [0, 1]")
    if not 0.0 < config.arrival_fraction <= 1.0:
        raise UsageError(f"--arrival-fraction {config.arrival_fraction} is invalid: expected a number in (0, 1]")
    if not 0.0 < config.learning_rate < 1.0:
        raise UsageError(f"--learning-rate {config.learning_rate} is invalid: expected a number in (0, 1)")
    for key in ("T_con_range", "start_distance"):
        value = getattr(config, key)
        if len(value) != 2 or not 0.0 < value[0] <= value[1]:
            raise UsageError(f"--{key.replace('_', '-')} {list(value)} is invalid: expected two numbers 0 < min <= max")
    if len(config.net_arch) == 0 or min(config.net_arch) < 1:
        raise UsageError(f"--net-arch {list(config.net_arch)} is invalid: expected layer sizes >= 1")
    if config.dataset:
        from train.datasets.store import DatasetError, dataset_env, load_dataset

        try:
            config.env_id = dataset_env(load_dataset(config.dataset, "--dataset"))[0]
        except DatasetError as error:
            raise UsageError(str(error)) from None
    validated_env_params(env_kwargs(config))
    if not casadi_available() and not config.dataset:
        raise UsageError('imitate needs the optimal planner (CasADi): pip install "dwr-gym[optimal]"')
    try:
        import stable_baselines3  # noqa: F401
    except ImportError as error:
        raise UsageError('stable-baselines3 is not installed: pip install "dwr-gym[train]"') from error
    source = config.dataset.rsplit("/", 1)[-1] if config.dataset else "optimal"
    run_dir = Path(args.run_dir or f"runs/bc-{source}-seed{config.seed}")
    if (run_dir / "model.zip").exists():
        raise UsageError(
            f"--run-dir {str(run_dir)!r} is invalid: it already holds a model.zip; choose another directory"
        )
    try:
        imitate(config, run_dir, progress=not args.no_progress)
    except KeyboardInterrupt:
        return 130
    print(f"wrote {run_dir / 'model.zip'}, config.yaml and evaluations.csv")
    return 0

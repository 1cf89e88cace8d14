"""``dwr-gym dataset``: a Minari dataset of any controller or saved agent, scored against the optimum."""

from __future__ import annotations

import argparse
import sys
from typing import Any

from train.commands.shared import UsageError, add_env_arguments, checked_env, count, load_agents

#: The scenario sets a dataset can be collected on: the env's own random starts, nominal or on an imperfect robot.
DATASET_SCENARIOS = ("random", "disturbed", "fault", "delay", "noise")


def add_parser(sub: Any) -> None:
    """The ``dataset`` subcommand."""
    from baselines.registry import CONTROLLER_NAMES

    p = sub.add_parser("dataset", help="write a Minari dataset of a controller or agent, scored against the optimum",
                       description="Collect episodes of a controller (--policy) or a saved agent (--agent) from the "
                       "native vector env and write them as a Minari dataset: each episode with its T_con, start, "
                       "goal, energy, disturbance and the optimum's energy; ref_max_score is the optimum's return, "
                       "ref_min_score random actions'. See docs/datasets.md.")  # fmt: skip
    p.add_argument("dataset_id", metavar="ID", help="Minari id namespace/name-vN, e.g. dwr-gym/ptc-nominal-v0")
    p.add_argument("--policy", metavar="NAME",
                   help=f"a controller: any of {', '.join(CONTROLLER_NAMES)}, or random")  # fmt: skip
    p.add_argument(
        "--agent", "--agents", dest="agent", metavar="PATH", help="a saved agent: a run directory or its model .zip"
    )
    p.add_argument("--scenarios", default="random", metavar="SET",
                   help=f"where: {', '.join(DATASET_SCENARIOS)} (the env's random starts, nominal or on the robot of "
                   "that robustness set); a DisturbanceDistribution per episode: --env-kwargs "
                   "disturbance_distribution='{}' (default: random)")  # fmt: skip
    p.add_argument("--episodes", type=count, default=1000, help="episodes to collect (default: 1000)")
    p.add_argument("--seed", type=count, default=0, help="robot i starts from seed + i (default: 0)")
    p.add_argument("--num-envs", type=count, default=1024, help="robots stepped at once (default: 1024)")
    p.add_argument("--ref-episodes", type=count, default=100,
                   help="episodes of the fixed evaluation set the reference scores are measured on (default: 100)")  # fmt: skip
    p.add_argument("--no-optimum", action="store_true",
                   help="do not solve each episode's optimum (its optimal_energy is then None)")  # fmt: skip
    p.add_argument("--overwrite", action="store_true", help="replace a dataset of the same id")
    p.add_argument("--description", default="", help="the dataset's description (default: what it holds)")
    p.add_argument("--no-progress", action="store_true", help="no progress bars")
    add_env_arguments(p, "T_con=25 disturbance_distribution='{\"probability\": 0.5}'")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Check everything, then collect and write the dataset."""
    from baselines.registry import CONTROLLER_NAMES
    from train.datasets.store import DatasetError, check_dataset_id, dataset_exists, datasets_root, require_minari
    from train.evaluation.optimum import casadi_available

    try:
        check_dataset_id(args.dataset_id, "ID")
        require_minari()
    except DatasetError as error:
        raise UsageError(str(error)) from None
    if args.policy is None and args.agent is None:
        raise UsageError("--policy is missing: expected --policy NAME (a controller or random) or --agent PATH")
    if args.policy is not None and args.agent is not None:
        raise UsageError(f"--policy {args.policy!r} and --agent {args.agent!r} are invalid together: give one of them")
    names = (*CONTROLLER_NAMES, "random")
    if args.policy is not None and args.policy not in names:
        raise UsageError(f"--policy {args.policy!r} is invalid: expected any of {', '.join(names)}")
    if args.scenarios not in DATASET_SCENARIOS:
        raise UsageError(f"--scenarios {args.scenarios!r} is invalid: expected one of {', '.join(DATASET_SCENARIOS)}")
    for flag, value, low, high in (("--episodes", args.episodes, 1, 10**7), ("--seed", args.seed, 0, 2**32 - 1),
                                   ("--num-envs", args.num_envs, 1, 100_000),
                                   ("--ref-episodes", args.ref_episodes, 1, 100_000)):  # fmt: skip
        if not low <= value <= high:
            raise UsageError(f"{flag} {value} is invalid: expected an integer in [{low}, {high}]")
    if not casadi_available():
        raise UsageError(
            'dwr-gym dataset needs CasADi for the optimum\'s reference score: pip install "dwr-gym[optimal]"'
        )
    if dataset_exists(args.dataset_id) and not args.overwrite:
        raise UsageError(f"ID {args.dataset_id!r} is invalid: it exists in {datasets_root()}; pass --overwrite to "
                         "replace it")  # fmt: skip
    env_id, env_kwargs = checked_env(args)
    if args.scenarios != "random":
        from dwr_gym.params import EnvParams
        from train.commands.shared import validated_env_params
        from train.evaluation.disturbance_sets import robustness_env_kwargs

        params: EnvParams = validated_env_params(env_kwargs)
        env_kwargs = {**robustness_env_kwargs(args.scenarios, params.T_con), **env_kwargs}
        validated_env_params(env_kwargs)
    from train.datasets.build import DatasetRequest, build_dataset, controller_policy

    if args.agent is not None:
        name, policy = next(iter(load_agents([args.agent], env_id).items()))
    else:
        name, policy = args.policy, controller_policy(args.policy, env_kwargs, args.seed)
    if args.policy in ("optimal", "robust-pt"):
        print(f"note: {args.policy} plans every episode with CasADi: the slowest policy to collect (the progress bar "
              "says how long)", file=sys.stderr)  # fmt: skip
    request = DatasetRequest(args.dataset_id, name, env_id, env_kwargs, args.episodes, seed=args.seed,
                             num_envs=args.num_envs, optimum=not args.no_optimum, ref_episodes=args.ref_episodes,
                             overwrite=args.overwrite, description=args.description)  # fmt: skip
    try:
        summary = build_dataset(request, policy, progress=not args.no_progress)
    except DatasetError as error:
        raise UsageError(str(error)) from None
    except KeyboardInterrupt:
        print(f"interrupted: nothing written under {args.dataset_id}")
        return 130
    print(f"wrote {summary['dataset_id']} ({summary['path']}): {int(summary['episodes'])} episodes, "
          f"{int(summary['steps']):,} steps of {name} in {summary['collect_seconds']:.1f} s")  # fmt: skip
    print(f"return {summary['return_mean']:.3f} +- {summary['return_std']:.3f}; in time {100 * summary['in_time']:.1f} %; "
          f"E/opt {summary['energy_ratio_mean']:.3f}; ref_min_score {summary['ref_min_score']:.3f}, ref_max_score "
          f"{summary['ref_max_score']:.3f} (the optimum); normalised score {summary['normalized_score']:.3f}")  # fmt: skip
    return 0

"""``dwr-gym info``: versions, the registered envs and the defaults of one of them."""

from __future__ import annotations

import argparse
import platform
from typing import Any

from train.commands.shared import UsageError

#: What each registered id is for, as ``info`` lists them.
DESCRIPTIONS = {
    "DWRPointStabilization-v2": "the task held to T_con, every command's default: the pose at T_con less the energy",
    "DWRPointStabilization-v1": "the same task ending on arrival (energy-optimal reward): the v1 agents' env",
    "DWRPointStabilization-v0": "the paper's original reward at T_con = 20 s, kept bit for bit for reproduction",
    "DWRPointStabilizationGoal-v0": "the goal-conditioned task for HER (Dict observations)",
}


def add_parser(sub: Any) -> None:
    """The ``info`` subcommand."""
    from train.env_ids import DEFAULT_ENV_ID

    p = sub.add_parser("info", help="versions, the registered envs and their defaults")
    p.add_argument("--env", default=DEFAULT_ENV_ID, metavar="ID",
                   help=f"the env whose defaults to print: any registered id (default: {DEFAULT_ENV_ID})")  # fmt: skip
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Print versions, the registered envs and the defaults of ``--env``."""
    import gymnasium
    import numpy

    import dwr_gym
    from dwr_gym.params import EnvParams

    env_id = str(args.env).removeprefix("dwr_gym:")
    if env_id not in DESCRIPTIONS:
        raise UsageError(f"--env {args.env!r} is invalid: expected any of {', '.join(DESCRIPTIONS)}")
    lines = [
        f"dwr-gym {dwr_gym.__version__}",
        f"python {platform.python_version()}, gymnasium {gymnasium.__version__}, numpy {numpy.__version__}",
    ]
    for module in ("stable_baselines3", "torch", "pygame", "matplotlib", "casadi"):
        try:
            mod = __import__(module)
            lines.append(f"{module} {getattr(mod, '__version__', '?')}")
        except ImportError:
            lines.append(f"{module} not installed")
    lines.append("registered envs (gymnasium.make, gymnasium.make_vec):")
    width = max(map(len, DESCRIPTIONS))
    lines += [f"  {name:<{width}}  {text}" for name, text in DESCRIPTIONS.items()]
    spec = gymnasium.spec(env_id)
    lines += [f"  {env_id}: entry point {spec.entry_point}" + (f", vector entry point {spec.vector_entry_point}"
                                                               if spec.vector_entry_point else "")]  # fmt: skip
    lines.append(f"defaults of {env_id} (dwr-gym info --env ID for another):")
    params = EnvParams.from_kwargs(**spec.kwargs)
    for key, value in params.as_dict().items():
        lines.append(f"    {key} = {value!r}")
    lines.append(f"    (horizon = {params.horizon} s, max_episode_steps = {params.max_episode_steps})")
    print("\n".join(lines))
    return 0

"""``dwr-gym info``: versions, the registered env and its defaults."""

from __future__ import annotations

import argparse
import platform
from typing import Any


def add_parser(sub: Any) -> None:
    """The ``info`` subcommand."""
    info = sub.add_parser("info", help="versions, the registered env and its defaults")
    info.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Print versions, the registered env and its defaults."""
    import gymnasium
    import numpy

    import dwr_gym

    spec = gymnasium.spec(dwr_gym.ENV_ID)
    lines = [
        f"dwr-gym {dwr_gym.__version__}",
        f"python {platform.python_version()}, gymnasium {gymnasium.__version__}, numpy {numpy.__version__}",
    ]
    for module in ("stable_baselines3", "torch", "pygame", "matplotlib"):
        try:
            mod = __import__(module)
            lines.append(f"{module} {getattr(mod, '__version__', '?')}")
        except ImportError:
            lines.append(f"{module} not installed")
    lines += [
        f"registered env: {spec.id}",
        f"  entry point: {spec.entry_point}",
        f"  vector entry point: {spec.vector_entry_point}",
        "  defaults:",
    ]
    params = dwr_gym.EnvParams()
    for key, value in params.as_dict().items():
        lines.append(f"    {key} = {value!r}")
    lines.append(f"    (horizon = {params.horizon} s, max_episode_steps = {params.max_episode_steps})")
    print("\n".join(lines))
    return 0

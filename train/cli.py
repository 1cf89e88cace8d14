"""The ``dwr-gym`` command line: ``info``, ``evaluate``, ``reproduce``, ``train``, ``compare``.

Every subcommand validates its input before doing any work; bad input ends with a one-line
error on stderr and exit code 2.
"""

from __future__ import annotations

import argparse
import json
import platform
import sys
from collections.abc import Callable, Sequence
from typing import Any


class UsageError(Exception):
    """Bad user input: printed as one line, exit code 2."""


def parse_env_kwargs(items: Sequence[str] | None) -> dict[str, Any]:
    """Parse ``KEY=VALUE`` pairs; VALUE is read as JSON when it parses, else as a string."""
    kwargs: dict[str, Any] = {}
    for item in items or ():
        key, sep, raw = item.partition("=")
        if not sep or not key:
            raise UsageError(f"--env-kwargs item {item!r} is invalid: expected KEY=VALUE, e.g. T_con=25")
        try:
            value = json.loads(raw)
        except json.JSONDecodeError:
            value = raw
        kwargs[key] = tuple(value) if isinstance(value, list) else value
    return kwargs


def validated_env_params(env_kwargs: dict[str, Any]) -> Any:
    """EnvParams from keywords, turning a ValueError into a UsageError."""
    from dwr_gym.params import EnvParams

    try:
        return EnvParams.from_kwargs(**env_kwargs)
    except ValueError as error:
        raise UsageError(f"invalid env keyword: {error}") from error


def cmd_info(args: argparse.Namespace) -> int:
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


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of ``dwr-gym``."""
    parser = argparse.ArgumentParser(prog="dwr-gym", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    info = sub.add_parser("info", help="versions, the registered env and its defaults")
    info.set_defaults(func=cmd_info)
    for register in _REGISTRARS:
        register(sub)
    return parser


_REGISTRARS: list[Callable[[Any], None]] = []


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``dwr-gym`` console script."""
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args))
    except UsageError as error:
        print(f"dwr-gym {args.command}: error: {error}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())

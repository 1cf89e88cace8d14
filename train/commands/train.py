"""``dwr-gym train``: an agent of one of the learners of :mod:`train.learning.learners`, plain or residual on an
expert; its options are the fields of :class:`train.learning.config.TrainConfig`."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from typing import Any

from train.commands.shared import UsageError, parse_env_kwargs


def add_parser(sub: Any) -> None:
    """The ``train`` subcommand, generated from the fields of :class:`train.learning.config.TrainConfig`."""
    import dataclasses

    from train.learning.config import TrainConfig

    p = sub.add_parser("train", help="train an agent with the learner of --algo on --backend, plain or residual on an expert",
                       description="Options left out take the YAML file's value, else the default shown.")  # fmt: skip
    for f in dataclasses.fields(TrainConfig):
        if f.metadata.get("cli") is False:
            continue
        flag = f.metadata.get("flag", "--" + f.name.replace("_", "-"))
        default = f.metadata.get("shown_default", f.default if f.default is not dataclasses.MISSING else "{}")
        text = f"{f.metadata['help']} (default: {default})" if default != "" else f.metadata["help"]
        if f.name == "progress":
            p.add_argument(
                "--no-progress",
                dest="progress",
                action="store_false",
                default=argparse.SUPPRESS,
                help="no progress bar",
            )
        elif isinstance(f.default, bool):
            p.add_argument(flag, action="store_true", default=argparse.SUPPRESS, help=text)
        elif f.name == "env_kwargs":
            p.add_argument(flag, nargs="*", metavar="KEY=VALUE", default=argparse.SUPPRESS, help=text)
        elif f.name == "hyperparams":
            p.add_argument(flag, nargs="+", metavar="FILE|KEY=VALUE", default=argparse.SUPPRESS, help=text)
        else:  # numbers are read as text and coerced by TrainConfig.validate, so 1e5 and 3e-4 work
            p.add_argument(flag, dest=f.name, metavar=f.metadata.get("metavar"), default=argparse.SUPPRESS, help=text)
    p.set_defaults(func=run)


def split_hyperparams(items: Sequence[str]) -> tuple[str | None, list[str]]:
    """``--hyperparams`` items: at most one YAML file, and KEY=VALUE (or KEY:VALUE) overrides."""
    from pathlib import Path

    files = [item for item in items if "=" not in item and (":" not in item or Path(item).is_file())]
    if len(files) > 1:
        raise UsageError(f"--hyperparams {files!r} is invalid: expected at most one YAML file")
    return (files[0] if files else None), [item for item in items if item not in files]


def run(args: argparse.Namespace) -> int:
    """Train an agent; bad input ends before any training starts."""

    given = {k: v for k, v in vars(args).items() if k not in ("func", "command")}
    if "env_kwargs" in given:
        given["env_kwargs"] = parse_env_kwargs(given["env_kwargs"])
    from train.learning.config import ConfigError, TrainConfig
    from train.learning.runs import RunDirError

    try:
        if "resume" not in given:  # the options alone, checked before torch and the learners are imported
            TrainConfig(**{k: v for k, v in given.items() if k != "hyperparams"}).validate()
        from importlib.util import find_spec

        if find_spec("stable_baselines3") is None:
            raise UsageError('stable-baselines3 is not installed: pip install "dwr-gym[train]"')
        from train.learning.hyperparams import parse_overrides, resolve_hyperparams
        from train.learning.runs import resume_config
        from train.learning.training import train

        if "hyperparams" in given:
            given["hyperparams"], overrides = split_hyperparams(given["hyperparams"])
            given["hyperparam_overrides"] = parse_overrides(overrides)
        if "resume" in given:
            config = resume_config(given)
        else:
            config = TrainConfig(**given)
            config.validate()
            config = resolve_hyperparams(config, set(given))
        train(config, command=["dwr-gym", *sys.argv[1:]])
    except (ConfigError, RunDirError) as error:  # all raised before any training starts
        raise UsageError(str(error)) from None
    except KeyboardInterrupt:
        return 130
    return 0

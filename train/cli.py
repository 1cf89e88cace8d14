"""The ``dwr-gym`` command line; ``dwr-gym --help`` lists its commands.

Every subcommand validates its input before doing any work; bad input ends with a one-line
error on stderr and exit code 2. Each command lives in its own module of :mod:`train.commands`;
this module only builds the parser and dispatches.
"""

from __future__ import annotations

import sys
from collections.abc import Sequence

from train.commands import benchmark, compare, dataset, evaluate, imitate, info, optimum, reproduce, robustness, sweep
from train.commands import train as train_command
from train.commands.shared import Parser, UsageError

#: The commands in the order ``dwr-gym --help`` lists them.
COMMANDS = (info, evaluate, reproduce, train_command, compare, imitate, sweep, robustness, benchmark, dataset, optimum)


def build_parser() -> Parser:
    """The argument parser of ``dwr-gym``."""
    parser = Parser(prog="dwr-gym")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for command in COMMANDS:
        command.add_parser(sub)
    parser.description = (
        "Prescribed-time point stabilization of a differential wheeled robot: evaluate, train and compare "
        f"controllers and agents. Commands: {', '.join(sub.choices)}; `dwr-gym COMMAND --help` for each."
    )
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``dwr-gym`` console script."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if argv is None and getattr(args, "code_paths", None) == "portable":  # the command line, not a Python caller
        from train.code_paths import pin

        pin(sys.argv[1:])  # once: this process becomes the same command on the portable code paths
    try:
        return int(args.func(args))
    except UsageError as error:
        print(f"dwr-gym {args.command}: error: {error}", file=sys.stderr)
        return 2
    except ImportError as error:
        if "dwr-gym[" not in str(error):  # not an optional dependency we name: a bug, shown with its traceback
            raise
        print(f"dwr-gym {args.command}: error: {error}", file=sys.stderr)  # a missing extra, named
        return 2
    except OSError as error:  # e.g. a disk that fills up or a directory removed during the run
        print(f"dwr-gym {args.command}: error: {error}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())

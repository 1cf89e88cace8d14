"""Commands run as a user runs them: ``dwr-gym ...`` in a fresh process of this checkout, a command of the suite
that is a ``dwr-gym`` command with fixed arguments, and the shell recipes."""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[2]


def checkout_env(**extra: str) -> dict[str, str]:
    """The environment of a child process that imports this checkout's code, without a display."""
    return {**os.environ, "PYTHONPATH": str(ROOT), "MPLBACKEND": "Agg", **extra}


def dwr_gym(args: list[str], cwd: str | Path = ROOT, **kwargs: Any) -> subprocess.CompletedProcess[str]:
    """``dwr-gym ARGS`` as this checkout's code, in ``cwd``, failing loudly (``kwargs`` go to subprocess.run)."""
    kwargs.setdefault("env", checkout_env())
    return subprocess.run([sys.executable, "-m", "train.cli", *args], cwd=cwd, check=True, text=True, **kwargs)


def command_main(args: list[str], docs: list[str]) -> Callable[[list[str] | None], int]:
    """The ``main`` of an entry that is ``dwr-gym ARGS``, run in a process of its own as the command line runs it (on
    its code paths, train/code_paths.py): ``--docs`` adds ``docs`` (where the docs' JSON goes), the other arguments go
    to the command."""

    def main(argv: list[str] | None = None) -> int:
        argv = list(argv or [])
        extra = docs if "--docs" in argv else []
        command = [*args, *extra, *(a for a in argv if a != "--docs")]
        if {"-h", "--help"} & set(argv):  # the command's help, printed here
            from train.cli import main as cli

            return cli(command)
        run = subprocess.run([sys.executable, "-m", "train.cli", *command], cwd=ROOT, env=checkout_env(), check=False)
        return run.returncode  # as the command line runs it

    return main


def recipe_main(script: Path) -> Callable[[list[str] | None], int]:
    """The ``main`` of a recipe entry: its shell script, run in the repository (``--docs`` is accepted and changes
    nothing: a recipe writes what it writes; other arguments go to bash)."""

    def main(argv: list[str] | None = None) -> int:
        args = [a for a in argv or [] if a != "--docs"]
        if {"-h", "--help"} & set(args):  # the script's header says what it runs and how long it takes
            header = [line[2:] for line in script.read_text().splitlines()[1:] if line.startswith("# ")]
            print(f"python -m benchmarks run {script.stem.replace('_', '-')}: runs {script.relative_to(ROOT)}\n")
            print("\n".join(header))
            return 0
        env = checkout_env(PATH=f"{Path(sys.executable).parent}{os.pathsep}{os.environ.get('PATH', '')}")
        return subprocess.run(["bash", str(script), *args], cwd=ROOT, env=env, check=False).returncode

    return main


def parser_for(name: str, doc: str | None, allow_abbrev: bool = True) -> argparse.ArgumentParser:
    """The argument parser of entry ``name``, as ``python -m benchmarks run NAME --help`` shows it: its docstring's
    first line as the description."""
    description = (doc or "").splitlines()[0]
    return argparse.ArgumentParser(
        prog=f"python -m benchmarks run {name}", description=description, allow_abbrev=allow_abbrev
    )


def add_json_output(parser: argparse.ArgumentParser, docs_json: str, flag: str = "--json") -> None:
    """``FLAG PATH``: write the results as JSON at PATH; ``--docs``: at the docs' ``docs_json`` (relative to the
    repository), from which ``python -m benchmarks run`` then renders the entry's blocks."""
    dest = flag.removeprefix("--").replace("-", "_")
    parser.add_argument(flag, dest=dest, type=Path, help="also write the results as JSON to this file")
    parser.add_argument("--docs", dest=dest, action="store_const", const=ROOT / docs_json,
                        help=f"write them to {docs_json} (and render its blocks)")  # fmt: skip

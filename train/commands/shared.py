"""What the commands share: the one-line usage error, argument types and checks, the scenario options,
loading agents. It imports no command."""

from __future__ import annotations

import argparse
import ast
import json
import sys
from collections.abc import Sequence
from contextlib import AbstractContextManager
from typing import Any, NoReturn


class UsageError(Exception):
    """Bad user input: printed as one line, exit code 2."""


class Parser(argparse.ArgumentParser):
    """An ArgumentParser whose errors are one line (no usage block), exit code 2, like every other bad input.

    Options must be spelled out: with argparse's prefix matching, ``--env`` would be read as ``--env-kwargs``.
    Subcommands' parsers are of this class too, so the same holds for every command.
    """

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        kwargs.setdefault("allow_abbrev", False)
        super().__init__(*args, **kwargs)

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")

    def parse_args(self, args: Sequence[str] | None = None, namespace: Any = None) -> Any:  # type: ignore[override]
        """As argparse's, but an unknown option is reported by the command it was given to (``dwr-gym train:
        ... (see dwr-gym train --help)``), with the nearest option it takes."""
        parsed, extras = self.parse_known_args(args, namespace)
        if extras:
            parser = self._chosen_command(parsed) or self
            parser.error(f"unrecognized arguments: {' '.join(extras)}{parser._near_options(extras)}")
        return parsed

    def _chosen_command(self, parsed: argparse.Namespace) -> Parser | None:
        for action in self._actions:
            if isinstance(action, argparse._SubParsersAction):
                chosen = action.choices.get(getattr(parsed, action.dest, None) or "")
                return chosen if isinstance(chosen, Parser) else None
        return None

    def _near_options(self, extras: Sequence[str]) -> str:
        import difflib

        options = sorted({flag for action in self._actions for flag in action.option_strings})
        flags = [item.partition("=")[0] for item in extras if item.startswith("--")]
        hints = []
        for flag in flags:
            near = difflib.get_close_matches(flag, options, n=1, cutoff=0.7)
            if near:
                hints.append(f"{near[0]} for {flag}" if len(flags) > 1 else near[0])
        return f" (did you mean {', '.join(hints)}?)" if hints else ""


def count(text: str) -> int:
    """An argparse type for counts and seeds: accepts 1000, 1e3 and 1_000; the option's own check says what range
    it allows, so that --n -5 and --n 0 get the same message."""
    from dwr_gym.validation import as_int

    try:
        return as_int("value", text.replace("_", ""), -(10**12), 10**12, text=True)
    except ValueError:
        raise argparse.ArgumentTypeError(f"invalid value {text!r}: expected an integer, e.g. 1000 or 1e3") from None


def check_writable_dir(flag: str, path: str) -> None:
    """Check, before any work starts, that files can be written in ``path``: in it if it exists, else in the
    nearest folder above it that does (where it will be created once there are results, so that a command that
    stops early leaves no empty folder behind)."""
    import os
    import tempfile
    from pathlib import Path

    out = Path(path).absolute()
    if out.exists() and not out.is_dir():
        raise UsageError(f"{flag} {path!r} is invalid: it is a file, expected a directory")
    existing = next(folder for folder in (out, *out.parents) if folder.exists())
    if not existing.is_dir():
        raise UsageError(f"{flag} {path!r} is invalid: {str(existing)!r} is a file, expected a directory")
    try:
        with tempfile.TemporaryFile(dir=existing):
            pass
    except OSError as error:
        raise UsageError(f"{flag} {path!r} is not writable: {error.strerror or error}") from None
    if not os.access(existing, os.W_OK | os.X_OK):
        raise UsageError(f"{flag} {path!r} is not writable: permission denied")


def add_threads_argument(p: argparse.ArgumentParser) -> None:
    """``--threads N``: torch's thread count while the command runs (:mod:`train.threads`)."""
    p.add_argument("--threads", type=count, default=None, metavar="N",
                   help="torch threads while the command runs; the caller's count is restored afterwards "
                   "(default: 1: a small network waits on a thread pool, most on a busy machine)")  # fmt: skip


def command_threads(args: argparse.Namespace) -> AbstractContextManager[int]:
    """The scope of ``--threads`` (:func:`train.threads.torch_threads`); a bad count is a UsageError."""
    from train.threads import check_threads, torch_threads

    try:
        return torch_threads(check_threads(getattr(args, "threads", None)))
    except ValueError as error:
        raise UsageError(str(error)) from None


def interrupted(rows: list[dict[str, Any]], env_id: str, out: str, stem: str) -> int:
    """After Ctrl-C: the rows of the scenario sets that finished written to ``out``, one line said; exit code 130."""
    from train.reporting.results import write_results

    cached = "the optima solved so far are cached"
    if rows:
        csv_path, json_path = write_results([{"env_id": env_id, **row} for row in rows], out, stem)  # a row's own wins
        counted = f"{len(rows)} row{'s' if len(rows) != 1 else ''}"
        print(f"\ninterrupted: wrote the {counted} finished so far to {csv_path} and {json_path}; {cached}",
              file=sys.stderr)  # fmt: skip
    else:
        print(f"\ninterrupted before the first scenario set finished: no results written; {cached}", file=sys.stderr)
    return 130


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
            try:  # Python literals such as (1.5, 3.0) or None
                value = ast.literal_eval(raw)
            except (ValueError, SyntaxError, MemoryError, RecursionError):
                value = _float_or_text(raw)
        kwargs[key] = tuple(value) if isinstance(value, list) else value
    return kwargs


def _float_or_text(raw: str) -> float | str:
    """``raw`` as a float where Python reads one (nan, inf, -inf, 1e3), so that the check names the number."""
    try:
        return float(raw)
    except ValueError:
        return raw


def add_env_arguments(p: argparse.ArgumentParser, kwargs_example: str = "T_con=25 dt=0.02") -> None:
    """``--env ID`` and ``--env-kwargs KEY=VALUE ...``: the env every command that makes one runs on."""
    from train.env_ids import DEFAULT_ENV_ID, ENV_HELP

    p.add_argument("--env", default=DEFAULT_ENV_ID, metavar="ID", help=f"{ENV_HELP} (default: {DEFAULT_ENV_ID})")
    p.add_argument("--env-kwargs", nargs="*", metavar="KEY=VALUE",
                   help=f"env keywords on top of the env id's, e.g. {kwargs_example}")  # fmt: skip


def add_agents_argument(p: argparse.ArgumentParser, what: str) -> None:
    """``--agents PATH ...``, the one spelling of every command (``--agent PATH``, repeatable, means the same)."""
    p.add_argument("--agents", "--agent", dest="agents", nargs="+", action="extend", metavar="PATH",
                   help=f"saved agents, each a run directory or its model .zip: {what}")  # fmt: skip


def checked_env(args: argparse.Namespace) -> tuple[str, dict[str, Any]]:
    """``--env`` without a ``dwr_gym:`` prefix, and the env's keywords: the id's registered ones, then ``--env-kwargs``."""
    from dwr_gym.serialization import env_kwargs_from_json
    from train.env_ids import check_env_id, env_keywords

    try:
        env_id = check_env_id(args.env)
    except ValueError as error:
        raise UsageError(str(error)) from None
    try:  # disturbances, robot and disturbance_distribution may be given in their JSON form (dwr_gym.serialization)
        kwargs = env_kwargs_from_json(env_keywords(env_id, parse_env_kwargs(args.env_kwargs)))
    except (TypeError, ValueError) as error:
        raise UsageError(f"invalid env keyword: {error}") from None
    validated_env_params(kwargs)
    return env_id, kwargs


def validated_env_params(env_kwargs: dict[str, Any]) -> Any:
    """EnvParams from keywords, turning a ValueError into a UsageError."""
    from dwr_gym.disturbances import split_env_kwargs
    from dwr_gym.params import EnvParams

    try:
        return EnvParams.from_kwargs(**split_env_kwargs(env_kwargs)[0])  # robot= and wheel_saturation= too
    except ValueError as error:
        raise UsageError(f"invalid env keyword: {error}") from error


def checked_optimum(args: argparse.Namespace) -> str:
    """``--optimum``, turned off with a notice when CasADi is not installed."""
    from train.evaluation.optimum import casadi_available

    if args.optimum != "none" and not casadi_available():
        print('note: energy / optimal needs CasADi: pip install "dwr-gym[optimal]"; skipped', file=sys.stderr)
        return "none"
    return str(args.optimum)


def checked_selection(args: argparse.Namespace) -> list[str]:
    """The controllers of ``--controllers`` ('all' expands); validates them, ``--scenarios`` and ``--n``."""
    from baselines.registry import CONTROLLER_NAMES, CONTROLLERS
    from train.evaluation.disturbance_sets import ROBUSTNESS_SETS
    from train.evaluation.optimum import casadi_available
    from train.evaluation.scenarios import SCENARIO_SETS

    if "all" in args.controllers:
        names = [*CONTROLLERS, *(["optimal", "robust-pt"] if casadi_available() else [])]  # both plan with CasADi
    else:
        names = args.controllers
    for name in names:
        if name not in CONTROLLER_NAMES:
            raise UsageError(
                f"--controllers {name!r} is invalid: expected 'all' or any of {', '.join(CONTROLLER_NAMES)}"
            )
        if name == "optimal" and not casadi_available():
            raise UsageError('--controllers optimal needs CasADi: pip install "dwr-gym[optimal]"')
    for T_con in args.T_con or ():
        if not 0.0 < T_con <= 1e6:
            raise UsageError(f"--T-con {T_con} is invalid: expected prescribed times in (0, 1e6] s")
    for name in args.scenarios:
        if name not in SCENARIO_SETS + ROBUSTNESS_SETS:
            raise UsageError(
                f"--scenarios {name!r} is invalid: expected any of {', '.join(SCENARIO_SETS + ROBUSTNESS_SETS)}"
            )
    if not 1 <= args.n <= 10**7:
        raise UsageError(f"--n {args.n} is invalid: expected an integer in [1, 1e7]")
    if not 1 <= args.n_optimal <= 10**7:
        raise UsageError(f"--n-optimal {args.n_optimal} is invalid: expected an integer in [1, 1e7]")
    if not 0 <= args.seed < 2**32:
        raise UsageError(f"--seed {args.seed} is invalid: expected an integer in [0, 2**32 - 1]")
    check_writable_dir("--out", args.out)
    return list(names)


def add_scenario_arguments(p: argparse.ArgumentParser, out: str, sets: Sequence[str] | None = None) -> None:
    """The options shared by ``evaluate`` and ``compare``: the env, the controllers and the scenario sets (by default
    ``sets``, else the scenario sets without disturbances)."""
    from baselines.registry import CONTROLLER_NAMES
    from train.code_paths import CODE_PATHS
    from train.evaluation.disturbance_sets import ROBUSTNESS_SETS
    from train.evaluation.optimum import OPTIMA
    from train.evaluation.scenarios import SCENARIO_SETS

    p.add_argument(
        "--controllers",
        nargs="+",
        default=["all"],
        metavar="NAME",
        help=f"controllers: 'all' or any of {', '.join(CONTROLLER_NAMES)} "
        "(default: all; 'optimal' needs the optimal extra)",
    )
    p.add_argument(
        "--T-con",
        type=float,
        nargs="+",
        metavar="SECONDS",
        help="evaluate at each of these prescribed times, one block each; replaces the env's T_con_range "
        "(default: the scenario's own: drawn per episode by v1's random set, the paper's for paper-fig5/7)",
    )
    p.add_argument("--optimum", choices=OPTIMA, default="pose",
                   help="the optimum of the E/opt columns: minimum energy to the goal 'pose' (default), to the "
                   "'position' only, or 'none'; solved once per episode with CasADi and cached")  # fmt: skip
    p.add_argument(
        "--scenarios",
        nargs="+",
        default=list(sets or SCENARIO_SETS),
        metavar="SET",
        help=f"scenario sets: any of {', '.join(SCENARIO_SETS)}, or the imperfect robots' "
        f"{', '.join(ROBUSTNESS_SETS)} (see the robustness page of the docs) (default: {' '.join(sets or SCENARIO_SETS)})",
    )
    p.add_argument("--n", type=count, default=1000, help="number of random start poses for 'random' (default: 1000)")
    p.add_argument("--n-optimal", type=count, default=50,
                   help="episodes of each disturbed set (disturbed, fault, delay, noise) that the 'optimal' controller "
                   "runs, the first of the n: it re-plans with CasADi whenever pushed off its plan (default: 50)")  # fmt: skip
    p.add_argument("--seed", type=count, default=0, help="seed of the random scenario set (default: 0)")
    p.add_argument("--out", default=out, help=f"output directory (default: {out})")
    p.add_argument("--code-paths", choices=CODE_PATHS, default=CODE_PATHS[0],
                   help="'portable' (default): numpy's, libm's, MKL's and torch's kernels limited to those every x86-64 "
                   "CPU runs, so the tables are the same on any such CPU (the command line re-runs itself once with "
                   "them set; a little slower); 'native': the fastest kernels this CPU has (docs/controllers.md)")  # fmt: skip
    p.add_argument(
        "--no-progress",
        action="store_true",
        help="no progress bar (where stderr is not a terminal: a plain line every 10 %% of the work)",
    )
    p.add_argument("--address", default=None, metavar="ADDRESS",
                   help="solve the optima, and run each policy on each set, as Ray tasks on this cluster: 'auto' "
                   "joins a running one (as dwr-gym sweep does), 'local' starts one here (default: local processes; "
                   "needs the sweep extra)")  # fmt: skip
    add_threads_argument(p)
    add_env_arguments(p)


def check_agent_paths(paths: Sequence[str] | None, flag: str = "--agents") -> list[str]:
    """Before any heavy import: every item of ``--agents`` is a path that exists or a shipped agent's name (``apg-v2``,
    ``train/pretrained/apg_v2``), else a UsageError naming the agents shipped with dwr-gym (a path that a user copied
    from an older version's docs is the common case). Returns the paths, a shipped agent's name resolved."""
    from pathlib import Path

    from train.learning.agents import not_shipped_note, shipped_agent

    resolved = []
    for path in paths or ():
        if Path(path).exists():
            resolved.append(path)
        elif (shipped := shipped_agent(path)) is not None:
            resolved.append(str(shipped))
        else:
            raise UsageError(f"{flag} {str(path)!r} is invalid: {not_shipped_note(path)}")
    return resolved


def load_agents(paths: Sequence[str] | None, env_id: str | None = None) -> dict[str, Any]:
    """Saved agents by label (the file's stem); a missing or unreadable file is a UsageError.

    With ``env_id``, a note on stderr names the agents trained on another env than the one they will run on.
    """
    if not paths:
        return {}
    from train.learning.agents import AgentLoadError, load_agent, trained_env_id

    agents, elsewhere = {}, {}
    for path in paths:
        try:
            label, agent = load_agent(path)
            trained = trained_env_id(path)
        except AgentLoadError as error:
            raise UsageError(str(error)) from error
        agents[label] = agent
        if env_id is not None and trained != env_id:
            elsewhere.setdefault(trained, []).append(label)
    for trained, labels in elsewhere.items():
        print(f"note: {', '.join(labels)} trained on {trained}, run here on {env_id}", file=sys.stderr)
    return agents

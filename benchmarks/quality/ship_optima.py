"""Ship the optima of `dwr-gym compare`'s and `dwr-gym evaluate`'s default scenario sets as package data.

    python -m benchmarks run ship-optima            # solve (or read from the cache) and write train/optima/
    dwr-gym optimum verify                          # then: every shipped optimum solved again and compared

The default sets are read from the commands' own parsers (their defaults: scenario sets, n, seed, env id, optimum),
so that a change of a default changes what is shipped (tests/test_shipped_optima.py checks that the shipped files
hold exactly these keys). Each optimum is solved as `compare` solves it, through the user's cache
(:func:`train.evaluation.optimum.optimal_energies`) with the shipped ones turned off, so that nothing shipped is
copied from an earlier shipped file; ``--fresh`` solves in an empty cache.
"""

from __future__ import annotations

import os
import tempfile
from collections import defaultdict
from typing import Any

from benchmarks.core.commands import parser_for

#: The commands whose defaults are shipped.
COMMANDS = ("compare", "evaluate")


def default_scenarios() -> list[tuple[Any, Any, str]]:
    """(scenario, its EnvParams, optimum) of every default set of :data:`COMMANDS`, as their parsers give them."""
    from dwr_gym.disturbances import split_env_kwargs
    from dwr_gym.params import EnvParams
    from train.cli import build_parser
    from train.commands.shared import checked_env
    from train.evaluation.scenarios import make_scenario

    found = []
    for command in COMMANDS:
        args = build_parser().parse_args([command])
        _, env_kwargs = checked_env(args)
        for name in args.scenarios:
            for T_con in args.T_con or [None]:
                kwargs = env_kwargs if T_con is None else {**env_kwargs, "T_con": T_con, "T_con_range": None}
                scenario = make_scenario(name, n=args.n, seed=args.seed, env_kwargs=kwargs)
                params = EnvParams.from_kwargs(**split_env_kwargs(scenario.env_kwargs)[0])
                found.append((scenario, params, args.optimum))
    return found


def default_keys() -> dict[str, tuple[dict[str, Any], set[str]]]:
    """The shipped file's name -> (its problem, the keys the default sets read in it)."""
    from train.evaluation.optimum import cache_keys

    files: dict[str, tuple[dict[str, Any], set[str]]] = {}
    for scenario, params, optimum in default_scenarios():
        if optimum == "none":
            continue
        name, problem, keys = cache_keys(params, scenario.starts, scenario.goals, scenario.T_cons,
                                         heading=optimum == "pose")  # fmt: skip
        files.setdefault(name, (problem, set()))[1].update(keys)
    return files


def ship(progress: bool = True) -> dict[str, int]:
    """Solve (or read from the user's cache) every default set's optimum and write train/optima/; returns the optima
    written per file."""
    from train.evaluation.optimum import cache_keys, optimal_energies
    from train.evaluation.shipped_optima import SHIPPED_DIR, SWITCH, write_shipped

    os.environ[SWITCH] = "0"  # solved (or read from the user's cache), never copied from the shipped files
    energies: dict[str, dict[str, float]] = defaultdict(dict)
    problems: dict[str, dict[str, Any]] = {}
    failures = []
    for scenario, params, optimum in default_scenarios():
        if optimum == "none":
            continue
        heading = optimum == "pose"
        solved, failed = optimal_energies(params, scenario.starts, scenario.goals, scenario.T_cons, heading=heading,
                                          progress=progress, description=f"{scenario.name}: optimum")  # fmt: skip
        name, problem, keys = cache_keys(params, scenario.starts, scenario.goals, scenario.T_cons, heading=heading)
        problems[name] = problem
        failures += [f"{scenario.name} {f}" for f in failed]
        energies[name].update({k: float(e) for k, e in zip(keys, solved, strict=True) if e == e})  # not NaN
    for old in SHIPPED_DIR.glob("optimal-energy-*.json"):
        if old.name not in energies:
            old.unlink()
    for name, values in energies.items():
        write_shipped(SHIPPED_DIR / name, problems[name], values)
    for line in failures:
        print(f"not shipped (no optimum): {line}")
    return {name: len(values) for name, values in energies.items()}


def main(argv: list[str] | None = None) -> None:
    parser = parser_for("ship-optima", __doc__)
    parser.add_argument("--fresh", action="store_true", help="solve every optimum in an empty cache")
    parser.add_argument("--no-progress", action="store_true", help="no progress bars")
    args = parser.parse_args(argv)
    if args.fresh:
        with tempfile.TemporaryDirectory() as tmp:
            os.environ["DWR_GYM_CACHE"] = tmp
            written = ship(not args.no_progress)
    else:
        written = ship(not args.no_progress)
    for name, count in written.items():
        print(f"wrote train/optima/{name}: {count} optima")

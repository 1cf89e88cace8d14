"""The ``dwr-gym`` command line: ``info``, ``evaluate``, ``reproduce``, ``train``, ``compare``, ``imitate``.

Every subcommand validates its input before doing any work; bad input ends with a one-line
error on stderr and exit code 2.
"""

from __future__ import annotations

import argparse
import ast
import json
import platform
import sys
from collections.abc import Sequence
from typing import Any, NoReturn


class UsageError(Exception):
    """Bad user input: printed as one line, exit code 2."""


class Parser(argparse.ArgumentParser):
    """An ArgumentParser whose errors are one line (no usage block), exit code 2, like every other bad input."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def count(text: str) -> int:
    """An argparse type for counts and seeds: accepts 1000, 1e3 and 1_000."""
    from dwr_gym.validation import as_int

    try:
        return as_int("value", text.replace("_", ""), 0, 10**12, text=True)
    except ValueError:
        raise argparse.ArgumentTypeError(f"invalid value {text!r}: expected a non-negative integer") from None


def check_writable_dir(flag: str, path: str) -> None:
    """Create ``path`` if needed and check a file can be written in it, before any work starts."""
    import tempfile
    from pathlib import Path

    out = Path(path)
    if out.exists() and not out.is_dir():
        raise UsageError(f"{flag} {path!r} is invalid: it is a file, expected a directory")
    try:
        out.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile(dir=out):
            pass
    except OSError as error:
        raise UsageError(f"{flag} {path!r} is not writable: {error.strerror or error}") from None


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
                value = raw
        kwargs[key] = tuple(value) if isinstance(value, list) else value
    return kwargs


def validated_env_params(env_kwargs: dict[str, Any]) -> Any:
    """EnvParams from keywords, turning a ValueError into a UsageError."""
    from dwr_gym.disturbances import split_env_kwargs
    from dwr_gym.params import EnvParams

    try:
        return EnvParams.from_kwargs(**split_env_kwargs(env_kwargs)[0])  # robot= and wheel_saturation= too
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


def format_table(rows: list[dict[str, Any]], columns: list[tuple[str, str, str]]) -> str:
    """Rows as an aligned text table; ``columns`` are (key, header, format)."""
    cells = [[header for _, header, _ in columns]]
    for row in rows:
        cells.append(
            [format(row[key], fmt) if isinstance(row[key], float) else str(row[key]) for key, _, fmt in columns]
        )
    widths = [max(len(r[i]) for r in cells) for i in range(len(columns))]
    lines = [
        "  ".join(c.rjust(w) if i else c.ljust(w) for i, (c, w) in enumerate(zip(r, widths, strict=True)))
        for r in cells
    ]
    lines.insert(1, "-" * len(lines[0]))
    return "\n".join(lines)


EVAL_COLUMNS = [
    ("scenario", "scenario", ""),
    ("T_con", "T_con", ".0f"),
    ("policy", "policy", ""),
    ("n", "n", ".0f"),
    ("success_rate", "success", ".3f"),
    ("arrival_time_mean", "t_arr mean", ".2f"),
    ("arrival_time_max", "t_arr max", ".2f"),
    ("arrival_fraction_max", "t_arr/T max", ".3f"),
    ("final_distance_max", "d_end max", ".4f"),
    ("final_heading_error_mean", "|psi_end| mean", ".3f"),
    ("peak_u_max", "peak u", ".3f"),
    ("peak_omega_max", "peak w", ".3f"),
    ("energy_mean", "energy", ".3f"),
    ("energy_ratio_mean", "E/opt mean", ".2f"),
    ("energy_ratio_max", "E/opt max", ".2f"),
    ("path_length_mean", "path", ".3f"),
    ("command_rate_rms_mean", "rate rms", ".3f"),
]


def json_safe(value: Any) -> Any:
    """``value`` with NaN and inf as null (bare NaN is not JSON) and numpy scalars as Python numbers."""
    import math

    if isinstance(value, dict):
        return {str(k): json_safe(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [json_safe(v) for v in value]
    if hasattr(value, "item") and not isinstance(value, (str, bytes)):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


FAILS_BY_DESIGN = {
    "fabregas": "fabregas is the slow law of ref. [9] (u = K0 d p, not prescribed-time): the paper compares it at "
    "T_con = 70 s (paper-fig7); it cannot arrive within T_con = 20 s, so its success there is 0 % by design",
}


def table_notes(rows: list[dict[str, Any]]) -> str:
    """One line per policy whose low success rate the table alone would not explain."""
    failing = {row["policy"] for row in rows if row["policy"] in FAILS_BY_DESIGN and row["success_rate"] < 0.5}
    return "\n".join(f"note: {FAILS_BY_DESIGN[name]}" for name in sorted(failing))


def write_results(rows: list[dict[str, Any]], out_dir: str, stem: str) -> list[str]:
    """Write rows as CSV and JSON into ``out_dir``; returns the paths written."""
    import csv
    from pathlib import Path

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    csv_path, json_path = out / f"{stem}.csv", out / f"{stem}.json"
    with csv_path.open("w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    json_path.write_text(json.dumps(json_safe(rows), indent=2, allow_nan=False) + "\n")
    return [str(csv_path), str(json_path)]


def print_blocks(rows: list[dict[str, Any]], columns: list[tuple[str, str, str]]) -> None:
    """The table, one block per (scenario, T_con), with a note under policies that fail by design."""

    def block_of(row: dict[str, Any]) -> str:
        T_con = row["T_con"]
        return f"{row['scenario']}, " + ("T_con drawn per episode" if T_con != T_con else f"T_con = {T_con:g} s")

    blocks: dict[str, list[dict[str, Any]]] = {}
    for row in rows:
        blocks.setdefault(block_of(row), []).append(row)
    for title, block in blocks.items():
        print(f"\n{title}")
        print(format_table(block, columns))
    noted = {block_of(r): r for r in rows if r.get("optimum_failures")}
    for title, row in noted.items():
        print(f"note: {title}: {row['optimum_failures']:.0f} episode(s) have no optimum (E/opt is nan there); "
              f"the first: {row['optimum_note']}")  # fmt: skip
    if any(row.get("planner_failures") for row in rows):
        print("note: the optimal controller found no plan for some robots (planner_failures in the JSON); "
              "they stood still and count as failures")  # fmt: skip
    if any(row["optimal_energy_mean"] == row["optimal_energy_mean"] for row in rows):  # not NaN
        print("E/opt: energy / minimum energy to the goal pose by T_con, over the episodes that succeeded")
    if any(row["policy"] == "fabregas" and row["success_rate"] == 0.0 for row in rows):
        print("fabregas: the slow law of ref. [9], which the paper compares at T_con = 70 s (paper-fig7); "
              "it is not designed to arrive by a shorter T_con")  # fmt: skip


def checked_optimum(args: argparse.Namespace) -> str:
    """``--optimum``, turned off with a notice when CasADi is not installed."""
    from train.optimum import casadi_available

    if args.optimum != "none" and not casadi_available():
        print('note: energy / optimal needs CasADi: pip install "dwr-gym[optimal]"; skipped', file=sys.stderr)
        return "none"
    return str(args.optimum)


def checked_selection(args: argparse.Namespace) -> list[str]:
    """The controllers of ``--controllers`` ('all' expands); validates them, ``--scenarios`` and ``--n``."""
    from baselines.controllers import CONTROLLER_NAMES, CONTROLLERS
    from train.evaluation import ROBUSTNESS_SETS, SCENARIO_SETS
    from train.optimum import casadi_available

    if "all" in args.controllers:
        names = [*CONTROLLERS, *(["optimal"] if casadi_available() else [])]
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
    if not 0 <= args.seed < 2**32:
        raise UsageError(f"--seed {args.seed} is invalid: expected an integer in [0, 2**32 - 1]")
    check_writable_dir("--out", args.out)
    return list(names)


def add_scenario_arguments(p: argparse.ArgumentParser, out: str) -> None:
    """The options shared by ``evaluate`` and ``compare``."""
    from baselines.controllers import CONTROLLER_NAMES
    from train.evaluation import ROBUSTNESS_SETS, SCENARIO_SETS
    from train.optimum import OPTIMA

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
        help="evaluate at each of these prescribed times, one block each (default: the scenario's own)",
    )
    p.add_argument("--optimum", choices=OPTIMA, default="pose",
                   help="the optimum of the E/opt columns: minimum energy to the goal 'pose' (default), to the "
                   "'position' only, or 'none'; solved once per episode with CasADi and cached")  # fmt: skip
    p.add_argument(
        "--scenarios",
        nargs="+",
        default=list(SCENARIO_SETS),
        metavar="SET",
        help=f"scenario sets: any of {', '.join(SCENARIO_SETS)} (default: these), or the imperfect robots' "
        f"{', '.join(ROBUSTNESS_SETS)} (see 'Robustness' in the README)",
    )
    p.add_argument("--n", type=count, default=1000, help="number of random start poses for 'random' (default: 1000)")
    p.add_argument("--seed", type=int, default=0, help="seed of the random scenario set (default: 0)")
    p.add_argument("--out", default=out, help=f"output directory (default: {out})")
    p.add_argument("--no-progress", action="store_true", help="no progress bars")  # fmt: skip


def cmd_evaluate(args: argparse.Namespace) -> int:
    """Evaluate controllers (and saved agents) on named scenario sets."""
    env_kwargs = parse_env_kwargs(args.env_kwargs)
    validated_env_params(env_kwargs)
    names = checked_selection(args)
    policies: dict[str, Any] = {name: name for name in names}
    policies.update(load_agents(args.agent))
    from train.evaluation import evaluate_sets

    rows = evaluate_sets(policies, args.scenarios, args.n, args.seed, env_kwargs, progress=not args.no_progress,
                          optimum=checked_optimum(args), T_cons=args.T_con)  # fmt: skip
    print_blocks(rows, EVAL_COLUMNS)
    if table_notes(rows):
        print(table_notes(rows))
    for path in write_results(rows, args.out, "evaluation"):
        print(f"wrote {path}")
    return 0


def load_agents(paths: Sequence[str] | None) -> dict[str, Any]:
    """Saved agents by label (the file's stem); a missing or unreadable file is a UsageError."""
    if not paths:
        return {}
    from train.agents import AgentLoadError, load_agent

    agents = {}
    for path in paths:
        try:
            label, agent = load_agent(path)
        except AgentLoadError as error:
            raise UsageError(str(error)) from error
        agents[label] = agent
    return agents


def add_evaluate_parser(sub: Any) -> None:
    """The ``evaluate`` subcommand."""

    p = sub.add_parser("evaluate", help="evaluate controllers and agents on named scenario sets")
    add_scenario_arguments(p, "results/evaluate")
    p.add_argument("--agent", action="append", metavar="PATH", help="a saved agent (.zip) to evaluate too; repeatable")
    p.add_argument("--env-kwargs", nargs="*", metavar="KEY=VALUE", help="env keywords, e.g. T_con=25 dt=0.02")
    p.set_defaults(func=cmd_evaluate)  # fmt: skip


def cmd_reproduce(args: argparse.Namespace) -> int:
    """Regenerate the paper's figures and the report of its claims."""
    from train.reproduce import reproduce

    if not 0.0 < args.dt <= 0.1:
        raise UsageError(f"--dt {args.dt} is invalid: expected a control period in (0, 0.1] s")
    try:
        import matplotlib  # noqa: F401
    except ImportError as error:
        raise UsageError('matplotlib is not installed: pip install "dwr-gym[plots]"') from error
    check_writable_dir("--out", args.out)
    claims = reproduce(args.out, dt=args.dt, gif=not args.no_gif)
    width = max(len(c.verdict) for c in claims)
    for claim in claims:
        print(f"[{claim.verdict:<{width}}] {claim.claim}\n    {claim.measured}")
    print(f"wrote figures and report.md to {args.out}")
    return 0


def add_reproduce_parser(sub: Any) -> None:
    """The ``reproduce`` subcommand."""
    p = sub.add_parser("reproduce", help="regenerate the paper's Figures 5-9 and a report of its claims")
    p.add_argument("--out", default="results/reproduce", help="output directory (default: results/reproduce)")
    p.add_argument("--dt", type=float, default=0.01, help="control period of the simulation [s] (default: 0.01)")
    p.add_argument("--no-gif", action="store_true", help="skip the animated GIF")
    p.set_defaults(func=cmd_reproduce)


def add_train_parser(sub: Any) -> None:
    """The ``train`` subcommand, generated from the fields of :class:`train.config.TrainConfig`."""
    import dataclasses

    from train.config import TrainConfig

    p = sub.add_parser("train", help="train a PPO/SAC/TD3 agent, plain or residual on the PTC expert",
                       description="Options left out take the YAML file's value, else the default shown.")  # fmt: skip
    for f in dataclasses.fields(TrainConfig):
        if f.metadata.get("cli") is False:
            continue
        flag = "--" + f.name.replace("_", "-")
        default = f.default if f.default is not dataclasses.MISSING else "{}"
        text = f"{f.metadata['help']} (default: {default})"
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
            p.add_argument(flag, default=argparse.SUPPRESS, help=text)
    p.set_defaults(func=cmd_train)


def split_hyperparams(items: Sequence[str]) -> tuple[str | None, list[str]]:
    """``--hyperparams`` items: at most one YAML file, and KEY=VALUE (or KEY:VALUE) overrides."""
    from pathlib import Path

    files = [item for item in items if "=" not in item and (":" not in item or Path(item).is_file())]
    if len(files) > 1:
        raise UsageError(f"--hyperparams {files!r} is invalid: expected at most one YAML file")
    return (files[0] if files else None), [item for item in items if item not in files]


def cmd_train(args: argparse.Namespace) -> int:
    """Train an agent; bad input ends before any training starts."""
    from train.config import ConfigError, TrainConfig, parse_overrides, resolve_hyperparams

    given = {k: v for k, v in vars(args).items() if k not in ("func", "command")}
    if "env_kwargs" in given:
        given["env_kwargs"] = parse_env_kwargs(given["env_kwargs"])
    try:
        import stable_baselines3  # noqa: F401
    except ImportError as error:
        raise UsageError('stable-baselines3 is not installed: pip install "dwr-gym[train]"') from error
    from train.training import RunDirError, resume_config, train

    try:
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


def add_compare_parser(sub: Any) -> None:
    """The ``compare`` subcommand."""

    p = sub.add_parser("compare", help="compare trained agents with the PTC expert and the other controllers")
    add_scenario_arguments(p, "results/compare")
    p.add_argument("--agents", nargs="+", metavar="PATH",
                   help="run directories or model .zip files (default: the pretrained agents shipped with dwr-gym)")  # fmt: skip
    p.set_defaults(func=cmd_compare)  # fmt: skip


def cmd_compare(args: argparse.Namespace) -> int:
    """Evaluate agents and controllers on the same scenarios; print the table, write CSV, JSON and plots."""
    from pathlib import Path

    controllers = checked_selection(args)
    try:
        import matplotlib  # noqa: F401
        import stable_baselines3  # noqa: F401
    except ImportError as error:
        raise UsageError(f'{error.name} is not installed: pip install "dwr-gym[train,plots]"') from error
    from train.agents import AgentLoadError, find_run_dir, pretrained_paths
    from train.compare import compare

    paths = [Path(p) for p in args.agents] if args.agents else list(pretrained_paths().values())
    if not paths:
        raise UsageError("no agents given and no pretrained agent is installed: pass --agents PATH")
    agents = load_agents([str(p) for p in paths])
    run_dirs = {}
    for label, path in zip(agents, paths, strict=True):
        try:
            run_dirs[label] = find_run_dir(path if path.is_dir() else path.parent)
        except AgentLoadError:
            pass
    rows = compare(agents, run_dirs, controllers, args.scenarios, args.n, args.seed, Path(args.out),
                   progress=not args.no_progress, optimum=checked_optimum(args), T_cons=args.T_con)  # fmt: skip
    print_blocks(rows, EVAL_COLUMNS)
    if table_notes(rows):
        print(table_notes(rows))
    for path in write_results(rows, args.out, "comparison"):
        print(f"wrote {path}")
    for name in ("trajectories.png", "time_series.png", "learning_curves.png"):
        if (Path(args.out) / name).exists():
            print(f"wrote {Path(args.out) / name}")
    return 0


def add_imitate_parser(sub: Any) -> None:
    """The ``imitate`` subcommand, generated from :class:`train.imitation.ImitationConfig`."""
    import dataclasses

    from train.imitation import ImitationConfig

    p = sub.add_parser("imitate", help="clone the optimal planner into a network policy for any T_con",
                       description="Record the optimal controller on DWRPointStabilization-v1's task and fit a PPO "
                       "MlpPolicy to its actions (behaviour cloning with noise injection).")  # fmt: skip
    for f in dataclasses.fields(ImitationConfig):
        flag = "--" + f.name.replace("_", "-")
        if isinstance(f.default, tuple):
            kind = int if f.name == "net_arch" else float
            p.add_argument(flag, type=kind, nargs="+", default=argparse.SUPPRESS,
                           help=f"{f.metadata['help']} (default: {' '.join(map(str, f.default))})")  # fmt: skip
        else:
            p.add_argument(flag, type=type(f.default), default=argparse.SUPPRESS,
                           help=f"{f.metadata['help']} (default: {f.default})")  # fmt: skip
    p.add_argument("--run-dir", default=None, help="output directory (default: runs/bc-optimal-seed<seed>)")
    p.add_argument("--no-progress", action="store_true", help="no progress bars")
    p.set_defaults(func=cmd_imitate)


def cmd_imitate(args: argparse.Namespace) -> int:
    """Behaviour cloning of the optimal controller; bad input ends before any work starts."""
    from pathlib import Path

    from train.imitation import ImitationConfig, imitate
    from train.optimum import casadi_available

    given = {k: v for k, v in vars(args).items() if k not in ("func", "command", "run_dir", "no_progress")}
    for key in ("T_con_range", "start_distance", "net_arch"):
        if key in given:
            given[key] = tuple(given[key])
    config = ImitationConfig(**given)
    positive = {"episodes": 1, "epochs": 1, "batch_size": 1, "eval_episodes": 1, "eval_every": 1}
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
    validated_env_params({"T_con_range": config.T_con_range, "start_distance": config.start_distance})
    if not casadi_available():
        raise UsageError('imitate needs the optimal planner (CasADi): pip install "dwr-gym[optimal]"')
    try:
        import stable_baselines3  # noqa: F401
    except ImportError as error:
        raise UsageError('stable-baselines3 is not installed: pip install "dwr-gym[train]"') from error
    run_dir = Path(args.run_dir or f"runs/bc-optimal-seed{config.seed}")
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


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of ``dwr-gym``."""
    parser = Parser(prog="dwr-gym", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    info = sub.add_parser("info", help="versions, the registered env and its defaults")
    info.set_defaults(func=cmd_info)
    add_evaluate_parser(sub)
    add_reproduce_parser(sub)
    add_train_parser(sub)
    add_compare_parser(sub)
    add_imitate_parser(sub)
    from train.sweep import add_sweep_parser  # dwr-gym sweep on Ray Tune (train/sweep.py)

    add_sweep_parser(sub)
    from train.robustness import add_robustness_parser

    add_robustness_parser(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``dwr-gym`` console script."""
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args))
    except UsageError as error:
        print(f"dwr-gym {args.command}: error: {error}", file=sys.stderr)
        return 2
    except OSError as error:  # e.g. a disk that fills up or a directory removed during the run
        print(f"dwr-gym {args.command}: error: {error}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    from train.cli import main as package_main  # the package's module: one UsageError class for all subcommands

    sys.exit(package_main())

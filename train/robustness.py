"""``dwr-gym robustness``: sweep each disturbance's magnitude and measure who still arrives by T_con.

For every disturbance of :data:`SWEEPS` and each of its magnitudes, every controller and agent is
run from the same seeded random start poses (the 'random' set) on the imperfect robot. The result
is one row per (disturbance, magnitude, policy) with the metrics of
:meth:`train.evaluation.RolloutResult.summary`, one figure per disturbance (success by T_con and
final distance against the magnitude), and the table of the largest magnitude up to which each
policy still succeeds in at least 95 % of the episodes.
"""

from __future__ import annotations

import argparse
import json
import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from dwr_gym.disturbances import (
    ActuatorFault,
    InputDelay,
    MeasurementDropout,
    VelocityBias,
    VelocityRandomWalk,
    VelocitySinusoid,
    WheelSlip,
)
from train.disturbance_sets import UNLIMITED_BURGER
from train.evaluation import Policy, Scenario, evaluate, make_scenario

#: Success rate that counts as "still arrives by T_con".
SUCCESS_LEVEL = 0.95


@dataclass(frozen=True)
class Sweep:
    """One disturbance swept over its magnitudes; ``env_kwargs(magnitude, T_con)`` builds the robot."""

    name: str
    magnitude: str
    """What the magnitude is, with its unit (the figure's x label)."""
    magnitudes: tuple[float, ...]
    env_kwargs: Callable[[float, float], dict[str, Any]]


SWEEPS: dict[str, Sweep] = {
    sweep.name: sweep
    for sweep in (
        Sweep("bias", "constant angular velocity bias [rad/s]", (0.0, 0.1, 0.2, 0.5, 1.0, 1.5),
              lambda m, T: {"disturbances": [VelocityBias(angular=m)]}),
        Sweep("sinusoid", "amplitude of a 4 s sinusoid on u [m/s] (and 4x on omega [rad/s])",
              (0.0, 0.1, 0.2, 0.3, 0.4, 0.5),
              lambda m, T: {"disturbances": [VelocitySinusoid(m, 4.0 * m, period=4.0)]}),
        Sweep("random-walk", "random-walk intensity on omega [rad/s/sqrt(s)] (u: a quarter of it in m/s)",
              (0.0, 0.025, 0.05, 0.1, 0.2, 0.4),
              lambda m, T: {"disturbances": [VelocityRandomWalk(m / 4.0, m)]}),
        Sweep("slip", "slip of both wheels: 1 - efficiency [-]", (0.0, 0.2, 0.4, 0.6, 0.7, 0.8),
              lambda m, T: {"robot": UNLIMITED_BURGER, "disturbances": [WheelSlip(1.0 - m, 1.0 - m)]}),
        Sweep("fault", "right motor's lost fraction from T_con/4 [-]", (0.0, 0.25, 0.5, 0.6, 0.75, 0.9),
              lambda m, T: {"robot": UNLIMITED_BURGER,
                            "disturbances": [ActuatorFault("right", 1.0 - m, start_time=T / 4.0)]}),
        Sweep("delay", "input delay [control periods of 0.05 s]", (0, 4, 8, 16, 24, 32),
              lambda m, T: {"disturbances": [InputDelay(int(m))]}),
        Sweep("dropout", "probability of a lost pose measurement [-]", (0.0, 0.5, 0.75, 0.9, 0.95, 0.98),
              lambda m, T: {"disturbances": [MeasurementDropout(m)]}),
        Sweep("noise", "pose measurement noise, std [m and rad]", (0.0, 0.01, 0.02, 0.05, 0.1, 0.2),
              lambda m, T: {"observation_noise": m}),
    )
}  # fmt: skip


def sweep(
    policies: dict[str, Policy | str],
    names: list[str] | tuple[str, ...],
    n: int = 200,
    seed: int = 0,
    env_kwargs: dict[str, Any] | None = None,
    progress: bool = False,
    log: Callable[[str], None] | None = None,
    n_optimal: int = 20,
) -> list[dict[str, Any]]:
    """Rows (disturbance, magnitude, policy, metrics...) of each sweep in ``names`` over its magnitudes.

    The ``optimal`` controller (one CasADi plan per robot and re-plan, about 1 s per disturbed
    episode) runs on the first ``n_optimal`` of the ``n`` start poses.
    """
    base = make_scenario("random", n=n, seed=seed, env_kwargs=env_kwargs)
    T_con = float(base.env_kwargs.get("T_con", 20.0))
    few = min(n, n_optimal)
    groups: list[tuple[dict[str, Policy | str], int]] = [
        ({k: v for k, v in policies.items() if k != "optimal"}, n),
        ({"optimal": "optimal"}, few),
    ]
    rows = []
    for name in names:
        spec = SWEEPS[name]
        for magnitude in spec.magnitudes:
            kwargs = {**base.env_kwargs, **spec.env_kwargs(magnitude, T_con)}
            results = {}
            for group, size in groups:
                if group and (group.keys() != {"optimal"} or "optimal" in policies):
                    scenario = Scenario(f"{name}={magnitude:g}", base.starts[:size], base.goals[:size], kwargs)
                    results.update(evaluate(group, scenario, seed=seed, progress=progress))
            for label, result in results.items():
                summary = result.summary()
                rows.append({"disturbance": name, "magnitude": float(magnitude), "policy": label,
                             "T_con": result.params.T_con, **summary})  # fmt: skip
                if log is not None:
                    log(f"{name:12s} {magnitude:6g} {label:18s} success {summary['success_rate']:.3f}  "
                        f"d_end mean {summary['final_distance_mean']:.4f}")  # fmt: skip
    return rows


def tolerated(rows: list[dict[str, Any]], level: float = SUCCESS_LEVEL) -> dict[tuple[str, str], float | None]:
    """(disturbance, policy) -> the largest magnitude up to which every swept magnitude had success >= level.

    None where the policy falls below ``level`` already without the disturbance (magnitude 0).
    """
    table: dict[tuple[str, str], float | None] = {}
    for key in dict.fromkeys((row["disturbance"], row["policy"]) for row in rows):
        points = sorted((row["magnitude"], row["success_rate"]) for row in rows
                        if (row["disturbance"], row["policy"]) == key)  # fmt: skip
        best = None
        for magnitude, rate in points:
            if rate < level:
                break
            best = magnitude
        table[key] = best
    return table


def tolerance_markdown(rows: list[dict[str, Any]], level: float = SUCCESS_LEVEL) -> str:
    """The tolerance table as Markdown: one row per disturbance, one column per policy.

    A cell "0.2" means success >= level at every swept magnitude up to 0.2; a trailing "+" that the
    policy held up to the largest magnitude swept; "-" that it is below the level even undisturbed;
    an empty cell that it was not run on that disturbance.
    """
    table = tolerated(rows, level)
    policies = list(dict.fromkeys(row["policy"] for row in rows))
    disturbances = list(dict.fromkeys(row["disturbance"] for row in rows))
    sizes = {row["policy"]: int(row["n"]) for row in rows}
    header = " | ".join(f"{policy} (n={sizes[policy]})" for policy in policies)
    lines = [f"| disturbance (magnitude) | {header} |", "|---" * (len(policies) + 1) + "|"]
    for name in disturbances:
        largest = max(row["magnitude"] for row in rows if row["disturbance"] == name)
        cells = []
        for policy in policies:
            value = table.get((name, policy), math.inf)  # inf: not run on this disturbance
            cells.append(
                "" if value == math.inf else "-" if value is None else f"{value:g}" + ("+" if value == largest else "")
            )
        lines.append(f"| {name} ({SWEEPS[name].magnitude if name in SWEEPS else ''}) | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def plot(rows: list[dict[str, Any]], out_dir: Path) -> list[Path]:
    """One PNG per disturbance: success by T_con and mean final distance against the magnitude."""
    from train.plotting import pyplot, save

    plt = pyplot()
    paths = []
    for name in dict.fromkeys(row["disturbance"] for row in rows):
        fig, (ax_success, ax_error) = plt.subplots(1, 2, figsize=(11, 4))
        for policy in dict.fromkeys(row["policy"] for row in rows):
            points = sorted((r["magnitude"], r["success_rate"], r["final_distance_mean"]) for r in rows
                            if r["disturbance"] == name and r["policy"] == policy)  # fmt: skip
            magnitude, success, error = (np.array(column) for column in zip(*points, strict=True))
            style = "--" if "ppo" in policy else "-"
            ax_success.plot(magnitude, success, style, marker="o", label=policy)
            ax_error.plot(magnitude, np.maximum(error, 1e-4), style, marker="o", label=policy)
        ax_success.axhline(SUCCESS_LEVEL, color="grey", lw=0.8, ls=":")
        ax_success.set(xlabel=SWEEPS[name].magnitude if name in SWEEPS else name, ylabel="success by T_con",
                       ylim=(-0.02, 1.02), title=f"{name}: arrival by T_con")  # fmt: skip
        ax_error.set(xlabel=SWEEPS[name].magnitude if name in SWEEPS else name, ylabel="final distance, mean [m]",
                     yscale="log", title=f"{name}: final distance")  # fmt: skip
        ax_error.legend(fontsize=8)
        path = out_dir / f"robustness_{name}.png"
        save(fig, path)
        paths.append(path)
    return paths


def cmd_robustness(args: argparse.Namespace) -> int:
    """Sweep disturbances for the controllers and agents; print the tolerance table, write CSV, JSON, PNG, MD."""
    from train.cli import (
        UsageError,
        checked_selection,
        load_agents,
        parse_env_kwargs,
        validated_env_params,
        write_results,
    )

    out = Path(args.out)
    if args.from_json:  # tables and figures of earlier runs, e.g. of disturbances swept in parallel
        rows = []
        for path in args.from_json:
            try:
                rows += json.loads(Path(path).read_text())
            except (OSError, ValueError) as error:
                raise UsageError(f"--from-json {path!r} is invalid: {error}") from error
        return report(rows, out, args.no_plots)
    env_kwargs = parse_env_kwargs(args.env_kwargs)
    validated_env_params(env_kwargs)
    for name in args.disturbances:
        if name not in SWEEPS:
            raise UsageError(f"--disturbances {name!r} is invalid: expected any of {', '.join(SWEEPS)}")
    args.scenarios, args.T_con = [], None
    policies: dict[str, Any] = {name: name for name in checked_selection(args)}
    if not args.no_shipped_agents:
        from train.agents import load_agent, pretrained_paths

        policies.update(dict(load_agent(path) for path in pretrained_paths().values()))
    policies.update(load_agents(args.agent))
    if args.n_optimal < 1:
        raise UsageError(f"--n-optimal {args.n_optimal} is invalid: expected an integer >= 1")
    rows: list[dict[str, Any]] = []
    for name in args.disturbances:  # the rows so far are saved after each disturbance: a long sweep can be cut short
        rows += sweep(policies, [name], n=args.n, seed=args.seed, env_kwargs=env_kwargs,
                      progress=not args.no_progress, log=print, n_optimal=args.n_optimal)  # fmt: skip
        write_results(rows, str(out), "robustness")
    return report(rows, out, args.no_plots)


def report(rows: list[dict[str, Any]], out: Path, no_plots: bool) -> int:
    """Print the tolerance table; write the rows (CSV, JSON), the table (Markdown) and the figures."""
    from train.cli import write_results

    keys = list(dict.fromkeys(key for row in rows for key in row))  # rows of several runs may differ in columns
    rows = [{key: row.get(key, math.nan) for key in keys} for row in rows]
    markdown = tolerance_markdown(rows)
    print(f"\nlargest magnitude with success >= {SUCCESS_LEVEL:.0%} by T_con (n: episodes per point):\n{markdown}")
    for path in write_results(rows, str(out), "robustness"):
        print(f"wrote {path}")
    (out / "robustness.md").write_text(markdown)
    print(f"wrote {out / 'robustness.md'}")
    if not no_plots:
        for figure in plot(rows, out):
            print(f"wrote {figure}")
    return 0


def add_robustness_parser(sub: Any) -> None:
    """The ``robustness`` subcommand."""
    from baselines.controllers import CONTROLLER_NAMES

    p = sub.add_parser("robustness", help="sweep disturbance magnitudes: who still arrives by T_con")
    p.add_argument(
        "--disturbances",
        nargs="+",
        default=list(SWEEPS),
        metavar="NAME",
        help=f"disturbances to sweep: any of {', '.join(SWEEPS)} (default: all)",
    )
    p.add_argument(
        "--controllers",
        nargs="+",
        default=["all"],
        metavar="NAME",
        help=f"controllers: 'all' or any of {', '.join(CONTROLLER_NAMES)} (default: all; "
        "'optimal' needs the optimal extra and is slow: it re-plans from the measured pose)",
    )
    p.add_argument("--agent", action="append", metavar="PATH", help="a saved agent (.zip) to sweep too; repeatable")
    p.add_argument("--no-shipped-agents", action="store_true", help="leave out the pretrained agents")
    p.add_argument("--n", type=int, default=200, help="random start poses per magnitude (default: 200)")
    p.add_argument(
        "--n-optimal",
        type=int,
        default=20,
        help="start poses for the (slow) optimal controller, the first of the n (default: 20)",
    )
    p.add_argument(
        "--from-json",
        nargs="+",
        metavar="FILE",
        help="run nothing: table and figures of the rows in these robustness.json files",
    )
    p.add_argument("--seed", type=int, default=0, help="seed of the start poses and disturbances (default: 0)")
    p.add_argument("--env-kwargs", nargs="*", metavar="KEY=VALUE", help="env keywords, e.g. T_con=25")
    p.add_argument("--out", default="results/robustness", help="output directory (default: results/robustness)")
    p.add_argument("--no-plots", action="store_true", help="write no figures")
    p.add_argument("--no-progress", action="store_true", help="no progress bars")
    p.set_defaults(func=cmd_robustness)  # fmt: skip


__all__ = ["SUCCESS_LEVEL", "SWEEPS", "Sweep", "plot", "sweep", "tolerance_markdown", "tolerated"]

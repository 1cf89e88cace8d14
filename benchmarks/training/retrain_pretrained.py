"""Retrain every shipped agent (train/pretrained/*) from its recipe over 3 seeds; mean +- sd beside the shipped one.

    OMP_NUM_THREADS=1 nice -n 10 python -m benchmarks run retrain-pretrained --docs        # full budgets, 3 seeds
    python -m benchmarks run retrain-pretrained --agents ppo --seeds 0 --budget 0.1        # a quicker check

The recipe of an agent is the ``command:`` its run recorded in config.yaml (``dwr-gym train ...``,
``python -m train.learning.imitation.dagger ...``, or any other module with ``--run-dir`` and ``--seed``; a later
step recorded as ``"then: <command>"`` runs after it, in the same run directory or, if it names another, starting
from the earlier one's, as ``robust`` starts from the DAgger hand-over network). Each is run again as it was typed,
with only ``--seed`` and the run directories replaced, so a new agent directory needs no change here (each recorded
command names its env; ``tests/test_pretrained.py`` parses each). What a command leaves unset takes today's defaults.

``--budget F`` multiplies the budget flags of every recipe (``--total-timesteps``, ``--episodes``,
``--dagger-episodes``) by F when the full budgets do not fit; the JSON and the docs block say so.
Every agent is evaluated on the ``random`` scenario set (1,000 seeded starts, seed 0) in the env of its
config, as in the results tables, beside the shipped agent. ``--jobs`` runs that many recipes at once.
"""

from __future__ import annotations

import math
import os
import platform
import shlex
import shutil
import statistics
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

from benchmarks.core.commands import parser_for
from benchmarks.core.docs import NUMBER, Schema, fenced
from benchmarks.core.record import load_average, report

ROOT = Path(__file__).resolve().parents[2]
PRETRAINED = ROOT / "train" / "pretrained"
JSON_PATH = ROOT / "docs" / "training" / "retrain.json"
GOAL_MINUTES = 30.0
BUDGET_FLAGS = ("--total-timesteps", "--episodes", "--dagger-episodes")
METRICS = (("success_rate", "success", "{:.1%}"), ("arrival_time_mean", "arrival [s]", "{:.2f}"),
           ("final_heading_error_mean", "heading [rad]", "{:.3f}"), ("energy_mean", "energy", "{:.2f}"))  # fmt: skip


def recipe(agent_dir: Path) -> list[list[str]]:
    """The recorded command of a shipped agent, as one argument list per step."""
    import yaml

    data = yaml.safe_load((agent_dir / "config.yaml").read_text())
    recorded = data.get("command") if isinstance(data, dict) else None
    if not isinstance(recorded, list) or not recorded:
        raise ValueError(f"{agent_dir / 'config.yaml'} records no command: it cannot be retrained from its recipe")
    steps: list[list[str]] = [[]]
    for word in map(str, recorded):
        if word.startswith("then:"):
            steps.append(shlex.split(word.removeprefix("then:")))
        else:
            steps[-1].append(word)
    return steps


def _set(args: list[str], flag: str, value: str) -> list[str]:
    """``args`` with ``flag``'s value replaced (``--flag V`` or ``--flag=V``), or appended if absent."""
    out, index = list(args), 0
    while index < len(out):
        if out[index] == flag and index + 1 < len(out):
            out[index + 1] = value
            return out
        if out[index].startswith(flag + "="):
            out[index] = f"{flag}={value}"
            return out
        index += 1
    return [*out, flag, value]


def moved_run_dirs(steps: list[list[str]], run_dir: Path) -> tuple[list[list[str]], list[Path]]:
    """The steps with their recorded run directories moved: the last step's is ``run_dir``, an earlier step's own one
    (a network that a later step starts from with ``--init-from``) lies beside it, and every mention follows."""
    recorded = [step[step.index("--run-dir") + 1] if "--run-dir" in step[:-1] else None for step in steps]
    moved = {old: run_dir.parent / f"{run_dir.name}_{Path(old).name}" for old in recorded if old is not None}
    if recorded[-1] is not None:
        moved[recorded[-1]] = run_dir
    steps = [[str(moved.get(word, word)) for word in step] for step in steps]
    return steps, [moved.get(old, run_dir) if old is not None else run_dir for old in recorded]


def runnable(step: list[str], seed: int, run_dir: Path, budget: float) -> list[str]:
    """One recorded step as this checkout runs it: the seed, run directory and budget replaced."""
    program, args = step[0], step[1:]
    if Path(program).name == "dwr-gym":
        args = ["-m", "train.cli", *args]
    elif not Path(program).name.startswith("python"):
        raise ValueError(f"recorded command {shlex.join(step)!r} is not dwr-gym or python: cannot replay it")
    args = _set(args, "--run-dir", str(run_dir))
    if any(a == "--seed" or a.startswith("--seed=") for a in args):
        args = _set(args, "--seed", str(seed))
    for flag in BUDGET_FLAGS:
        for index, word in enumerate(args[:-1]):
            if word == flag and budget != 1.0:
                args[index + 1] = str(max(1, round(float(args[index + 1]) * budget)))
    return [sys.executable, *args]


def evaluate_agent(path: Path, n: int) -> dict[str, float | None]:
    """The summary of a saved agent on the random scenario set (seed 0) in the env of its config."""
    from train.evaluation.rollout import rollout
    from train.evaluation.scenarios import make_scenario
    from train.learning.agents import load_agent
    from train.learning.runs import load_config

    config = load_config(path)
    _, policy = load_agent(path)
    scenario = make_scenario("random", n=n, seed=0, env_kwargs=config.env_keywords())
    summary = rollout(policy, config.env_params(), scenario.starts, scenario.goals, T_con=scenario.T_cons,
                      env_kwargs=scenario.env_kwargs).summary()  # fmt: skip
    return {key: (summary[key] if math.isfinite(summary[key]) else None) for key, _, _ in METRICS}


def retrain(agent_dir: Path, seed: int, out: Path, budget: float, n: int) -> dict[str, Any]:
    """Run an agent's recipe at ``seed``; its wall time and its evaluation."""
    run_dir = out / f"{agent_dir.name}_s{seed}"
    if run_dir.exists():
        shutil.rmtree(run_dir)
    steps, dirs = moved_run_dirs(recipe(agent_dir), run_dir)
    commands = [runnable(step, seed, step_dir, budget) for step, step_dir in zip(steps, dirs, strict=True)]
    began = time.time()
    for command in commands:
        print(f"[{agent_dir.name} seed {seed}] {shlex.join(command[1:])}", flush=True)
        done = subprocess.run(command, cwd=ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        if done.returncode != 0:
            raise RuntimeError(f"{agent_dir.name} seed {seed} failed ({done.returncode}):\n{done.stderr[-2000:]}")
    seconds = time.time() - began
    print(f"[{agent_dir.name} seed {seed}] trained in {seconds:.0f} s", flush=True)
    return {"seed": seed, "seconds": round(seconds, 1), "commands": [shlex.join(c[1:]) for c in commands],
            "metrics": evaluate_agent(run_dir, n)}  # fmt: skip


def run(
    agents: list[Path], seeds: dict[str, list[int]], out: Path, budgets: dict[str, float], n: int, jobs: int
) -> dict[str, Any]:
    """Every agent's recipe at its seeds, ``jobs`` at once; ``budgets`` gives each agent's budget fraction."""
    import torch

    tasks = [(agent, seed) for agent in agents for seed in seeds[agent.name]]
    began = time.time()
    with ThreadPoolExecutor(jobs) as pool:  # each task is a subprocess; threads only wait for them
        done = list(pool.map(lambda task: retrain(task[0], task[1], out, budgets[task[0].name], n), tasks))
    training_seconds = time.time() - began
    results: dict[str, Any] = {"machine": f"{platform.machine()}, {os.cpu_count()} cores, torch {torch.__version__}, "
                               f"OMP_NUM_THREADS={os.environ.get('OMP_NUM_THREADS')}",
                               "load_average_1min_at_end": load_average(),
                               "seeds": sorted({s for agent in agents for s in seeds[agent.name]}), "jobs": jobs,
                               "n": n, "agents": {}}  # fmt: skip
    for agent in agents:
        runs = [r for (a, _), r in zip(tasks, done, strict=True) if a == agent]
        results["agents"][agent.name] = {"budget": budgets[agent.name], "runs": runs,
                                         "shipped": evaluate_agent(agent, n)}  # fmt: skip
    results["wall_seconds"] = round(training_seconds, 1)  # the training and the retrained agents' evaluations
    results["goal_minutes"] = GOAL_MINUTES
    return results


def mean_sd(values: list[float | None], fmt: str) -> str:
    present = [v for v in values if v is not None]
    if not present:
        return "n/a"
    sd = statistics.stdev(present) if len(present) > 1 else 0.0
    note = "" if len(present) == len(values) else f" ({len(present)} of {len(values)})"
    return f"{fmt.format(statistics.fmean(present))} +- {fmt.format(sd)}{note}"


def render(results: dict[str, Any]) -> list[str]:
    """The docs block: per agent, the retrained seeds (mean +- sd) beside the shipped agent, and the times."""
    full = all(entry["budget"] == 1.0 for entry in results["agents"].values())
    budget = "the full budgets" if full else "budget fractions as the agents' names say"
    every_seed = all(len(entry["runs"]) >= 3 for entry in results["agents"].values())
    seeds = "seeds 0, 1, 2" if every_seed else "the seeds the agents' rows count"
    lines = [f"{results['machine']}; load average {results['load_average_1min_at_end']} (1 min, at the end)",
             f"{seeds}, {budget}, {results['jobs']} recipes at once; evaluation: {results['n']} "
             "random starts (seed 0) in each agent's env", "",
             f"{'agent':<40}" + "".join(f"{title:>22}" for _, title, _ in METRICS) + f"{'train [min]':>16}"]  # fmt: skip
    for name, entry in results["agents"].items():
        runs = entry["runs"]
        minutes = mean_sd([r["seconds"] / 60 for r in runs], "{:.1f}")
        label = name + ("" if entry["budget"] == 1.0 else f" x{entry['budget']:g} budget") + f" ({len(runs)} seeds)"
        lines.append(f"{label:<40}"
                     + "".join(f"{mean_sd([r['metrics'][k] for r in runs], fmt):>22}" for k, _, fmt in METRICS)
                     + f"{minutes:>16}")  # fmt: skip
        shipped = entry["shipped"]
        lines.append(f"{name + ' (shipped)':<40}" + "".join(
            f"{(fmt.format(shipped[k]) if shipped[k] is not None else 'n/a'):>22}" for k, _, fmt in METRICS))  # fmt: skip
    minutes = results["wall_seconds"] / 60
    agents_everyone = results.get("all_agents", True) and every_seed
    verdict = "met" if minutes <= results["goal_minutes"] and full and agents_everyone else "NOT met"
    lines += ["", f"wall time of all of it: {minutes:.1f} min; the busy-machine goal, every shipped agent over 3 seeds at "
              f"the full budget in <= {results['goal_minutes']:.0f} min: {verdict}"]  # fmt: skip
    return lines


def main(argv: list[str] | None = None) -> int:
    parser = parser_for("retrain-pretrained", __doc__)
    parser.add_argument("--agents", nargs="+", help="names under train/pretrained/ (default: every one)")
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    parser.add_argument("--budget", type=float, default=1.0, help="fraction of each recipe's budget (default: 1)")
    parser.add_argument("--budget-of", nargs="+", default=[], metavar="NAME=F", help="one agent's budget fraction")
    parser.add_argument("--seeds-of", nargs="+", default=[], metavar="NAME=S,S", help="one agent's seeds")
    parser.add_argument("--n", type=int, default=1000, help="random starts in the evaluation (default: 1000)")
    parser.add_argument("--jobs", type=int, default=2, help="recipes run at once (default: 2, one per core)")
    parser.add_argument("--out", default="runs/retrain", help="where the runs go (default: runs/retrain)")
    parser.add_argument("--pretrained", default=str(PRETRAINED), help="the agents' directory")
    parser.add_argument("--docs", action="store_true", help=f"write {JSON_PATH.relative_to(ROOT)} and render its block")
    args = parser.parse_args(argv)
    shipped = sorted(p.parent for p in Path(args.pretrained).glob("*/config.yaml"))
    budgets = {p.name: args.budget for p in shipped}
    for item in args.budget_of:
        name, _, value = item.partition("=")
        if name not in budgets:
            parser.error(f"--budget-of {item} is invalid: expected NAME=F with NAME one of {sorted(budgets)}")
        try:
            budgets[name] = float(value)
        except ValueError:
            parser.error(f"--budget-of {item} is invalid: F must be a number")
    if not all(0 < b <= 1e3 for b in budgets.values()) or args.n < 1 or args.jobs < 1:
        parser.error(f"--budget={args.budget}, --budget-of={args.budget_of}, --n={args.n}, --jobs={args.jobs}: "
                     "expected budgets in (0, 1000], n >= 1 and jobs >= 1")  # fmt: skip
    seeds = {p.name: list(args.seeds) for p in shipped}
    for item in args.seeds_of:
        name, _, value = item.partition("=")
        if name not in budgets:
            parser.error(f"--seeds-of {item} is invalid: expected NAME one of {sorted(budgets)}")
        try:
            seeds[name] = [int(v) for v in value.split(",")]
        except ValueError:
            parser.error(f"--seeds-of {item} is invalid: expected NAME=S,S with integer seeds")
    everyone = len(shipped)
    if args.agents:
        unknown = sorted(set(args.agents) - {p.name for p in shipped})
        if unknown:
            parser.error(f"--agents {' '.join(unknown)} is invalid: expected some of {[p.name for p in shipped]}")
        shipped = [p for p in shipped if p.name in args.agents]
    if not shipped:
        print(f"no */config.yaml under {args.pretrained}", file=sys.stderr)
        return 1
    results = run(shipped, seeds, Path(args.out).resolve(), budgets, args.n, args.jobs)
    results["all_agents"] = len(shipped) == everyone
    return report(render(results), results, JSON_PATH if args.docs else None)


#: The block of docs/training.md.
BLOCKS = (fenced("retrain", "docs/training/retrain.json", render,
                 Schema({"machine": str, "load_average_1min_at_end": NUMBER, "seeds": list, "jobs": int, "n": int,
                         "agents": dict, "wall_seconds": NUMBER, "goal_minutes": NUMBER})),)  # fmt: skip

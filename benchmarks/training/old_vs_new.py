"""Learning against wall-clock time: `dwr-gym train`'s old defaults against the new, PPO, residual PPO and SAC.

    OMP_NUM_THREADS=1 nice -n 10 python -m benchmarks run training-old-vs-new --docs   # 18 runs of --cap seconds
    python -m benchmarks run training-old-vs-new --render                               # the figure from the JSON

Each run is the `dwr-gym train` command line (DWRPointStabilization-v1, seeds 0, 1, 2), stopped by Ctrl-C
(SIGINT, which saves the model) after ``--cap`` seconds of wall time: the full budgets do not fit on 2
shared cores, so the figure shows the first minutes of each run. The old defaults are those before the batch-sized ones
(16 robots; PPO: n_steps 256, batch 512, 10 epochs; evaluations every 20,000 and checkpoints every 50,000
env steps); the new are the defaults now. Old and new runs alternate, so a change in the machine's load
falls on both. The curves are the runs' own evaluations (``evaluations.csv``: 100 fixed random scenarios),
plus one of the model saved at the stop, at the wall time of that save. Writes
docs/training/old_vs_new.json (every number plotted) and docs/training/old_vs_new.png.
"""

from __future__ import annotations

import csv
import os
import platform
import signal
import statistics
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any

from benchmarks.core.commands import parser_for
from benchmarks.core.docs import NUMBER, Schema, fenced
from benchmarks.core.record import load_average, read_json, write_json

ROOT = Path(__file__).resolve().parents[2]
JSON_PATH = ROOT / "docs" / "training" / "old_vs_new.json"
FIGURE = ROOT / "docs" / "training" / "old_vs_new.png"
AGENTS = {"ppo": ["--algo", "ppo"], "residual_ppo": ["--algo", "ppo", "--residual"], "sac": ["--algo", "sac"]}
OLD = {"ppo": ["--num-envs", "16", "--hyperparams", "n_steps=256", "batch_size=512", "n_epochs=10"],
       "sac": ["--num-envs", "16"]}  # fmt: skip
OLD_COMMON = ["--eval-freq", "20000", "--checkpoint-freq", "50000"]
STYLE = {"old": {"color": "tab:orange", "marker": "o", "label": "old defaults (16 robots)"},
         "new": {"color": "tab:blue", "marker": "s", "label": "new defaults (PPO 256 robots, SAC 64)"}}  # fmt: skip


def command(agent: str, setting: str, seed: int, run_dir: Path) -> list[str]:
    """The `dwr-gym train` command line of one run."""
    args = [sys.executable, "-m", "train.cli", "train", *AGENTS[agent], "--seed", str(seed), "--run-dir",
            str(run_dir), "--overwrite", "--no-progress"]  # fmt: skip
    if setting == "old":
        args += OLD[AGENTS[agent][1]] + OLD_COMMON
    return args


def evaluate_saved(run_dir: Path) -> dict[str, float]:
    """The saved model on the run's own evaluation set (as its callback evaluates), at the save's wall time."""
    from train.evaluation.rollout import rollout
    from train.evaluation.scenarios import make_scenario
    from train.learning.agents import load_agent
    from train.learning.runs import load_config, read_state

    config = load_config(run_dir)
    _, policy = load_agent(run_dir / "model.zip")
    scenario = make_scenario("random", n=config.eval_episodes, seed=config.eval_seed, env_kwargs=config.env_keywords())
    summary = rollout(policy, config.env_params(), scenario.starts, scenario.goals, T_con=scenario.T_cons,
                      env_kwargs=scenario.env_kwargs).summary()  # fmt: skip
    state = read_state(run_dir)
    return {"timesteps": int(state["timesteps"]), "wall_time": float(state["wall_time"]),
            "success_rate": float(summary["success_rate"]), "return_mean": float(summary["return_mean"])}  # fmt: skip


def one_run(agent: str, setting: str, seed: int, out: Path, cap: float) -> dict[str, Any]:
    """Train until ``cap`` seconds, stop with SIGINT, read the curve, evaluate the saved model."""
    run_dir = out / f"{agent}_{setting}_s{seed}"
    process = subprocess.Popen(command(agent, setting, seed, run_dir), cwd=ROOT, stdout=subprocess.DEVNULL,
                               stderr=subprocess.PIPE, text=True)  # fmt: skip
    stalls = watch_stalls(process)
    try:
        process.wait(timeout=cap)
    except subprocess.TimeoutExpired:
        process.send_signal(signal.SIGINT)  # saves at the end of the rollout
        process.wait()
    if process.returncode not in (0, 130):
        raise RuntimeError(f"{agent} {setting} seed {seed} failed:\n{process.stderr.read() if process.stderr else ''}")
    with (run_dir / "evaluations.csv").open() as handle:
        rows = [{k: float(v) for k, v in row.items() if k in ("timesteps", "wall_time", "success_rate", "return_mean")}
                for row in csv.DictReader(handle)]  # fmt: skip
    final = evaluate_saved(run_dir)
    if final["timesteps"] > rows[-1]["timesteps"]:
        rows.append(final)
    return {"seed": seed, "curve": rows, "fps": final["timesteps"] / final["wall_time"], "stalled_seconds": sum(stalls)}


def watch_stalls(process: subprocess.Popen[str], gap: float = 2.0) -> list[float]:
    """The stalls of the machine while ``process`` runs: gaps of more than ``gap`` s between wake-ups of a thread
    that sleeps 0.25 s (this shared virtual machine is sometimes paused for minutes, which no load explains)."""
    stalls: list[float] = []

    def watch() -> None:
        last = time.monotonic()
        while process.poll() is None:
            time.sleep(0.25)
            now = time.monotonic()
            if now - last > gap:
                stalls.append(round(now - last, 1))
            last = now

    threading.Thread(target=watch, daemon=True).start()
    return stalls


def run(cap: float, seeds: list[int], out: Path) -> dict[str, Any]:
    import torch

    runs: dict[str, dict[str, list[dict[str, Any]]]] = {agent: {"old": [], "new": []} for agent in AGENTS}
    for seed in seeds:
        for agent in AGENTS:
            for setting in ("old", "new"):
                result = one_run(agent, setting, seed, out, cap)
                runs[agent][setting].append(result)
                last = result["curve"][-1]
                print(f"{agent} {setting} seed {seed}: {result['fps']:,.0f} steps/s, {last['timesteps']:,.0f} steps, "
                      f"success {last['success_rate']:.2f}, return {last['return_mean']:.2f}", flush=True)  # fmt: skip
    return {"machine": f"{platform.machine()}, {os.cpu_count()} cores, torch {torch.__version__}, "
            f"OMP_NUM_THREADS={os.environ.get('OMP_NUM_THREADS')}",
            "load_average_1min_at_end": load_average(), "cap_seconds": cap, "seeds": seeds,
            "env_id": "DWRPointStabilization-v1", "old_arguments": {"ppo": OLD["ppo"] + OLD_COMMON,
            "sac": OLD["sac"] + OLD_COMMON}, "runs": runs}  # fmt: skip


def mean_sd(values: list[float], fmt: str) -> str:
    sd = statistics.stdev(values) if len(values) > 1 else 0.0
    return f"{fmt.format(statistics.fmean(values))} +- {fmt.format(sd)}"


def render(results: dict[str, Any]) -> list[str]:
    """The docs block: per agent and setting, env steps per second and the last evaluation before the cap."""
    lines = [f"{results['machine']}; load average {results['load_average_1min_at_end']} (1 min, at the end)",
             f"{results['env_id']}, seeds {results['seeds']}, each run stopped after {results['cap_seconds']:.0f} s "
             "of wall time; mean +- sd over the seeds", "",
             f"{'agent':<14}{'defaults':<10}{'env steps/s':>18}{'steps at stop':>22}{'success at stop':>18}"
             f"{'return at stop':>20}"]  # fmt: skip
    for agent, settings in results["runs"].items():
        for setting, runs in settings.items():
            last = [r["curve"][-1] for r in runs]
            lines.append(f"{agent:<14}{setting:<10}{mean_sd([r['fps'] for r in runs], '{:,.0f}'):>18}"
                         f"{mean_sd([x['timesteps'] for x in last], '{:,.0f}'):>22}"
                         f"{mean_sd([x['success_rate'] for x in last], '{:.2f}'):>18}"
                         f"{mean_sd([x['return_mean'] for x in last], '{:.1f}'):>20}")  # fmt: skip
    for agent, settings in results["runs"].items():
        for setting, runs in settings.items():
            for r in runs:
                if r.get("stalled_seconds", 0) > 0:
                    lines.append(
                        f"{agent} {setting} seed {r['seed']}: the machine stalled {r['stalled_seconds']:.0f} s"
                    )
    for redo in results.get("redone", []):
        lines.append(f"run again: {redo['agent']} seed {redo['seed']}, old and new ({redo['why']})")
    return lines


def plot(results: dict[str, Any], path: Path) -> None:
    """Success and return against wall time, one column per agent, every seed's curve."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    agents = list(results["runs"])
    fig, axes = plt.subplots(2, len(agents), figsize=(4.2 * len(agents), 6.4), sharex=True, squeeze=False)
    for column, agent in enumerate(agents):
        for setting, runs in results["runs"][agent].items():
            for index, run_ in enumerate(runs):
                times = [row["wall_time"] for row in run_["curve"]]
                for row_axes, key in zip(axes[:, column], ("success_rate", "return_mean"), strict=True):
                    row_axes.plot(times, [row[key] for row in run_["curve"]], color=STYLE[setting]["color"],
                                  marker=STYLE[setting]["marker"], markersize=4, linewidth=1.2, alpha=0.85,
                                  label=STYLE[setting]["label"] if index == 0 else None)  # fmt: skip
        axes[0, column].set_title(agent.replace("_", " "))
        axes[0, column].set_ylim(-0.03, 1.03)
        axes[1, column].set_xlabel("wall-clock time [s]")
        for row_axes in axes[:, column]:
            row_axes.grid(alpha=0.3)
    axes[0, 0].set_ylabel("evaluation success rate [-]")
    axes[1, 0].set_ylabel("evaluation mean return [-]")
    handles, labels = axes[0, 0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=2, bbox_to_anchor=(0.5, 0.0), frameon=False)
    fig.suptitle(f"dwr-gym train on {results['env_id']}, old vs new defaults: {len(results['seeds'])} seeds each, "
                 f"every run stopped at {results['cap_seconds']:.0f} s (2 shared cores, loaded)")  # fmt: skip
    fig.tight_layout(rect=(0, 0.06, 1, 0.95))
    fig.savefig(path, dpi=110)
    plt.close(fig)
    print(f"wrote {path}")


def main(argv: list[str] | None = None) -> None:
    parser = parser_for("training-old-vs-new", __doc__)
    parser.add_argument("--cap", type=float, default=60.0, help="wall-clock seconds per run (default: 60)")
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    parser.add_argument("--out", default="runs/old_vs_new", help="where the runs go (default: runs/old_vs_new)")
    parser.add_argument("--docs", action="store_true", help="write the JSON and the figure (and render the block)")
    parser.add_argument("--render", action="store_true", help="only the figure, from the JSON")
    parser.add_argument(
        "--redo",
        nargs=2,
        metavar=("AGENT", "SEED"),
        help="run both settings of one agent and seed again and replace them in the JSON, with the "
        "reason given by --why (e.g. a run starved of CPU by another process)",
    )
    parser.add_argument("--why", default="", help="the reason for --redo, recorded in the JSON and the docs block")
    args = parser.parse_args(argv)
    if not args.cap > 0:
        parser.error(f"--cap={args.cap} is invalid: expected a positive number of seconds")
    if args.redo:
        agent, seed = args.redo[0], int(args.redo[1])
        if agent not in AGENTS or not args.why:
            parser.error(f"--redo {agent} {seed} is invalid: expected an agent of {sorted(AGENTS)} and a --why")
        results = read_json(JSON_PATH)
        for setting in ("old", "new"):
            runs = results["runs"][agent][setting]
            index = [r["seed"] for r in runs].index(seed)
            runs[index] = one_run(agent, setting, seed, Path(args.out).resolve(), results["cap_seconds"])
        results.setdefault("redone", []).append({"agent": agent, "seed": seed, "why": args.why})
        write_json(JSON_PATH, results)
    elif args.render:
        results = read_json(JSON_PATH)
    else:
        began = time.time()
        results = run(args.cap, args.seeds, Path(args.out).resolve())
        results["total_seconds"] = round(time.time() - began, 1)
    print("\n".join(render(results)))
    if args.docs:
        write_json(JSON_PATH, results)
    if args.docs or args.render or args.redo:
        plot(results, FIGURE)


#: The block of docs/training.md.
BLOCKS = (fenced("old-vs-new", "docs/training/old_vs_new.json", render,
                 Schema({"machine": str, "load_average_1min_at_end": NUMBER, "cap_seconds": NUMBER, "seeds": list,
                         "env_id": str, "runs": dict})),)  # fmt: skip

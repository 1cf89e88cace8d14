"""The README's training example, run as a user runs it: its wall and CPU time, and whether the agent arrives.

    nice -n 10 python -m benchmarks run readme-training --docs     # writes docs/training/readme_example.json, ~5-30 min

Runs ``COMMAND`` (a fresh `dwr-gym train` process, in a temporary directory), times it (wall clock, and the CPU time
of the process and its children: on an idle machine the wall time of a run on one thread), then evaluates the
run's model (``model.zip``, what ``--agents RUN`` loads: for APG with ``keep_best`` the best policy on the run's own
validation episodes; ``best_model.zip`` is the evaluation with the most episodes in time) and the PTC expert with
`dwr-gym evaluate` on 200 random starts of the env (seed 0, neither the training's evaluation set nor its validation
episodes). The README quotes both times, the load average and the share that arrives in time.
"""

from __future__ import annotations

import json
import resource
import subprocess
import tempfile
import time
from pathlib import Path
from typing import Any

from benchmarks.core.commands import checkout_env, dwr_gym, parser_for
from benchmarks.core.docs import NUMBER, Block, Schema
from benchmarks.core.record import load_average, report, torch_machine

ROOT = Path(__file__).resolve().parents[2]
JSON_PATH = ROOT / "docs" / "training" / "readme_example.json"
#: The example: the residual on PTC by analytic policy gradients on the task held to T_con (the ``jax`` extra), the
#: learner of this repository that ends with less energy than PTC (docs/rl-benchmark.md).
RUN = "runs/apg-residual-v2"
V2 = "DWRPointStabilization-v2"
COMMAND = ["dwr-gym", "train", "--algo", "apg", "--backend", "jax", "--env", V2, "--residual", "--expert", "ptc",
           "--total-timesteps", "30000000", "--run-dir", RUN]  # fmt: skip
EVALUATE = ["dwr-gym", "evaluate", "--agents", RUN, "--controllers", "ptc", "--env", V2, "--scenarios", "random",
            "--n", "200", "--optimum", "none"]  # fmt: skip


KEPT = ("policy", "n", "success_rate", "energy_mean", "final_heading_error_mean")


def cli(args: list[str], cwd: str) -> subprocess.CompletedProcess[str]:
    """``dwr-gym ...`` (``args`` as the README types them) as this checkout's code, in ``cwd``."""
    env = checkout_env()
    env.pop("OMP_NUM_THREADS", None)  # the user's setting: none
    return dwr_gym(args[1:], cwd, env=env, capture_output=True)


def measure() -> dict[str, Any]:
    """Train as the README says, then evaluate the final model and PTC; the times and the rows."""
    with tempfile.TemporaryDirectory() as tmp:
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        began = time.perf_counter()
        cli([*COMMAND, "--no-progress"], tmp)
        wall = time.perf_counter() - began
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        load = load_average()
        cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
        from train.learning.runs import read_evaluations

        curve = read_evaluations(Path(tmp) / RUN / "evaluations.csv")
        best = json.loads((Path(tmp) / RUN / "run_state.json").read_text())["best"]
        cli([*EVALUATE, "--no-progress", "--out", "out"], tmp)
        rows = json.loads((Path(tmp) / "out" / "evaluation.json").read_text())
    return {
        "machine": torch_machine(),
        "command": " ".join(COMMAND),
        "evaluate": " ".join(EVALUATE),
        "wall_seconds": round(wall, 1),
        "cpu_seconds": round(cpu, 1),
        "load_average_1min_at_end": load,
        "curve": curve,
        "best": best,
        "evaluation": [{k: row[k] for k in KEPT} for row in rows],
    }


def render(results: dict[str, Any]) -> str:
    """The README's lines: the command, its times, and who arrives in time on the 200 starts."""
    rows = {row["policy"]: row for row in results["evaluation"]}
    agent = next(row for name, row in rows.items() if name != "ptc")
    ptc = rows["ptc"]
    steps = int(results["curve"][-1]["timesteps"])
    run = results["command"].split()[-1]
    command = results["command"].replace(" --run-dir", " \\\n  --run-dir")
    return (
        f"\n```bash\n{command}     # {steps:,} env steps\n{results['evaluate']}\n```\n\n"
        f"Measured ({results['machine']}): {results['cpu_seconds'] / 60:.1f} min of CPU time, about its wall time on "
        f"an idle machine (it runs on one core; the wall time where it was measured, {results['wall_seconds'] / 60:.1f} "
        f"min at a load average of {results['load_average_1min_at_end']:g}, says more of that machine than of the "
        f"command). Its model (`model.zip`, what `--agents {run}` loads) arrives in time on "
        f"{agent['success_rate']:.0%} of the 200 random starts, with a mean energy of {agent['energy_mean']:.2f} "
        f"(PTC: {ptc['success_rate']:.0%}, {ptc['energy_mean']:.2f}); final heading error "
        f"{agent['final_heading_error_mean']:.2f} rad on average (PTC: {ptc['final_heading_error_mean']:.2f}). "
        "One seed, from `docs/training/readme_example.json` (`python -m benchmarks run readme-training`).\n"
    )


def main(argv: list[str] | None = None) -> int:
    parser = parser_for("readme-training", __doc__)
    parser.add_argument("--docs", action="store_true", help=f"write {JSON_PATH.relative_to(ROOT)} and render its block")
    args = parser.parse_args(argv)
    results = measure()
    return report([render(results)], results, JSON_PATH if args.docs else None)


#: The block of the README.
BLOCKS = (Block("readme-training", "docs/training/readme_example.json", render,
                Schema({"machine": str, "command": str, "evaluate": str, "wall_seconds": NUMBER, "cpu_seconds": NUMBER,
                        "load_average_1min_at_end": NUMBER, "curve": list, "best": dict, "evaluation": list})),)  # fmt: skip

"""What `dwr-gym train --algo es --backend jax` learns on DWRPointStabilization-v1 within a wall-clock budget.

    nice -n 5 python -m benchmarks run es-learn --seeds 0 --time-limit 900 --docs     # docs/jax/es_learn.json
    nice -n 5 python -m benchmarks run es-learn --name es-arena50 --seeds 0 --time-limit 900 \
        --env-kwargs arena_radius=50 --docs

Each seed trains in ``<out>/<name>-seed<k>`` with the shipped settings (train/hyperparams/es.yml) and the overrides
given (and the training env's keywords ``--env-kwargs``; the evaluation is on v1 as registered), for
``--time-limit`` seconds (compilation included) or ``--env-steps``, evaluated every ``--eval-freq`` env
steps on `dwr-gym train`'s fixed set (100 starts of v1, seed 12345); then its last model (model.zip) is evaluated
as `dwr-gym benchmark` evaluates an agent: the RL benchmark's metrics on its nominal set (``--n`` starts of v1,
seed 3232; E/opt on its first 50 episodes, the optimum cached) and at each fixed T_con of 10, 20, 40 and 60 s. The
time to the first evaluation with >= 99 % in time is read from evaluations.csv. A run already finished is only
evaluated again. Each call adds its rows to the JSON (by name and seed).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
from pathlib import Path
from typing import Any

from benchmarks.core.commands import parser_for
from benchmarks.core.docs import NUMBER, Schema, fenced
from benchmarks.core.record import write_json

ROOT = Path(__file__).resolve().parents[2]
JSON_PATH = ROOT / "docs" / "jax" / "es_learn.json"
T_CONS = (10.0, 20.0, 40.0, 60.0)
CRITERIA = {"in_time": 0.99, "energy_ratio": 1.5, "final_heading": 0.1}


def train_seed(name: str, seed: int, out: Path, overrides: dict[str, Any], env_kwargs: dict[str, Any],
               args: argparse.Namespace, command: list[str]) -> Path:  # fmt: skip
    from train.learning.config import TrainConfig
    from train.learning.hyperparams import resolve_hyperparams
    from train.learning.runs import read_state
    from train.learning.training import train

    run_dir = out / f"{name}-seed{seed}"
    if read_state(run_dir).get("finished"):
        return run_dir
    config = TrainConfig(algo="es", backend="jax", seed=seed, run_dir=str(run_dir), progress=False, overwrite=True,
                         eval_freq=args.eval_freq, checkpoint_freq=args.eval_freq, time_limit=args.time_limit,
                         hyperparam_overrides=overrides, env_kwargs=env_kwargs)  # fmt: skip
    if args.env_steps:
        config.total_timesteps = args.env_steps
    config.validate()
    config = resolve_hyperparams(config, {"total_timesteps"} if args.env_steps else set())
    train(config, command=command)
    return run_dir


def first_reaching(run_dir: Path, in_time: float) -> dict[str, float] | None:
    """The first evaluation of evaluations.csv with at least ``in_time`` in time: its steps and wall seconds."""
    from train.learning.runs import read_evaluations

    for row in read_evaluations(run_dir / "evaluations.csv"):
        if float(row["success_rate"]) >= in_time:
            return {"steps": int(row["timesteps"]), "wall_s": float(row["wall_time"])}
    return None


def evaluate_seed(run_dir: Path, n: int) -> dict[str, Any]:
    from train.env_ids import TASK_ENV_ID, env_keywords
    from train.evaluation.benchmark import EVAL_SEED, evaluate_policy, metrics_of
    from train.evaluation.evaluate import evaluate_sets
    from train.learning.agents import load_agent
    from train.learning.runs import read_evaluations, read_state

    _, policy = load_agent(run_dir)
    nominal = evaluate_policy(policy, n=n, sets=("random",))["random"]
    rows = evaluate_sets(
        {"agent": policy}, ["random"], n, EVAL_SEED, env_keywords(TASK_ENV_ID, {}), T_cons=list(T_CONS)
    )
    per_T_con = {str(row["T_con"]): metrics_of(row) for row in rows}
    state = read_state(run_dir)
    curve = [{"steps": int(r["timesteps"]), "wall_s": float(r["wall_time"]), "in_time": float(r["success_rate"]),
              "final_heading": float(r["final_heading_error_mean"]), "energy": float(r["energy_mean"]),
              "return": float(r["return_mean"])} for r in read_evaluations(run_dir / "evaluations.csv")]  # fmt: skip
    return {"env_steps": state.get("timesteps"), "wall_s": state.get("wall_time"), "nominal": nominal,
            "per_T_con": per_T_con, "first_99_in_time": first_reaching(run_dir, CRITERIA["in_time"]), "curve": curve}  # fmt: skip


def render(data: dict[str, Any]) -> list[str]:
    lines = [data["machine"], f"nominal set: {data['n']} starts of v1 (seed 3232), E/opt on its first 50; fixed "
             f"T_con: the same starts; criteria: in time >= 99 %, E/opt <= 1.5, final heading <= 0.1 rad", "",
             f"{'run':<28}{'env steps':>12}{'wall s':>8}{'in time':>9}{'E/opt':>7}{'heading':>9}{'first 99 %':>12}"]  # fmt: skip
    for key, row in sorted(data["runs"].items()):
        m = row["nominal"]
        first = row["first_99_in_time"]
        reached = f"{first['wall_s']:.0f} s" if first else "not reached"
        ratio = f"{m['energy_ratio']:.2f}" if m["energy_ratio"] is not None else "-"
        lines.append(f"{key:<28}{row['env_steps']:>12,}{row['wall_s']:>8.0f}{m['in_time']:>9.1%}{ratio:>7}"
                     f"{m['final_heading']:>9.3f}{reached:>12}")  # fmt: skip
    lines += ["", f"{'run, at fixed T_con':<28}" + "".join(f"{f'T_con {t:g} s':>18}" for t in T_CONS),
              f"{'':<28}" + "".join(f"{'in time / heading':>18}" for _ in T_CONS)]  # fmt: skip
    for key, row in sorted(data["runs"].items()):
        cells = "".join(f"{row['per_T_con'][str(t)]['in_time']:>11.1%} / {row['per_T_con'][str(t)]['final_heading']:.2f}"
                        for t in T_CONS)  # fmt: skip
        lines.append(f"{key:<28}{cells}")
    return lines


def main(argv: list[str] | None = None) -> int:
    parser = parser_for("es-learn", __doc__)
    parser.add_argument("--name", default="es", help="the runs' name (default: es)")
    parser.add_argument("--seeds", type=int, nargs="+", default=[0], help="seeds (default: 0)")
    parser.add_argument("--time-limit", type=float, default=900.0, help="seconds per seed (default: 900)")
    parser.add_argument("--env-steps", type=int, help="env steps per seed (default: es.yml's n_timesteps)")
    parser.add_argument("--eval-freq", type=int, default=5_000_000, help="env steps between evaluations (5000000)")
    parser.add_argument("--hyperparams", nargs="*", default=[], metavar="KEY=VALUE", help="ES overrides")
    parser.add_argument("--env-kwargs", nargs="*", default=[], metavar="KEY=VALUE", help="training env keywords")
    parser.add_argument("--n", type=int, default=200, help="evaluation starts (default: 200)")
    parser.add_argument("--out", default="results/es", help="run directories (default: results/es)")
    parser.add_argument("--docs", action="store_true", help=f"add to {JSON_PATH.relative_to(ROOT)} (and its block)")
    args = parser.parse_args(argv)
    if args.n < 1:
        parser.error(f"--n {args.n} is invalid: expected >= 1")
    from train.commands.shared import parse_env_kwargs
    from train.learning.hyperparams import parse_overrides

    overrides, env_kwargs = parse_overrides(args.hyperparams), parse_env_kwargs(args.env_kwargs)
    command = ["python", "-m", "benchmarks", "run", "es-learn", *(argv or [])]
    data = json.loads(JSON_PATH.read_text()) if JSON_PATH.is_file() else {"runs": {}}
    data.update({"machine": f"{platform.machine()}, {os.cpu_count()} cores", "n": args.n})
    for seed in args.seeds:
        run_dir = train_seed(args.name, seed, Path(args.out), overrides, env_kwargs, args, command)
        data["runs"][f"{args.name}-seed{seed}"] = {"overrides": args.hyperparams, "env_kwargs": args.env_kwargs,
                                                   **evaluate_seed(run_dir, args.n)}  # fmt: skip
        data["load_average_1min_at_end"] = round(os.getloadavg()[0], 2)
        print("\n".join(render(data)))
        if args.docs:  # read again: another call may have added its runs meanwhile
            saved = json.loads(JSON_PATH.read_text()) if JSON_PATH.is_file() else {"runs": {}}
            data["runs"] = {**saved["runs"], **data["runs"]}
            write_json(JSON_PATH, data)
    return 0


#: The block of docs/evolution.md.
BLOCKS = (
    fenced(
        "es-learn",
        "docs/jax/es_learn.json",
        render,
        Schema({"machine": str, "n": int, "runs": dict, "load_average_1min_at_end": NUMBER}),
    ),
)

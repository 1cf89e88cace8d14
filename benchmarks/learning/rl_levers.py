"""Short runs of the levers that might make PPO learn v1 from its reward, one seed each.

Each lever is ``dwr-gym train`` with a few options, stopped after ``--seconds`` of wall time (the machine's share
of 2 busy cores decides the env steps); its learning curve (evaluations.csv on 100 v1 episodes) goes to
docs/rl_benchmark/levers.json. A first look, not the protocol: one seed, minutes each. ``--collect DIR`` reads
runs already made in DIR/<lever>/ instead of training.

    OMP_NUM_THREADS=1 nice -n 10 python -m benchmarks run rl-levers --seconds 300 --out runs/levers --docs
"""

from __future__ import annotations

import csv
import os
import shlex
from pathlib import Path

from benchmarks.core.commands import dwr_gym, parser_for
from benchmarks.core.docs import NUMBER, Schema, table
from benchmarks.core.record import write_json

ROOT = Path(__file__).resolve().parents[2]

NORM = "--normalize-obs --normalize-reward"
LOW_STD = "--hyperparams 'policy_kwargs=dict(net_arch=[64, 64], log_std_init={})'"
LEVERS: dict[str, str] = {
    "ppo (defaults)": "--eval-freq 100000",
    "ppo, normalised obs and reward": f"--eval-freq 100000 {NORM}",
    "ppo, action repeat 5, normalised": f"--eval-freq 20000 --action-repeat 5 {NORM}",
    "ppo, action repeat 10, normalised": f"--eval-freq 10000 --action-repeat 10 {NORM}",
    "ppo, sigma0 exp(-2), normalised": f"--eval-freq 100000 {NORM} {LOW_STD.format(-2)}",
    "residual ppo on ptc (defaults)": "--eval-freq 65536 --residual --expert ptc",
    "residual ppo on ptc, sigma0 exp(-3)": f"--eval-freq 65536 --residual --expert ptc {LOW_STD.format(-3)}",
    "residual ppo on pt-astolfi (defaults)": "--eval-freq 65536 --residual --expert pt-astolfi",
}
"""Lever -> options of dwr-gym train; the action repeat's --eval-freq counts decisions (K env steps each)."""
DIRS = {"ppo (defaults)": "A_default", "ppo, normalised obs and reward": "D_norm",
        "ppo, action repeat 5, normalised": "B_rep5_norm", "ppo, action repeat 10, normalised": "C_rep10_norm",
        "ppo, sigma0 exp(-2), normalised": "P_ls2_norm", "residual ppo on ptc (defaults)": "R_ptc",
        "residual ppo on ptc, sigma0 exp(-3)": "R_ptc_ls3",
        "residual ppo on pt-astolfi (defaults)": "R_astolfi"}  # fmt: skip


def repeat_of(text: str) -> int:
    options = shlex.split(text)
    return int(options[options.index("--action-repeat") + 1]) if "--action-repeat" in options else 1


def curve(run_dir: Path, repeat: int) -> list[dict[str, float]]:
    with (run_dir / "evaluations.csv").open() as handle:
        return [{"env_steps": int(r["timesteps"]) * repeat, "wall_time": float(r["wall_time"]),
                 "in_time": float(r["success_rate"]), "energy": float(r["energy_mean"]),
                 "final_heading": float(r["final_heading_error_mean"])} for r in csv.DictReader(handle)]  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    parser = parser_for("rl-levers", __doc__)
    parser.add_argument("--seconds", type=float, default=300.0, help="wall time per run (default 300)")
    parser.add_argument("--out", default="runs/levers", help="where the runs go (default runs/levers)")
    parser.add_argument("--collect", help="read the runs in this directory instead of training")
    parser.add_argument(
        "--docs", action="store_true", help="write docs/rl_benchmark/levers.json (and render its table)"
    )
    args = parser.parse_args(argv)
    out = Path(args.collect or args.out)
    data = {"seconds": args.seconds, "machine": f"{os.cpu_count()} cores, shared", "levers": {}}
    for lever, options in LEVERS.items():
        run_dir = out / DIRS[lever]
        if not args.collect:
            dwr_gym(["train", "--run-dir", str(run_dir), "--overwrite", "--no-progress", "--threads", "1",
                     "--total-timesteps", "100000000", "--time-limit", str(args.seconds), *shlex.split(options)])  # fmt: skip
        if (run_dir / "evaluations.csv").is_file():
            data["levers"][lever] = {"options": options, "curve": curve(run_dir, repeat_of(options))}
    if args.docs:
        write_json(ROOT / "docs" / "rl_benchmark" / "levers.json", data)
    return 0


BLOCKS = (table("rl-levers", Schema({"seconds": NUMBER, "machine": str, "levers": dict})),)

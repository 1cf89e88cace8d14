"""Instructions per step, counted by valgrind's callgrind, for our env and Gymnasium's CartPole.

    python -m benchmarks run instructions           # single envs and vector envs at N = 4096 (5-10 minutes)
    python -m benchmarks run instructions --single  # single envs only (about 1 minute)
    python -m benchmarks run instructions --docs    # also write docs/throughput/instructions.json, render its block

Time on a shared machine varies by tens of percent from one run to the next; the number of instructions a
step executes does not (the same code, inputs and libraries give the same count). It is the measure to
compare two versions of the code with: it counts the work, not the memory stalls, so it complements the
timings of ``throughput`` and does not replace them. Each count is the difference between two runs
that differ only in the number of steps, so start-up and imports cancel. Needs valgrind (Debian:
``apt install valgrind``). Our vector env runs as it does by default (torch's float64 kernels when torch
is installed), with one OpenMP thread (its operations at N = 4096 run on one thread anyway).
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

from benchmarks.core.commands import parser_for
from benchmarks.core.docs import Schema, fenced

ROOT = Path(__file__).resolve().parents[2]
DOCS_JSON = "docs/throughput/instructions.json"
#: (label, env id, vector size or 0 for a single env, steps counted)
CASES = (
    ("single env, ours (v0, gym.make)", "DWRPointStabilization-v0", 0, 3000),
    ("single env, CartPole-v1 (gym.make)", "CartPole-v1", 0, 3000),
    ("vector env N = 4096, ours float64", "DWRPointStabilization-v0", 4096, 60),
    ("vector env N = 4096, CartPoleVectorEnv", "CartPole-v1", 4096, 60),
)


def child(env_id: str, num_envs: int, steps: int) -> None:
    """Make the env, step it 50 times, then ``steps`` more times (what is counted is the difference)."""
    import warnings

    import gymnasium as gym
    import numpy as np

    import dwr_gym  # noqa: F401

    warnings.filterwarnings("ignore")
    if num_envs:
        env = gym.make_vec(env_id, num_envs=num_envs, vectorization_mode="vector_entry_point")
        sample = env.action_space.sample()
        action = (
            np.random.default_rng(0).uniform(-1, 1, sample.shape).astype(np.float32)
            if sample.dtype.kind == "f"
            else sample
        )
    else:
        env = gym.make(env_id)
        action = env.action_space.sample()
    env.reset(seed=0)
    for _ in range(50 + steps):
        _, _, terminated, truncated, _ = env.step(action)
        if not num_envs and (terminated or truncated):
            env.reset()


def collected(env_id: str, num_envs: int, steps: int) -> int:
    """Instructions callgrind collected for one child run."""
    with tempfile.TemporaryDirectory() as tmp:
        command = ["valgrind", "--tool=callgrind", f"--callgrind-out-file={tmp}/out", sys.executable, "-m",
                   "benchmarks", "run", "instructions", "--child", env_id, str(num_envs), str(steps)]  # fmt: skip
        # str hashes vary between runs, and with them dict work; idle OpenMP threads spin, and callgrind counts that
        env = {**os.environ, "PYTHONHASHSEED": "0", "OMP_NUM_THREADS": "1"}
        result = subprocess.run(command, capture_output=True, text=True, check=True, env=env, cwd=ROOT)
    match = re.search(r"Collected\s*:\s*(\d+)", result.stderr)
    if match is None:
        raise RuntimeError(f"callgrind printed no count:\n{result.stderr[-2000:]}")
    return int(match.group(1))


def per_step(case: tuple[str, str, int, int]) -> float:
    _, env_id, num_envs, steps = case
    return (collected(env_id, num_envs, steps) - collected(env_id, num_envs, 0)) / steps


def main(argv: list[str] | None = None) -> int:
    parser = parser_for("instructions", __doc__)
    parser.add_argument("--single", action="store_true", help="single envs only")
    parser.add_argument("--json", type=Path, help="also write the counts and ratios to this JSON file")
    parser.add_argument("--docs", action="store_true", help=f"write {DOCS_JSON} (and render its block)")
    parser.add_argument("--child", nargs=3, metavar=("ENV_ID", "NUM_ENVS", "STEPS"), help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.child:
        child(args.child[0], int(args.child[1]), int(args.child[2]))
        return 0
    if args.docs:
        args.json = ROOT / DOCS_JSON
    if shutil.which("valgrind") is None:
        sys.exit("valgrind is not installed: this benchmark counts instructions with callgrind (apt install valgrind)")
    cases = [case for case in CASES if case[2] == 0 or not args.single]
    with ThreadPoolExecutor(max_workers=2) as pool:  # one valgrind process per core
        counts = list(pool.map(per_step, cases))
    for (label, *_), count in zip(cases, counts, strict=True):
        print(f"{label:<40} {count:>14,.0f} instructions per step")
    for i in range(0, len(cases), 2):
        print(f"ratio, {cases[i][0].split(',')[0]}: {counts[i] / counts[i + 1]:.2f}x CartPole's")
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        record = {
            "instructions_per_step": {label: count for (label, *_), count in zip(cases, counts, strict=True)},
            "ratios": {cases[i][0].split(",")[0]: counts[i] / counts[i + 1] for i in range(0, len(cases), 2)},
        }
        args.json.write_text(json.dumps(record, indent=1) + "\n")
        print(f"wrote {args.json}")
    return 0


def render_instructions(record: dict[str, Any]) -> list[str]:
    """The lines of the docs block, from the record ``--json`` wrote."""
    lines = [
        f"{label:<40} {count:>12,.0f} instructions per step" for label, count in record["instructions_per_step"].items()
    ]
    lines += [f"ratio, {kind}: {ratio:.2f}x CartPole's" for kind, ratio in record["ratios"].items()]
    return lines


BLOCKS = (fenced("instructions", DOCS_JSON, render_instructions,
                 Schema({"instructions_per_step": dict, "ratios": dict})),)  # fmt: skip

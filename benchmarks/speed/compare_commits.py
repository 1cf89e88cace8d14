"""Time the vector env of two commits against each other, alternating, each against CartPoleVectorEnv.

    python -m benchmarks run compare-commits 279a9bf HEAD            # 6 rounds (about 40 seconds)
    python -m benchmarks run compare-commits 279a9bf HEAD --rounds 8 --num-envs 1024
    python -m benchmarks run compare-commits 630ea6d HEAD --load 2 --docs    # 2 busy background processes

This machine has slow phases that last seconds to minutes, in which every step takes up to 1.5x as long:
two timing runs made minutes apart can differ more than two versions of the code do. So the two commits
run alternately, each in a fresh process (``git worktree`` checkouts, so the working tree is not touched),
and each run times our float64 vector env and Gymnasium's CartPoleVectorEnv in interleaved repeats. What
is compared is each run's median ratio to CartPole, and the median over the rounds. With ``--load N``, N
busy background processes (:func:`benchmarks.core.timing.background_load`) run throughout, as other work on a
user's machine. ``--docs`` writes docs/throughput/compare_loaded.json (with ``--load``) or
compare_quiet_one_thread.json (without), the records of docs/throughput.md's blocks. Instruction counts
(``instructions``) compare two versions without noise but leave out memory stalls and
waiting for threads; this measures time.
"""

from __future__ import annotations

import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[2]
DOCS_JSON = {True: "docs/throughput/compare_loaded.json", False: "docs/throughput/compare_quiet_one_thread.json"}
"""With busy background processes or not -> the record of the docs' block."""


def child(num_envs: int, repeats: int, steps: int) -> None:
    """Print the median step time of ours and CartPole's, and their median ratio (CartPole's time / ours)."""
    import warnings

    import gymnasium as gym
    import numpy as np

    import dwr_gym

    warnings.filterwarnings("ignore")
    envs = {
        "ours": gym.make_vec("DWRPointStabilization-v0", num_envs=num_envs),
        "cart": gym.make_vec("CartPole-v1", num_envs=num_envs, vectorization_mode="vector_entry_point"),
    }
    rng = np.random.default_rng(0)
    actions = {
        "ours": rng.uniform(-1, 1, (num_envs, 2)).astype(np.float32),  # as throughput.py: fixed random actions
        "cart": rng.integers(0, 2, num_envs),
    }
    for name, env in envs.items():
        env.reset(seed=0)
        env.step(actions[name])
    times: dict[str, list[float]] = {"ours": [], "cart": []}
    for _ in range(repeats):
        for name, env in envs.items():
            start = time.perf_counter()
            for _ in range(steps):
                env.step(actions[name])
            times[name].append((time.perf_counter() - start) / steps)
    ratio = statistics.median(c / o for o, c in zip(times["ours"], times["cart"], strict=True))
    print(dwr_gym.__file__)
    print(f"{statistics.median(times['ours']) * 1e6:.1f} {statistics.median(times['cart']) * 1e6:.1f} {ratio:.4f}")


def checkout(commit: str, into: Path) -> Path:
    """A detached worktree of ``commit`` in ``into``."""
    result = subprocess.run(["git", "-C", str(ROOT), "worktree", "add", "--detach", "-f", str(into), commit],
                            capture_output=True, text=True)  # fmt: skip
    if result.returncode:
        sys.exit(f"commit {commit!r} is invalid: expected a git revision of {ROOT} ({result.stderr.strip()})")
    return into


def resolve(commit: str) -> str:
    """The short hash of the git revision ``commit``."""
    result = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", f"{commit}^{{commit}}"],
                            capture_output=True, text=True)  # fmt: skip
    if result.returncode:
        sys.exit(f"commit {commit!r} is invalid: expected a git revision of {ROOT} ({result.stderr.strip()})")
    return result.stdout.strip()


def measure(tree: Path, num_envs: int) -> tuple[float, float, float]:
    """(our step [us], CartPole's step [us], CartPole's time / ours) of one run of the code in ``tree``."""
    result = subprocess.run(  # this file, run by path: its child imports nothing of the suite, only the tree's env
        [sys.executable, __file__, "--child", str(num_envs)], cwd=tree, capture_output=True, text=True, check=True,
        env={**os.environ, "PYTHONPATH": str(tree)},
    )  # fmt: skip
    where, *numbers = result.stdout.split()
    if not Path(where).resolve().is_relative_to(tree.resolve()):  # e.g. a non-editable install shadows PYTHONPATH
        sys.exit(f"the run imported dwr_gym from {where}, not from the checkout {tree}: uninstall that copy")
    ours, cart, ratio = map(float, numbers)
    return ours, cart, ratio


def main(argv: list[str] | None = None) -> int:
    from benchmarks.core.commands import parser_for  # (here: the child, run by path elsewhere, imports no suite)

    parser = parser_for("compare-commits", __doc__)
    parser.add_argument("old", nargs="?", help="the first commit (any git revision)")
    parser.add_argument("new", nargs="?", help="the second commit")
    parser.add_argument("--rounds", type=int, default=6, help="alternations of the two (default 6)")
    parser.add_argument("--num-envs", type=int, default=4096, help="robots in the vector env (default 4096)")
    parser.add_argument("--load", type=int, default=0, help="busy background processes throughout (default 0)")
    parser.add_argument("--json", type=Path, help="also write the rounds and medians to this JSON file")
    parser.add_argument("--docs", action="store_true", help=f"write the JSON of the docs' block ({DOCS_JSON[True]} "
                        f"with --load, else {DOCS_JSON[False]})")  # fmt: skip
    args = parser.parse_args(argv)
    if args.docs:
        args.json = ROOT / DOCS_JSON[args.load > 0]
    if not (args.old and args.new):
        parser.error("give two commits, e.g. 279a9bf HEAD")
    if args.rounds < 1 or args.num_envs < 1:
        parser.error(f"--rounds={args.rounds} and --num-envs={args.num_envs} must be positive integers")
    if not 0 <= args.load <= 64:
        parser.error(f"--load={args.load} is invalid: expected 0 to 64 background processes")
    from benchmarks.core.timing import background_load

    commits = (resolve(args.old), resolve(args.new))  # hashes: HEAD and branch names move, the record must not
    ratios: list[list[float]] = [[], []]
    with tempfile.TemporaryDirectory() as tmp, background_load(args.load, 60.0 * args.rounds + 300.0):
        trees: list[Path] = []
        try:
            for i, commit in enumerate(commits):
                trees.append(checkout(commit, Path(tmp) / f"tree{i}"))
            for round_ in range(args.rounds):
                for i, tree in enumerate(trees):
                    ours, cart, ratio = measure(tree, args.num_envs)
                    ratios[i].append(ratio)
                    print(f"round {round_ + 1}: {commits[i]:>12}  ours {ours:7.1f} us  CartPoleVectorEnv {cart:6.1f} us"
                          f"  ratio {ratio:.3f}", flush=True)  # fmt: skip
        finally:
            for tree in trees:
                subprocess.run(["git", "-C", str(ROOT), "worktree", "remove", "--force", str(tree)], check=False)
    old, new = map(statistics.median, ratios)
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        record = {"commits": list(commits), "num_envs": args.num_envs, "load_processes": args.load,
                  "omp_num_threads": os.environ.get("OMP_NUM_THREADS"), "rounds": args.rounds, "ratios": ratios,
                  "median_ratios": [old, new]}  # fmt: skip
        args.json.write_text(json.dumps(record, indent=1) + "\n")
    loaded = f", {args.load} busy background processes" if args.load else ""
    print(f"median ratio to CartPoleVectorEnv at N = {args.num_envs}{loaded}: {commits[0]} {old:.3f}, {commits[1]} {new:.3f} "
          f"({new / old:.2f}x)")  # fmt: skip
    return 0


def render_compare(record: dict[str, Any]) -> list[str]:
    """The lines of a docs block, from the record ``--json`` wrote."""
    (old, new), load = record["commits"], record["load_processes"]
    threads = record.get("omp_num_threads")
    setting = f"OMP_NUM_THREADS={threads}" if threads else "default threads"
    lines = [f"float64 vector env at N = {record['num_envs']}, {load} busy background processes, {setting}; speed "
             "relative to CartPoleVectorEnv in the same process, per round:"]  # fmt: skip
    for commit, ratios in zip(record["commits"], record["ratios"], strict=True):
        lines.append(f"{commit:>8}: " + "  ".join(f"{r:.3f}x" for r in ratios))
    old_median, new_median = record["median_ratios"]
    lines.append(
        f"median: {old} {old_median:.3f}x, {new} {new_median:.3f}x ({new_median / old_median:.1f} times as fast)"
    )
    return lines


def _blocks() -> tuple[Any, ...]:
    from benchmarks.core.docs import Schema, fenced

    schema = Schema({"commits": list, "num_envs": int, "load_processes": int, "ratios": list, "median_ratios": list})
    return (fenced("compare-commits-loaded", DOCS_JSON[True], render_compare, schema),
            fenced("compare-commits-quiet", DOCS_JSON[False], render_compare, schema))  # fmt: skip


BLOCKS = _blocks() if __name__ != "__main__" else ()  # (run by path, as the child, the suite is not importable)

if __name__ == "__main__":  # the child of measure(), run by path in another commit's checkout: no suite there
    child(int(sys.argv[sys.argv.index("--child") + 1]), repeats=15, steps=50)

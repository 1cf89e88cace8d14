"""Env steps per second of sbx-rl (JAX) against stable-baselines3 (torch) for SAC, TQC and CrossQ, in one run.

    nice -n 5 python -m benchmarks run sbx-speed --docs    # docs/rl_benchmark/sbx_speed.json and its table

Each algorithm trains with the settings of ``dwr-gym train`` (train/hyperparams/<algo>.yml on
DWRPointStabilization-v1: 64 robots, one gradient step of 256 samples per step of the 64) on the native vector env,
through ``train.learning.training_env.make_training_env``, once with each library. The compile (sbx) and the replay
buffer's warm-up (``learning_starts``) run first and are not timed; then ``--steps`` env steps of training are timed.
The libraries alternate within each of ``--repeats`` rounds, so the ratio sbx / sb3 of each round is measured
seconds apart on the same load; the JSON keeps every round, the medians and the load average (written after each
round). Both run on one
thread (torch's ``set_num_threads(1)``, XLA without its Eigen thread pool), as ``dwr-gym train`` does by default.
"""

from __future__ import annotations

import os
import platform
import statistics
import time
from pathlib import Path
from typing import Any

from benchmarks.core.commands import parser_for
from benchmarks.core.docs import NUMBER, Schema, table
from benchmarks.core.record import write_json

ROOT = Path(__file__).resolve().parents[2]
JSON_PATH = ROOT / "docs" / "rl_benchmark" / "sbx_speed.json"
ALGORITHMS = ("sac", "tqc", "crossq")
BACKENDS = ("sb3", "sbx")


def one_thread() -> None:
    """torch and XLA on one thread each, as ``dwr-gym train`` runs by default; before either is imported."""
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    os.environ["XLA_FLAGS"] = f"{os.environ.get('XLA_FLAGS', '')} --xla_cpu_multi_thread_eigen=false".strip()


def steps_per_second(algo: str, backend: str, steps: int, env_id: str) -> float:
    """Env steps per second of training ``algo`` with ``backend``, after its warm-up (not timed)."""
    from train.learning.config import TrainConfig
    from train.learning.hyperparams import algorithm_class, build_algo_kwargs, resolve_hyperparams
    from train.learning.training_env import make_training_env

    config = TrainConfig(algo=algo, backend=backend, env_id=env_id, progress=False)
    config.validate()
    resolve_hyperparams(config, set())
    env = make_training_env(config)
    model = algorithm_class(algo, backend)(env=env, seed=0, device="cpu", verbose=0,
                                           **build_algo_kwargs(config.algo_kwargs, backend))  # fmt: skip
    model.learn(int(config.algo_kwargs.get("learning_starts", 0)) + 10 * config.num_envs)  # warm-up and compile
    began = time.perf_counter()
    done = model.num_timesteps
    model.learn(steps, reset_num_timesteps=False)
    rate = (model.num_timesteps - done) / (time.perf_counter() - began)
    env.close()
    return rate


def run(repeats: int, steps: int, env_id: str, algorithms: tuple[str, ...], path: Path | None = None) -> dict[str, Any]:
    """Alternate the libraries ``repeats`` times per algorithm; every round, the medians and their ratio (written to
    ``path`` after each round, so that a run cut short keeps the rounds it finished)."""
    import torch

    torch.set_num_threads(1)
    rounds: list[dict[str, float]] = []
    data: dict[str, Any] = {}
    for index in range(repeats):
        entry = {f"{algo}-{backend}": steps_per_second(algo, backend, steps, env_id)
                 for algo in algorithms for backend in BACKENDS}  # fmt: skip
        rounds.append(entry)
        print(f"round {index + 1}/{repeats}: " + ", ".join(f"{k} {v:.0f}" for k, v in entry.items()), flush=True)
        data = summarize(rounds, steps, env_id, algorithms)
        if path is not None:
            write_json(path, data)
    return data


def summarize(rounds: list[dict[str, float]], steps: int, env_id: str, algorithms: tuple[str, ...]) -> dict[str, Any]:
    """The JSON of the docs: every round, and per algorithm the medians over rounds and the ratio sbx / sb3."""
    summary = {}
    for algo in algorithms:
        ratios = [r[f"{algo}-sbx"] / r[f"{algo}-sb3"] for r in rounds]
        summary[algo] = {"sb3_steps_per_s": statistics.median(r[f"{algo}-sb3"] for r in rounds),
                         "sbx_steps_per_s": statistics.median(r[f"{algo}-sbx"] for r in rounds),
                         "ratio_sbx_over_sb3": statistics.median(ratios), "ratios": ratios}  # fmt: skip
    return {"env_id": env_id, "steps_timed": steps, "repeats": len(rounds), "rounds": rounds, "summary": summary,
            "machine": f"{platform.machine()}, {os.cpu_count()} cores", "load_average": os.getloadavg()[0],
            "versions": _versions()}  # fmt: skip


def _versions() -> dict[str, str]:
    from importlib.metadata import version

    return {name: version(name) for name in ("stable-baselines3", "sb3-contrib", "sbx-rl", "torch", "jax")}


def main(argv: list[str] | None = None) -> int:
    parser = parser_for("sbx-speed", __doc__)
    parser.add_argument("--repeats", type=int, default=3, help="rounds, each timing every library (default: 3)")
    parser.add_argument("--steps", type=int, default=32_000, help="env steps timed per measurement (default: 32000)")
    parser.add_argument("--env", default="DWRPointStabilization-v1", help="env id (default: DWRPointStabilization-v1)")
    parser.add_argument("--algorithms", nargs="+", default=list(ALGORITHMS), choices=ALGORITHMS)
    parser.add_argument("--docs", action="store_true", help=f"write {JSON_PATH.relative_to(ROOT)} (and its table)")
    args = parser.parse_args(argv)
    if args.repeats < 1 or args.steps < 1:
        parser.error(f"--repeats {args.repeats} and --steps {args.steps}: expected both >= 1")
    one_thread()
    data = run(args.repeats, args.steps, args.env, tuple(args.algorithms), JSON_PATH if args.docs else None)
    from train.reporting.doc_tables import sbx_speed_table

    print(sbx_speed_table(data))
    return 0


#: The table of docs/rl-libraries.md.
BLOCKS = (table("sbx-speed", Schema({"env_id": str, "steps_timed": int, "repeats": int, "rounds": list,
                                     "summary": dict, "machine": str, "load_average": NUMBER,
                                     "versions": dict})),)  # fmt: skip

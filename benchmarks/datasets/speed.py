"""How fast ``dwr-gym dataset`` makes 1 M transitions of an analytic expert (PTC): collection and Minari's write.

    OMP_NUM_THREADS=1 python -m benchmarks run dataset-speed              # writes docs/datasets/speed.json

The goal: 1 M transitions in at most 60 s on 2 cores, from the collection in the native vector env to the
dataset on disk (without the optimum of each episode, which CasADi solves once per episode and caches: its time
is measured apart). Minari's write is also timed as Minari 0.5 does it, recomputing the dataset's size after each
episode, on a fifth of the episodes, to show why the write skips that.
"""

from __future__ import annotations

import json
import os
import platform
import shutil
import tempfile
import time
from pathlib import Path

from benchmarks.core.commands import parser_for
from benchmarks.core.docs import NUMBER, Schema, table

ROOT = Path(__file__).resolve().parents[2]
OUT = ROOT / "docs" / "datasets" / "speed.json"
GOAL_SECONDS = 60.0


def main(argv: list[str] | None = None) -> int:
    parser = parser_for("dataset-speed", __doc__)
    parser.add_argument("--transitions", type=int, default=1_000_000)
    parser.add_argument("--out", type=Path, default=OUT)
    parser.add_argument("--docs", action="store_true", help="(--out is the docs' JSON by default; renders its table)")
    args = parser.parse_args(argv)
    root = Path(tempfile.mkdtemp(prefix="dwr-gym-dataset-speed-"))
    os.environ["MINARI_DATASETS_PATH"] = str(root)
    import minari

    from baselines.expert import ExpertPolicy
    from baselines.registry import make_controller
    from train.datasets.collect import collect
    from train.datasets.store import write_dataset
    from train.env_ids import TASK_ENV_ID, env_keywords

    kwargs = env_keywords(TASK_ENV_ID)
    policy = ExpertPolicy(make_controller("ptc"), 0.5, 2.0)
    probe = collect(policy, kwargs, 64, seed=10**6)  # the mean episode length, to ask for the right number
    episodes = round(args.transitions / (probe.steps / 64))
    began = time.perf_counter()
    data = collect(policy, kwargs, episodes, seed=0)
    collected = time.perf_counter()
    write_dataset("bench/ptc-v0", data, TASK_ENV_ID, kwargs, algorithm_name="ptc", description="speed",
                  ref_min_score=0.0, ref_max_score=1.0)  # fmt: skip
    written = time.perf_counter()
    total = written - began
    began_load = time.perf_counter()
    loaded = minari.load_dataset("bench/ptc-v0")
    steps_back = sum(len(e.rewards) for e in loaded.iterate_episodes())
    load_seconds = time.perf_counter() - began_load
    # Minari's own write of a fifth of the episodes, with the size recomputed after each episode
    from minari.data_collector import EpisodeBuffer

    fifth = episodes // 5
    buffers = [EpisodeBuffer(id=k, observations=data.observations[k], actions=data.actions[k],
                             rewards=data.rewards[k], terminations=data.terminations[k],
                             truncations=data.truncations[k]) for k in range(fifth)]  # fmt: skip
    start = time.perf_counter()
    minari.create_dataset_from_buffers("bench/ptc-unpatched-v0", buffers, env=TASK_ENV_ID, algorithm_name="ptc",
                                       author="bench", code_permalink="-", description="-", data_format="arrow",
                                       author_email="-")  # fmt: skip
    unpatched = time.perf_counter() - start
    start = time.perf_counter()
    write_dataset("bench/ptc-fifth-v0", type(data)(data.observations[:fifth], data.actions[:fifth],
                  data.rewards[:fifth], data.terminations[:fifth], data.truncations[:fifth], data.metadata[:fifth]),
                  TASK_ENV_ID, kwargs, algorithm_name="ptc", description="-", ref_min_score=0.0, ref_max_score=1.0)  # fmt: skip
    patched = time.perf_counter() - start
    shutil.rmtree(root, ignore_errors=True)
    result = {
        "transitions": data.steps, "episodes": episodes, "collect_seconds": round(collected - began, 2),
        "write_seconds": round(written - collected, 2), "total_seconds": round(total, 2),
        "transitions_per_second": round(data.steps / total), "goal_seconds": GOAL_SECONDS,
        "goal_met": total <= GOAL_SECONDS, "load_seconds": round(load_seconds, 2), "loaded_steps": steps_back,
        "fifth_episodes": fifth, "fifth_minari_write_seconds": round(unpatched, 2),
        "fifth_our_write_seconds": round(patched, 2), "cores": os.cpu_count(), "python": platform.python_version(),
        "minari": minari.__version__, "command": "OMP_NUM_THREADS=1 python -m benchmarks run dataset-speed",
    }  # fmt: skip
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=1) + "\n")
    print(json.dumps(result, indent=1))
    return 0


BLOCKS = (table("datasets-speed", Schema({"transitions": int, "episodes": int, "collect_seconds": NUMBER,
                                          "write_seconds": NUMBER, "total_seconds": NUMBER, "goal_seconds": NUMBER,
                                          "goal_met": bool, "command": str})),)  # fmt: skip

"""Env steps per second of an APG update against its episodes per update, on the backend jax runs on (CPU or GPU).

The update is `dwr-gym train --algo apg --backend jax`'s, with the options of the benchmark entry
``apg-hold-heading10-time-scaled-30min-v2`` (train/hyperparams/apg_teacher.yml under them), only ``episodes``
changed: how much an update's cost grows with the episodes it plays, which decides whether a wider batch (or a GPU)
would buy a seed more env steps in the goal's 30 minutes.

    nice -n 5 python -m benchmarks run apg-speed --docs     # docs/jax/apg_speed.json and docs/jax-training.md's block
    python -m benchmarks run apg-speed --json OUT.json       # any backend, e.g. on a GPU

Each round plays one update of every size, in turn (the same state, so the same episodes), so that the ratios hold on
a busy machine; an update's env steps are its episodes' own, not the held steps of those already ended that the scan
still computes. Compilation is timed apart. Process CPU time beside wall time shows the cores used.
"""

from __future__ import annotations

import os
import statistics
from pathlib import Path
from typing import Any

from benchmarks.core.commands import parser_for
from benchmarks.core.docs import NUMBER, Schema, fenced
from benchmarks.core.record import write_json
from benchmarks.core.timing import jax_machine, jax_timed

ROOT = Path(__file__).resolve().parents[2]
JSON_PATH = ROOT / "docs" / "jax" / "apg_speed.json"
ENTRY = "apg-hold-heading10-time-scaled-30min-v2"
EPISODES = (16, 64, 256, 1024)


def measure(episodes: tuple[int, ...], repeats: int) -> dict[str, Any]:
    import jax

    from train.learning.benchmark import parse_entry, train_config
    from train.learning.hyperparams import fill_budget, resolve_hyperparams
    from train.learning.jitted.apg import JaxAPG
    from train.learning.jitted.apg_settings import APGSettings
    from train.learning.jitted.setup import make_jax_env

    config = train_config(parse_entry(ENTRY), 0, ROOT / "results" / "apg-speed", {})
    config = resolve_hyperparams(config, set())
    fill_budget(config)
    config.num_envs = 1
    env, env_params = make_jax_env(config)
    learners, states, steps, compile_s = {}, {}, {}, {}
    for n in episodes:
        settings = APGSettings.from_algo_kwargs({**config.algo_kwargs, "episodes": n})
        learners[n] = JaxAPG(settings, env, env_params, total_timesteps=float(config.total_timesteps))
        states[n] = learners[n].init(0)
        wall, _, _ = jax_timed(lambda n=n: learners[n].update(states[n]))
        compile_s[str(n)] = round(wall, 1)
        steps[n] = int(jax_timed(lambda n=n: learners[n].update(states[n]))[2][1]["steps"])
    rounds = []
    for _ in range(repeats):
        row = {}
        for n in episodes:
            wall, cpu, _ = jax_timed(lambda n=n: learners[n].update(states[n]))
            row[str(n)] = {"steps_per_s": steps[n] / wall, "update_s": wall, "cpu_per_wall": cpu / wall}
        rounds.append(row)
    median = {str(n): statistics.median(r[str(n)]["steps_per_s"] for r in rounds) for n in episodes}
    return {"machine": jax_machine(), "backend": jax.default_backend(), "entry": ENTRY,
            "recipe_episodes": int(config.algo_kwargs.get("episodes", 64)), "max_steps": learners[episodes[0]].max_steps,
            "steps_per_update": {str(n): steps[n] for n in episodes}, "compile_seconds": compile_s, "rounds": rounds,
            "median_steps_per_s": median,
            "median_update_s": {str(n): statistics.median(r[str(n)]["update_s"] for r in rounds) for n in episodes},
            "median_cpu_per_wall": {str(n): statistics.median(r[str(n)]["cpu_per_wall"] for r in rounds)
                                    for n in episodes},
            "load_average_1min_at_end": round(os.getloadavg()[0], 2)}  # fmt: skip


def render(data: dict[str, Any]) -> list[str]:
    fps, update_s, cores = data["median_steps_per_s"], data["median_update_s"], data["median_cpu_per_wall"]
    recipe = str(data["recipe_episodes"])
    lines = [data["machine"], f"load average {data['load_average_1min_at_end']} (1 min, at the end); "
             f"{len(data['rounds'])} alternating rounds; medians; the scan is {data['max_steps']:,} steps long",
             "", f"{'episodes per update':<22}{'env steps':>12}{'update s':>10}{'env steps/s':>13}{'vs ' + recipe:>8}"
             f"{'CPU/wall':>10}{'compile s':>11}"]  # fmt: skip
    for n, rate in fps.items():
        mark = " (the recipe's)" if n == recipe else ""
        lines.append(f"{n + mark:<22}{data['steps_per_update'][n]:>12,}{update_s[n]:>10.3f}{rate:>13,.0f}"
                     f"{rate / fps[recipe] if recipe in fps else float('nan'):>7.2f}x{cores[n]:>10.2f}"
                     f"{data['compile_seconds'][n]:>11.1f}")  # fmt: skip
    return lines


def main(argv: list[str] | None = None) -> int:
    parser = parser_for("apg-speed", __doc__)
    parser.add_argument("--episodes", type=int, nargs="+", default=list(EPISODES),
                        help=f"episodes per update to time (default: {' '.join(map(str, EPISODES))})")  # fmt: skip
    parser.add_argument("--repeats", type=int, default=5, help="alternating rounds (default: 5)")
    parser.add_argument("--threads", type=int, default=1, help="XLA CPU threads (default: 1; ignored on a GPU)")
    parser.add_argument("--docs", action="store_true", help=f"write {JSON_PATH.relative_to(ROOT)} (and its block)")
    parser.add_argument("--json", default=None, metavar="PATH", help="write the measurement here (any backend)")
    args = parser.parse_args(argv)
    if args.repeats < 1 or min(args.episodes) < 1 or args.threads < 1:
        parser.error(f"--repeats {args.repeats}, --episodes {args.episodes} and --threads {args.threads}: "
                     "expected each >= 1")  # fmt: skip
    from train.learning.jitted.setup import configure_threads

    configure_threads(args.threads)
    data = measure(tuple(dict.fromkeys(args.episodes)), args.repeats)
    data["threads"] = args.threads
    print("\n".join(render(data)))
    if args.json is not None:
        write_json(Path(args.json), data)
    if args.docs and data["backend"] != "cpu":
        parser.error(f"--docs records the CPU's measurement, not {data['backend']}'s: use --json PATH there, or "
                     "JAX_PLATFORMS=cpu")  # fmt: skip
    if args.docs:
        write_json(JSON_PATH, data)
    return 0


SCHEMA = Schema({"machine": str, "backend": str, "entry": str, "recipe_episodes": int, "max_steps": int,
                 "steps_per_update": dict, "compile_seconds": dict, "rounds": list, "median_steps_per_s": dict,
                 "median_update_s": dict, "median_cpu_per_wall": dict, "load_average_1min_at_end": NUMBER,
                 "threads": int})  # fmt: skip
#: The block of docs/jax-training.md.
BLOCKS = (fenced("apg-speed", "docs/jax/apg_speed.json", render, SCHEMA),)

"""Each env version's vector step against v0's, in the same run: what a version's task costs per step.

    python -m benchmarks run env-versions            # N = 4096, 9 interleaved repeats (about a minute on 2 cores)
    python -m benchmarks run env-versions --docs     # writes docs/throughput/env_versions.json and renders its block

Every id of ``train.env_ids.ENV_IDS`` (a new version is measured as soon as it is listed there) as the native vector
env, float64, each with the same fixed random actions (:func:`benchmarks.speed.throughput.vector_stepper`), episodes
ending and restarting as they do. The envs take turns within each repeat (:func:`benchmarks.core.timing.interleaved`),
and each ratio to v0 is the median of the ratios within one repeat, so a drift in the machine's load hits both sides.
"""

from __future__ import annotations

import contextlib
import statistics
from pathlib import Path
from typing import Any

from benchmarks.core.commands import parser_for
from benchmarks.core.docs import NUMBER, Schema, fenced
from benchmarks.core.record import load_average, report, torch_machine
from benchmarks.core.timing import Stepper, interleaved, paired_ratio

JSON_PATH = Path(__file__).resolve().parents[2] / "docs" / "throughput" / "env_versions.json"


def measure(num_envs: int, repeats: int, number: int) -> dict[str, Any]:
    """Seconds per step of each version, and its speed relative to v0's, in interleaved repeats."""
    import gymnasium as gym

    from benchmarks.speed.throughput import vector_stepper
    from train.env_ids import ENV_IDS, PAPER_ENV_ID

    steppers: dict[str, Stepper] = {}
    for env_id in sorted(ENV_IDS):
        envs = gym.make_vec(env_id, num_envs=num_envs, vectorization_mode="vector_entry_point")
        steppers[env_id] = (vector_stepper(envs), contextlib.nullcontext)
    times = interleaved(steppers, repeats, number)
    rows = [{"env_id": env_id, "us_per_step": statistics.median(seconds) * 1e6,
             "env_steps_per_second": num_envs / statistics.median(seconds),
             "speed_to_reference": paired_ratio(times, env_id, PAPER_ENV_ID)} for env_id, seconds in times.items()]  # fmt: skip
    return {"machine": torch_machine(), "load_average_1min_at_end": load_average(), "num_envs": num_envs,
            "repeats": repeats, "steps_per_turn": number, "reference": PAPER_ENV_ID, "rows": rows}  # fmt: skip


def render(data: dict[str, Any]) -> list[str]:
    """The docs block: one line per version, from the JSON alone."""
    lines = [f"{data['machine']}; load average {data['load_average_1min_at_end']} (1 min, at the end)",
             f"N = {data['num_envs']} robots, float64; medians of {data['repeats']} interleaved repeats of "
             f"{data['steps_per_turn']} steps", "",
             f"{'env id':<28}{'us per step':>12}{'M env-steps/s':>15}{'speed / ' + data['reference'][-2:]:>12}"]  # fmt: skip
    for row in data["rows"]:
        lines.append(f"{row['env_id']:<28}{row['us_per_step']:>12,.0f}{row['env_steps_per_second'] / 1e6:>15.2f}"
                     f"{row['speed_to_reference']:>11.2f}x")  # fmt: skip
    return lines


def main(argv: list[str] | None = None) -> int:
    parser = parser_for("env-versions", __doc__)
    parser.add_argument("--num-envs", type=int, default=4096, help="robots per step (default 4096)")
    parser.add_argument("--repeats", type=int, default=9, help="interleaved repeats (default 9)")
    parser.add_argument("--steps", type=int, default=40, help="steps per turn of each env (default 40)")
    parser.add_argument("--docs", action="store_true", help=f"write {JSON_PATH.name} (and render its block)")
    args = parser.parse_args(argv)
    for name in ("num_envs", "repeats", "steps"):
        if getattr(args, name) < 1:
            parser.error(f"--{name.replace('_', '-')}={getattr(args, name)} is invalid: expected a positive integer")
    data = measure(args.num_envs, args.repeats, args.steps)
    return report(render(data), data, JSON_PATH if args.docs else None)


BLOCKS = (fenced("env-versions", "docs/throughput/env_versions.json", render,
                 Schema({"machine": str, "num_envs": int, "repeats": int, "reference": str, "rows": list,
                         "load_average_1min_at_end": NUMBER})),)  # fmt: skip

"""Retrain every shipped agent (train/pretrained/*/config.yaml) from its own config over 3 seeds; print mean +- sd.

    OMP_NUM_THREADS=1 nice -n 10 python benchmarks/retrain_pretrained.py                 # the full budgets
    python benchmarks/retrain_pretrained.py --total-timesteps 150000 --seeds 0           # a quicker check

Each run is ``dwr-gym train`` with the shipped run's saved configuration, only the seed and the run
directory changed (and the budget, if given). Every agent is then evaluated on the ``random`` scenario set
(1,000 seeded starts, seed 0) as in the README's results table, beside the shipped agent itself.
"""

from __future__ import annotations

import argparse
import statistics
import sys
from pathlib import Path
from typing import Any

METRICS = (("success_rate", "arrival before T_con", "{:.1%}"), ("arrival_time_mean", "mean arrival [s]", "{:.2f}"),
           ("final_heading_error_mean", "heading error [rad]", "{:.3f}"), ("energy_mean", "energy", "{:.2f}"))  # fmt: skip


def evaluate_agent(path: Path, n: int) -> dict[str, float]:
    """The summary of a saved agent on the random scenario set of the README (seed 0)."""
    from train.evaluation.rollout import rollout
    from train.evaluation.scenarios import make_scenario
    from train.learning.agents import load_agent
    from train.learning.runs import load_config

    config = load_config(path.parent if path.is_file() else path)
    _, policy = load_agent(path)
    scenario = make_scenario("random", n=n, seed=0, env_kwargs=config.env_keywords())
    return rollout(policy, config.env_params(), scenario.starts, scenario.goals, T_con=scenario.T_cons).summary()


def mean_sd(values: list[float], fmt: str) -> str:
    sd = statistics.stdev(values) if len(values) > 1 else 0.0
    return f"{fmt.format(statistics.fmean(values))} +- {fmt.format(sd)}"


def main() -> int:
    import torch

    from train.learning.runs import load_config
    from train.learning.training import train

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    parser.add_argument("--total-timesteps", type=float, default=None, help="budget per run (default: the config's)")
    parser.add_argument("--n", type=int, default=1000, help="random starts in the evaluation (default: 1000)")
    parser.add_argument("--out", default="runs/retrain", help="where the runs go (default: runs/retrain)")
    parser.add_argument("--pretrained", default=str(Path(__file__).parents[1] / "train" / "pretrained"))
    args = parser.parse_args()
    torch.set_num_threads(1)
    shipped = sorted(p.parent for p in Path(args.pretrained).glob("*/config.yaml"))
    if not shipped:
        print(f"no train/pretrained/*/config.yaml under {args.pretrained}", file=sys.stderr)
        return 1
    results: dict[str, list[dict[str, Any]]] = {}
    for run in shipped:
        for seed in args.seeds:
            config = load_config(run)
            config.seed, config.run_dir, config.overwrite, config.progress = (
                seed,
                f"{args.out}/{run.name}_s{seed}",
                True,
                False,
            )
            if args.total_timesteps:
                config.total_timesteps = int(args.total_timesteps)
            print(f"training {run.name} seed {seed} ({config.total_timesteps} steps) into {config.run_dir}", flush=True)
            run_dir = train(config)
            results.setdefault(run.name, []).append(evaluate_agent(run_dir / "model.zip", args.n))
    header = f"{'agent':<28}" + "".join(f"{title:>24}" for _, title, _ in METRICS)
    print("\n" + header + "\n" + "-" * len(header))
    for run in shipped:
        rows = results[run.name]
        label = f"{run.name} ({len(rows)} seeds)"
        print(f"{label:<28}" + "".join(f"{mean_sd([r[k] for r in rows], fmt):>24}" for k, _, fmt in METRICS))
        reference = evaluate_agent(run / "model.zip", args.n)
        print(f"{run.name + ' (shipped)':<28}" + "".join(f"{fmt.format(reference[k]):>24}" for k, _, fmt in METRICS))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

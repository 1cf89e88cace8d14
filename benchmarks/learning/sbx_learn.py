"""What sbx's TQC learns on v2 at the goal's budget: five seeds of 30 minutes, `dwr-gym benchmark` with references.

    nice -n 5 python -m benchmarks run sbx-learn v2-30min-tqc --docs     # about 2.5 hours on 2 cores

The suite's name for the ``dwr-gym benchmark`` command behind docs/rl-libraries.md's tables ``sbx-v2-30min-tqc``
(TQC, five seeds of 1800 s each, two runs side by side). It writes ``results/sbx-<run>/`` (a run already finished
there is only aggregated again); ``--docs`` copies its benchmark.json to ``docs/rl_benchmark/sbx_<run>.json``, from
which the tables are rendered, and writes its seeds' curves beside keeping still. The briefer runs of SAC, TQC and
CrossQ on v1 and v2 answered their question (none learns the task): their JSONs are rows of docs/what-was-tried.md.
"""

from __future__ import annotations

import csv
import math
import shutil
from pathlib import Path
from typing import Any

from benchmarks.core.commands import dwr_gym, parser_for
from benchmarks.core.docs import BENCHMARK, Schema, fenced, table
from benchmarks.core.record import write_json

ROOT = Path(__file__).resolve().parents[2]
RUN = "v2-30min-tqc"
#: The agents of its ``dwr-gym benchmark`` and their options: the goal's budget, 30 min a seed (the time limit, not
#: the env steps, ends it), two runs side by side.
COMMAND = ["benchmark", "--agents", "tqc-sbx-v2", "--seeds", "5", "--jobs", "2", "--time-limit", "1800",
           "--env-steps", "50000000", "--eval-freq", "1000000", "--eval-episodes", "200", "--disturbed-episodes",
           "20", "--optimum-episodes", "50", "--references"]  # fmt: skip
OUT = ROOT / "results" / f"sbx-{RUN}"
DOCS_JSON = "docs/rl_benchmark/sbx_v2_30min_tqc.json"
#: Its seeds' curves in brief beside keeping still (:func:`curves`), written with ``--docs``.
CURVES_JSON = "docs/rl_benchmark/sbx_v2_30min_tqc_curves.json"


def still_return(run_dir: Path, known: dict[str, float]) -> float:
    """The mean return of a robot that does not move (zero commands) on a run's own evaluation set, the set of its
    evaluations.csv: what a policy that learned nothing but to keep still would score. ``known``: the returns already
    measured, by evaluation set (the seeds of a run share theirs)."""
    import numpy as np

    from train.evaluation.rollout import rollout
    from train.evaluation.scenarios import make_scenario
    from train.learning.runs import load_config

    config = load_config(run_dir)
    key = repr((config.env_id, config.eval_seed, config.eval_episodes, config.env_keywords()))
    if key not in known:
        scenario = make_scenario("random", n=config.eval_episodes, seed=config.eval_seed,
                                 env_kwargs=config.env_keywords())  # fmt: skip

        class Still:
            def predict(self, obs: Any, **_: Any) -> tuple[Any, None]:
                return np.zeros((len(obs), 2)), None

        still = rollout(Still(), config.env_params(), scenario.starts, scenario.goals,
                        T_con=scenario.T_cons, env_kwargs=scenario.env_kwargs)  # fmt: skip
        known[key] = float(np.mean(still.episode_return))
    return known[key]


def curves() -> dict[str, Any]:
    """Each seed's learning curve of a run in brief (its evaluations.csv: the best in-time rate and where, the last
    evaluation) beside the return of keeping still on the same evaluation set."""
    seeds: dict[str, Any] = {}
    known: dict[str, float] = {}
    for run_dir in sorted((OUT / "runs").glob("*-seed*")):
        with (run_dir / "evaluations.csv").open() as handle:
            rows = [{k: float(v) if v else math.nan for k, v in row.items()} for row in csv.DictReader(handle)]
        peak = max(rows, key=lambda row: row["success_rate"])
        last = rows[-1]
        seeds[run_dir.name] = {
            "evaluations": len(rows), "peak_in_time": peak["success_rate"], "peak_env_steps": int(peak["timesteps"]),
            "last_env_steps": int(last["timesteps"]), "last_in_time": last["success_rate"],
            "last_return": last["return_mean"], "last_final_distance": last["final_distance_mean"],
            "last_energy": last["energy_mean"], "still_return": still_return(run_dir, known),
        }  # fmt: skip
    return {"run": RUN, "seeds": seeds}


def render_curves(data: dict[str, Any]) -> list[str]:
    lines = [f"{'run':<22}{'peak in time':>13}{'at env steps':>14}{'last in time':>13}{'last return':>12}"
             f"{'keeping still':>14}{'final distance':>15}{'energy':>8}"]  # fmt: skip
    for name, seed in data["seeds"].items():
        lines.append(f"{name:<22}{seed['peak_in_time']:>13.1%}{seed['peak_env_steps']:>14,}{seed['last_in_time']:>13.1%}"
                     f"{seed['last_return']:>12.2f}{seed['still_return']:>14.2f}{seed['last_final_distance']:>13.2f} m"
                     f"{seed['last_energy']:>8.2f}")  # fmt: skip
    return lines


def main(argv: list[str] | None = None) -> int:
    parser = parser_for("sbx-learn", __doc__)
    parser.epilog = f"{RUN}: dwr-gym {' '.join(COMMAND)}"
    parser.add_argument("run", nargs="?", choices=(RUN,), help="the run (the only one)")
    parser.add_argument("--docs", action="store_true", help=f"copy its benchmark.json to {DOCS_JSON}, write its curves")
    args = parser.parse_args(argv)
    dwr_gym([*COMMAND, "--out", str(OUT)])
    if args.docs:
        shutil.copyfile(OUT / "benchmark.json", ROOT / DOCS_JSON)
        print(f"wrote {DOCS_JSON}")
        data = curves()
        print("\n".join(render_curves(data)))
        write_json(ROOT / CURVES_JSON, data)
    return 0


#: The tables of docs/rl-libraries.md.
BLOCKS = (table("sbx-v2-30min-tqc", BENCHMARK), table("sbx-v2-30min-tqc-per-T_con", BENCHMARK),
          fenced("sbx-v2-30min-tqc-curves", CURVES_JSON, render_curves,
                 Schema({"run": str, "seeds": dict})))  # fmt: skip

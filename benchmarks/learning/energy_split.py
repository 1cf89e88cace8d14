"""Where the energy goes on v2, and how far the laws get by their gains alone (the v2 residual goal, sized).

    python -m benchmarks run energy-split --docs         # 100 episodes each (about 1.5 min on 2 cores)
    python -m benchmarks run energy-split --n 20         # a quick look (printed, nothing written)

``--docs`` writes docs/rl_benchmark/energy_split.json, from which the tables ``energy-split`` and ``law-gains`` of
docs/rl-apg.md are rendered. What is measured and how: train/evaluation/energy_split.py.
"""

from __future__ import annotations

import platform
import time
from pathlib import Path

from benchmarks.core.commands import parser_for
from benchmarks.core.docs import Schema, table
from benchmarks.core.record import write_json

ROOT = Path(__file__).resolve().parents[2]
JSON_PATH = ROOT / "docs" / "rl_benchmark" / "energy_split.json"
#: The policies whose energy is split: the optimum, the two laws the residual agents start from, the shipped v2 agents.
CONTROLLERS = ("optimal", "ptc", "pt-astolfi")
AGENTS = ("es_residual_v2", "residual_ppo_jax_v2", "apg_residual_v2")
#: The laws' own gains (baselines' defaults: the paper's for PTC), marked in the gains table.
DEFAULTS = {"ptc": {"K1": 2.0, "K2": 10.0}, "pt-astolfi": {"k_rho": 1.5, "k_alpha": 4.7, "k_beta": -1.7}}


def main(argv: list[str] | None = None) -> int:
    from train.evaluation.energy_split import energy_split, law_gains
    from train.learning.agents import PRETRAINED_DIR, load_agent

    parser = parser_for("energy-split", __doc__)
    parser.add_argument("--n", type=int, default=100, help="episodes of each measurement (default: 100)")
    parser.add_argument("--docs", action="store_true", help=f"write {JSON_PATH.relative_to(ROOT)} (and its tables)")
    args = parser.parse_args(argv)
    if args.n < 1:
        parser.error(f"--n {args.n} is invalid: expected an integer >= 1")
    start = time.time()
    policies = {name: name for name in CONTROLLERS} | {
        name.replace("_", "-"): load_agent(PRETRAINED_DIR / name)[1] for name in AGENTS
    }
    split = energy_split(policies, n=args.n)
    for row in split["rows"]:
        print(f"{row['policy']}: energy {row['energy_mean']:.3f} (linear {row['linear_mean']:.3f}, turning "
              f"{row['turning_mean']:.3f}), shares {[round(s, 2) for s in row['shares']]}")  # fmt: skip
    gains = law_gains(n=args.n)
    for law, best in gains["best"].items():
        print(law, {which: None if row is None else (row["gains"], round(row["energy_ratio"], 3),
                                                     round(row["final_heading"], 3)) for which, row in best.items()})  # fmt: skip
    data = {"split": split, "gains": gains, "defaults": DEFAULTS,
            "machine": {"python": platform.python_version(), "platform": platform.platform(),
                        "seconds": round(time.time() - start)}}  # fmt: skip
    if args.docs:
        write_json(JSON_PATH, data)
    return 0


SCHEMA = Schema({"split": dict, "gains": dict, "defaults": dict, "machine": dict})
BLOCKS = (table("energy-split", SCHEMA), table("law-gains", SCHEMA))

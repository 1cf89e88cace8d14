"""How fast should robust-pt's filter follow a disturbance? Its random-walk rates of (b_u, b_omega), measured.

Faster rates follow a push that changes quickly; but the filter then takes the late response of a delayed robot
for a disturbance. This runs ``robust-pt`` with each rate on one magnitude of each kind of disturbance (those of
``tests/test_robust.py``) and prints in-time rate and energy; ``--docs`` writes the rows (docs/robust/filter_rates.json,
the table of docs/robust.md).

    python -m benchmarks run robust-filter-rates --n 24 --docs
"""

from __future__ import annotations

import sys
from typing import Any

from benchmarks.core.commands import add_json_output, parser_for
from benchmarks.core.docs import NUMBER, Schema, table
from benchmarks.core.record import write_json

DOCS_JSON = "docs/robust/filter_rates.json"
RATES = ((0.02, 0.1), (0.05, 0.25), (0.1, 0.5))
T_CON = 20.0


def kinds() -> dict[str, dict[str, Any]]:
    """One magnitude of each kind: a 0.1 m/s (0.4 rad/s) sinusoid, 0.3 s of delay, a motor at half power, noise."""
    from dwr_gym.disturbances import ActuatorFault, InputDelay, VelocitySinusoid
    from dwr_gym.randomization import DEFAULT_GEOMETRY

    return {
        "sinusoid": {"disturbances": [VelocitySinusoid(0.1, 0.4, period=4.0)]},
        "delay": {"disturbances": [InputDelay(6)]},
        "fault": {"robot": DEFAULT_GEOMETRY, "disturbances": [ActuatorFault("left", 0.5, start_time=T_CON / 4)]},
        "noise": {"observation_noise": 0.01, "actuation_noise": 0.05},
    }


def main(argv: list[str] | None = None) -> None:
    parser = parser_for("robust-filter-rates", __doc__, allow_abbrev=False)
    parser.add_argument("--n", type=int, default=24, help="starts 0.3-3 m away per kind (default: 24)")
    parser.add_argument("--seed", type=int, default=5)
    add_json_output(parser, DOCS_JSON)
    args = parser.parse_args(argv)
    from baselines import ExpertPolicy, make_controller
    from baselines.estimation import PoseFilterParams
    from train.evaluation.evaluate import evaluate
    from train.evaluation.scenarios import make_scenario

    rows = []
    for kind, env_kwargs in kinds().items():
        scenario = make_scenario("random", n=args.n, seed=args.seed,
                                 env_kwargs={"T_con": T_CON, "start_distance": (0.3, 3.0), **env_kwargs})  # fmt: skip
        for rate in RATES:
            controller = make_controller("robust-pt", T_con=T_CON, estimator=PoseFilterParams(disturbance_rate=rate))
            result = evaluate({"robust-pt": ExpertPolicy(controller, 0.5, 2.0)}, scenario, seed=args.seed)["robust-pt"]
            controller.close()
            summary = result.summary()
            rows.append({"kind": kind, "disturbance_rate": list(rate), "n": args.n,
                         "success_rate": summary["success_rate"], "energy_mean": summary["energy_mean"]})  # fmt: skip
            print(f"{kind:9} rates {rate}: in time {100 * summary['success_rate']:5.1f} %, "
                  f"energy {summary['energy_mean']:.3f}", file=sys.stderr, flush=True)  # fmt: skip
    if args.json:
        write_json(args.json, {"T_con": T_CON, "seed": args.seed, "rows": rows})


BLOCKS = (table("robust-filter-rates", Schema({"T_con": NUMBER, "seed": int, "rows": list})),)

"""What limits RL on DWRPointStabilization-v1: the energy that exploration noise costs, measured.

v1 charges ``energy_weight * dt * (u^2 + omega^2)`` on the commands executed. An RL agent explores by adding
Gaussian noise of standard deviation sigma (in normalised action units) to its actions, so while it learns it
pays for the noise's energy too: about 2 * (u_max^2 + omega_max^2) * E[clip(N(0, sigma))^2] per second, which is
a cost per second of episode whatever the agent does, i.e. a reward for ending the episode early. This script
runs the PTC law with such noise on its actions (its deterministic behaviour is the same in every row) on v1's
task and reports, per sigma: the in-time rate, the energy, its ratio to the optimum and the return, beside the
optimum's own energy. The return of the noisy law falls with sigma while its arrival does not: the reward an
exploring agent sees is dominated by the noise's energy, which pays for arriving early (rushing), not for the
minimum-energy motion the task asks for.

    python -m benchmarks run rl-diagnosis --n 200 --docs     # writes docs/rl_benchmark/diagnosis.json
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from benchmarks.core.commands import parser_for
from benchmarks.core.docs import NUMBER, Schema, table
from benchmarks.core.record import write_json

ROOT = Path(__file__).resolve().parents[2]

SIGMAS = (0.0, 0.05, 0.14, 0.22, 0.5, 1.0)
"""Noise levels: 0.22 is exp(-1.5), the residual agents' initial sigma; 1.0 is exp(0), SB3's PPO default."""


class NoisyPolicy:
    """A policy with Gaussian noise of ``sigma`` added to its actions (as an exploring agent acts), clipped."""

    def __init__(self, policy: Any, sigma: float, seed: int = 0) -> None:
        self.policy, self.sigma, self.rng = policy, sigma, np.random.default_rng(seed)

    def predict(self, obs: Any, state: Any = None, episode_start: Any = None, deterministic: bool = True) -> Any:
        actions, state = self.policy.predict(obs, state, episode_start, deterministic)
        noise = self.sigma * self.rng.standard_normal(np.shape(actions))
        return np.clip(np.asarray(actions) + noise, -1.0, 1.0), state


def clipped_second_moment(sigma: float, samples: int = 200_000) -> float:
    """E[clip(N(0, sigma^2), -1, 1)^2], the mean squared action of pure noise."""
    x = np.clip(sigma * np.random.default_rng(0).standard_normal(samples), -1.0, 1.0)
    return float(np.mean(x * x))


def main(argv: list[str] | None = None) -> int:
    parser = parser_for("rl-diagnosis", __doc__)
    parser.add_argument("--n", type=int, default=200, help="episodes of the benchmark's nominal set (default 200)")
    parser.add_argument("--docs", action="store_true", help="write docs/rl_benchmark/diagnosis.json (and its table)")
    args = parser.parse_args(argv)

    from baselines.expert import ExpertPolicy
    from dwr_gym.disturbances import split_env_kwargs
    from dwr_gym.params import EnvParams
    from train.env_ids import TASK_ENV_ID, env_keywords
    from train.evaluation.benchmark import EVAL_SEED
    from train.evaluation.evaluate import evaluate
    from train.evaluation.scenarios import controller_for, make_scenario

    kwargs = env_keywords(TASK_ENV_ID, {})
    params = EnvParams.from_kwargs(**split_env_kwargs(kwargs)[0])
    scenario = make_scenario("random", n=args.n, seed=EVAL_SEED, env_kwargs=kwargs)
    rows = []
    for sigma in SIGMAS:
        ptc = ExpertPolicy(controller_for("ptc", scenario, params), params.u_max, params.omega_max)
        result = evaluate({"ptc": NoisyPolicy(ptc, sigma)}, scenario, optimum="pose")["ptc"]
        s = result.summary()
        duration = np.where(np.isfinite(result.arrival_time), result.arrival_time, result.T_con * params.horizon_factor)
        noise_rate = params.energy_weight * clipped_second_moment(sigma) * (params.u_max**2 + params.omega_max**2)
        rows.append({"sigma": sigma, "in_time": s["success_rate"], "energy": s["energy_mean"],
                     "energy_ratio": s["energy_ratio_mean"], "return": s["return_mean"],
                     "optimal_energy": s["optimal_energy_mean"], "episode_seconds": float(np.mean(duration)),
                     "noise_cost_per_second": noise_rate})  # fmt: skip
        print(f"sigma {sigma:4.2f}: in time {s['success_rate']:.3f}, energy {s['energy_mean']:.2f} "
              f"(optimum {s['optimal_energy_mean']:.2f}), return {s['return_mean']:.1f}, "
              f"noise's energy cost {noise_rate:.3f}/s over {np.mean(duration):.1f} s")  # fmt: skip
    data = {"env_id": TASK_ENV_ID, "n": args.n, "seed": EVAL_SEED, "energy_weight": params.energy_weight,
            "arrival_bonus": params.arrival_bonus, "rows": rows}  # fmt: skip
    if args.docs:
        write_json(ROOT / "docs" / "rl_benchmark" / "diagnosis.json", data)
    return 0


BLOCKS = (table("rl-diagnosis", Schema({"env_id": str, "n": int, "seed": int, "energy_weight": NUMBER,
                                        "arrival_bonus": NUMBER, "rows": list})),)  # fmt: skip

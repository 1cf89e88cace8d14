"""Where a PPO run's time goes: env step, expert, policy forward (rollout collection) and the update.

    python -m benchmarks run training-time                    # PPO and residual PPO on PTC, 16 envs, 65,536 steps
    python -m benchmarks run training-time --steps 200000 --num-envs 64

It trains with the same pieces as ``dwr-gym train`` (the native vector env behind the SB3 adapter, which keeps
the episode statistics, and the residual wrapper) and times, with a wrapper around each: the env's ``step_wait``,
the expert's ``predict``, the whole rollout collection (whose remainder is the policy's forward pass and
SB3's buffer bookkeeping) and ``train`` (the gradient updates). It prints steps per second and each
part's share, so a user sees whether the env is ever the bottleneck. Timings depend on the machine and
its load; the shares are steadier.
"""

from __future__ import annotations

import os
import platform
import time
from collections import defaultdict
from collections.abc import Callable
from typing import Any

from benchmarks.core.commands import parser_for

TIMES: dict[str, float] = defaultdict(float)


def timed(name: str, fn: Callable[..., Any]) -> Callable[..., Any]:
    """``fn`` that adds its wall time to TIMES[name]."""

    def wrapper(*args: Any, **kwargs: Any) -> Any:
        began = time.perf_counter()
        try:
            return fn(*args, **kwargs)
        finally:
            TIMES[name] += time.perf_counter() - began

    return wrapper


def profile(residual: bool, steps: int, num_envs: int) -> dict[str, float]:
    """Train PPO (residual on PTC if asked) for ``steps`` env steps; return the seconds spent in each part."""
    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import VecEnvWrapper

    from baselines.expert import ExpertPolicy
    from baselines.registry import make_controller
    from dwr_gym.sb3 import make_sb3_vec_env
    from train.learning.residual import ResidualVecEnv

    class TimedEnv(VecEnvWrapper):
        """Times the native env's step (below the residual wrapper and the monitor)."""

        def reset(self) -> Any:
            return self.venv.reset()

        def step_wait(self) -> Any:
            return timed("env step", self.venv.step_wait)()

    TIMES.clear()
    venv: Any = TimedEnv(make_sb3_vec_env(num_envs, seed=0))
    if residual:
        expert = ExpertPolicy(make_controller("ptc"), 0.5, 2.0)
        expert.predict = timed("expert", expert.predict)  # type: ignore[method-assign]
        venv = ResidualVecEnv(venv, expert, 0.5)
    model = PPO("MlpPolicy", venv, n_steps=1024, batch_size=256, seed=0, device="cpu", verbose=0)
    model.collect_rollouts = timed("rollout collection", model.collect_rollouts)  # type: ignore[method-assign]
    model.train = timed("update (backward)", model.train)  # type: ignore[method-assign]
    began = time.perf_counter()
    model.learn(steps)
    total = time.perf_counter() - began
    parts = dict(TIMES)
    collection = parts.pop("rollout collection")
    parts["policy forward + buffer"] = collection - parts["env step"] - parts.get("expert", 0.0)
    parts["other (logging, callbacks)"] = total - collection - parts["update (backward)"]
    parts["total"] = total
    return parts


def main(argv: list[str] | None = None) -> None:
    parser = parser_for("training-time", __doc__)
    parser.add_argument("--steps", type=int, default=65_536)
    parser.add_argument("--num-envs", type=int, default=16)
    args = parser.parse_args(argv)
    import torch

    torch.set_num_threads(max(1, (os.cpu_count() or 1)))
    print(f"{platform.machine()}, {os.cpu_count()} cores, torch {torch.__version__}, {torch.get_num_threads()} threads")
    for residual in (False, True):
        parts = profile(residual, args.steps, args.num_envs)
        total = parts.pop("total")
        label = "residual PPO on PTC" if residual else "PPO"
        print(f"\n{label}: {args.steps} steps, {args.num_envs} envs, {total:.1f} s, {args.steps / total:,.0f} steps/s")
        for name, seconds in sorted(parts.items(), key=lambda item: -item[1]):
            print(f"  {name:<28} {seconds:7.2f} s  {100 * seconds / total:5.1f} %")

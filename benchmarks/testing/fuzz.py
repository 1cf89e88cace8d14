"""Fuzz the env, the vector env and every controller over random and edge states; print the NaN/inf count.

    python -m benchmarks run fuzz            # 1e6 vector-env states, 5e4 single-env steps, 5e6 controller calls
    python -m benchmarks run fuzz --states 1e5

States mix uniform draws with edge values: distance 0, 1e-12 and up to 1e6 m, headings at +-pi and at the
singular angles +-pi/2 of the law, t at and past T_con, T_con from 1e-3 s to 1e6 s, dt equal to T_con.
The count must be 0.
"""

from __future__ import annotations

import math
import time

import gymnasium as gym
import numpy as np

import dwr_gym  # noqa: F401  (registers the env)
from baselines.base import ControllerInput
from baselines.registry import CONTROLLERS, make_controller
from benchmarks.core.commands import parser_for

EDGE_DISTANCES = np.array([0.0, 1e-12, 1e-6, 0.01, 1.0, 1e3, 9.99e5])
EDGE_ANGLES = np.array([-math.pi, math.pi, 0.0, math.pi / 2, -math.pi / 2, math.nextafter(math.pi, 0.0)])
T_CONS = (1e-3, 0.05, 20.0, 70.0, 1e6)


def edge_or_uniform(rng: np.random.Generator, n: int, edges: np.ndarray, low: float, high: float) -> np.ndarray:
    """Half edge values, half uniform in [low, high]."""
    return np.where(rng.random(n) < 0.5, rng.choice(edges, n), rng.uniform(low, high, n))


def fuzz_env(rng: np.random.Generator, n_states: int, batch: int = 2000, steps: int = 5) -> tuple[int, int]:
    """(states tried, non-finite values) over vector envs stepped from edge starts, float64 and float32."""
    tried = bad = 0
    configs = [(t, dt, dtype) for t in T_CONS for dt in (t, min(0.05, t)) for dtype in ("float64", "float32")]
    while tried < n_states:
        T_con, dt, dtype = configs[(tried // (batch * steps)) % len(configs)]
        venv = gym.make_vec("DWRPointStabilization-v0", num_envs=batch, vectorization_mode="vector_entry_point",
                            T_con=T_con, dt=dt, arena_radius=1e6, dtype=dtype)  # fmt: skip
        d = edge_or_uniform(rng, batch, EDGE_DISTANCES, 0.0, 5.0)
        bearing, heading = (edge_or_uniform(rng, batch, EDGE_ANGLES, -math.pi, math.pi) for _ in range(2))
        start = np.stack([d * np.cos(bearing), d * np.sin(bearing), heading], axis=1)
        obs, _ = venv.reset(seed=int(rng.integers(2**31)), options={"start": start})
        bad += int(np.count_nonzero(~np.isfinite(obs)))
        for _ in range(steps):
            actions = rng.choice(np.array([-1.0, 0.0, 1.0]), (batch, 2)) * rng.uniform(0, 1e3, (batch, 1))
            obs, reward, *_ = venv.step(actions.clip(-1, 1).astype(np.float32))
            bad += int(np.count_nonzero(~np.isfinite(obs)) + np.count_nonzero(~np.isfinite(reward)))
            tried += batch
        venv.close()
    return tried, bad


def fuzz_single_env(rng: np.random.Generator, n_states: int, steps: int = 5) -> tuple[int, int]:
    """(states tried, non-finite values) over single envs (Python-float path) from edge starts."""
    tried = bad = 0
    envs = {t: gym.make("DWRPointStabilization-v0", T_con=t, dt=t, arena_radius=1e6).unwrapped for t in T_CONS}
    while tried < n_states:
        env = envs[T_CONS[int(rng.integers(len(T_CONS)))]]
        d = edge_or_uniform(rng, 1, EDGE_DISTANCES, 0.0, 5.0)[0]
        bearing, heading = edge_or_uniform(rng, 2, EDGE_ANGLES, -math.pi, math.pi)
        obs, _ = env.reset(options={"start": (d * math.cos(bearing), d * math.sin(bearing), heading)})
        bad += int(np.count_nonzero(~np.isfinite(obs)))
        for _ in range(steps):
            obs, reward, terminated, truncated, _ = env.step(rng.choice([-1.0, 0.0, 1.0], 2).astype(np.float32))
            bad += int(np.count_nonzero(~np.isfinite(obs))) + (not math.isfinite(reward))
            tried += 1
            if terminated or truncated:
                break
    return tried, bad


def fuzz_controllers(rng: np.random.Generator, n_states: int) -> tuple[int, int]:
    """(controller calls, non-finite commands) over edge inputs, t from 0 to far past T_con."""
    T_con = rng.choice(np.array(T_CONS), n_states)
    time_fraction = np.where(rng.random(n_states) < 0.5, rng.choice([0.0, 1 - 1e-12, 1.0, 1.5, 1e3], n_states),
                             rng.uniform(0, 2, n_states))  # fmt: skip
    inputs = ControllerInput(
        edge_or_uniform(rng, n_states, EDGE_DISTANCES, 0.0, 5.0),
        edge_or_uniform(rng, n_states, EDGE_ANGLES, -math.pi, math.pi),
        edge_or_uniform(rng, n_states, EDGE_ANGLES, -math.pi, math.pi),
        time_fraction * T_con,
        edge_or_uniform(rng, n_states, EDGE_DISTANCES, 0.0, 5.0),
        rng.uniform(-3.7, 3.7, n_states),
        T_con,
    )
    bad = 0
    for name in CONTROLLERS:
        u, omega = make_controller(name)(inputs)
        bad += int(np.count_nonzero(~np.isfinite(u)) + np.count_nonzero(~np.isfinite(omega)))
    return n_states * len(CONTROLLERS), bad


def main(argv: list[str] | None = None) -> int:
    parser = parser_for("fuzz", __doc__)
    parser.add_argument("--states", type=float, default=1e6, help="env states to try (default: 1e6)")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    rng = np.random.default_rng(args.seed)
    start = time.time()
    single_states, single_bad = fuzz_single_env(rng, int(args.states) // 20)
    env_states, env_bad = fuzz_env(rng, int(args.states))
    calls, controller_bad = fuzz_controllers(rng, int(args.states))
    env_bad += single_bad
    print(f"single env:       {single_states} states, {single_bad} NaN/inf")
    print(f"vector env:       {env_states} states, {env_bad - single_bad} NaN/inf")
    print(f"controllers:      {calls} calls, {controller_bad} NaN/inf")
    print(f"NaN/inf count: {env_bad + controller_bad} ({time.time() - start:.0f} s)")
    return 0 if env_bad + controller_bad == 0 else 1

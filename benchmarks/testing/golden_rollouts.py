"""Record (or check) the seeded float64 rollouts that pin the env's results while it is made faster.

    python -m benchmarks run golden-rollouts --write   # record the ids the record lacks (a new env version)
    python -m benchmarks run golden-rollouts           # largest difference of the current code from the record

The record holds, for DWRPointStabilization-v0, -v1 and -v2: 300 steps of the native vector env (16 robots,
random actions, autoreset) and of the PTC law in it, and one single-env episode under random actions;
observations, rewards, flags, poses, energies and every reward term. tests/test_golden.py compares them to 1e-12.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

import dwr_gym  # noqa: F401
from baselines import ExpertPolicy, PTCController
from benchmarks.core.commands import parser_for

PATH = Path(__file__).resolve().parents[2] / "tests" / "data" / "golden_rollouts.npz"
ENV_IDS = ("DWRPointStabilization-v0", "DWRPointStabilization-v1", "DWRPointStabilization-v2")


RECORDED = 16
"""Robots recorded per vector rollout. A rollout may run more (``num_envs``): sub-env i draws as
``reset(seed=s + i)`` whatever the count, so the first ones are the same robots, and large batches exercise
the torch-computed functions of dwr_gym.model (numpy's below ``TORCH_MIN_SIZE``)."""


def vector_rollout(env_id: str, policy: str, steps: int = 300, num_envs: int = RECORDED) -> dict[str, np.ndarray]:
    """Stack of what the vector env returns for its first RECORDED robots over ``steps`` steps under random
    actions or the PTC law."""
    n = num_envs
    kwargs: dict[str, Any] = {"T_con": 5.0} if env_id.endswith("v0") else {"T_con_range": (3.0, 8.0)}
    envs = gym.make_vec(env_id, num_envs=n, **kwargs)
    obs, _ = envs.reset(seed=7)
    rng, other = np.random.default_rng(3), np.random.default_rng(4)
    expert = ExpertPolicy.from_env(envs, PTCController())
    out: dict[str, list[np.ndarray]] = {}
    for _ in range(steps):
        if policy == "random":
            action = rng.uniform(-1.2, 1.2, (RECORDED, 2)).astype(np.float32)
            action = np.concatenate([action, other.uniform(-1.2, 1.2, (n - RECORDED, 2)).astype(np.float32)])
        else:
            action = expert(obs)
        obs, reward, terminated, truncated, info = envs.step(action)
        record = {"obs": obs, "reward": reward, "terminated": terminated, "truncated": truncated,
                  "pose": info["pose"], "energy": info["energy"], "distance": info["distance"],
                  **{f"term_{k}": v for k, v in info["reward_terms"].items() if not k.startswith("_")}}  # fmt: skip
        for key, value in record.items():
            value = np.array(value[:RECORDED], dtype=np.float32 if key == "obs" else np.float64)
            out.setdefault(key, []).append(value)
    envs.close()
    return {key: np.stack(values) for key, values in out.items()}


def single_rollout(env_id: str, steps: int = 300) -> dict[str, np.ndarray]:
    """One single env under random actions, reset when an episode ends."""
    env = gym.make(env_id, T_con=5.0)
    obs, _ = env.reset(seed=11)
    rng = np.random.default_rng(5)
    rows = []
    for _ in range(steps):
        obs, reward, terminated, truncated, info = env.step(rng.uniform(-1, 1, 2).astype(np.float32))
        rows.append(np.concatenate([obs, [reward, terminated, truncated, info["energy"]], info["pose"]]))
        if terminated or truncated:
            obs, _ = env.reset()
    env.close()
    return {"single": np.array(rows, dtype=np.float64)}


def rollouts(num_envs: int = RECORDED) -> dict[str, np.ndarray]:
    """Every recorded array, keyed "<env id>/<rollout>/<name>", the vector env running ``num_envs`` robots."""
    arrays = {}
    for env_id in ENV_IDS:
        for policy in ("random", "ptc"):
            for key, value in vector_rollout(env_id, policy, num_envs=num_envs).items():
                arrays[f"{env_id}/{policy}/{key}"] = value
        for key, value in single_rollout(env_id).items():
            arrays[f"{env_id}/{key}"] = value
    return arrays


def main(argv: list[str] | None = None) -> None:
    parser = parser_for("golden-rollouts", __doc__)
    parser.add_argument("--write", action="store_true", help="record the rollouts of the ids the record lacks")
    args = parser.parse_args(argv)
    if args.write:  # an id recorded once stays as recorded: its record pins that version's behaviour
        kept = dict(np.load(PATH)) if PATH.exists() else {}
        arrays = {**rollouts(), **kept}
        np.savez_compressed(PATH, **arrays)
        print(f"wrote {PATH} ({len(arrays) - len(kept)} arrays added to the {len(kept)} kept)")
        return
    golden = np.load(PATH)
    for num_envs in (RECORDED, 1024):
        arrays = rollouts(num_envs)
        worst = max((float(np.max(np.abs(arrays[k] - golden[k]))), k) for k in golden.files)
        print(f"num_envs={num_envs}: largest difference from the record {worst[0]:.3e} ({worst[1]})")

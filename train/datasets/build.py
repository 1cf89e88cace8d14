"""A dataset from a policy: collect, add each episode's optimum, score the references, write.

Reference scores (Minari's ``ref_min_score`` and ``ref_max_score``, which ``minari.get_normalized_score`` maps
to 0 and 1) are measured on a fixed evaluation set of the dataset's own env (``REF_EPISODES`` episodes from
seed ``REF_SEED``, apart from any data seed):

- ``ref_min_score``: the mean return of uniformly random actions on the evaluation env;
- ``ref_max_score``: the mean return of the optimum, the ``optimal`` controller (minimum-energy plans to the goal
  pose by T_con, re-planned), on the same starts and prescribed times without the env's disturbances and noise.

Both are cached in the optimum's cache directory, keyed by the env and its keywords.
"""

from __future__ import annotations

import hashlib
import json
import math
import sys
from dataclasses import dataclass
from typing import Any

import numpy as np

from dwr_gym.disturbances import ROBOT_KEYWORDS, split_env_kwargs
from dwr_gym.params import EnvParams
from dwr_gym.serialization import env_kwargs_to_json
from train.datasets.collect import Episodes, RandomPolicy, collect
from train.evaluation.optimum import cache_dir, optimal_energies
from train.evaluation.rollout import Policy

REF_EPISODES = 100
REF_SEED = 12345
#: Bump when the reference scores' definition changes, so that stale cached ones are not reused.
REF_VERSION = 1
#: Env keywords that make the robot imperfect: the optimum of ``ref_max_score`` runs without them.
IMPERFECTIONS = (*ROBOT_KEYWORDS, "observation_noise", "actuation_noise")


@dataclass(frozen=True)
class DatasetRequest:
    """What ``dwr-gym dataset`` writes: the id, the policy's name, the env, the episodes and the seed."""

    dataset_id: str
    policy_name: str
    env_id: str
    env_kwargs: dict[str, Any]
    episodes: int
    seed: int = 0
    num_envs: int = 1024
    optimum: bool = True
    ref_episodes: int = REF_EPISODES
    overwrite: bool = False
    description: str = ""


def controller_policy(name: str, env_kwargs: dict[str, Any], seed: int = 0) -> Policy:
    """The policy of a controller name of :mod:`baselines.registry`, or ``random``, for the env of ``env_kwargs``."""
    if name == "random":
        return RandomPolicy(seed)
    from baselines.expert import ExpertPolicy
    from train.evaluation.scenarios import Scenario, controller_for

    params = EnvParams.from_kwargs(**split_env_kwargs(env_kwargs)[0])
    nowhere = Scenario("dataset", np.zeros((0, 3)), np.zeros((0, 3)))
    return ExpertPolicy(controller_for(name, nowhere, params), params.u_max, params.omega_max)


def nominal(env_kwargs: dict[str, Any]) -> dict[str, Any]:
    """``env_kwargs`` without the robot's imperfections (disturbances, wheels, noise)."""
    return {k: v for k, v in env_kwargs.items() if k not in IMPERFECTIONS}


def reference_scores(
    env_id: str, env_kwargs: dict[str, Any], episodes: int = REF_EPISODES, progress: bool = False
) -> tuple[float, float]:
    """(ref_min_score, ref_max_score) of the env over ``episodes`` evaluation episodes; see the module's docstring.
    Solved once, then cached."""
    key = json.dumps([REF_VERSION, env_id, env_kwargs_to_json(env_kwargs), episodes, REF_SEED], sort_keys=True)
    path = cache_dir() / f"dataset-reference-{hashlib.sha256(key.encode()).hexdigest()[:16]}.json"
    try:
        cached = json.loads(path.read_text())
        return float(cached["ref_min_score"]), float(cached["ref_max_score"])
    except (OSError, ValueError, KeyError):
        pass
    random = collect(RandomPolicy(REF_SEED), env_kwargs, episodes, seed=REF_SEED, progress=progress,
                     description="ref_min_score: random")  # fmt: skip
    optimum = controller_policy("optimal", nominal(env_kwargs))
    best = collect(optimum, nominal(env_kwargs), episodes, seed=REF_SEED, progress=progress,
                   description="ref_max_score: optimum (CasADi plans)")  # fmt: skip
    _close(optimum)
    scores = float(np.mean(random.returns())), float(np.mean(best.returns()))
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps({"key": key, "ref_min_score": scores[0], "ref_max_score": scores[1]}))
    except OSError as error:  # a read-only home: the scores are still returned, just not kept
        print(f"warning: could not cache reference scores in {path.parent}: {error}", file=sys.stderr)
    return scores


def add_optimum(episodes: Episodes, env_kwargs: dict[str, Any], progress: bool = False) -> int:
    """Each episode's optimal energy (to the goal pose by its T_con, from the cache or CasADi) and E/opt in its
    metadata; None where there is none. Returns the number of episodes without an optimum."""
    params = EnvParams.from_kwargs(**split_env_kwargs(env_kwargs)[0])
    starts = np.array([m["start"] for m in episodes.metadata])
    goals = np.array([m["goal"] for m in episodes.metadata])
    T_cons = np.array([m["T_con"] for m in episodes.metadata])
    energies, failures = optimal_energies(params, starts, goals, T_cons, progress=progress,
                                          description="optimum of each episode")  # fmt: skip
    for meta, optimum in zip(episodes.metadata, energies, strict=True):
        finite = math.isfinite(optimum) and optimum > 0.0
        meta["optimal_energy"] = float(optimum) if math.isfinite(optimum) else None
        meta["energy_ratio"] = meta["energy"] / optimum if finite and meta["in_time"] else None
    return len(failures)


def statistics(episodes: Episodes) -> dict[str, float]:
    """Size and return statistics of collected episodes (what the suite's table shows)."""
    returns = episodes.returns()
    meta = episodes.metadata
    ratios = [m["energy_ratio"] for m in meta if m.get("energy_ratio") is not None]
    return {
        "episodes": float(len(returns)), "steps": float(episodes.steps), "return_mean": float(np.mean(returns)),
        "return_std": float(np.std(returns)), "return_min": float(np.min(returns)), "return_max": float(np.max(returns)),
        "in_time": float(np.mean([m["in_time"] for m in meta])),
        "heading_error_mean": float(np.mean([m["heading_error"] for m in meta])),
        "energy_ratio_mean": float(np.mean(ratios)) if ratios else math.nan,
    }  # fmt: skip


def _close(policy: Any) -> None:
    close = getattr(getattr(policy, "controller", None), "close", None)
    if close is not None:
        close()


def build_dataset(request: DatasetRequest, policy: Policy, progress: bool = False) -> dict[str, Any]:
    """Collect, add the optimum, score the references and write ``request``'s dataset; returns its summary."""
    from train.datasets.store import check_dataset_id, dataset_exists, write_dataset

    check_dataset_id(request.dataset_id)
    if dataset_exists(request.dataset_id) and not request.overwrite:  # before any work, and again when writing
        from train.datasets.store import DatasetError, datasets_root

        raise DatasetError(f"dataset_id {request.dataset_id!r} is invalid: it exists in {datasets_root()}; "
                           "pass --overwrite to replace it")  # fmt: skip
    episodes = collect(policy, request.env_kwargs, request.episodes, seed=request.seed, num_envs=request.num_envs,
                       progress=progress, description=f"{request.policy_name}: episodes")  # fmt: skip
    _close(policy)
    json_kwargs = env_kwargs_to_json(request.env_kwargs)
    fixed = {k: v for k, v in json_kwargs.items() if k in IMPERFECTIONS and k != "disturbance_distribution"}
    for meta in episodes.metadata:
        meta["policy"] = request.policy_name
        if meta["disturbance"] is None and fixed:  # the same robot in every episode: the env's keywords of it
            meta["disturbance"] = fixed
    missing = add_optimum(episodes, request.env_kwargs, progress) if request.optimum else len(episodes.metadata)
    ref_min, ref_max = reference_scores(request.env_id, request.env_kwargs, request.ref_episodes, progress)
    stats = statistics(episodes)
    description = request.description or (
        f"{request.episodes} episodes of {request.policy_name} on {request.env_id}; ref_max_score: the optimum's "
        f"mean return (minimum-energy plans, nominal robot), ref_min_score: random actions'"
    )
    path = write_dataset(request.dataset_id, episodes, request.env_id, request.env_kwargs,
                         algorithm_name=request.policy_name, description=description, ref_min_score=ref_min,
                         ref_max_score=ref_max, overwrite=request.overwrite,
                         extra_metadata={"dwr_gym_seed": request.seed})  # fmt: skip
    normalised = (stats["return_mean"] - ref_min) / (ref_max - ref_min) if ref_max != ref_min else math.nan
    return {"dataset_id": request.dataset_id, "policy": request.policy_name, "env_id": request.env_id,
            "path": str(path), **stats, "ref_min_score": ref_min, "ref_max_score": ref_max,
            "normalized_score": normalised, "episodes_without_optimum": missing,
            "collect_seconds": episodes.seconds}  # fmt: skip


__all__ = ["REF_EPISODES", "REF_SEED", "DatasetRequest", "add_optimum", "build_dataset", "controller_policy",
           "nominal", "reference_scores", "statistics"]  # fmt: skip

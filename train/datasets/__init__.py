"""Minari datasets of any controller or agent, each episode with its optimum: ``dwr-gym dataset`` and its API.

>>> from train.datasets import make_dataset, episode_metadata  # doctest: +SKIP
>>> make_dataset("dwr-gym/ptc-demo-v0", policy="ptc", episodes=20)  # doctest: +SKIP
"""

from __future__ import annotations

from typing import Any

from train.datasets.collect import RandomPolicy, collect
from train.datasets.store import (
    DatasetError,
    check_dataset_id,
    dataset_env,
    episode_metadata,
    load_dataset,
    transitions,
    write_dataset,
)


def make_dataset(
    dataset_id: str,
    policy: Any = "ptc",
    episodes: int = 1000,
    *,
    env_id: str = "DWRPointStabilization-v1",
    env_kwargs: dict[str, Any] | None = None,
    seed: int = 0,
    num_envs: int = 1024,
    ref_episodes: int = 100,
    optimum: bool = True,
    overwrite: bool = False,
    progress: bool = False,
) -> dict[str, Any]:
    """Write Minari dataset ``dataset_id`` of ``policy`` (a controller's name, ``"random"``, or anything with
    stable-baselines3's ``predict``) on ``env_id`` with ``env_kwargs`` on top of its registered ones (their JSON
    form accepted); returns its size and return statistics. What ``dwr-gym dataset`` does."""
    from dwr_gym.serialization import env_kwargs_from_json
    from train.datasets.build import DatasetRequest, build_dataset, controller_policy
    from train.env_ids import check_env_id, env_keywords

    env_id = check_env_id(env_id, "env_id")
    kwargs = env_kwargs_from_json(env_keywords(env_id, env_kwargs))
    name = policy if isinstance(policy, str) else type(policy).__name__
    acting = controller_policy(policy, kwargs, seed) if isinstance(policy, str) else policy
    request = DatasetRequest(dataset_id, name, env_id, kwargs, episodes, seed=seed, num_envs=num_envs,
                             optimum=optimum, ref_episodes=ref_episodes, overwrite=overwrite)  # fmt: skip
    return build_dataset(request, acting, progress=progress)


__all__ = ["DatasetError", "RandomPolicy", "check_dataset_id", "collect", "dataset_env", "episode_metadata",
           "load_dataset", "make_dataset", "transitions", "write_dataset"]  # fmt: skip

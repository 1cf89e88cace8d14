"""Minari datasets of collected episodes: written through Minari's buffer API, atomically, and read back.

A dataset is written under a hidden staging directory inside Minari's data path (``MINARI_DATASETS_PATH``,
default ``~/.minari/datasets``; Minari lists no hidden directory) and renamed to its id when complete, so an
interrupted run leaves no half dataset under the id. The env spec is stored with its keywords in JSON
(:mod:`dwr_gym.serialization`: disturbances included), so ``dataset.recover_environment()`` rebuilds the env.
Each episode's metadata (T_con, start, goal, energy, the optimum's energy, the disturbance drawn, ...) is in
:func:`episode_metadata`.
"""

from __future__ import annotations

import contextlib
import dataclasses
import os
import re
import shutil
import uuid
import warnings
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from dwr_gym.serialization import env_kwargs_to_json
from train.datasets.collect import Episodes

#: Minari's id form, with the namespace required: ``namespace/name-vN`` (the namespace may have more levels).
DATASET_ID = re.compile(r"[A-Za-z0-9_.-]+(/[A-Za-z0-9_.-]+)*/[A-Za-z0-9_.-]+-v\d+")
DATA_FORMAT = "arrow"  # Minari's default, HDF5, needs h5py; arrow needs pyarrow, which the minari extra brings
AUTHOR = "dwr-gym"


class DatasetError(ValueError):
    """A dataset that cannot be written or read as asked; the message is one line."""


def require_minari() -> Any:
    """The ``minari`` module, or a DatasetError naming the extra to install."""
    try:
        import minari
    except ImportError:
        raise DatasetError('datasets need Minari: pip install "dwr-gym[minari]"') from None
    return minari


def check_dataset_id(dataset_id: str, flag: str = "dataset_id") -> str:
    """``dataset_id`` when it has Minari's ``namespace/name-vN`` form, else a DatasetError naming the form."""
    if not isinstance(dataset_id, str) or not DATASET_ID.fullmatch(dataset_id):
        raise DatasetError(f"{flag} {dataset_id!r} is invalid: expected Minari's form namespace/name-vN, "
                           "e.g. dwr-gym/ptc-nominal-v0")  # fmt: skip
    return dataset_id


def datasets_root() -> Path:
    """Minari's data path: ``$MINARI_DATASETS_PATH``, else ``~/.minari/datasets``."""
    return Path(os.environ.get("MINARI_DATASETS_PATH") or Path.home() / ".minari" / "datasets")


def dataset_exists(dataset_id: str) -> bool:
    return (datasets_root() / dataset_id).exists()


def env_spec(env_id: str, env_kwargs: dict[str, Any]) -> Any:
    """The registered spec of ``env_id`` with ``env_kwargs`` in JSON form (its own ones and the caller's)."""
    import gymnasium

    import dwr_gym  # noqa: F401  (registers the ids)

    try:
        kwargs = env_kwargs_to_json(env_kwargs)
    except ValueError as error:
        raise DatasetError(str(error)) from None
    return dataclasses.replace(gymnasium.spec(env_id), kwargs=kwargs)


@contextlib.contextmanager
def _size_once() -> Iterator[None]:
    """Minari 0.5's arrow storage recomputes the dataset's size (a walk over every file) after each episode it
    writes: 132 s for 1,200 episodes on the suite's machine, against 10 s without. Inside this block that walk is
    skipped; :func:`write_dataset` computes the size once at the end."""
    from minari.dataset.minari_storage import MinariStorage

    original = MinariStorage.get_size
    MinariStorage.get_size = lambda self: 0.0  # type: ignore[method-assign]
    try:
        yield
    finally:
        MinariStorage.get_size = original  # type: ignore[method-assign]


@contextlib.contextmanager
def _data_path(path: Path) -> Iterator[None]:
    previous = os.environ.get("MINARI_DATASETS_PATH")
    os.environ["MINARI_DATASETS_PATH"] = str(path)
    try:
        yield
    finally:
        if previous is None:
            os.environ.pop("MINARI_DATASETS_PATH", None)
        else:
            os.environ["MINARI_DATASETS_PATH"] = previous


def write_dataset(
    dataset_id: str,
    episodes: Episodes,
    env_id: str,
    env_kwargs: dict[str, Any],
    *,
    algorithm_name: str,
    description: str,
    ref_min_score: float,
    ref_max_score: float,
    overwrite: bool = False,
    extra_metadata: dict[str, Any] | None = None,
) -> Path:
    """Write ``episodes`` as Minari dataset ``dataset_id``; returns its directory.

    The collecting env and the evaluation env are both ``env_id`` with ``env_kwargs``. An existing id is a
    DatasetError unless ``overwrite``; the old dataset is replaced only once the new one is complete.
    """
    minari = require_minari()
    from minari.data_collector import EpisodeBuffer
    from minari.namespace import create_namespace, list_local_namespaces

    check_dataset_id(dataset_id)
    root = datasets_root()
    final = root / dataset_id
    if final.exists() and not overwrite:
        raise DatasetError(f"dataset_id {dataset_id!r} is invalid: it exists in {root}; pass --overwrite to replace it")
    spec = env_spec(env_id, env_kwargs)
    buffers = [
        EpisodeBuffer(id=k, observations=obs, actions=act, rewards=rew, terminations=term, truncations=trunc)
        for k, (obs, act, rew, term, trunc) in enumerate(zip(episodes.observations, episodes.actions,
                                                              episodes.rewards, episodes.terminations,
                                                              episodes.truncations, strict=True))
    ]  # fmt: skip
    root.mkdir(parents=True, exist_ok=True)
    staging = root / f".partial-{os.getpid()}-{uuid.uuid4().hex[:8]}"
    try:
        with _data_path(staging), _size_once(), warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)  # Minari's notes on optional fields, all given here
            dataset = minari.create_dataset_from_buffers(
                dataset_id, buffers, env=spec, eval_env=spec, algorithm_name=algorithm_name, author=AUTHOR,
                ref_min_score=float(ref_min_score), ref_max_score=float(ref_max_score), description=description,
                data_format=DATA_FORMAT,
            )  # fmt: skip
            dataset.storage.update_episode_metadata(episodes.metadata, range(len(episodes.metadata)))
            if extra_metadata:
                dataset.storage.update_metadata(extra_metadata)
        dataset.storage.update_metadata({"dataset_size": dataset.storage.get_size()})
        namespace = dataset_id.rsplit("/", 1)[0]
        with _data_path(root):
            if namespace not in list_local_namespaces():
                create_namespace(namespace)
        old = root / f".replaced-{uuid.uuid4().hex[:8]}"
        if final.exists():
            final.rename(old)  # overwrite: the old one goes only once the new one is complete
        (staging / dataset_id).rename(final)
        shutil.rmtree(old, ignore_errors=True)
    finally:
        shutil.rmtree(staging, ignore_errors=True)
    return final


def load_dataset(dataset_id: str, flag: str = "dataset_id") -> Any:
    """A local Minari dataset by id, or a DatasetError naming the id and what exists."""
    minari = require_minari()
    check_dataset_id(dataset_id, flag)
    if not dataset_exists(dataset_id):
        known = sorted(minari.list_local_datasets())
        raise DatasetError(f"{flag} {dataset_id!r} is invalid: no such dataset in {datasets_root()}; local ones: "
                           f"{', '.join(known) if known else 'none'} (write one with dwr-gym dataset)")  # fmt: skip
    return minari.load_dataset(dataset_id)


def episode_metadata(dataset: Any) -> list[dict[str, Any]]:
    """Each episode's metadata: T_con, start, goal, energy, optimal_energy, disturbance, return, in_time, ..."""
    return list(dataset.storage.get_episode_metadata(range(dataset.total_episodes)))


def dataset_env(dataset: Any) -> tuple[str, dict[str, Any]]:
    """(env id, env keywords as objects) of the env a dataset was collected on."""
    from dwr_gym.serialization import env_kwargs_from_json

    spec = dataset.spec.env_spec
    if spec is None:
        raise DatasetError(f"dataset {dataset.spec.dataset_id!r} is invalid here: it stores no env spec")
    return spec.id, env_kwargs_from_json(dict(spec.kwargs))


def transitions(dataset: Any) -> dict[str, NDArray[Any]]:
    """All steps of the dataset as flat arrays: observations, actions, rewards, next_observations, terminals,
    timeouts (the arrays offline RL libraries take)."""
    parts: dict[str, list[NDArray[Any]]] = {k: [] for k in ("observations", "actions", "rewards", "next_observations",
                                                               "terminals", "timeouts")}  # fmt: skip
    for episode in dataset.iterate_episodes():
        parts["observations"].append(episode.observations[:-1])
        parts["next_observations"].append(episode.observations[1:])
        parts["actions"].append(episode.actions)
        parts["rewards"].append(episode.rewards)
        parts["terminals"].append(episode.terminations)
        parts["timeouts"].append(episode.truncations)
    return {k: np.concatenate(v) for k, v in parts.items()}


__all__ = ["DATASET_ID", "DatasetError", "check_dataset_id", "dataset_env", "datasets_root", "episode_metadata", "load_dataset",
           "require_minari", "transitions", "write_dataset"]  # fmt: skip

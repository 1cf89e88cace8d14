"""A grid of independent calls as Ray tasks: ``dwr-gym benchmark --ray`` (or ``--address ADDR``) runs its agent x
seed grid with it, each task the :func:`train.learning.benchmark.run_one` that the local processes run.

Without ``address`` a Ray is started on this machine; ``auto`` (or ``ray://host:10001``) joins a running cluster,
whose workers must have dwr-gym installed and see the output directory at the same path (a shared filesystem), as
``dwr-gym sweep`` needs.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

from train.learning.config import ConfigError

RAY_EXTRA = 'pip install "dwr-gym[sweep]"'


def run_on_ray(
    function: Callable[..., Any],
    calls: Sequence[tuple[Any, ...]],
    address: str | None = None,
    resources: dict[str, float] | None = None,
) -> list[Any]:
    """``function(*args)`` for every ``args`` of ``calls``, each a Ray task of ``resources`` (``cpu``, ``gpu`` and
    custom ones; default one CPU); the results in the order of ``calls``. A task that fails fails the grid (its
    exception is raised here, as its own class); the tasks already finished keep what they wrote."""
    try:
        import ray
    except ImportError as error:
        raise ConfigError(f"running on Ray needs ray ({error.name} is missing): {RAY_EXTRA}") from None
    needs = dict(resources or {"cpu": 1.0})
    options = {"num_cpus": needs.pop("cpu", 1.0), "num_gpus": needs.pop("gpu", 0.0), "resources": needs,
               "max_retries": 0}  # fmt: skip
    started = not ray.is_initialized()
    if started:
        ray.init(address=address, include_dashboard=False, configure_logging=False, log_to_driver=False)
    try:
        task = ray.remote(function).options(**options)
        return list(ray.get([task.remote(*args) for args in calls]))
    finally:
        if started:
            ray.shutdown()


__all__ = ["RAY_EXTRA", "run_on_ray"]

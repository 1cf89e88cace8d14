"""``dwr-gym train``: the learner of ``--algo`` on ``--backend`` (:mod:`train.learning.learners`) trains the
configuration in its run directory (:mod:`train.learning.runs`).

Every learner keeps one contract: periodic evaluation on a fixed seeded scenario set, checkpoints that resume bit
for bit, ``--time-limit``, and Ctrl-C, which saves the last model and raises KeyboardInterrupt.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

from train.learning.config import ConfigError, TrainConfig
from train.learning.learners import find_learner


def train(
    config: TrainConfig,
    command: list[str] | None = None,
    on_evaluation: Callable[[dict[str, Any]], None] | None = None,
) -> Path:
    """Train as configured; returns the run directory. ``on_evaluation`` receives each periodic evaluation as a dict
    of EVAL_FIELDS (e.g. to report it to a tuner); ``command`` is what config.yaml records (default: ``sys.argv``).

    torch runs on ``config.threads`` threads (default 1) while it trains; the caller's count is restored afterwards
    (:mod:`train.threads`). Ctrl-C saves a checkpoint at the next boundary of the learner's work (a rollout, a
    compiled chunk); a second Ctrl-C stops sooner. Then it prints the command that resumes and raises
    KeyboardInterrupt.
    """
    config.validate()
    learner = find_learner(config.algo, config.backend)
    try:
        learner.check_installed()
    except ImportError as error:
        raise ConfigError(str(error)) from None
    trainer: Callable[..., Path] = learner.function(f"{learner.trainer}:train")
    return trainer(config, command, on_evaluation)


__all__ = ["train"]

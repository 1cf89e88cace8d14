"""rl-zoo3 finds dwr-gym's tuned hyperparameters by itself.

rl-zoo3 reads hyperparameters from its own ``hyperparams/<algo>.yml`` unless ``--conf-file`` is given,
and those files do not know our env ids. ``python -m rl_zoo3.train --env DWRPointStabilization-v0
--gym-packages dwr_gym`` imports dwr_gym after rl-zoo3 is loaded; :func:`use_our_hyperparameters` then
points rl-zoo3's default configuration file at ``train/hyperparams/<algo>.yml`` for our env ids only, so
that command works as it is. An explicit ``--conf-file`` is left alone.
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

HYPERPARAMS_DIR = Path(__file__).resolve().parent.parent / "train" / "hyperparams"


def use_our_hyperparameters() -> None:
    """Patch rl-zoo3's ExperimentManager (once, and only if rl-zoo3 is already imported)."""
    module = sys.modules.get("rl_zoo3.exp_manager")
    manager = getattr(module, "ExperimentManager", None)
    if manager is None or getattr(manager, "_dwr_gym_defaults", False):
        return
    original = manager.read_hyperparameters

    def read_hyperparameters(self: Any) -> Any:
        ours = HYPERPARAMS_DIR / f"{self.algo}.yml"
        own_default = Path(str(self.config)).parent.name == "hyperparams" and "rl_zoo3" in str(self.config)
        if own_default and str(self.env_name.gym_id).startswith("DWRPointStabilization") and ours.is_file():
            self.config = str(ours)
        return original(self)

    manager.read_hyperparameters = read_hyperparameters
    manager._dwr_gym_defaults = True

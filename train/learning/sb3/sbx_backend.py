"""``dwr-gym train --backend sbx``: SAC, TD3, TQC and CrossQ of sbx-rl (the JAX stable-baselines) on the same path
as stable-baselines3 (:mod:`train.learning.sb3.trainer`).

sbx keeps stable-baselines3's API (``learn`` with SB3 callbacks, ``predict``, ``save``/``load`` to the same zip,
the replay buffer) and runs the networks and their updates in JAX, compiled by XLA. So the run directory, the
evaluation on the fixed set, checkpoints, resume and Ctrl-C are those of the SB3 path unchanged, and a saved sbx
agent loads wherever agents load (:func:`train.learning.agents.load_agent` reads ``backend`` from config.yaml;
its class is its entry's ``model`` in :mod:`train.learning.learners`).
"""

from __future__ import annotations

from typing import Any

from train.learning.config import ConfigError, TrainConfig

FLAX_ACTIVATIONS = {"nn.Tanh": "tanh", "nn.ReLU": "relu", "nn.ELU": "elu", "nn.LeakyReLU": "leaky_relu",
                    "nn.SiLU": "silu", "nn.GELU": "gelu", "nn.Sigmoid": "sigmoid"}  # fmt: skip
"""rl-zoo3's torch spellings of ``activation_fn`` (the YAML files') as the flax functions sbx's networks take."""


def check_sbx_config(config: TrainConfig) -> None:
    """Raise ConfigError (one line) for a --device other than cpu. (Its algorithms, and that it trains no residual,
    whose start at the expert zeroes the last layer of a torch network, are its entries in
    :mod:`train.learning.learners`.)"""
    if config.device != "cpu":  # JAX places the networks itself, on its default device
        raise ConfigError(f"--device {config.device!r} is invalid with --backend sbx: it runs on JAX's default "
                          "device; leave --device at cpu (JAX_PLATFORMS=cuda chooses a GPU)")  # fmt: skip


def sbx_policy_kwargs(policy_kwargs: dict[str, Any]) -> dict[str, Any]:
    """``policy_kwargs`` for sbx: ``activation_fn`` as the flax function of the same name."""
    kwargs = dict(policy_kwargs)
    if isinstance(kwargs.get("activation_fn"), str):
        import flax.linen

        kwargs["activation_fn"] = getattr(flax.linen, FLAX_ACTIVATIONS[kwargs["activation_fn"]])
    return kwargs


__all__ = ["check_sbx_config", "sbx_policy_kwargs"]

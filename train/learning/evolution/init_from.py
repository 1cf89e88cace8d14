"""ES from a saved network (``dwr-gym train --algo es --backend jax --init-from RUN``): the search is centred on the
actor of a saved SB3 PPO agent (a cloned network, an earlier ES or jitted PPO run) instead of a fresh network.

The run adopts the saved actor's architecture (its hidden sizes and activation) and takes raw observations as the
saved network does (no observation normalisation: a network that was never normalised would see other inputs). Only
the actor (hidden layers, mean head) is read; the critic is not used by ES. Fine-tuning a cloned network this way
pays nothing for exploring (ES scores each candidate by its deterministic return), where PPO's fine-tuning pays the
energy of its action noise (docs/rl-benchmark.md, 'Robust RL').
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from train.learning.config import ConfigError
from train.learning.evolution.settings import ESSettings
from train.learning.jitted.policy import TORCH_ACTIVATIONS
from train.learning.runs import saved_model

#: Our activation names by torch's class names.
ACTIVATION_NAMES = {torch_name: name for name, torch_name in TORCH_ACTIVATIONS.items()}


def saved_actor(init_from: str) -> tuple[dict[str, dict[str, np.ndarray]], tuple[int, ...], str]:
    """The actor of the saved PPO agent ``init_from`` (a run directory or a model .zip): its layers named as the
    jitted network's (``policy_<i>``, ``action``; kernels (in, out)), its hidden sizes and its activation's name.
    A ConfigError of one line naming ``--init-from`` where it is not a PPO MlpPolicy agent."""
    import torch
    from stable_baselines3 import PPO

    path = saved_model(init_from)
    if not path.is_file():
        raise ConfigError(f"--init-from {init_from!r} is invalid: {path} does not exist")
    try:
        policy = PPO.load(path, device="cpu").policy
    except Exception as error:  # a zip of another algorithm or no SB3 model at all
        raise ConfigError(f"--init-from {init_from!r} is invalid with --algo es: not a PPO model "
                          f"({type(error).__name__}: {str(error)[:120]})") from None  # fmt: skip
    linears = [m for m in policy.mlp_extractor.policy_net if isinstance(m, torch.nn.Linear)]
    activations = {type(m).__name__ for m in policy.mlp_extractor.policy_net if not isinstance(m, torch.nn.Linear)}
    if len(activations) > 1 or not activations <= set(ACTIVATION_NAMES):
        raise ConfigError(f"--init-from {init_from!r} is invalid with --algo es: its actor's activation "
                          f"({', '.join(sorted(activations))}) is not one of {', '.join(ACTIVATION_NAMES)}")  # fmt: skip
    activation = ACTIVATION_NAMES[activations.pop()] if activations else "tanh"

    def layer(linear: Any) -> dict[str, np.ndarray]:
        return {"kernel": linear.weight.detach().numpy().T.astype(np.float32),
                "bias": linear.bias.detach().numpy().astype(np.float32)}  # fmt: skip

    layers = {f"policy_{i}": layer(linear) for i, linear in enumerate(linears)}
    layers["action"] = layer(policy.action_net)
    return layers, tuple(int(linear.out_features) for linear in linears), activation


def adopt(settings: ESSettings, net_arch: tuple[int, ...], activation: str) -> ESSettings:
    """``settings`` with the saved actor's architecture and without observation normalisation."""
    return dataclasses.replace(settings, net_arch=net_arch, activation=activation, normalize_observations=False)


def centred_on(params: Any, actor: dict[str, dict[str, np.ndarray]], init_from: str) -> Any:
    """The network's ``params`` with ``actor``'s layers in place of its own; a ConfigError where a shape differs."""
    import jax.numpy as jnp

    layers = dict(params["params"])
    for name, saved in actor.items():
        for key, value in saved.items():
            if name not in layers or tuple(layers[name][key].shape) != value.shape:
                raise ConfigError(f"--init-from {init_from!r}: the saved actor's {name}.{key} {value.shape} does not fit "
                                  "the run's network")  # fmt: skip
        layers[name] = {key: jnp.asarray(value, layers[name][key].dtype) for key, value in saved.items()}
    return {**params, "params": layers}


__all__ = ["adopt", "centred_on", "saved_actor"]
